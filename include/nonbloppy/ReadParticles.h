// SPDX-License-Identifier: Apache-2.0
/// @file ReadParticles.h
/// @brief Stage "read particles": load a particle file into a ParticleSet.
///
/// Formats, chosen by the file extension (case-insensitive):
/// - `.vtk`  legacy VTK (ASCII or binary big-endian), UNSTRUCTURED_GRID or POLYDATA,
///           float or double POINTS; POINT_DATA arrays (SCALARS, VECTORS, FIELD) are kept by name.
/// - `.ply`  PLY (ascii, binary_little_endian, binary_big_endian); vertex x y z (float or
///           double) plus every other scalar vertex property as a 1-component attribute.
/// - `.xyz`  raw little-endian float32 triples, no header.
/// Cost: one pass over the file; memory is the particle set itself plus the file buffer.

#ifndef NONBLOPPY_READ_PARTICLES_H
#define NONBLOPPY_READ_PARTICLES_H

#include <nonbloppy/Particles.h>

#include <string>

namespace nonbloppy {

/// Read every particle and per-particle attribute of @a path.
/// @throw FileError  for a missing, unreadable, truncated or corrupt file, or an unknown
///                   extension; the message names @a path.
/// @throw ParameterError  for NaN or infinite coordinates (naming the file and particle).
/// Thread-safe: yes (no shared state).
ParticleSet readParticles(const std::string& path);

/// True if @a path has an extension readParticles() understands.
bool isParticleFile(const std::string& path);

} // namespace nonbloppy

#endif // NONBLOPPY_READ_PARTICLES_H
