// SPDX-License-Identifier: Apache-2.0
/// @file ExtractSurface.h
/// @brief Stage "extract surface": the iso-surface φ = r_0 of a density grid, via
///        openvdb::tools::volumeToMesh, oriented so that faces look out of the fluid.

#ifndef NONBLOPPY_EXTRACT_SURFACE_H
#define NONBLOPPY_EXTRACT_SURFACE_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>

#include <openvdb/openvdb.h>

namespace nonbloppy {

/// Extract the surface φ = @a threshold from a density grid in which the inside is φ > r_0.
/// volumeToMesh returns such surfaces clockwise seen from outside; every polygon is
/// reversed here so that the mesh is counter-clockwise (outward normals).
/// The grid may come from anywhere (rasterizeDensity(), a file, a caller's edit); its
/// transform places the vertices in world space. The result has no normals.
/// @param density     scalar grid, larger values inside the fluid (not a level set)
/// @param threshold   iso-value r_0, in the grid's value units
/// @param adaptivity  volumeToMesh's adaptivity in [0,1]: 0 keeps every polygon, larger
///                    values merge polygons in flat regions.
/// Cost: O(active voxels), parallel inside OpenVDB; deterministic. Not interruptible:
/// volumeToMesh takes no interrupter, and stopping it through its TBB context is unsafe
/// (its serial steps then size arrays from uninitialised counts: measured, up to 1.4·10⁹
/// points allocated and zeroed). buildSurface() and SurfaceReconstructor therefore mesh
/// their own density grids region by region (about SurfaceParameters::regionLeaves leaves
/// each), asking the interrupter in between; the result has
/// the same vertices and polygons as this function's, in another order (or in the same
/// order where seam vertices that share a position make them call this function instead).
/// Thread-safety: reentrant; the grid is only read.
/// @throw ParameterError if adaptivity lies outside [0,1], threshold is not finite or not
///        above the grid's background value (0 for rasterizeDensity()'s: "--threshold must lie
///        above the density grid's background value 0 (its value outside the fluid), got 0"),
///        or the grid is classed as a level set (GRID_LEVEL_SET: smaller values inside).
NONBLOPPY_API SurfaceMesh extractSurface(const openvdb::FloatGrid& density, double threshold,
                           double adaptivity = 0.0);
/// The same for a double-precision density a caller computed or edited; parameters, cost,
/// exceptions and thread-safety as above.
NONBLOPPY_API SurfaceMesh extractSurface(const openvdb::DoubleGrid& density, double threshold,
                           double adaptivity = 0.0);

/// Replace every leaf of @a density that lies deep inside the fluid by an active tile holding
/// the leaf's smallest value. A leaf is deep inside when it and all 26 neighbouring leaves
/// exist and hold only values above @a threshold: then no cell that crosses the surface has
/// a corner in it, so extractSurface() returns the very same mesh from the tiled grid while
/// scanning, and storing, fewer voxels. The grid's values inside are no longer exact.
/// Cost: O(leaves · 512) to find leaf minima, parallel. Returns the number of leaves replaced.
/// Thread-safety: not for the same grid concurrently (it is modified).
/// @throw ParameterError if the grid is classed as a level set or @a threshold is not finite
///        or not above the grid's background value, as extractSurface().
NONBLOPPY_API size_t tileDeepInterior(openvdb::FloatGrid& density, double threshold);

} // namespace nonbloppy

#endif // NONBLOPPY_EXTRACT_SURFACE_H
