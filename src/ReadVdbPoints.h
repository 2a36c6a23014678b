// SPDX-License-Identifier: Apache-2.0
/// @file ReadVdbPoints.h
/// @brief Private: the OpenVDB points reader by path, streaming the file instead of loading it.
///
/// readVdbPointsParticles() (ParticleReaders.h) runs the same code over a memory block (the
/// fuzz target's input); both give the same particles and, word for word, the same errors.

#ifndef NONBLOPPY_READ_VDB_POINTS_H
#define NONBLOPPY_READ_VDB_POINTS_H

#include <nonbloppy/Particles.h>

#include <string>

namespace nonbloppy {
namespace io_internal {

/// The first openvdb::points::PointDataGrid of the `.vdb` file @a path. The file is walked
/// and checked through a bounded window (pread), then libopenvdb parses the grid from the
/// same open file through a bounded stream buffer, so peak memory is the PointDataGrid plus
/// the particle arrays, not the file. A pipe or other non-regular file, which cannot be
/// read twice, is read whole first.
/// @throw FileError naming @a path.
ParticleSet readVdbPointsFile(const std::string& path);

/// Walk the `.vdb` file @a path as far as it can be walked without parsing value trees:
/// header, file metadata, every grid descriptor, each grid's metadata and transform, and
/// every PointDataGrid's tree and attribute pages as readVdbPointsFile() checks them,
/// checking every length and offset against the file's size (a grid must end inside the file).
/// OpenVDB's io::File trusts them: a truncated file made it allocate gigabytes for a
/// "string" and report an unregistered grid type of a billion spaces.
/// @throw FileError naming @a path ("cannot read .vdb file: truncated grid 'density' ...").
void checkVdbLayout(const std::string& path);

} // namespace io_internal
} // namespace nonbloppy

#endif // NONBLOPPY_READ_VDB_POINTS_H
