// SPDX-License-Identifier: Apache-2.0
/// @file CorrectSurface.cc
/// @brief Relaxed-surface threshold calibration, fold repair, normal offset and volume correction.

#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/EstimateParameters.h>
#include <nonbloppy/Kernel.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/ComputeNormals.h>

#include "Cancellation.h"
#include "ParameterChecks.h"
#include "PolygonIndices.h"
#include "SurfaceStages.h"
#include "VectorArea.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>

namespace nonbloppy {

namespace {

using cancellation_internal::CancelPoll;

/// Lattice cell sampled on a kSamples × kSamples grid, as calibrateThreshold() does.
constexpr int kSamples = 8;

/// MPS weight in double precision, with the library's clamp near d = 0.
double weight(double d, double ratio)
{
    if (!(d < ratio)) return 0.0;
    return ratio / std::max(d, double(kMinDistanceFraction) * ratio) - 1.0;
}

/// Call @a op(r, w) for every point r of the unit lattice filling z ≤ 0 whose weight w at
/// @a x is not zero, in the order of x, then y ascending and z descending. Only the points in
/// the box of half-width r_e (+1 for rounding) around x are visited: adding the zero weights
/// outside changes no bit of a sum, and skipping them is 7× faster at r_e = 2.1 s.
template<typename OpT>
void forEachLatticeNeighbour(double ratio, const openvdb::Vec3d& x, OpT&& op)
{
    const int iLow = int(std::floor(x[0] - ratio)), iHigh = int(std::ceil(x[0] + ratio));
    const int jLow = int(std::floor(x[1] - ratio)), jHigh = int(std::ceil(x[1] + ratio));
    const int kLow = int(std::floor(x[2] - ratio)), kHigh = std::min(0, int(std::ceil(x[2] + ratio)));
    for (int i = iLow; i <= iHigh; ++i)
        for (int j = jLow; j <= jHigh; ++j)
            for (int k = kHigh; k >= kLow; --k) {
                const openvdb::Vec3d r(i, j, k);
                const double w = weight((x - r).length(), ratio);
                if (w != 0.0) op(r, w);
            }
}

/// Unit lattice filling z ≤ 0 (spacing 1, r_e = ratio): density at (x, y, z).
double latticeDensity(double ratio, const openvdb::Vec3d& x)
{
    double sum = 0.0;
    forEachLatticeNeighbour(ratio, x, [&](const openvdb::Vec3d&, double w) { sum += w; });
    return sum;
}

/// One relaxation step of vertex @a x against the unit lattice filling z ≤ 0, no longer than
/// @a maxStep (lattice spacings; 0: uncapped), as relaxVertices() takes it.
openvdb::Vec3d relaxOnLattice(double ratio, double blend, double maxStep, const openvdb::Vec3d& x)
{
    double sw = 0.0;
    openvdb::Vec3d mean(0.0);
    forEachLatticeNeighbour(ratio, x, [&](const openvdb::Vec3d& r, double w) {
        sw += w;
        mean += w * r;
    });
    if (!(sw > 0.0)) return x;
    openvdb::Vec3d step = blend * (mean / sw - x);
    const double length2 = step.lengthSqr();
    if (maxStep > 0.0 && length2 > maxStep * maxStep) step *= maxStep / std::sqrt(length2);
    return x + step;
}

/// Mean height, over the lattice cell, of vertices that start at height @a z0 after
/// @a iterations relaxation steps of at most @a maxStep. A vertex that a step leaves where it
/// is stays there, so its remaining steps are skipped: with c = 0.3 they all settle early
/// enough that t = 10⁶ calibrates in under a second (the dam-break frame). Asks @a poll
/// before every step.
double relaxedHeight(double ratio, double blend, double maxStep, int iterations, double z0, CancelPoll& poll)
{
    double sum = 0.0;
    for (int a = 0; a < kSamples; ++a)
        for (int b = 0; b < kSamples; ++b) {
            openvdb::Vec3d x((a + 0.5) / kSamples, (b + 0.5) / kSamples, z0);
            for (int t = 0; t < iterations; ++t) {
                poll.throwIfStopped();
                const openvdb::Vec3d next = relaxOnLattice(ratio, blend, maxStep, x);
                if (next == x) break;
                x = next;
            }
            sum += x[2];
        }
    return sum / (kSamples * kSamples);
}

/// Mean density over the lattice cell at height @a z; asks @a poll before every sample.
double planeDensity(double ratio, double z, CancelPoll& poll)
{
    double sum = 0.0;
    for (int a = 0; a < kSamples; ++a)
        for (int b = 0; b < kSamples; ++b) {
            poll.throwIfStopped();
            sum += latticeDensity(ratio, openvdb::Vec3d((a + 0.5) / kSamples, (b + 0.5) / kSamples, z));
        }
    return sum / (kSamples * kSamples);
}

/// Twice the area-weighted normal of triangle abc.
inline openvdb::Vec3d triangleNormal(const openvdb::Vec3s& a, const openvdb::Vec3s& b, const openvdb::Vec3s& c)
{
    return twiceVectorArea(openvdb::Vec3d(a), openvdb::Vec3d(b), openvdb::Vec3d(c));
}

/// Call @a op(i, j, k) for every triangle of polygons [first, end) of the mesh (triangles,
/// then quads; quads split along 0–2), in that order.
template<typename OpT>
void forEachTriangleOf(const SurfaceMesh& mesh, size_t first, size_t end, OpT&& op)
{
    for (size_t n = first; n < end; ++n) {
        const auto [corners, count] = polygon_indices_internal::cornersOf(mesh, n);
        op(corners[0], corners[1], corners[2]);
        if (count == 4) op(corners[0], corners[2], corners[3]);
    }
}

/// Call @a op(a, b) for every edge of every polygon, in polygon order (triangles, then
/// quads), each polygon's edges in its winding; asks @a poll every kItemsPerPoll polygons
/// and throws its CancelledError on a stop.
template<typename OpT>
void forEachPolygonEdge(const SurfaceMesh& mesh, CancelPoll& poll, OpT&& op)
{
    const auto edgesOf = [&](const auto& polygon, int corners) {
        for (int i = 0; i < corners; ++i) op(polygon[i], polygon[(i + 1) % corners]);
    };
    for (size_t n = 0; n < mesh.triangles.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        edgesOf(mesh.triangles[n], 3);
    }
    for (size_t n = 0; n < mesh.quads.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        edgesOf(mesh.quads[n], 4);
    }
}

void requireSameSize(const SurfaceMesh& mesh, const std::vector<openvdb::Vec3s>& before)
{
    if (before.size() != mesh.points.size()) {
        throw ParameterError("fold repair needs the positions before relaxation of all " +
                             std::to_string(mesh.points.size()) + " vertices, got " +
                             std::to_string(before.size()));
    }
}

/// Mark the vertices of folded triangles; return how many triangles are folded. Parallel over
/// polygons; the folded triangles (few) are listed per task and marked afterwards, so the
/// marks and the count are the same in any order. Given @a moved (the vertices moved since
/// the last call, which marked every folded triangle then), only triangles with a moved
/// corner are tested: the others kept their shape, and were not folded.
size_t markFolded(const SurfaceMesh& mesh, const openvdb::Vec3s* before,
                  std::vector<char>& marked, CancelPoll& poll, const std::vector<char>* moved = nullptr)
{
    std::fill(marked.begin(), marked.end(), 0);
    const auto isFolded = [&](unsigned i, unsigned j, unsigned k) {
        if (moved && !(*moved)[i] && !(*moved)[j] && !(*moved)[k]) return false;
        const openvdb::Vec3d now = triangleNormal(mesh.points[i], mesh.points[j], mesh.points[k]);
        const openvdb::Vec3d then = triangleNormal(before[i], before[j], before[k]);
        return now.dot(then) < 0.0;
    };
    tbb::enumerable_thread_specific<std::vector<openvdb::Vec3I>> foldedPerThread;
    const size_t triangleCount = mesh.triangles.size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, triangleCount + mesh.quads.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            std::vector<openvdb::Vec3I>& folded = foldedPerThread.local();
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stoppedAt(n - range.begin())) return;
                if (n < triangleCount) {
                    const openvdb::Vec3I& t = mesh.triangles[n];
                    if (isFolded(t[0], t[1], t[2])) folded.push_back(t);
                } else {
                    const openvdb::Vec4I& q = mesh.quads[n - triangleCount];
                    if (isFolded(q[0], q[1], q[2])) folded.push_back(openvdb::Vec3I(q[0], q[1], q[2]));
                    if (isFolded(q[0], q[2], q[3])) folded.push_back(openvdb::Vec3I(q[0], q[2], q[3]));
                }
            }
        });
    poll.throwIfStopped();
    size_t count = 0;
    for (const std::vector<openvdb::Vec3I>& folded : foldedPerThread) {
        count += folded.size();
        for (const openvdb::Vec3I& t : folded) marked[t[0]] = marked[t[1]] = marked[t[2]] = 1;
    }
    return count;
}

