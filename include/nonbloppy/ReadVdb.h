// SPDX-License-Identifier: Apache-2.0
/// @file ReadVdb.h
/// @brief Read back every grid of a `.vdb` file (the caches writeVdb() writes), checked
///        first, for `nonbloppy inspect` and callers that load those caches.

#ifndef NONBLOPPY_READ_VDB_H
#define NONBLOPPY_READ_VDB_H

#include <nonbloppy/Export.h>

#include <openvdb/openvdb.h>

#include <string>

namespace nonbloppy {

/// What a `.vdb` file holds.
struct VdbFileContents
{
    std::string formatVersion;  ///< "<library major.minor>/<file format>", as io::File::version() spells it
    openvdb::MetaMap metadata;  ///< the file's own metadata
    openvdb::GridPtrVec grids;  ///< every grid, trees included, in file order
};

/// Read every grid of @a path. Before OpenVDB parses anything, the header, the file
/// metadata, every grid descriptor and each grid's metadata and transform are walked and
/// checked against the file's size, and each grid must end inside the file: OpenVDB's
/// io::File trusts those lengths, and a truncated file made it allocate gigabytes.
/// The trees themselves are then read by OpenVDB; corrupt values inside them give its
/// error, on one line and shortened, or "it asks for more memory than there is".
/// Cost: one pass over the file. Thread-safety: reentrant.
/// @throw FileError naming @a path: "cannot open", "not a VDB file", "truncated ...".
NONBLOPPY_API VdbFileContents readVdbFile(const std::string& path);

} // namespace nonbloppy

#endif // NONBLOPPY_READ_VDB_H
