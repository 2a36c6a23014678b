// SPDX-License-Identifier: Apache-2.0
/// @file FidelityShapes.h
/// @brief Particle sets with a known true surface, and the distances that measure a mesh
///        against it. Shared by the fidelity benchmark (tests/bench/fidelity.cc) and its
///        regression tests (tests/test_Fidelity.cc).
///
/// Every shape is a set of lattice points of spacing s, each moved by up to jitter·s per axis
/// with a fixed seed. Its true surface is the set of lattice cells grown around the points
/// (the shape grown by s/2), whose volume is N·s³: a box for the box, slab and jet; for the
/// ball, the sphere whose volume is exactly N·s³ (a lattice cannot do better for a curve).
/// All distances are reported in units of s.

#ifndef NONBLOPPY_FIDELITY_SHAPES_H
#define NONBLOPPY_FIDELITY_SHAPES_H

#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/Mesh.h>

#include <openvdb/openvdb.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

namespace nonbloppy_fidelity {

using openvdb::Vec3d;
using openvdb::Vec3f;

/// A particle set and its true surface.
struct Shape
{
    std::string name;                       ///< short name, e.g. "box"
    std::string description;                ///< e.g. "12×12×12 particles"
    double spacing = 1.0;                   ///< s, world units
    std::vector<Vec3f> particles;           ///< jittered lattice points
    std::function<double(const Vec3d&)> sdf;///< signed distance to the true surface, < 0 inside
    std::vector<Vec3d> truthSamples;        ///< points on the true surface, about s/8 apart
    double trueVolume = 0.0;                ///< N·s³
};

namespace detail {

inline double boxSdf(const Vec3d& p, const Vec3d& lo, const Vec3d& hi)
{
    const Vec3d centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
    Vec3d q;
    for (int a = 0; a < 3; ++a) q[a] = std::abs(p[a] - centre[a]) - half[a];
    const Vec3d outside(std::max(q[0], 0.0), std::max(q[1], 0.0), std::max(q[2], 0.0));
    return outside.length() + std::min(std::max(q[0], std::max(q[1], q[2])), 0.0);
}

/// Points on the surface of the box [lo, hi], about @a step apart, including edges and corners.
inline std::vector<Vec3d> boxSamples(const Vec3d& lo, const Vec3d& hi, double step)
{
    std::vector<Vec3d> out;
    int n[3];
    for (int a = 0; a < 3; ++a) n[a] = std::max(1, int(std::ceil((hi[a] - lo[a]) / step)));
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        for (int side = 0; side < 2; ++side) {
            for (int i = 0; i <= n[b]; ++i)
                for (int j = 0; j <= n[c]; ++j) {
                    Vec3d p;
                    p[a] = side ? hi[a] : lo[a];
                    p[b] = lo[b] + (hi[b] - lo[b]) * i / n[b];
                    p[c] = lo[c] + (hi[c] - lo[c]) * j / n[c];
                    out.push_back(p);
                }
        }
    }
    return out;
}

/// Lattice points (i, j, k)·s for which @a keep is true, searched over [-n, n]³, jittered.
inline std::vector<Vec3f> lattice(double s, int n, const std::function<bool(int, int, int)>& keep,
                                  double jitter, unsigned seed)
{
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> offset(-jitter * s, jitter * s);
    std::vector<Vec3f> out;
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
            for (int k = -n; k <= n; ++k) {
                if (!keep(i, j, k)) continue;
                Vec3d p(i * s, j * s, k * s);
                const double dx = offset(random), dy = offset(random), dz = offset(random);
                if (jitter > 0.0) p += Vec3d(dx, dy, dz);
                out.emplace_back(p);
            }
    return out;
}

/// A box of nx × ny × nz particles, centred near the origin (s = spacing).
inline Shape boxShape(const std::string& name, const std::string& description, int nx, int ny, int nz,
                      double s, double jitter, unsigned seed)
{
    const int ox = nx / 2, oy = ny / 2, oz = nz / 2;  // first index -o, last n - 1 - o
    Shape shape;
    shape.name = name;
    shape.description = description;
    shape.spacing = s;
    const int reach = std::max({nx, ny, nz});
    shape.particles = lattice(s, reach, [=](int i, int j, int k) {
        return i >= -ox && i < nx - ox && j >= -oy && j < ny - oy && k >= -oz && k < nz - oz;
    }, jitter, seed);
    const Vec3d lo = s * (Vec3d(-ox, -oy, -oz) - Vec3d(0.5));
    const Vec3d hi = s * (Vec3d(nx - ox, ny - oy, nz - oz) - Vec3d(0.5));
    shape.sdf = [lo, hi](const Vec3d& p) { return boxSdf(p, lo, hi); };
    shape.truthSamples = boxSamples(lo, hi, s / 8.0);
    shape.trueVolume = double(shape.particles.size()) * s * s * s;
    return shape;
}

} // namespace detail