/// Convexity of every vertex: (v − mean of its edge neighbours) · n, world units, > 0 where
/// the surface bulges outwards. Each polygon adds its two edge neighbours to each corner, so
/// on a closed manifold mesh every neighbour is counted once from each side of their edge:
/// the mean is that of the distinct neighbours, with no adjacency lists to build.
std::vector<double> vertexConvexity(const SurfaceMesh& mesh, CancelPoll& poll)
{
    std::vector<openvdb::Vec3d> neighbourSum(mesh.points.size(), openvdb::Vec3d(0.0));
    std::vector<uint32_t> neighbourCount(mesh.points.size(), 0);
    auto addEdge = [&](unsigned a, unsigned b) {
        neighbourSum[a] += openvdb::Vec3d(mesh.points[b]);
        neighbourSum[b] += openvdb::Vec3d(mesh.points[a]);
        ++neighbourCount[a];
        ++neighbourCount[b];
    };
    forEachPolygonEdge(mesh, poll, addEdge);
    std::vector<double> convexity(mesh.points.size(), 0.0);
    for (size_t i = 0; i < convexity.size(); ++i) {
        if (neighbourCount[i] == 0) continue;
        const openvdb::Vec3d mean = neighbourSum[i] / double(neighbourCount[i]);
        convexity[i] = (openvdb::Vec3d(mesh.points[i]) - mean).dot(openvdb::Vec3d(mesh.normals[i]));
    }
    return convexity;
}

