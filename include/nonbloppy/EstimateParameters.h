// SPDX-License-Identifier: Apache-2.0
/// @file EstimateParameters.h
/// @brief Stage "estimate parameters": particle spacing, and the method's parameters the
///        user did not give, derived from it.

#ifndef NONBLOPPY_ESTIMATE_PARAMETERS_H
#define NONBLOPPY_ESTIMATE_PARAMETERS_H

#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Export.h>
#include <nonbloppy/ParticleIndex.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

#include <optional>
#include <vector>

namespace nonbloppy {

/// Samples estimateSpacing() takes by default (and resolveParameters() always). The medians
/// it takes settle long before: on the dam-break frame (24,389 particles) 4,096, 8,192,
/// 10,000 and 20,000 samples gave s within 0.013% of one another (0.0467246, 0.0467139,
/// 0.0467215, 0.0467186, measured before the particle index ordered each cell by position;
/// 8,192 give 0.0467213 since), and 8,192 halve the cost of 20,000 (14 → 7 ms, a fifth of
/// the frame's compute).
constexpr size_t kSpacingSamples = 8192;

/// The particle spacing s, in world units: the cube root of the volume per particle inside the
/// fluid. Over a fixed deterministic sample of at most @a maxSamples particles (all of them
/// when fewer), it finds the median distance d to the nearest neighbour, then counts the
/// particles within 2 d of every sampled particle whose neighbours surround it evenly (a
/// smooth count, within 0.5% on lattices) and returns the median spacing that count
/// implies. When fewer than 10 (or 1%) of the samples are surrounded, as in a sheet two
/// particles thick, it returns d. The nearest neighbour alone underestimates disordered
/// fluids: d is 0.90 s on a lattice jittered by ±0.1 s and 0.82–0.93 s in the SPlisHSPlasH
/// frames of tests/data (whose particles fill 0.8·(2 r)³ each, s = 0.0464 for r = 0.025).
/// Cost: O(N) to bucket the particles plus O(samples) neighbour searches.
/// @param positions    particle positions, world units (only read)
/// @param maxSamples   how many particles' nearest neighbours to search, evenly spread
///                     (0 counts as 1)
/// @param interrupter  optional; asked every 4096 particles of the bounding box, as in
///                     ParticleIndex::build() while bucketing, and every 16 samples of each
///                     parallel search task; no start()/end()
/// @throw ParameterError with fewer than two particles, a non-finite position ("non-finite
///        position of particle N"), all particles at one position, a median of 0 (half the
///        particles sit on top of another one), or no neighbour found within 2⁴⁰ times the
///        first guess ("cannot estimate the particle spacing; give --spacing");
///        CancelledError("interrupted during estimate parameters") when @a interrupter says stop.
NONBLOPPY_API double estimateSpacing(const std::vector<openvdb::Vec3f>& positions,
                                     size_t maxSamples = kSpacingSamples,
                                     openvdb::util::NullInterrupter* interrupter = nullptr);

/// Widest kernel, in particle spacings (r_e/s), for which calibrateThreshold() and
/// calibrateRelaxedThreshold() compute r_0: their lattice sums grow as (r_e/s)³, to 1.5 s
/// at this limit for the default t = 2 on the benchmark machine. A wider kernel, which
/// reaches across tens of thousands of particles, needs r_0 given (--threshold). With the
/// default voxel size h = s/2, the limit of 32 voxels per radius already stops r_e at 16 s.
constexpr double kMaxCalibratedRadiusOverSpacing = 32.0;

/// The iso-value r_0 for which a flat, uniform half-space of particles on a cubic lattice of
/// spacing s has its unrelaxed (t = 0) surface s/2 outside the outer particle layer, so the
/// fluid's volume is about N·s³. The density there is averaged over the lattice cell.
/// The result depends only on the ratio r_e/s. Cost: 256·(2⌈r_e/s⌉ + 4)²·(⌈r_e/s⌉ + 2)
/// kernel evaluations: 65,536 at r_e = 2 s (under 1 ms), 40M at the limit of 32 s.
/// @throw ParameterError if @a effectiveRadiusOverSpacing ≤ 0.5 (the density at s/2 outside
///        would be 0 and no threshold could place the surface there), so close above 0.5
///        that the kernel reaches none of the samples there (up to about 0.502), or above
///        kMaxCalibratedRadiusOverSpacing.
NONBLOPPY_API double calibrateThreshold(double effectiveRadiusOverSpacing);

/// Defaults of the method relative to the particle spacing s.
constexpr double kDefaultRadiusOverSpacing = 2.0;  ///< r_e = 2 s
constexpr double kDefaultVoxelOverSpacing = 0.5;   ///< h = s / 2
constexpr double kDefaultBlend = 0.3;              ///< c
constexpr int kDefaultIterations = 2;              ///< t
constexpr double kDefaultAdaptivity = 0.0;         ///< volumeToMesh adaptivity, in [0,1]
/// Kept density leaves per extraction region (SurfaceParameters::regionLeaves): a cancel
/// takes effect within about 50 ms on the 1.5M-particle benchmark input on two cores.
constexpr size_t kDefaultRegionLeaves = 1024;

/// Method::Faithful: one relaxation step moves a vertex at most s/2 (RelaxSettings::maxStep).
/// With c ≤ 0.5 and r_e = 2 s a step is shorter than c·r_e ≤ s anyway; the cap matters for
/// larger blends, where vertices that see only a few particles would jump onto them.
constexpr double kDefaultMaxStepOverSpacing = 0.5;
/// Method::Faithful, VolumeOffset::Uniform: the volume correction moves the surface at most
/// s/4 along its normals.
constexpr double kMaxVolumeOffsetOverSpacing = 0.25;
/// Method::Faithful, VolumeOffset::Convex: no vertex moves more than s/2 (the edges of a
/// box of particles move about 0.15 s, its flat faces not at all).
constexpr double kMaxConvexOffsetOverSpacing = 0.5;
/// Method::Faithful, VolumeOffset::Convex: convexity below s/100 counts as flat. Relaxation
/// leaves bumps of about that height on the flat faces of a jittered lattice; a floor of
/// 0 moves them too (mean distance 0.039 s instead of 0.033 s on the box of docs/fidelity.md),
/// a floor of s/50 leaves part of the edges rounded (0.040 s).
constexpr double kConvexityFloorOverSpacing = 0.01;

/// Which variant of the method buildSurface() runs.
enum class Method
{
    /// The paper's plain method, exactly: extract φ = r_0 (r_0 calibrated for the unrelaxed
    /// surface), relax t times, nothing else. Reproduces the paper's behaviour, including
    /// the shrinking and the rounding it warns about.
    Paper,
    /// The default: the paper's method with the corrections of CorrectSurface.h, tuned so
    /// that the surface lies within 0.1 s of the fluid's true surface (docs/fidelity.md).
    Faithful,
};

/// What the user asks for; every unset optional is derived from the particle spacing.
/// All lengths are absolute, in world units (not multiples of the spacing).
struct SurfaceParameters
{
    std::optional<double> spacing;          ///< s; default: estimateSpacing()
    std::optional<double> effectiveRadius;  ///< r_e; default: 2 s
    /// r_0 (dimensionless); default: calibrateRelaxedThreshold(r_e/s, c, t, nullptr,
    /// maxStep/s) (Faithful: calibrated for the capped steps the mesh takes) or
    /// calibrateThreshold(r_e/s) (Paper)
    std::optional<double> threshold;
    std::optional<double> voxelSize;        ///< h; default: s / 2
    double blend = kDefaultBlend;           ///< c in [0,1]
    int iterations = kDefaultIterations;    ///< t ≥ 0
    double adaptivity = kDefaultAdaptivity; ///< in [0,1]
    /// Return the exact density grid in SurfaceResult::density. false lets the extraction
    /// free the grid's leaves as its regions pass (adaptivity 0 and regionLeaves > 0), and
    /// SurfaceResult::density is then null: the same mesh, bit for bit, with a lower peak
    /// memory (64x benchmark input, `mesh` without and with `--vdb`, which sets
    /// trimFreedMemory: peak RSS 313 against 394 MiB).
    bool keepDensity = true;
    /// With keepDensity false: hand the freed leaves' pages back to the system as the
    /// extraction goes (glibc's malloc_trim(0) after every 32,768 freed leaves), which they
    /// otherwise keep in malloc's free lists, unusable by the mesh's large arrays (64x
    /// benchmark input, two threads: peak RSS 322 MB against 371 MB). malloc_trim walks
    /// every malloc arena of the process and briefly stalls its other threads, so it is off
    /// unless asked for; the command-line tool asks.
    bool trimFreedMemory = false;
    Method method = Method::Faithful;       ///< Paper: the plain method; see Method
    /// Faithful only: cap on how far one relaxation step moves a vertex, world units
    /// (RelaxSettings::maxStep), ≥ 0; default kDefaultMaxStepOverSpacing·s, 0 or +inf for no cap
    /// (also when every length was given and s is unknown).
    std::optional<double> maxStep;
    /// Faithful only: offset the relaxed surface along its normals so that it encloses N·s³
    /// (preserveVolume(), spread as volumeOffset says).
    /// Default: on when the spacing is given, off when it is estimated (an estimate 1% off
    /// moves the target 3%, and a sheet's fallback estimate, the nearest-neighbour distance,
    /// is 10% low on a jittered lattice: N·s³ would then shrink the fluid).
    std::optional<bool> preserveVolume;
    /// Faithful only: how the volume correction spreads its offset (VolumeOffset). Default:
    /// Convex, which puts the volume back at the edges, corners and thin features relaxation
    /// took it from, when r_0 is calibrated for the relaxed surface and that calibration
    /// reaches it (calibrateRelaxedThreshold()); otherwise Uniform, since the whole surface
    /// then lies inside and moving only its convex parts would make them bulge (measured:
    /// c = 0.5, t = 4 gives a mean distance of 0.40 s with Convex, 0.23 s with Uniform).
    std::optional<VolumeOffset> volumeOffset;
    /// Faithful only: unfold triangles relaxation folded over (repairFolds()).
    bool repairFolds = true;
    /// Faithful only: smooth the surface after the volume correction without rounding its
    /// edges (smoothSurface(), spatial width kDefaultSmoothWidthOverSpacing·s). Default: on
    /// when the volume correction runs. The two belong together: the volume correction puts
    /// back at edges and thin features what relaxation took, the smoothing then removes the
    /// particles' jitter from the faces (docs/fidelity.md, row "− smoothing"); without the
    /// correction the smoothing alone leaves box and slab no closer.
    std::optional<bool> smoothSurface;
    /// With adaptivity 0 the surface is extracted region by region, about this many density
    /// leaves that the surface touches per region (0: the whole grid at once). The extracted
    /// surface has the same polygons and vertices whatever the value (only their order changes),
    /// and so has the relaxed one; the smoothing (spacing given) sums over neighbours in that
    /// order, so its vertices can differ in their last bits (a few float steps of their
    /// coordinates). The value trades cancel latency against speed, since OpenVDB's
    /// volumeToMesh cannot be stopped inside a region. On the 64x benchmark input (1.56M particles, two
    /// cores, no --vdb, 2026-12-05 at fca7043), extraction wall time / process peak,
    /// medians of 3-5 alternating runs: 1024 leaves 0.61-0.63 s / 313-321 MB (longest
    /// region 34-41 ms when measured at 2b7aabc), 2048 leaves 0.63 s / 319 MB, 4096 leaves
    /// 0.64 s / 355 MB, 16384 leaves 0.63-0.64 s / 480 MB, whole grid 0.56 s / 446-483 MB
    /// (one call that cannot be stopped). Scratch memory grows with the region; at one
    /// thread 1024, 2048 and 4096 leaves took 1.10-1.27 s alike.
    size_t regionLeaves = kDefaultRegionLeaves;
};

/// Every parameter's value as used, and whether the user gave it.
struct ResolvedParameters
{
    double spacing = 0;                     ///< s, world units
    double effectiveRadius = 0;             ///< r_e, world units
    double threshold = 0;                   ///< r_0, dimensionless
    double voxelSize = 0;                   ///< h, world units
    double blend = kDefaultBlend;           ///< c in [0,1]
    int iterations = kDefaultIterations;    ///< t ≥ 0
    double adaptivity = kDefaultAdaptivity; ///< in [0,1]
    bool spacingGiven = false;              ///< s came from SurfaceParameters, not estimated
    bool effectiveRadiusGiven = false;      ///< r_e came from SurfaceParameters
    bool thresholdGiven = false;            ///< r_0 came from SurfaceParameters
    bool voxelSizeGiven = false;            ///< h came from SurfaceParameters
    Method method = Method::Faithful;       ///< the variant run
    double maxStep = 0.0;                   ///< cap on one relaxation step, world units; 0: none
    bool preserveVolume = false;            ///< the volume correction runs
    VolumeOffset volumeOffset = VolumeOffset::Convex;  ///< how it spreads its offset
    bool repairFolds = false;               ///< fold repair runs
    bool smoothSurface = false;             ///< the feature-preserving smoothing runs
    size_t regionLeaves = kDefaultRegionLeaves;  ///< leaves per extraction region; 0: whole grid
    /// False when r_0 was calibrated for the relaxed surface but no start height within
    /// reach lets relaxation end a flat face at s/2 (calibrateRelaxedThreshold()'s
    /// reachesSurface: c and t so strong that the faces end inside the particles).
    bool thresholdReachesSurface = true;
};

/// Check what @a params fixes without looking at particles: each value's range (r_0 also
/// within float's, the density grid's type), and where the lengths are given or set by a
/// given spacing (r_e = 2 s, h = s/2), the limits between them (r_e and h at least OpenVDB's
/// smallest cell, r_e/h in [1, kMaxVoxelsPerRadius], r_e ≤ 1e18), and r_e/s within the
/// threshold calibration's (1/2, kMaxCalibratedRadiusOverSpacing] when s and r_e are given
/// and r_0 is not. resolveParameters() makes the same checks first; the command line calls
/// this before reading a file, so a mistake costs nothing. Cost: O(1).
/// @throw ParameterError naming the parameter, as resolveParameters(); a length set by the
///        spacing is named as such: "--spacing 1e-06: the voxel size 0.5 s = 5e-07 is below
///        1.5e-05, the smallest OpenVDB accepts: give the positions in a smaller unit".
NONBLOPPY_API void checkParameters(const SurfaceParameters& params);

/// Check @a params and fill in what is missing. @a positions is only read when the spacing
/// must be estimated: spacing unset and effectiveRadius, threshold or voxelSize unset, or
/// (Faithful) preserveVolume or smoothSurface on, which need s for the volume N·s³ and the
/// smoothing's width. Empty @a positions throw ParameterError("no particles to mesh").
/// @throw ParameterError naming the parameter, e.g. "--blend must lie in [0,1], got 1.5"
///        (parameters are named by their command-line spelling); a length derived from an
///        estimated spacing is named as such: "--spacing 1e-09 (estimated): the voxel size
///        0.5 s = 5e-10 is below 1.5e-05, the smallest OpenVDB accepts: give the positions in
///        a smaller unit".
/// Cost: that of estimateSpacing() when it is needed, plus the threshold calibration (a few
/// ms at r_e = 2 s, growing as (r_e/s)³ and with t; it asks @a interrupter before every
/// sample), else O(1).
/// @param params       what the user gave
/// @param positions    particle positions, world units (only read)
/// @param interrupter  optional; passed to estimateSpacing() and asked after each step;
///                     no start()/end() (buildSurface() announces "estimate parameters")
/// @throw CancelledError("interrupted during estimate parameters") when @a interrupter says stop.
/// Thread-safety (all functions of this header): reentrant, no shared state.
NONBLOPPY_API ResolvedParameters resolveParameters(const SurfaceParameters& params,
                                     const std::vector<openvdb::Vec3f>& positions,
                                     openvdb::util::NullInterrupter* interrupter = nullptr);

/// resolveParameters() for particles already indexed (any cell size): the spacing, when it
/// must be estimated, is searched through @a index instead of an index of its own, which
/// saves building one (on 1.5 million particles about 0.1 s, most of the estimate).
/// buildSurface() takes this path when --radius is given, indexing the particles first; the
/// samples are then spread over this index's slots, so s may differ from the other
/// overload's in its last digits.
NONBLOPPY_API ResolvedParameters resolveParametersIndexed(const SurfaceParameters& params,
                                                          const ParticleIndex& index,
                                                          openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace nonbloppy

#endif // NONBLOPPY_ESTIMATE_PARAMETERS_H
