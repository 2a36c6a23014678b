// SPDX-License-Identifier: Apache-2.0
/// @file WriteParticles.h
/// @brief Stage "write particles": save a ParticleSet with its attributes (for
///        `nonbloppy convert` and `--vdb-points`), and build an OpenVDB PointDataGrid.

#ifndef NONBLOPPY_WRITE_PARTICLES_H
#define NONBLOPPY_WRITE_PARTICLES_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Particles.h>

#include <openvdb/openvdb.h>

#include <string>
#include <vector>

namespace nonbloppy {

/// Options of writeParticles().
struct ParticleWriteSettings
{
    /// Write files of 1 MiB or more with direct I/O (O_DIRECT, past the page cache) on local
    /// ext4, XFS or Btrfs disks, as MeshWriteSettings::directIo; false, and other file
    /// systems, use the page cache. The bytes are the same.
    bool directIo = true;
};

/// Write @a particles to @a path; the format follows the extension:
/// - `.ply`  binary little-endian; float x y z, then each attribute component as a vertex
///           property in its type ("velocity_x/_y/_z" for 3-vectors, "name_<c>" for other
///           multi-component attributes); 64-bit integers (PLY has none) as int or uint
///           when every value fits 32 bits, which keeps them integers, else as double.
/// - `.vtk`  legacy binary UNSTRUCTURED_GRID, float POINTS, one VTK_VERTEX cell per
///           particle, every attribute as a FIELD array in its type.
/// - `.vtu`  VTK XML UnstructuredGrid, raw appended data with UInt64 headers, Float32
///           points, vertex cells, attributes in their types.
/// - `.xyz`  raw little-endian float32 triples (attributes cannot be stored: dropped).
/// - `.csv`  header "x,y,z,<name>" (multi-component: "<name>:0,<name>:1,...", as ParaView;
///           a name holding ',' or a quote in double quotes, a '"' in it doubled: RFC 4180),
///           shortest round-trip decimal text (whole float attribute values as "300.0", so
///           that they read back as floats, not integers; positions are always floats).
/// - `.vdb`  one PointDataGrid named "points" (see makePointDataGrid()).
/// Attribute names are written in the format's alphabet (spaces, commas, quotes, <, >, &
/// and non-ASCII bytes become '_', but for commas and quotes in CSV; for `.vdb` all but
/// letters, digits, '_', '|' and ':'),
/// and kept distinct: a name that would repeat another column, or that the format's
/// reader takes for positions (x, y, z, P; in CSV also X, Points:0, p_y, ...), gets _2,
/// _3, ...; names that need no change keep theirs ("a b" beside "a_b" is "a_b_2").
/// Written through a temporary file renamed into place; same particles, same bytes (with
/// or without direct I/O, see ParticleWriteSettings; `.vdb` goes through OpenVDB's own
/// writer and always uses the page cache).
/// @throw FileError for an unknown extension or an unwritable path; ParameterError for an
///        attribute that does not hold one value per particle or has more than 4096
///        components (the most the readers take; not for `.xyz`), or (`.vdb`) a uint64 value
///        above 2^63 - 1 or a non-finite position ("non-finite position of particle N,
///        which a .vdb points grid cannot hold (PATH)"; other formats write it as it is).
NONBLOPPY_API void writeParticles(const ParticleSet& particles, const std::string& path,
                                  const ParticleWriteSettings& settings = ParticleWriteSettings());

/// The names writeParticles() gives @a particles' attributes in @a path's format, one per
/// attribute in order (see the renaming rules above; a multi-component attribute's columns
/// are derived from its name as described per format); empty strings for `.xyz`, which
/// drops attributes. Compare with ParticleAttribute::name to tell a caller what was renamed.
/// Cost: O(A log A) for A attributes; reads no particle data.
/// @throw FileError for an unknown extension, as writeParticles().
NONBLOPPY_API std::vector<std::string> writtenAttributeNames(const ParticleSet& particles,
                                                             const std::string& path);

/// The names of @a particles' attributes whose values writeParticles() stores rounded in
/// @a path's format: 64-bit integers (Int64, UInt64) past ±2^53 that the format holds as
/// doubles only, a PLY property (PLY has no 64-bit integer) or a `.vdb` 3-vector (OpenVDB's
/// integer vectors are 32-bit; its scalars are int64, exact). Empty for `.vtk`, `.vtu` and
/// `.csv`, which keep every value, and `.xyz`, which keeps none.
/// Cost: one pass over the values of the 64-bit integer attributes, until one is past 2^53.
/// @throw FileError for an unknown extension, as writeParticles().
NONBLOPPY_API std::vector<std::string> roundedAttributes(const ParticleSet& particles, const std::string& path);

/// True if @a path has an extension writeParticles() understands.
NONBLOPPY_API bool isParticleOutputFile(const std::string& path);

/// Refuses @a path as writeParticles() would, by its extension alone, so that a caller can
/// check an output name before reading its input. Cost: O(length of @a path).
/// @throw FileError "particle file name has no extension (out); expected .ply, .vtk, .vtu,
///        .xyz, .csv or .vdb", or "unknown particle output extension '.obj' (out.obj); ..."
NONBLOPPY_API void requireParticleOutputFile(const std::string& path);

/// The particles as an openvdb::points::PointDataGrid named "points": position `P`
/// (world positions, NullCodec) and every attribute in the nearest OpenVDB type (3
/// components become vec3s, vec3d, vec3i for int8 to int32, uint8 and uint16, vec3d for
/// uint32, int64 and uint64; scalar unsigned integers widen to the next signed type,
/// uint64 to int64; other component counts become one scalar attribute per component,
/// "name_<c>"), its values bit for bit (-0.0 stays -0.0). The grid
/// holds the particles in voxel order: readParticles() gives them back in that order.
/// No particles with attributes make one leaf of no points, which names them (OpenVDB
/// describes attributes in its leaves only; readParticles() gives them back, empty).
/// @a voxelSize ≤ 0 picks one with about 8 points per voxel (points::computeVoxelSize),
/// rounded to a power of two, which gives every position back bit for bit (but -0.0 as
/// +0.0). OpenVDB stores positions as float offsets within their voxel and scales their sum
/// by the size: a given size that is not a power of two may move some by a float step, and
/// one far above the particles' extent keeps them to about voxelSize·6e-8 only.
/// @throw ParameterError for a NaN or infinite @a voxelSize or one below kMinCellSize, one
///        that puts a particle past 32-bit voxel coordinates ("particle coordinates up to
///        1e+09 are too far from the origin for a voxel size of 0.001 (32-bit index space)"), a uint64
///        value above 2^63 - 1, a non-finite position, or an attribute that does not hold
///        one value per particle (as writeParticles(), without the path).
/// Returned as GridBase so this header stays light (cast with
/// openvdb::gridPtrCast<openvdb::points::PointDataGrid>).
NONBLOPPY_API openvdb::GridBase::Ptr makePointDataGrid(const ParticleSet& particles, double voxelSize = 0.0);

} // namespace nonbloppy

#endif // NONBLOPPY_WRITE_PARTICLES_H
