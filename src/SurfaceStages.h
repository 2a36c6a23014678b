// SPDX-License-Identifier: Apache-2.0
/// @file SurfaceStages.h
/// @brief Private: the chain of stages that buildSurface() and SurfaceReconstructor share
///        (rasterize density → extract surface → relax vertices → correct surface →
///        compute normals), and the cancellation check between stages. Only src/ includes it.

#ifndef NONBLOPPY_SURFACE_STAGES_H
#define NONBLOPPY_SURFACE_STAGES_H

#include "Cancellation.h"
#include "InstructionSet.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/SmoothSurface.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

#include <exception>
#include <string>
#include <vector>

namespace nonbloppy {
namespace surface_stages_internal {

/// The particle index's cell edge as a fraction of r_e: a search box of ±r_e then spans about
/// five cells per axis, which wastes less work on particles outside the support sphere than
/// cells of r_e (three per axis, 27 r_e³ visited for a 4.2 r_e³ sphere).
constexpr double kCellOverRadius = 0.5;

/// How a parameter check names r_e and h in its message: as the options, or, when a given
/// --spacing set them, as their derivation ("the radius 2 s =", followed by the value).
struct LengthNames
{
    std::string radius = "--radius";
    std::string voxelSize = "--voxel-size";
};

/// Throw ParameterError("--voxel-size <h> is too small for --radius <r_e>: at most 32 voxels
/// per radius", the lengths named by @a names) if r_e/h > kMaxVoxelsPerRadius: the one check
/// of rasterizeDensity() and of the parameter estimate, which makes it before the threshold's
/// calibration (whose cost grows as (r_e/s)³).
void requireVoxelsPerRadius(double effectiveRadius, double voxelSize, const LengthNames& names = {});

/// Throw ParameterError("no particles to mesh") if @a positions is empty: the one check of
/// resolveParameters() and of buildSurface() with kept parameters, which skips it.
void requireParticles(const std::vector<openvdb::Vec3f>& positions);

/// Throw CancelledError("interrupted during <stage>") if @a interrupter (may be null) asks to
/// stop. Cost: one wasInterrupted() call. Thread-safety: as the interrupter's.
void checkCancelled(openvdb::util::NullInterrupter* interrupter, const char* stage);

/// Times one stage in a StageTimings and announces it to the interrupter (start(name) on
/// construction, end() on destruction, also when the stage throws), for the stages whose
/// functions do not announce themselves. Cost: two clock reads.
class StageScope
{
public:
    StageScope(StageTimings& timings, openvdb::util::NullInterrupter* interrupter, const char* stage)
        : mTimer(timings, stage), mAnnounced(interrupter, stage) {}

private:
    ScopedStageTimer mTimer;  // destroyed last: the time includes end()
    cancellation_internal::AnnouncedStage mAnnounced;
};

/// The stages "estimate parameters" and "index particles", timed in result.timings and
/// announced to @a interrupter: result.parameters from @a params (or @a kept, when given,
/// as they are), and @a index over @a positions with cells of kCellOverRadius·r_e. With a
/// usable r_e given (> 0, finite) the particles are indexed first and the spacing estimate
/// searches that index (resolveParametersIndexed()); otherwise the estimate comes first, as
/// r_e, hence the cells, may depend on it (a bad r_e is left for resolveParameters() to
/// refuse with its own message). @a positions is moved into the index and left empty.
/// @throw ParameterError, CancelledError as buildSurface().
void resolveAndIndex(const SurfaceParameters& params, const ResolvedParameters* kept,
                     std::vector<openvdb::Vec3f>& positions, ParticleIndex& index, SurfaceResult& result,
                     openvdb::util::NullInterrupter* interrupter);

/// What runSurfaceStages() does with the buffer fold repair compares against once each
/// repair is done.
enum class UnrelaxedBuffer
{
    Release,  ///< free its memory after each repair, so that it is not held while the normals
              ///< are computed (the peak of a frame without the spacing)
    Keep,     ///< keep its capacity for the next frame
};

/// Run the stages after "index particles" with the parameters in result.parameters, each
/// announced to @a interrupter (start()/end()) and checked at its end:
/// rasterize density (metadata holding the parameters), extract surface (into result.mesh's
/// vectors, which keep their capacity), relax vertices, fold repair, compute normals, the
/// volume correction and the smoothing (each followed by a fold repair against the surface
/// it started from), timing each in result.timings. Of @a params only keepDensity
/// (result.density is reset when false) and trimFreedMemory are read.
/// @param index        the frame's particle index, cell size kCellOverRadius·r_e
/// @param unrelaxed    scratch for the vertex positions before each step fold repair checks
///                     (relaxation, then the volume correction and the smoothing), a
///                     std::vector<openvdb::Vec3s> or a memory_internal::UnwrittenVector of
///                     them (filled in parallel without a serial memset first)
/// @param whenRepaired whether @a unrelaxed is freed or kept after each fold repair
/// Cost: as buildSurface() minus its first two stages. Thread-safety: reentrant.
/// @throw ParameterError, CancelledError as buildSurface(); result is then unspecified.
template<typename VertexBufferT>
void runSurfaceStages(const ParticleIndex& index, const SurfaceParameters& params, SurfaceResult& result,
                      VertexBufferT& unrelaxed, UnrelaxedBuffer whenRepaired,
                      openvdb::util::NullInterrupter* interrupter);

/// repairFolds(), preserveVolume(mesh, VolumeSettings) and smoothSurface() without the check
/// that every polygon corner is a vertex of the mesh, which the public functions make first
/// (polygon_indices_internal::requireValidIndices(): 3.5 ms per call on two threads for a
/// synthetic mesh of 2.66M polygons, the 64x benchmark mesh's size): the chain's mesh comes
/// from extractSurface(), valid by construction, and passes through all three. Same results,
/// same other checks.
/// @a before holds mesh.points.size() positions (the public functions check that).
size_t repairFoldsUnchecked(SurfaceMesh& mesh, const openvdb::Vec3s* before, int maxRounds,
                            openvdb::util::NullInterrupter* interrupter);
double preserveVolumeUnchecked(SurfaceMesh& mesh, const VolumeSettings& settings,
                               openvdb::util::NullInterrupter* interrupter);
void smoothSurfaceUnchecked(SurfaceMesh& mesh, const SmoothSettings& settings,
                            openvdb::util::NullInterrupter* interrupter,
                            instruction_set_internal::InstructionSet set = instruction_set_internal::InstructionSet::Auto);

/// Leaf layers (8 voxels each) per region at least, along each axis it is cut on. Each region
/// also meshes three voxel planes beyond each cut face, but volumeToMesh scans whole leaves,
/// so a cut face costs a whole leaf layer: at four layers a region cut on two axes scans
/// (4+2)²/4² = 2.25 times its own leaves. Measured on the 64x benchmark input (1024 leaves
/// per region, two threads): leaves scanned / extraction wall / longest region, 4 layers
/// 70,185 / 1.49-1.63 s / 48 ms, 8 layers 64,762 / 1.19-1.21 s / 38-40 ms, 12 layers
/// 61,164 / 0.99-1.12 s / 34-41 ms, 16 layers 55,713 / 0.91-0.97 s / 45-49 ms (45,688 leaves
/// touch the surface). Twelve keeps regions short (the cancel latency) and most of the gain.
constexpr int kMinLayersPerRegion = 12;

/// extractSurface() into @a mesh's existing vectors (which keep their capacity); normals and
/// attributes are cleared. Same checks and orientation as extractSurface(); with adaptivity 0
/// and @a leavesPerRegion > 0 through extractByRegion() (the same polygons and vertices, in
/// another order), polled for a cancel between regions. Defined in ExtractSurface.cc, the only translation unit that
/// includes tools/VolumeToMesh.h.
/// @param release  optional, for a grid that is destroyed afterwards: @a density's own tree.
///                 Region by region, the leaves of the leaf layers no later region reads
///                 become inactive tiles, so the grid's memory goes as the mesh's grows (the
///                 grid is left partial, fit only to be destroyed); the mesh is the same, bit
///                 for bit (tested). Null leaves the grid untouched.
/// @param trimFreedMemory  with @a release: hand the freed leaves' pages back to the system
///                 as it goes (see SurfaceParameters::trimFreedMemory)
/// @throw ParameterError as extractSurface(); CancelledError("interrupted during extract
///        surface"); AmbiguousSeamError as extractByRegion()
void extractSurfaceInto(const openvdb::FloatGrid& density, double threshold, double adaptivity,
                        size_t leavesPerRegion, SurfaceMesh& mesh,
                        openvdb::util::NullInterrupter* interrupter, openvdb::FloatTree* release = nullptr,
                        bool trimFreedMemory = false);

/// Thrown by extractByRegion() when two vertices near a seam share one position (welding by
/// position cannot tell them apart) after it freed leaves of the grid (@a release): the
/// caller rasterizes the grid again and meshes it whole. Never leaves the library.
struct AmbiguousSeamError : std::exception
{
    const char* what() const noexcept override { return "two seam vertices at one position"; }
};

/// The surface φ = @a threshold of a density grid (adaptivity 0), meshed region by region:
/// slabs across the grid's longest axis, each cut again across the second longest when it
/// holds more than @a leavesPerRegion kept leaves, every cut at least @a minLayersPerRegion
/// leaf layers apart. Each region is a volumeToMesh call on a copy of its leaves plus three
/// voxel planes beyond each cut face; it keeps the quads whose centroid lies in it, and the
/// vertices at a seam are welded by exact position (a cell's vertices depend only on its
/// corner values and the signs of the cells next to it). Leaves that no crossing edge
/// touches are left out, or become tiles, so the regions scan fewer voxels than the whole
/// grid holds. Regions are meshed one per thread at a time (a batch), then welded in region
/// order. The result holds exactly the vertices and polygons of extractSurface()
/// (tested), oriented the same way, ordered region by region; deterministic at any thread
/// count. A grid that makes one region, has tiles larger than a leaf or a transform that is
/// not an axis-aligned scale is meshed whole, as extractSurface().
/// Cost: O(voxels) as extractSurface(), plus copying the leaves a crossing touches and, per
/// region, its shell (see SurfaceParameters::regionLeaves); scratch memory is one region's
/// per thread plus the seam vertices of two slabs. The interrupter (may be null) is asked
/// while leaves are classified and before each region of a batch. Thread-safety: reentrant;
/// the grid is only read.
/// @param release  optional: @a density's own tree, whose leaves are freed as the slabs pass
///                 (see extractSurfaceInto()); null leaves the grid untouched
/// @param trimFreedMemory  as extractSurfaceInto()'s
/// Two vertices at one position near a seam (see AmbiguousSeamError) make it mesh the
/// whole grid instead, as extractSurface(); if leaves were freed already, it throws.
/// @throw ParameterError if @a threshold is not finite; CancelledError as above;
///        AmbiguousSeamError as said
void extractByRegion(const openvdb::FloatGrid& density, double threshold, SurfaceMesh& mesh,
                     openvdb::util::NullInterrupter* interrupter, size_t leavesPerRegion,
                     int minLayersPerRegion = kMinLayersPerRegion, openvdb::FloatTree* release = nullptr,
                     bool trimFreedMemory = false);

} // namespace surface_stages_internal
} // namespace nonbloppy

#endif // NONBLOPPY_SURFACE_STAGES_H
