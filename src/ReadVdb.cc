// SPDX-License-Identifier: Apache-2.0
/// @file ReadVdb.cc
/// @brief readVdbFile(): the layout walk of ReadVdbPoints.cc, then openvdb::io::File.

#include <nonbloppy/ReadVdb.h>

#include <nonbloppy/Error.h>

#include "FileFormats.h"
#include "ReadVdbPoints.h"

#include <openvdb/io/File.h>

#include <new>

namespace nonbloppy {

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
        // OpenVDB quotes whatever bytes it read: one printable line of at most 200 characters.
        constexpr size_t kMaxQuoted = 200;
        throw FileError("cannot read .vdb file: corrupt grid data (OpenVDB: " + io_internal::printable(e.what(), kMaxQuoted) +
                        ") (" + path + ")");
    }
    return contents;
}

} // namespace nonbloppy
