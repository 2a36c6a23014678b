// SPDX-License-Identifier: Apache-2.0
#include "Cancellation.h"
#include "NumberText.h"
#include "OpenVdbScale.h"
#include "ParameterChecks.h"
#include "ParticleIndexImpl.h"
#include "SurfaceStages.h"

#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/EstimateParameters.h>
#include <nonbloppy/Kernel.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

namespace nonbloppy {

namespace {

using cancellation_internal::CancelPoll;
using surface_stages_internal::LengthNames;

std::string formatNumber(double value)
{
    return number_text_internal::sixDigits(value);
}

/// Run @a perSample(i, forNeighbours) in parallel for every sampled slot i (sorted order,
/// position x), where forNeighbours(radius, visit) calls visit(k, offset) for every particle
/// k in the box of half-width radius around x, offset = x_k − x (x itself included,
/// k == samples[i]). A wide box visits thousands of particles per sample: @a poll is asked
/// every 16 samples, and a stop leaves later samples unvisited.
template<typename PerSampleOp>
void forEachSampleNeighbourhood(const ParticleIndex& index, const std::vector<size_t>& samples,
                                CancelPoll& poll, PerSampleOp&& perSample)
{
    using namespace particle_index_internal;
    const auto& positions = index.sortedPositions();
    const auto& grid = *index.impl().grid;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            auto accessor = grid.getConstAccessor();
            for (size_t i = range.begin(); i < range.end(); ++i) {
                if ((i - range.begin()) % 16 == 0 && poll.stopped()) return;
                const openvdb::Vec3d x = positions[samples[i]];
                const auto forNeighbours = [&](double radius, auto&& visit) {
                    forEachRunInBox(index.impl(), accessor, x - openvdb::Vec3d(radius),
                        x + openvdb::Vec3d(radius), [&](uint32_t first, uint32_t end) {
                            for (uint32_t k = first; k < end; ++k) visit(k, openvdb::Vec3d(positions[k]) - x);
                        });
                };
                perSample(i, forNeighbours);
            }
        });
}

/// Nearest-neighbour distance of each sampled slot, searched within @a searchRadius;
/// +inf where no other particle lies that close. Unspecified after a stop of @a poll.
std::vector<double> nearestWithin(const ParticleIndex& index, const std::vector<size_t>& samples,
                                  double searchRadius, CancelPoll& poll)
{
    std::vector<double> nearest(samples.size());
    forEachSampleNeighbourhood(index, samples, poll, [&](size_t i, const auto& forNeighbours) {
        // Most neighbours lie well within the search radius: look in a box half as wide
        // first (an eighth of the volume, though whole index cells are read: 2.7-2.9
        // instead of 5.8-6.0 ms on the 1x benchmark frame), and in the whole one only when
        // that finds none. Either way the nearest one within the radius is found.
        for (const double radius : {0.5 * searchRadius, searchRadius}) {
            double best = radius * radius;
            bool found = false;
            forNeighbours(radius, [&](uint32_t k, const openvdb::Vec3d& offset) {
                if (k == samples[i]) return;
                const double d2 = offset.lengthSqr();
                if (d2 <= best) { best = d2; found = true; }
            });
            nearest[i] = found ? std::sqrt(best) : std::numeric_limits<double>::infinity();
            if (found) break;
        }
    });
    return nearest;
}

/// Smooth count W(q) = (1 − q²)³ for q = distance / radius < 1: smooth enough that its sum
/// over a lattice matches its integral, 4π·16/315 · radius³ per lattice cell, to 1% at a
/// radius of two spacings (0.3% in s); a plain count of the 27 lattice points within that
/// radius against the ball's 33.5 cells would put s 7% high.
constexpr double kSmoothCountIntegral = 4.0 * 3.14159265358979323846 * 16.0 / 315.0;
/// A particle counts as inside the fluid when the W-weighted mean of the offsets to its
/// neighbours is shorter than this fraction of the radius (at a flat surface it is ~0.3)...
constexpr double kInteriorCentroidFraction = 0.05;
/// ...and at least this many neighbours lie within the radius (two nearest-neighbour
/// distances): about 20–30 in a liquid, 5.5 on average in a spray of scattered particles,
/// whose volume per particle is not a particle size.
constexpr int kInteriorNeighbours = 12;

