// SPDX-License-Identifier: Apache-2.0
/// @file ParticleReaders.h
/// @brief Private: the particle readers added after VTK/PLY/XYZ, one source file each,
///        working on a buffer holding the whole file (so the fuzz targets in tests/fuzz/
///        can feed them bytes directly); readParticles() reads files otherwise:
///        BGEO, CSV/TXT and JSON files go through the streaming path readers of
///        StreamReader.h, which run the same code over a bounded buffer, .vtu/.vtp
///        through readVtuFile() (ReadVtu.h), which streams the file through expat, and
///        .vdb through readVdbPointsFile() (ReadVdbPoints.h), which reads the open file
///        through bounded windows (a .vdb pipe is read whole, then walked).
///
/// Each one names @a path in its errors only; it never opens it. Every count read from a
/// header is checked against the bytes present before anything is allocated.

#ifndef NONBLOPPY_PARTICLE_READERS_H
#define NONBLOPPY_PARTICLE_READERS_H

#include <nonbloppy/Particles.h>

#include <cstddef>
#include <string>

namespace nonbloppy {
namespace io_internal {

/// Houdini classic BGEO (`BgeoV`, version 5, big-endian), gzip-compressed or not.
ParticleSet readBgeoParticles(const char* data, size_t size, const std::string& path);

/// VTK XML UnstructuredGrid or PolyData (`.vtu`, `.vtp`).
ParticleSet readVtuParticles(const char* data, size_t size, const std::string& path);

/// Delimited text with a header row naming the columns (`.csv`, `.txt`).
ParticleSet readTableParticles(const char* data, size_t size, const std::string& path);

/// JSON `[[x,y,z], ...]`.
ParticleSet readJsonParticles(const char* data, size_t size, const std::string& path);

/// The first openvdb::points::PointDataGrid of a `.vdb` file.
ParticleSet readVdbPointsParticles(const char* data, size_t size, const std::string& path);

} // namespace io_internal
} // namespace nonbloppy

#endif // NONBLOPPY_PARTICLE_READERS_H