/// Box of n³ particles: flat faces, sharp edges and corners.
inline Shape makeBox(int n, double s = 1.0, double jitter = 0.1, unsigned seed = 11)
{
    const std::string d = std::to_string(n);
    return detail::boxShape("box", d + "×" + d + "×" + d + " particles", n, n, n, s, jitter, seed);
}

/// Slab two particles thick, n × n across: a thin sheet.
inline Shape makeSlab(int n, double s = 1.0, double jitter = 0.1, unsigned seed = 12)
{
    const std::string d = std::to_string(n);
    return detail::boxShape("slab", d + "×" + d + "×2 particles", n, n, 2, s, jitter, seed);
}

/// Jet: a cylinder three particles across (3×3 cross-section; on a cubic lattice its grown
/// shape is a 3s × 3s square prism) and @a length particles long: a thin jet.
inline Shape makeJet(int length, double s = 1.0, double jitter = 0.1, unsigned seed = 13)
{
    return detail::boxShape("jet", "3×3×" + std::to_string(length) + " particles", 3, 3, length, s, jitter,
                            seed);
}

/// Ball: the lattice points within @a radius·s of the origin. Its true surface is the sphere
/// of volume N·s³ (radius ∛(3N/4π)·s), about s/2 outside the outer particles.
inline Shape makeBall(double radius, double s = 1.0, double jitter = 0.1, unsigned seed = 14)
{
    Shape shape;
    shape.name = "ball";
    shape.spacing = s;
    const int reach = int(std::ceil(radius)) + 1;
    const double r2 = radius * radius;
    shape.particles = detail::lattice(s, reach, [=](int i, int j, int k) {
        return double(i * i + j * j + k * k) <= r2;
    }, jitter, seed);
    const double n = double(shape.particles.size());
    const double trueRadius = std::cbrt(3.0 * n / (4.0 * M_PI)) * s;
    char text[96];
    std::snprintf(text, sizeof(text), "%zu particles within %.1f s, sphere of radius %.2f s",
                  shape.particles.size(), radius, trueRadius / s);
    shape.description = text;
    shape.sdf = [trueRadius](const Vec3d& p) { return p.length() - trueRadius; };
    // Fibonacci sphere: about one point per (s/8)² of area.
    const double area = 4.0 * M_PI * trueRadius * trueRadius;
    const int count = int(std::ceil(area / (s * s / 64.0)));
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
        const double z = 1.0 - 2.0 * (i + 0.5) / count;
        const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
        shape.truthSamples.emplace_back(trueRadius * rho * std::cos(golden * i),
                                        trueRadius * rho * std::sin(golden * i), trueRadius * z);
    }
    shape.trueVolume = n * s * s * s;
    return shape;
}

// ------------------------------------------------------------------------------------------
// Distances

/// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
inline Vec3d closestOnTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c)
{
    const Vec3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
    const Vec3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
    }
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

/// The mesh's triangles (quads split), in double precision.
inline std::vector<std::array<Vec3d, 3>> triangles(const nonbloppy::SurfaceMesh& mesh)
{
    std::vector<std::array<Vec3d, 3>> out;
    out.reserve(mesh.triangleCount());
    auto at = [&](unsigned i) { return Vec3d(mesh.points[i]); };
    for (const auto& t : mesh.triangles) out.push_back({at(t[0]), at(t[1]), at(t[2])});
    for (const auto& q : mesh.quads) {
        out.push_back({at(q[0]), at(q[1]), at(q[2])});
        out.push_back({at(q[0]), at(q[2]), at(q[3])});
    }
    return out;
}