/// Spacing of each sampled slot from the number of particles around it: within @a radius,
/// Σ W(|x_j − x| / radius) (itself included) ≈ kSmoothCountIntegral·radius³ / s³ inside a fluid
/// of spacing s. Slots whose neighbourhood is lopsided (near a surface, where the sum counts
/// only part of a ball) are left out. Unspecified after a stop of @a poll.
std::vector<double> interiorSpacings(const ParticleIndex& index, const std::vector<size_t>& samples,
                                     double radius, CancelPoll& poll)
{
    std::vector<double> spacing(samples.size(), 0.0);  // 0: not inside
    forEachSampleNeighbourhood(index, samples, poll,
        [&](size_t i, const auto& forNeighbours) {
            double count = 0.0;
            int neighbours = -1;  // itself is counted below
            openvdb::Vec3d offsetSum(0.0);
            const double radiusSqr = radius * radius;
            forNeighbours(radius, [&](uint32_t, const openvdb::Vec3d& offset) {
                // Most of the box lies outside the ball: reject those before dividing
                // (d² ≥ r² implies d²/r² ≥ 1, so this rejects nothing the test below keeps).
                const double distanceSqr = offset.lengthSqr();
                if (!(distanceSqr < radiusSqr)) return;
                const double q2 = distanceSqr / radiusSqr;
                if (!(q2 < 1.0)) return;
                const double w = (1.0 - q2) * (1.0 - q2) * (1.0 - q2);
                count += w;
                offsetSum += w * offset;
                ++neighbours;
            });
            if (neighbours >= kInteriorNeighbours &&
                (offsetSum / count).length() < kInteriorCentroidFraction * radius) {
                spacing[i] = radius * std::cbrt(kSmoothCountIntegral / count);
            }
        });
    return spacing;
}

/// Radius of the particle count, in nearest-neighbour distances: wide enough to smooth the
/// disorder, narrow enough that most particles of a 10-particle-thick fluid are inside.
constexpr double kSpacingRadiusOverNearest = 2.0;
/// Fewest particles inside the fluid, absolute and per sample, for interiorSpacings() to be used.
constexpr size_t kMinInteriorSamples = 10;
constexpr double kMinInteriorFraction = 0.01;

} // namespace

