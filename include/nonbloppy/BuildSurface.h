// SPDX-License-Identifier: Apache-2.0
/// @file BuildSurface.h
/// @brief The one-call front door: particles in, relaxed surface mesh (and density grid) out.
///
/// @code
/// nonbloppy::SurfaceParameters params;        // everything derived from the spacing
/// params.iterations = 2;
/// nonbloppy::SurfaceResult result = nonbloppy::buildSurface(myParticles, params);
/// nonbloppy::writeMesh(result.mesh, "fluid.obj");
/// @endcode
/// The stages it chains are callable one by one: estimateSpacing/resolveParameters →
/// ParticleIndex::build (with r_e given, the index comes first and the estimate searches it:
/// ParticleIndex::build → resolveParametersIndexed) → rasterizeDensity → extractSurface →
/// relaxVertices → (Faithful: repairFolds) → computeNormals → (spacing given:
/// preserveVolume → smoothSurface → computeNormals; Faithful: each of the two followed by
/// repairFolds against the surface it started from, and computeNormals).

#ifndef NONBLOPPY_BUILD_SURFACE_H
#define NONBLOPPY_BUILD_SURFACE_H

#include <nonbloppy/Export.h>
#include <nonbloppy/EstimateParameters.h>
#include <nonbloppy/Mesh.h>
#include <nonbloppy/Timing.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>
#include <tbb/parallel_for.h>

#include <vector>

namespace nonbloppy {

/// Everything buildSurface() produces.
struct SurfaceResult
{
    SurfaceMesh mesh;                   ///< relaxed, counter-clockwise, with vertex normals
    /// the "density" grid, metadata holds the parameters; null when
    /// SurfaceParameters::keepDensity is false
    openvdb::FloatGrid::Ptr density;
    ResolvedParameters parameters;      ///< every value used, and which were given
    size_t particleCount = 0;           ///< number of input particles
    /// The smallest box holding every input particle, world units. Positions are floats,
    /// whose step grows with the distance from the origin: where it nears the spacing,
    /// the surface is quantized, and droplets collapse to points and are lost.
    openvdb::BBoxd particleBounds;
    StageTimings timings;               ///< seconds per stage
};

/// Run the whole pipeline on @a positions (world units), which it takes over.
/// @param positions    particle positions, world units; moved into the particle index
/// @param params       method parameters; lengths absolute, in world units (see SurfaceParameters)
/// @param interrupter  optional; every stage is announced with start(name) … end() under
///                     the names of the timings, and every loop of nonbloppy's own asks
///                     wasInterrupted() about every 0.1 ms of work (see each stage's
///                     header). "extract surface" meshes regions of about regionLeaves leaves
///                     and asks between them (volumeToMesh itself takes no interrupter);
///                     with adaptivity > 0 or regionLeaves = 0 it is one volumeToMesh()
///                     call and cannot be stopped, as it is when two vertices near a seam
///                     share a position and a later region welds to it (then the grid is
///                     meshed whole, rasterized again if keepDensity is false). Not interruptible either: OpenVDB's
///                     point partitioner (part of "index particles" and of "estimate
///                     parameters") and measureAreaAndVolume() in the volume correction.
///                     A stop throws CancelledError("interrupted during <stage>") and
///                     discards every partial result.
/// Cost: dominated by "extract surface", O(active voxels), "rasterize density",
/// O(N·(r_e/h)³), "relax vertices", O(t·V·particles within r_e), and, when the spacing is
/// given (smoothing on by default), "smooth surface", O(V) per round. On the 64x benchmark
/// input (1.56 M particles, two threads) extraction takes about 40% of the time, rasterizing
/// 25% and relaxing 15%. Memory: the density grid, 16 bytes per particle for the index, and
/// the mesh plus a 12-byte copy of each unrelaxed vertex.
/// Runs in parallel (TBB); the result does not depend on the thread count.
/// Thread-safety: reentrant; concurrent calls on different inputs are safe.
/// @throw ParameterError for bad parameters, non-finite positions or no positions at all
///        ("no particles to mesh"), CancelledError when @a interrupter asks to stop.
NONBLOPPY_API SurfaceResult buildSurface(std::vector<openvdb::Vec3f> positions,
                           const SurfaceParameters& params = SurfaceParameters(),
                           openvdb::util::NullInterrupter* interrupter = nullptr);

/// Run the whole pipeline on any ParticleList (see Particles.h); the caller's particles are
/// read once through getPos() into the index's own float array, never modified.
/// Parameters, cost, thread-safety and exceptions as for the overload above; getPos() is
/// called concurrently from several threads.
template<typename ParticleListT>
SurfaceResult buildSurface(const ParticleListT& particles,
                           const SurfaceParameters& params = SurfaceParameters(),
                           openvdb::util::NullInterrupter* interrupter = nullptr)
{
    std::vector<openvdb::Vec3f> positions(particles.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, positions.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            openvdb::Vec3R xyz;
            for (size_t n = range.begin(); n < range.end(); ++n) {
                particles.getPos(n, xyz);
                positions[n] = openvdb::Vec3f(xyz);
            }
        });
    return buildSurface(std::move(positions), params, interrupter);
}

} // namespace nonbloppy

#endif // NONBLOPPY_BUILD_SURFACE_H