/// What a volume-correction pass measures of the mesh (quads split along 0–2).
struct PassMeasures
{
    AreaAndVolume total;             ///< measureAreaAndVolume()'s, to the last bit
    /// A third of the area of every triangle around each vertex: the volume the surface
    /// sweeps when vertex i moves by δ along its normal is about Σ δ·vertexArea_i.
    std::vector<double> vertexArea;
};

/// The mesh's area and volume, summed triangle by triangle in polygon order as
/// measureAreaAndVolume() sums them, and every vertex's area, each vertex's thirds added in
/// the same order: the same bits as the serial loops that did this before. The per-triangle
/// terms (a cross product, its length, a triple product) are computed in parallel, a block of
/// polygons at a time, while one thread adds up the blocks before, in order (a pipeline).
/// 64x benchmark input, --spacing, two threads: a pass took 0.034 s for the area and volume
/// plus 0.033 s for the vertex areas as two serial loops, 0.027–0.033 s this way (0.044–0.049
/// s at one thread). Scratch: 24 bytes per triangle of the blocks in flight. Asks @a poll
/// between blocks.
PassMeasures measurePass(const SurfaceMesh& mesh, CancelPoll& poll)
{
    constexpr size_t kBlockPolygons = 16384;
    const size_t triangleCount = mesh.triangles.size();
    const size_t polygonCount = triangleCount + mesh.quads.size();
    const size_t blockCount = (polygonCount + kBlockPolygons - 1) / kBlockPolygons;
    /// Per triangle of a block, in order (a quad's two after each other): its area, six
    /// times its signed volume, and a third of its area.
    struct BlockTerms
    {
        size_t first = 0, end = 0;  ///< polygons [first, end)
        std::vector<double> area, sixVolume, third;
    };
    PassMeasures out;
    out.vertexArea.assign(mesh.points.size(), 0.0);
    size_t nextBlock = 0;
    const size_t threads = size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    tbb::parallel_pipeline(threads + 1,
        tbb::make_filter<void, std::shared_ptr<BlockTerms>>(tbb::filter_mode::serial_in_order,
            [&](tbb::flow_control& control) {
                if (nextBlock == blockCount || poll.stopped()) {
                    control.stop();
                    return std::shared_ptr<BlockTerms>();
                }
                auto block = std::make_shared<BlockTerms>();
                block->first = nextBlock * kBlockPolygons;
                block->end = std::min(polygonCount, block->first + kBlockPolygons);
                ++nextBlock;
                return block;
            })
        & tbb::make_filter<std::shared_ptr<BlockTerms>, std::shared_ptr<BlockTerms>>(tbb::filter_mode::parallel,
            [&](std::shared_ptr<BlockTerms> block) {
                // A polygon each, and a second triangle for each quad (quads follow the triangles).
                const size_t triangles = (block->end - block->first)
                                         + (block->end > triangleCount ? block->end - std::max(block->first, triangleCount) : 0);
                block->area.resize(triangles);
                block->sixVolume.resize(triangles);
                block->third.resize(triangles);
                size_t slot = 0;
                forEachTriangleOf(mesh, block->first, block->end, [&](unsigned i, unsigned j, unsigned k) {
                    const openvdb::Vec3d a(mesh.points[i]), b(mesh.points[j]), c(mesh.points[k]);
                    const double length = twiceVectorArea(a, b, c).length();
                    block->area[slot] = 0.5 * length;
                    block->sixVolume[slot] = sixTimesSignedVolume(a, b, c);
                    block->third[slot] = length / 6.0;
                    ++slot;
                });
                return block;
            })
        & tbb::make_filter<std::shared_ptr<BlockTerms>, void>(tbb::filter_mode::serial_in_order,
            [&](std::shared_ptr<BlockTerms> block) {
                size_t slot = 0;
                forEachTriangleOf(mesh, block->first, block->end, [&](unsigned i, unsigned j, unsigned k) {
                    out.total.area += block->area[slot];
                    out.total.volume += block->sixVolume[slot] / 6.0;
                    const double third = block->third[slot];
                    out.vertexArea[i] += third;
                    out.vertexArea[j] += third;
                    out.vertexArea[k] += third;
                    ++slot;
                });
            }));
    poll.throwIfStopped();
    return out;
}