namespace {

/// First search radius of estimateSpacing(), and the cell size of its index: the spacing of
/// the particles spread evenly over their bounding box, or over its two longest sides when
/// that is larger (a sheet), or along its longest one (a line). Fluids rarely fill their
/// box, so this tends to be too large, which only costs a wider first search. Too small is
/// worse: the index's cells, and the search's doublings, multiply. A flat 60 × 60 sheet
/// spaced 0.05 got the line's guess, 0.0008, and its estimate took 21 s; now 0.05.
double spacingGuess(const std::vector<openvdb::Vec3f>& positions, CancelPoll& poll)
{
    if (positions.size() < 2) {
        throw ParameterError(std::string("cannot estimate the particle spacing from ")
                             + (positions.empty() ? "no particles" : "1 particle")
                             + "; give --spacing or --radius, --threshold and --voxel-size");
    }
    // One parallel pass (the serial loop it replaced read the 512x benchmark input's 150 MB
    // of positions on one thread).
    const particle_index_internal::PositionScan scan = particle_index_internal::scanPositions(positions, poll);
    poll.throwIfStopped();
    if (scan.firstNonFinite < positions.size()) {
        // An infinite coordinate was reported as an infinite cell size, or as all particles
        // at one position.
        throw ParameterError(particle_index_internal::nonFinitePositionMessage(scan.firstNonFinite));
    }
    openvdb::Vec3d extent = openvdb::Vec3d(scan.max) - openvdb::Vec3d(scan.min);
    std::sort(extent.asPointer(), extent.asPointer() + 3);  // ascending
    const double count = double(positions.size());
    const double guess = std::max({std::cbrt(extent[0] * extent[1] * extent[2] / count),
                                   std::sqrt(extent[1] * extent[2] / count), extent[2] / count});
    if (!(guess > 0.0)) {
        throw ParameterError("cannot estimate the particle spacing: all particles are at the same position");
    }
    return guess;
}

/// estimateSpacing() over @a index (any cell size), searching from @a guess outwards. The
/// samples are evenly spread over the index's sorted slots.
double estimateSpacingOf(const ParticleIndex& index, double guess, size_t maxSamples, CancelPoll& poll)
{
    const std::vector<openvdb::Vec3f>& positions = index.sortedPositions();
    const size_t sampleCount = std::min(std::max<size_t>(maxSamples, 1), positions.size());
    std::vector<size_t> samples(sampleCount);
    for (size_t i = 0; i < sampleCount; ++i) samples[i] = i * positions.size() / sampleCount;

    // A neighbour found within the search radius is the true nearest one, so the median is
    // exact once more than half the samples found one; otherwise widen the search.
    double radius = guess;
    for (int attempt = 0; attempt < 40; ++attempt, radius *= 2.0) {
        std::vector<double> nearest = nearestWithin(index, samples, radius, poll);
        poll.throwIfStopped();
        const size_t middle = nearest.size() / 2;
        std::nth_element(nearest.begin(), nearest.begin() + middle, nearest.end());
        const double median = nearest[middle];
        if (std::isfinite(median)) {
            if (!(median > 0.0)) {
                throw ParameterError("cannot estimate the particle spacing: most particles sit on top of "
                                     "another one; give --spacing");
            }
            // The nearest neighbour of a disordered particle is closer than the spacing
            // (0.9 s on a lattice jittered by ±0.1 s, 0.79–0.84 s in SPlisHSPlasH frames): the
            // spacing is the cube root of the volume per particle, measured where the
            // particles surround one all round. Thin sheets and jets have no such particle,
            // and keep the median distance.
            std::vector<double> inside = interiorSpacings(index, samples, kSpacingRadiusOverNearest * median, poll);
            poll.throwIfStopped();
            inside.erase(std::remove(inside.begin(), inside.end(), 0.0), inside.end());
            if (inside.size() < kMinInteriorSamples || inside.size() < kMinInteriorFraction * samples.size()) {
                return median;
            }
            const size_t half = inside.size() / 2;
            std::nth_element(inside.begin(), inside.begin() + half, inside.end());
            return inside[half];
        }
    }
    throw ParameterError("cannot estimate the particle spacing; give --spacing");
}

/// estimateSpacing() of @a positions, searched through @a shared when it is given (an index
/// of those same particles: none of its own to build).
double estimateSpacingWith(const std::vector<openvdb::Vec3f>& positions, const ParticleIndex* shared,
                           size_t maxSamples, CancelPoll& poll, openvdb::util::NullInterrupter* interrupter)
{
    const double guess = spacingGuess(positions, poll);
    // The caller's index (cells of r_e/2) serves unless its cells are far finer than the
    // spacing: each search then walks (guess/cell)³ cells, 40 s for --radius 0.001 on a
    // cube of spacing 0.05, before the error that r_e is too small.
    constexpr double kMinSharedCellOverGuess = 0.25;
    if (shared && shared->cellSize() >= kMinSharedCellOverGuess * guess) {
        return estimateSpacingOf(*shared, guess, maxSamples, poll);
    }
    ParticleIndex index;
    try {
        // Cells no smaller than OpenVDB allows: the estimate still works (on wider cells),
        // and the caller then names the voxel size it implies.
        index = ParticleIndex::build(positions, std::max(guess, kMinCellSize), interrupter);
    } catch (const CancelledError&) {
        throw CancelledError(std::string("interrupted during ") + poll.stage());  // this stage's name
    }
    return estimateSpacingOf(index, guess, maxSamples, poll);
}

} // namespace

double estimateSpacing(const std::vector<openvdb::Vec3f>& positions, size_t maxSamples,
                       openvdb::util::NullInterrupter* interrupter)
{
    CancelPoll poll(interrupter, "estimate parameters");
    return estimateSpacingWith(positions, nullptr, maxSamples, poll, interrupter);
}

double calibrateThreshold(double effectiveRadiusOverSpacing)
{
    CancelPoll never(nullptr, "estimate parameters");
    return cancellation_internal::calibrateThreshold(effectiveRadiusOverSpacing, never);
}

namespace {

/// @throw ParameterError unless r_e/s (@a ratio) lies in (1/2, kMaxCalibratedRadiusOverSpacing]:
/// the calibration's lattice has no density at the surface's plane below, and its cost grows
/// as the ratio cubed above.
void requireCalibratableRadius(double ratio)
{
    if (!(ratio > 0.5) || !std::isfinite(ratio)) {
        throw ParameterError("--radius must exceed half the particle spacing to calibrate --threshold, got " +
                             formatNumber(ratio) + " spacings");
    }
    if (ratio > kMaxCalibratedRadiusOverSpacing) {
        throw ParameterError("--radius must be at most " + formatNumber(kMaxCalibratedRadiusOverSpacing) +
                             " particle spacings to calibrate --threshold, got " + formatNumber(ratio) +
                             " spacings; give --threshold");
    }
}

} // namespace

