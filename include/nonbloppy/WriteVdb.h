// SPDX-License-Identifier: Apache-2.0
/// @file WriteVdb.h
/// @brief Stage "write vdb": save intermediate grids (the density) as a `.vdb` cache that
///        OpenVDB tools such as `vdb_print` read.

#ifndef NONBLOPPY_WRITE_VDB_H
#define NONBLOPPY_WRITE_VDB_H

#include <nonbloppy/Export.h>

#include <openvdb/openvdb.h>

#include <string>

namespace nonbloppy {

/// Write @a grids to @a path (temporary file, then rename), with @a fileMetadata as the
/// file's metadata, plus "creator" = versionLine() ("nonbloppy 0.1.0 (OpenVDB 10.0.1)")
/// unless @a fileMetadata has one.
/// Grids keep their own metadata (names, class, nonbloppy parameters).
/// Written without compression timestamps, so the same grids give the same bytes.
/// Cost: one pass over the grids' voxels to write the temporary file, then one read of it
/// to hash its bytes into the file UUID, written in place before the rename.
/// Thread-safety: reentrant; concurrent calls must write different paths.
/// @throw FileError naming @a path when it cannot be written.
NONBLOPPY_API void writeVdb(const openvdb::GridCPtrVec& grids, const std::string& path,
              const openvdb::MetaMap& fileMetadata = openvdb::MetaMap());

} // namespace nonbloppy

#endif // NONBLOPPY_WRITE_VDB_H