void requireTargetVolume(double targetVolume)
{
    if (!(targetVolume > 0.0) || !std::isfinite(targetVolume)) {
        std::ostringstream msg;
        msg << "target volume must be > 0, got " << targetVolume;
        throw ParameterError(msg.str());
    }
}

void requireNormals(const SurfaceMesh& mesh)
{
    if (mesh.normals.size() != mesh.points.size()) {
        throw ParameterError("offsetting a surface needs its normals (computeNormals())");
    }
}

} // namespace

double calibrateRelaxedThreshold(double effectiveRadiusOverSpacing, double blend, int iterations,
                                 bool* reachesSurface, double maxStepOverSpacing)
{
    CancelPoll never(nullptr, "estimate parameters");
    return cancellation_internal::calibrateRelaxedThreshold(effectiveRadiusOverSpacing, blend, iterations,
                                                            reachesSurface, maxStepOverSpacing, never);
}

double cancellation_internal::calibrateRelaxedThreshold(double effectiveRadiusOverSpacing, double blend,
                                                        int iterations, bool* reachesSurface,
                                                        double maxStepOverSpacing, CancelPoll& poll)
{
    if (reachesSurface) *reachesSurface = true;
    const double ratio = effectiveRadiusOverSpacing;
    parameter_checks_internal::requireUnitInterval(blend, "--blend");
    if (iterations < 0) {
        throw ParameterError("--iterations must be >= 0, got " + std::to_string(iterations));
    }
    const double maxStep = parameter_checks_internal::stepCap(maxStepOverSpacing, " spacings");
    const double blobThreshold = cancellation_internal::calibrateThreshold(ratio, poll);  // checks the ratio
    if (iterations == 0 || blend == 0.0) return blobThreshold;

    // Far from the particles few of them are in reach and relaxation jumps towards them, so
    // the relaxed height is not monotone in the start height over all of [1/2, r_e]: take the
    // first start height, scanning outwards from 1/2, that relaxes to 1/2 or beyond, and
    // bisect within that step. Starting farther out than kMaxStart (or 3/4 r_e) would merge
    // fluid bodies 2·kMaxStart apart before relaxation could separate them: strong
    // relaxations (large c·t) stop there and end inside (preserveVolume() can finish).
    constexpr double kScanStep = 0.05, kMaxStart = 1.5;
    const double limit = std::min(kMaxStart, 0.75 * ratio);
    // The limit itself is tried too: the scan gave up on reaching it untried, and c = 0.5,
    // t = 2, r_e = 2 s, which relaxes a start at 1.5 to 0.5009, fell back for that (bug hunt).
    double low = 0.5, high = 0.5;
    while (relaxedHeight(ratio, blend, maxStep, iterations, high, poll) < 0.5) {
        if (high >= limit) {
            if (reachesSurface) *reachesSurface = false;
            return cancellation_internal::requireCalibratedThreshold(planeDensity(ratio, limit, poll), ratio);
        }
        low = high;
        high = std::min(high + kScanStep, limit);
    }
    for (int step = 0; step < 24; ++step) {
        const double middle = 0.5 * (low + high);
        (relaxedHeight(ratio, blend, maxStep, iterations, middle, poll) < 0.5 ? low : high) = middle;
    }
    return cancellation_internal::requireCalibratedThreshold(planeDensity(ratio, 0.5 * (low + high), poll), ratio);
}