/// Exact unsigned distance from points to a triangle soup: triangles are binned into cubic
/// cells by their bounding boxes, and a query visits shells of cells outwards until no
/// unvisited cell can hold anything closer than the best triangle found.
class TriangleDistance
{
public:
    TriangleDistance(std::vector<std::array<Vec3d, 3>> tris, double cellSize)
        : mTris(std::move(tris)), mCell(cellSize)
    {
        for (size_t t = 0; t < mTris.size(); ++t) {
            openvdb::Coord lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
            for (const Vec3d& v : mTris[t]) {
                lo.minComponent(cellOf(v));
                hi.maxComponent(cellOf(v));
            }
            for (int i = lo[0]; i <= hi[0]; ++i)
                for (int j = lo[1]; j <= hi[1]; ++j)
                    for (int k = lo[2]; k <= hi[2]; ++k) mBins[key(openvdb::Coord(i, j, k))].push_back(t);
        }
    }

    /// Distance from @a p to the nearest triangle; +inf beyond @a maxDistance (or no triangles).
    double operator()(const Vec3d& p, double maxDistance) const
    {
        const openvdb::Coord c = cellOf(p);
        double best2 = std::numeric_limits<double>::infinity();
        const int maxRing = int(std::ceil(maxDistance / mCell)) + 1;
        for (int ring = 0; ring <= maxRing; ++ring) {
            // Cells of this ring are at least (ring − 1)·cell away from p.
            const double reach = std::max(0, ring - 1) * mCell;
            if (reach * reach > best2) break;
            for (int i = -ring; i <= ring; ++i)
                for (int j = -ring; j <= ring; ++j)
                    for (int k = -ring; k <= ring; ++k) {
                        if (std::max({std::abs(i), std::abs(j), std::abs(k)}) != ring) continue;
                        auto found = mBins.find(key(c.offsetBy(i, j, k)));
                        if (found == mBins.end()) continue;
                        for (size_t t : found->second) {
                            const auto& tri = mTris[t];
                            best2 = std::min(best2, (closestOnTriangle(p, tri[0], tri[1], tri[2]) - p).lengthSqr());
                        }
                    }
        }
        return std::sqrt(best2);
    }

private:
    openvdb::Coord cellOf(const Vec3d& p) const
    {
        return openvdb::Coord(int(std::floor(p[0] / mCell)), int(std::floor(p[1] / mCell)),
                              int(std::floor(p[2] / mCell)));
    }
    static uint64_t key(const openvdb::Coord& c)
    {
        return (uint64_t(uint32_t(c[0] + (1 << 20))) << 42) | (uint64_t(uint32_t(c[1] + (1 << 20))) << 21) |
               uint64_t(uint32_t(c[2] + (1 << 20)));
    }

    std::vector<std::array<Vec3d, 3>> mTris;
    double mCell;
    std::unordered_map<uint64_t, std::vector<size_t>> mBins;
};

/// How far a mesh lies from a shape's true surface, in units of s.
struct Fidelity
{
    double meanDistance = 0;    ///< area-weighted mean |sdf| over vertices and face samples
    double p95Distance = 0;     ///< its area-weighted 95th percentile
    double maxDistance = 0;     ///< largest |sdf| of any sample
    double truthP95 = 0;        ///< 95th percentile of true surface → mesh distance
    double truthMax = 0;        ///< largest true surface → mesh distance
    double volumeError = 0;     ///< (mesh volume − N·s³) / N·s³
    bool closed = false;        ///< measureMesh(): no boundary edges
    bool manifold = false;      ///< measureMesh(): two consistently oriented faces per edge
    size_t triangles = 0;       ///< triangles after splitting quads
};

