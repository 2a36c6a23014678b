// SPDX-License-Identifier: Apache-2.0
/// @file DiagnoseSurface.h
/// @brief What a finished surface tells about how it was made: the conditions a caller
///        should warn its user of (the command-line tool prints them as warnings, the
///        Python module raises them as nonbloppy.SurfaceWarning).
///
/// @code
/// nonbloppy::SurfaceResult result = nonbloppy::buildSurface(particles, params);
/// const nonbloppy::SurfaceDiagnostics d = nonbloppy::diagnoseSurface(result);
/// if (d.empty) log("no surface: the density nowhere reaches r_0 =", result.parameters.threshold);
/// if (d.coarseFloats()) log("positions step by", d.floatStep, "this far from the origin");
/// @endcode

#ifndef NONBLOPPY_DIAGNOSE_SURFACE_H
#define NONBLOPPY_DIAGNOSE_SURFACE_H

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Export.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace nonbloppy {

/// What diagnoseSurface() finds. Every condition leaves a mesh that was made as asked, but
/// not as the caller will expect; none is an error.
struct SurfaceDiagnostics
{
    /// r_0 was calibrated for the relaxed surface, but c and t relax so strongly that no
    /// r_0 lets a flat face end at s/2: flat faces end inside the particles
    /// (ResolvedParameters::thresholdReachesSurface is false).
    bool facesEndInside = false;
    /// There were particles but the mesh has no vertex: the density, sampled at the voxel
    /// size, nowhere reaches r_0 (an out-of-scale threshold; a lone particle between voxel
    /// centres). A frame of spray can be empty for that reason alone.
    bool empty = false;
    /// The particles' largest |coordinate|, world units.
    double farthestCoordinate = 0.0;
    /// The step between floats at farthestCoordinate, world units (positions are floats:
    /// their step grows with the distance from the origin).
    double floatStep = 0.0;
    /// The float step the surface tolerates: 1/16 of the spacing, or 1/8 of the voxel size
    /// where no spacing is known (r_e, r_0 and h all given); 0 with neither.
    double floatStepLimit = 0.0;
    /// Vertices whose normal is (0, 0, 0): the faces around them have no area (c = 1
    /// collapses a droplet onto its particles' mean). They shade black or not at all.
    size_t verticesWithoutNormal = 0;
    /// Per float attribute of the mesh (SurfaceMesh::attributes, in their order), the
    /// number of vertices holding a NaN or infinite value in any component; attributes with
    /// none are left out. Particles holding such values make every vertex within r_e of
    /// them NaN (interpolateAttributes()).
    std::vector<std::pair<std::string, size_t>> nonFiniteAttributes;

    /// The surface is quantized by the positions' float step: floatStep exceeds floatStepLimit.
    bool coarseFloats() const { return floatStepLimit > 0.0 && floatStep > floatStepLimit; }
    /// So coarse (8 times the limit or more) that droplets may collapse to points and vanish.
    bool dropletsMayVanish() const { return coarseFloats() && floatStep >= 8.0 * floatStepLimit; }
};

/// Diagnose @a result as buildSurface() (and interpolateAttributes(), for the attributes)
/// left it: its parameters, particle bounds and count, and its mesh.
/// Cost: a parallel pass over the normals and one over each float attribute's values
/// (about 4 ms for the 2.4M normals of the 64x benchmark frame, two threads); reads
/// nothing else. Thread-safety: reentrant.
NONBLOPPY_API SurfaceDiagnostics diagnoseSurface(const SurfaceResult& result);

} // namespace nonbloppy

#endif // NONBLOPPY_DIAGNOSE_SURFACE_H