double cancellation_internal::calibrateThreshold(double effectiveRadiusOverSpacing, CancelPoll& poll)
{
    const double ratio = effectiveRadiusOverSpacing;
    requireCalibratableRadius(ratio);
    // Lattice of unit spacing filling z ≤ 0; average φ over the plane z = 1/2 by sampling one
    // lattice cell on a regular grid.
    constexpr int kSamples = 16;
    const int reach = int(std::ceil(ratio)) + 1;
    double sum = 0.0;
    for (int sx = 0; sx < kSamples; ++sx) {
        for (int sy = 0; sy < kSamples; ++sy) {
            poll.throwIfStopped();  // a sample: 1.6·10⁵ evaluations at the limit, under 1 ms
            const double x = (sx + 0.5) / kSamples, y = (sy + 0.5) / kSamples, z = 0.5;
            for (int i = -reach; i <= reach + 1; ++i) {
                for (int j = -reach; j <= reach + 1; ++j) {
                    for (int k = -reach; k <= 0; ++k) {
                        const double d = std::sqrt((x - i) * (x - i) + (y - j) * (y - j) + (z - k) * (z - k));
                        if (d < ratio) sum += ratio / d - 1.0;
                    }
                }
            }
        }
    }
    return cancellation_internal::requireCalibratedThreshold(sum / (kSamples * kSamples), ratio);
}

double cancellation_internal::requireCalibratedThreshold(double threshold, double effectiveRadiusOverSpacing)
{
    if (!(threshold > 0.0)) {
        // Just above half a spacing the kernel reaches no sample of the plane where the
        // surface belongs: r_0 = 0, which every entry point refuses, would mesh nothing.
        throw ParameterError("--radius is too small to calibrate --threshold: at " +
                             formatNumber(effectiveRadiusOverSpacing) +
                             " spacings the density where the surface belongs is 0; give a larger --radius "
                             "or --threshold");
    }
    return threshold;
}

namespace {

/// @throw ParameterError if a voxel of @a voxelSize is wider than @a effectiveRadius (both
/// given): particles whose support holds no voxel centre would be lost (with h = 64 r_e,
/// every one: an empty mesh). At h ≤ r_e the nearest centre is at most (√3/2) h < r_e away.
void requireVoxelWithinRadius(double effectiveRadius, double voxelSize, const LengthNames& names = {})
{
    if (voxelSize > effectiveRadius) {
        const auto [voxelText, radiusText] = number_text_internal::numbersApart(voxelSize, effectiveRadius);
        throw ParameterError(names.voxelSize + " " + voxelText + " is too large for " + names.radius + " " +
                             radiusText + ": at least one voxel per radius");
    }
}

void requireRadiusBelowMaximum(double effectiveRadius, const LengthNames& names = {})
{
    parameter_checks_internal::requireRadiusBelowMaximum(effectiveRadius, names.radius);
}

/// The limits of the lengths that are known: each against OpenVDB's smallest (voxel, index
/// cell), and against each other when both are; messages name the lengths as @a names says.
void requireLengthLimits(std::optional<double> effectiveRadius, std::optional<double> voxelSize,
                         const LengthNames& names = {})
{
    using openvdb_scale_internal::requireOpenVdbScale;
    if (voxelSize) requireOpenVdbScale(*voxelSize, kMinCellSize, names.voxelSize.c_str());
    if (effectiveRadius) {
        requireOpenVdbScale(*effectiveRadius, kMinCellSize / surface_stages_internal::kCellOverRadius,
                            names.radius.c_str());
        if (voxelSize) {
            surface_stages_internal::requireVoxelsPerRadius(*effectiveRadius, *voxelSize, names);
            requireVoxelWithinRadius(*effectiveRadius, *voxelSize, names);
        }
        requireRadiusBelowMaximum(*effectiveRadius, names);
    }
}

/// The limits of the lengths that the spacing @a spacing sets where @a params gives none
/// (r_e = 2 s, h = s/2), with the given ones; messages start "<@a spacingName>: " and name
/// each derived length by its formula ("the voxel size 0.5 s = 5e-07 is below ...").
void requireLengthLimitsFromSpacing(const SurfaceParameters& params, double spacing, const std::string& spacingName)
{
    const double radius = params.effectiveRadius.value_or(kDefaultRadiusOverSpacing * spacing);
    const double voxelSize = params.voxelSize.value_or(kDefaultVoxelOverSpacing * spacing);
    LengthNames names;
    if (!params.effectiveRadius) names.radius = "the radius " + formatNumber(kDefaultRadiusOverSpacing) + " s =";
    if (!params.voxelSize) names.voxelSize = "the voxel size " + formatNumber(kDefaultVoxelOverSpacing) + " s =";
    try {
        // A radius the spacing sets is checked against the maximum first (requireLengthLimits
        // checks it last): with a given --voxel-size, the voxels-per-radius limit it may also
        // break would otherwise be named instead of the cause, the spacing's size.
        if (!params.effectiveRadius) requireRadiusBelowMaximum(radius, names);
        requireLengthLimits(radius, voxelSize, names);
    } catch (const ParameterError& e) {
        throw ParameterError(spacingName + ": " + e.what());
    }
}

} // namespace