namespace detail {

/// Smallest value whose cumulative weight reaches @a q of the total.
inline double weightedQuantile(std::vector<std::pair<double, double>> valueWeight, double q)
{
    if (valueWeight.empty()) return std::numeric_limits<double>::infinity();
    std::sort(valueWeight.begin(), valueWeight.end());
    double total = 0;
    for (const auto& vw : valueWeight) total += vw.second;
    double sum = 0;
    for (const auto& vw : valueWeight) {
        sum += vw.second;
        if (sum >= q * total) return vw.first;
    }
    return valueWeight.back().first;
}

} // namespace detail

/// Measure @a mesh against @a shape.
/// Mesh → truth: |sdf| at every vertex (weight: a third of its triangles' area) and at the
/// centroids of the four sub-triangles of every triangle (weight: a quarter of its area).
/// Truth → mesh: exact point–triangle distance (TriangleDistance) from every truth sample;
/// a sample farther than 4 s from any triangle counts as +inf (a hole or a missing part).
inline Fidelity measureFidelity(const nonbloppy::SurfaceMesh& mesh, const Shape& shape)
{
    Fidelity f;
    const double s = shape.spacing;
    const nonbloppy::MeshMeasures measures = nonbloppy::measureMesh(mesh);
    f.closed = measures.closed;
    f.manifold = measures.manifold;
    f.volumeError = (measures.volume - shape.trueVolume) / shape.trueVolume;
    const auto tris = triangles(mesh);
    f.triangles = tris.size();

    std::vector<std::pair<double, double>> samples;
    std::vector<double> vertexWeight(mesh.points.size(), 0.0);
    samples.reserve(5 * tris.size());
    for (const auto& t : tris) {
        const double area = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        // Centroids of the 4 sub-triangles of the midpoint subdivision.
        const Vec3d m01 = 0.5 * (t[0] + t[1]), m12 = 0.5 * (t[1] + t[2]), m20 = 0.5 * (t[2] + t[0]);
        const Vec3d centres[4] = {(t[0] + m01 + m20) / 3.0, (t[1] + m12 + m01) / 3.0,
                                  (t[2] + m20 + m12) / 3.0, (m01 + m12 + m20) / 3.0};
        for (const Vec3d& c : centres) samples.emplace_back(std::abs(shape.sdf(c)) / s, 0.25 * area);
    }
    auto addVertexWeight = [&](unsigned a, unsigned b, unsigned c) {
        const Vec3d pa(mesh.points[a]), pb(mesh.points[b]), pc(mesh.points[c]);
        const double third = (pb - pa).cross(pc - pa).length() / 6.0;
        vertexWeight[a] += third;
        vertexWeight[b] += third;
        vertexWeight[c] += third;
    };
    for (const auto& t : mesh.triangles) addVertexWeight(t[0], t[1], t[2]);
    for (const auto& q : mesh.quads) {
        addVertexWeight(q[0], q[1], q[2]);
        addVertexWeight(q[0], q[2], q[3]);
    }
    for (size_t i = 0; i < mesh.points.size(); ++i) {
        samples.emplace_back(std::abs(shape.sdf(Vec3d(mesh.points[i]))) / s, vertexWeight[i]);
    }
    double sum = 0, weight = 0;
    for (const auto& vw : samples) {
        sum += vw.first * vw.second;
        weight += vw.second;
        f.maxDistance = std::max(f.maxDistance, vw.first);
    }
    f.meanDistance = weight > 0 ? sum / weight : std::numeric_limits<double>::infinity();
    f.p95Distance = detail::weightedQuantile(std::move(samples), 0.95);

    const TriangleDistance distance(tris, s);
    std::vector<double> truth(shape.truthSamples.size());
    for (size_t i = 0; i < truth.size(); ++i) truth[i] = distance(shape.truthSamples[i], 4.0 * s) / s;
    std::vector<double> sorted = truth;
    std::sort(sorted.begin(), sorted.end());
    f.truthMax = sorted.empty() ? std::numeric_limits<double>::infinity() : sorted.back();
    f.truthP95 = sorted.empty() ? std::numeric_limits<double>::infinity()
                                : sorted[std::min(sorted.size() - 1, size_t(std::ceil(0.95 * sorted.size())) - 1)];
    return f;
}

} // namespace nonbloppy_fidelity

#endif // NONBLOPPY_FIDELITY_SHAPES_H
