// SPDX-License-Identifier: Apache-2.0
/// @file ExtractSurface.h
/// @brief Stage "extract surface": the iso-surface φ = r_0 of a density grid, via
///        openvdb::tools::volumeToMesh, oriented so that faces look out of the fluid.

#ifndef NONBLOPPY_EXTRACT_SURFACE_H
#define NONBLOPPY_EXTRACT_SURFACE_H

#include <nonbloppy/Mesh.h>

#include <openvdb/openvdb.h>

namespace nonbloppy {

/// Extract the surface φ = @a threshold from a density grid in which the inside is φ > r_0.
/// volumeToMesh returns such surfaces clockwise seen from outside; every polygon is
/// reversed here so that the mesh is counter-clockwise (outward normals).
/// @param adaptivity  volumeToMesh's adaptivity in [0,1]: 0 keeps every polygon, larger
///                    values merge polygons in flat regions.
/// Cost: O(active voxels), parallel inside OpenVDB; deterministic.
/// @throw ParameterError if adaptivity lies outside [0,1] or threshold is not finite.
SurfaceMesh extractSurface(const openvdb::FloatGrid& density, double threshold,
                           double adaptivity = 0.0);
/// The same for a double-precision density a caller computed or edited.
SurfaceMesh extractSurface(const openvdb::DoubleGrid& density, double threshold,
                           double adaptivity = 0.0);

} // namespace nonbloppy

#endif // NONBLOPPY_EXTRACT_SURFACE_H
