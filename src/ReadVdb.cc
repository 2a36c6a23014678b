// SPDX-License-Identifier: Apache-2.0
/// @file ReadVdb.cc
/// @brief readVdbFile(): the layout walk of ReadVdbPoints.cc, then openvdb::io::File.

#include <nonbloppy/ReadVdb.h>

#include <nonbloppy/Error.h>

#include "ReadVdbPoints.h"

#include <openvdb/io/File.h>

#include <new>

namespace nonbloppy {

namespace {

/// An exception's text as one short printable line: OpenVDB quotes whatever bytes it read.
std::string oneLine(const std::string& text)
{
    constexpr size_t kMaxLength = 200;
    std::string line = text.substr(0, kMaxLength);
    for (char& ch : line) {
        if (static_cast<unsigned char>(ch) < 0x20 || static_cast<unsigned char>(ch) >= 0x7f) ch = '?';
    }
    return text.size() > kMaxLength ? line + "..." : line;
}

} // namespace

VdbFileContents readVdbFile(const std::string& path)
{
    openvdb::initialize();
    io_internal::checkVdbLayout(path);
    VdbFileContents contents;
    try {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        contents.formatVersion = file.version();
        if (const openvdb::MetaMap::Ptr metadata = file.getMetadata()) contents.metadata = *metadata;
        if (const openvdb::GridPtrVecPtr grids = file.getGrids()) contents.grids = *grids;
        file.close();
    } catch (const std::bad_alloc&) {
        throw FileError("cannot read .vdb file: it asks for more memory than there is (" + path + ")");
    } catch (const std::exception& e) {
        // The layout was sound, so this is damage inside a tree (compressed values, masks).
        throw FileError("cannot read .vdb file: corrupt grid data (OpenVDB: " + oneLine(e.what()) + ") (" + path + ")");
    }
    return contents;
}

} // namespace nonbloppy