size_t countFoldedTriangles(const SurfaceMesh& mesh, const std::vector<openvdb::Vec3s>& before)
{
    requireSameSize(mesh, before);
    polygon_indices_internal::requireValidIndices(mesh);
    std::vector<char> marked(mesh.points.size());
    CancelPoll never(nullptr, "correct surface");
    return markFolded(mesh, before.data(), marked, never);
}

size_t repairFolds(SurfaceMesh& mesh, const std::vector<openvdb::Vec3s>& before, int maxRounds,
                   openvdb::util::NullInterrupter* interrupter)
{
    polygon_indices_internal::requireValidIndices(mesh);
    requireSameSize(mesh, before);
    return surface_stages_internal::repairFoldsUnchecked(mesh, before.data(), maxRounds, interrupter);
}

size_t surface_stages_internal::repairFoldsUnchecked(SurfaceMesh& mesh, const openvdb::Vec3s* before,
                                                     int maxRounds, openvdb::util::NullInterrupter* interrupter)
{
    if (maxRounds < 0) {
        throw ParameterError("fold repair rounds must be >= 0, got " + std::to_string(maxRounds));
    }
    CancelPoll poll(interrupter, "correct surface");
    std::vector<char> marked(mesh.points.size()), moved(mesh.points.size());
    const size_t first = markFolded(mesh, before, marked, poll);
    size_t folded = first;
    for (int round = 0; folded > 0; ++round) {
        const bool last = round >= maxRounds;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, marked.size()), [&](const tbb::blocked_range<size_t>& range) {
            for (size_t i = range.begin(); i < range.end(); ++i) {
                if (marked[i]) mesh.points[i] = last ? before[i] : 0.5f * (mesh.points[i] + before[i]);
            }
        });
        if (last) break;
        // Only the triangles around the vertices just moved can have changed.
        moved.swap(marked);
        folded = markFolded(mesh, before, marked, poll, &moved);
    }
    return first;
}

void offsetSurface(SurfaceMesh& mesh, double distance)
{
    if (!std::isfinite(distance)) {  // NaN made every vertex NaN
        std::ostringstream msg;
        msg << "offset distance must be finite, got " << distance;
        throw ParameterError(msg.str());
    }
    requireNormals(mesh);
    const float d = float(distance);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.points.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t i = range.begin(); i < range.end(); ++i) mesh.points[i] += d * mesh.normals[i];
        });
}

namespace {

/// @throw ParameterError unless @a maxDistance > 0 (a negative one moved the surface the
///        wrong way, and turned it inside out when large).
void requireMaxDistance(double maxDistance)
{
    if (!(maxDistance > 0.0)) {
        std::ostringstream msg;
        msg << "largest volume offset must be > 0, got " << maxDistance;
        throw ParameterError(msg.str());
    }
}

} // namespace