void checkParameters(const SurfaceParameters& params)
{
    auto requirePositive = [](const std::optional<double>& value, const char* name) {
        if (value) parameter_checks_internal::requirePositive(*value, name);
    };
    requirePositive(params.spacing, "--spacing");
    requirePositive(params.effectiveRadius, "--radius");
    requirePositive(params.threshold, "--threshold");
    requirePositive(params.voxelSize, "--voxel-size");
    parameter_checks_internal::requireUnitInterval(params.blend, "--blend");
    if (params.iterations < 0) {
        throw ParameterError("--iterations must be >= 0, got " + std::to_string(params.iterations));
    }
    parameter_checks_internal::requireUnitInterval(params.adaptivity, "--adaptivity");
    // An out-of-range enumerator (a cast integer, memory from another build) ran as neither
    // variant: the Paper mesh without its threshold calibration.
    if (params.method != Method::Paper && params.method != Method::Faithful) {
        throw ParameterError("method must be Paper or Faithful, got " + std::to_string(int(params.method)));
    }
    if (params.volumeOffset) parameter_checks_internal::requireVolumeOffset(*params.volumeOffset);
    if (params.method == Method::Faithful && params.maxStep) parameter_checks_internal::stepCap(*params.maxStep);
    // The limits between lengths, where the lengths are given; resolveParameters() checks
    // them again once the others are derived.
    requireLengthLimits(params.effectiveRadius, params.voxelSize);
    // A float density grid compares its values with float(r_0): 1e-46 became 0 (an empty mesh,
    // blamed on the particles) and 1e39 infinity. Range first: only then is the cast defined.
    if (params.threshold && !(*params.threshold <= double(std::numeric_limits<float>::max()) &&
                              float(*params.threshold) > 0.0f)) {
        throw ParameterError("--threshold must be a positive number within float's range (the density grid's values), got " +
                             number_text_internal::numberBeside(*params.threshold, double(std::numeric_limits<float>::max())));
    }
    // Lengths that a given spacing alone sets (r_e = 2 s, h = s/2) meet the same limits
    // whatever the particles: checked now and said of --spacing. "--voxel-size 5e-07 is
    // below ..." named an option never given, and only once the input had been read.
    if (params.spacing && !(params.effectiveRadius && params.voxelSize)) {
        requireLengthLimitsFromSpacing(params, *params.spacing, "--spacing " + formatNumber(*params.spacing));
    }
    // The threshold's calibration needs r_e/s within its range: known now when both are given.
    if (params.spacing && params.effectiveRadius && !params.threshold) {
        requireCalibratableRadius(*params.effectiveRadius / *params.spacing);
    }
}

namespace {

/// resolveParameters() of @a positions, searched through @a shared (an index of those same
/// particles) when it is given.
ResolvedParameters resolveParametersWith(const SurfaceParameters& params, const std::vector<openvdb::Vec3f>& positions,
                                         const ParticleIndex* shared, openvdb::util::NullInterrupter* interrupter)
{
    CancelPoll poll(interrupter, "estimate parameters");
    checkParameters(params);
    surface_stages_internal::requireParticles(positions);

    ResolvedParameters out;
    out.blend = params.blend;
    out.iterations = params.iterations;
    out.adaptivity = params.adaptivity;
    out.regionLeaves = params.regionLeaves;
    out.spacingGiven = bool(params.spacing);
    out.effectiveRadiusGiven = bool(params.effectiveRadius);
    out.thresholdGiven = bool(params.threshold);
    out.voxelSizeGiven = bool(params.voxelSize);

    const bool needSpacing = !params.effectiveRadius || !params.threshold || !params.voxelSize;
    if (params.spacing) out.spacing = *params.spacing;
    else if (needSpacing) out.spacing = estimateSpacingWith(positions, shared, kSpacingSamples, poll, interrupter);
    poll.throwIfStopped();

    out.effectiveRadius = params.effectiveRadius ? *params.effectiveRadius
                                                 : kDefaultRadiusOverSpacing * out.spacing;
    out.voxelSize = params.voxelSize ? *params.voxelSize : kDefaultVoxelOverSpacing * out.spacing;
    // Lengths derived from an estimated spacing meet the limits that checkParameters() made of
    // the given ones (and of those a given spacing sets), before the threshold's calibration,
    // whose cost grows as (r_e/s)³. Said of the estimate: "--voxel-size 5e-10 is below ..."
    // named an option never given.
    if (!params.spacing && !(params.effectiveRadius && params.voxelSize)) {
        requireLengthLimitsFromSpacing(params, out.spacing, "--spacing " + formatNumber(out.spacing) + " (estimated)");
    }
    out.method = params.method;
    const bool faithful = params.method == Method::Faithful;
    if (faithful) {
        out.maxStep = params.maxStep ? parameter_checks_internal::stepCap(*params.maxStep)
                                     : kDefaultMaxStepOverSpacing * out.spacing;
    }
    bool calibratedForRelaxedSurface = false;
    if (params.threshold) out.threshold = *params.threshold;
    else if (faithful) out.threshold = cancellation_internal::calibrateRelaxedThreshold(
                           out.effectiveRadius / out.spacing, out.blend, out.iterations,
                           &calibratedForRelaxedSurface, out.maxStep / out.spacing, poll);
    else out.threshold = cancellation_internal::calibrateThreshold(out.effectiveRadius / out.spacing, poll);
    out.thresholdReachesSurface = params.threshold || !faithful || calibratedForRelaxedSurface;
    if (faithful) {
        out.preserveVolume = params.preserveVolume ? *params.preserveVolume : out.spacingGiven;
        out.volumeOffset = params.volumeOffset ? *params.volumeOffset
                           : calibratedForRelaxedSurface ? VolumeOffset::Convex : VolumeOffset::Uniform;
        out.repairFolds = params.repairFolds;
        out.smoothSurface = params.smoothSurface ? *params.smoothSurface : out.preserveVolume;
        // The volume target N·s³ and the smoothing's width need s even when r_e, r_0 and h
        // were all given.
        if ((out.preserveVolume || out.smoothSurface) && !(out.spacing > 0.0)) {
            out.spacing = estimateSpacingWith(positions, shared, kSpacingSamples, poll, interrupter);
        }
        const double volume = double(positions.size()) * out.spacing * out.spacing * out.spacing;
        if (out.preserveVolume && !std::isfinite(volume)) {
            throw ParameterError("--spacing " + formatNumber(out.spacing) + " is too large: the fluid's volume N s^3 (N = " +
                                 std::to_string(positions.size()) + ") is not a finite number");
        }
    }

    // A derived r_e, after the volume check, which names --spacing when that was given (a
    // given r_e was checked by checkParameters()).
    requireRadiusBelowMaximum(out.effectiveRadius);

    poll.throwIfStopped();
    return out;
}

} // namespace

ResolvedParameters resolveParameters(const SurfaceParameters& params,
                                     const std::vector<openvdb::Vec3f>& positions,
                                     openvdb::util::NullInterrupter* interrupter)
{
    return resolveParametersWith(params, positions, nullptr, interrupter);
}

ResolvedParameters resolveParametersIndexed(const SurfaceParameters& params, const ParticleIndex& index,
                                            openvdb::util::NullInterrupter* interrupter)
{
    return resolveParametersWith(params, index.sortedPositions(), &index, interrupter);
}

} // namespace nonbloppy