double preserveVolume(SurfaceMesh& mesh, double targetVolume, double maxDistance,
                      openvdb::util::NullInterrupter* interrupter)
{
    requireTargetVolume(targetVolume);
    requireMaxDistance(maxDistance);
    CancelPoll poll(interrupter, "correct surface");
    double total = 0.0;
    for (int pass = 0; pass < 2; ++pass) {
        poll.throwIfStopped();
        const AreaAndVolume measures = measureAreaAndVolume(mesh);  // serial, O(P)
        poll.throwIfStopped();
        if (!(measures.area > 0.0)) break;
        const double distance = std::clamp((targetVolume - measures.volume) / measures.area,
                                           -maxDistance - total, maxDistance - total);
        if (distance == 0.0) break;
        offsetSurface(mesh, distance);
        cancellation_internal::computeNormals(mesh, poll);
        total += distance;
    }
    return total;
}

double preserveVolume(SurfaceMesh& mesh, const VolumeSettings& settings,
                      openvdb::util::NullInterrupter* interrupter)
{
    polygon_indices_internal::requireValidIndices(mesh);
    return surface_stages_internal::preserveVolumeUnchecked(mesh, settings, interrupter);
}

double surface_stages_internal::preserveVolumeUnchecked(SurfaceMesh& mesh, const VolumeSettings& settings,
                                                        openvdb::util::NullInterrupter* interrupter)
{
    if (!(settings.convexityFloor >= 0.0) || !std::isfinite(settings.convexityFloor)) {
        std::ostringstream msg;
        msg << "convexity floor must be >= 0, got " << settings.convexityFloor;
        throw ParameterError(msg.str());
    }
    requireMaxDistance(settings.maxDistance);
    parameter_checks_internal::requireVolumeOffset(settings.offset);
    if (settings.offset == VolumeOffset::Uniform) {
        return preserveVolume(mesh, settings.targetVolume, settings.maxDistance, interrupter);
    }
    const double target = settings.targetVolume;
    requireTargetVolume(target);
    requireNormals(mesh);
    CancelPoll poll(interrupter, "correct surface");

    // Where to put the volume is decided once, on the relaxed surface: later passes only
    // rescale it, so the offset cannot feed back into its own convexity.
    std::vector<double> share = vertexConvexity(mesh, poll);
    bool anyConvex = false;
    for (double& c : share) {
        c = std::max(0.0, c - settings.convexityFloor);
        anyConvex = anyConvex || c > 0.0;
    }
    if (!anyConvex) return preserveVolume(mesh, target, settings.maxDistance, interrupter);

    // Three passes: each solves the volume to first order (Σ α·share_i·area_i), the next
    // absorbs the curvature term and what the clamp to ±maxDistance left over.
    constexpr int kPasses = 3;
    std::vector<double> moved(mesh.points.size(), 0.0);
    for (int pass = 0; pass < kPasses; ++pass) {
        poll.throwIfStopped();
        const PassMeasures measured = measurePass(mesh, poll);
        const AreaAndVolume& measures = measured.total;
        const std::vector<double>& area = measured.vertexArea;
        double sweptPerUnit = 0.0;
        for (size_t i = 0; i < share.size(); ++i) sweptPerUnit += share[i] * area[i];
        if (!(sweptPerUnit > 0.0)) break;
        const double alpha = (target - measures.volume) / sweptPerUnit;
        if (alpha == 0.0) break;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.points.size()),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t i = range.begin(); i < range.end(); ++i) {
                    const double total = std::clamp(moved[i] + alpha * share[i],
                                                    -settings.maxDistance, settings.maxDistance);
                    mesh.points[i] += float(total - moved[i]) * mesh.normals[i];
                    moved[i] = total;
                }
            });
        cancellation_internal::computeNormals(mesh, poll);
    }
    double farthest = 0.0;
    for (double d : moved) {
        if (std::abs(d) > std::abs(farthest)) farthest = d;
    }
    return farthest;
}

} // namespace nonbloppy
