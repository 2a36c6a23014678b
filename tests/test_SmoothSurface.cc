// SPDX-License-Identifier: Apache-2.0
// smoothSurface(): jitter leaves flat faces, a 90° ridge stays sharp, flat meshes stay put,
// the same bits for any thread count, and exact messages for bad settings; the exponential of
// its normal filter is within 1 ulp of e^x.

#include "../src/ExpNonPositive.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/SmoothSurface.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

using namespace nonbloppy;

namespace {

/// A height field z = height(x, y) + noise on an n×n grid of step h centred on the origin,
/// as triangles (two per cell, counter-clockwise seen from +z).
template<typename HeightT>
SurfaceMesh heightField(int n, double h, HeightT height, double noise, unsigned seed = 3)
{
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> jitter(-noise, noise);
    SurfaceMesh mesh;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const double x = (i - 0.5 * (n - 1)) * h, y = (j - 0.5 * (n - 1)) * h;
            mesh.points.emplace_back(float(x), float(y), float(height(x, y) + jitter(random)));
        }
    }
    for (int j = 0; j + 1 < n; ++j) {
        for (int i = 0; i + 1 < n; ++i) {
            const unsigned a = unsigned(j * n + i), b = a + 1, c = a + unsigned(n) + 1, d = a + unsigned(n);
            mesh.triangles.emplace_back(a, b, c);
            mesh.triangles.emplace_back(a, c, d);
        }
    }
    return mesh;
}

double roof(double x, double) { return -std::abs(x); }  // two faces meeting at 90°

/// Mean |z − roof(x)|, measured along z, over the vertices at least @a margin from the
/// grid's border (whose one-sided neighbourhoods this test does not judge), split into those
/// within @a ridgeBand of the ridge x = 0 and the rest.
struct RoofError
{
    double ridge = 0, faces = 0;
};

RoofError roofError(const SurfaceMesh& mesh, double margin, double halfWidth, double ridgeBand)
{
    double ridgeSum = 0, faceSum = 0;
    int ridgeCount = 0, faceCount = 0;
    for (const openvdb::Vec3s& p : mesh.points) {
        if (std::abs(p[0]) > halfWidth - margin || std::abs(p[1]) > halfWidth - margin) continue;
        const double error = std::abs(p[2] - roof(p[0], p[1]));
        if (std::abs(p[0]) < ridgeBand) { ridgeSum += error; ++ridgeCount; }
        else { faceSum += error; ++faceCount; }
    }
    return RoofError{ridgeSum / ridgeCount, faceSum / faceCount};
}

SmoothSettings settingsFor(double spacing)
{
    SmoothSettings settings;
    settings.spatialWidth = kDefaultSmoothWidthOverSpacing * spacing;
    return settings;
}

std::string message(SurfaceMesh mesh, const SmoothSettings& settings)
{
    try {
        smoothSurface(mesh, settings);
    } catch (const ParameterError& e) {
        return e.what();
    }
    return "(no error)";
}

} // namespace

TEST(SmoothSurface, JitteredRoofGetsFlatFacesAndKeepsItsRidge)
{
    // Grid step 0.25 as a mesh at h = s/2 for s = 0.5; jitter ±0.05 = ±0.1 s, as the fidelity
    // shapes' particles. Measured: faces 0.0245 → 0.0021, ridge band 0.0224 → 0.0031.
    const double step = 0.25, noise = 0.05;
    const int n = 41;
    const double halfWidth = 0.5 * (n - 1) * step;
    SurfaceMesh mesh = heightField(n, step, roof, noise);
    const RoofError before = roofError(mesh, 1.0, halfWidth, 0.3);
    smoothSurface(mesh, settingsFor(2 * step));
    const RoofError after = roofError(mesh, 1.0, halfWidth, 0.3);
    EXPECT_LT(after.faces, before.faces / 5) << before.faces << " -> " << after.faces;
    EXPECT_LT(after.ridge, before.ridge / 3) << before.ridge << " -> " << after.ridge;

    // Without the normal range weight (σ_r far above the 1.41 between the two faces' normals)
    // the same filter is a plain smoothing, and it rounds the ridge (measured 0.36).
    SurfaceMesh plain = heightField(n, step, roof, noise);
    SmoothSettings settings = settingsFor(2 * step);
    settings.normalWidth = 100.0;
    smoothSurface(plain, settings);
    EXPECT_GT(roofError(plain, 1.0, halfWidth, 0.3).ridge, 10 * after.ridge);
}

TEST(SmoothSurface, FlatMeshStaysWhereItIs)
{
    SurfaceMesh mesh = heightField(12, 0.25, [](double, double) { return 0.75; }, 0.0);
    const std::vector<openvdb::Vec3s> before = mesh.points;
    smoothSurface(mesh, settingsFor(0.5));
    ASSERT_EQ(mesh.points.size(), before.size());
    for (size_t i = 0; i < before.size(); ++i) {
        EXPECT_EQ(mesh.points[i][0], before[i][0]) << i;  // vertices move along normals only
        EXPECT_EQ(mesh.points[i][1], before[i][1]) << i;
        EXPECT_NEAR(mesh.points[i][2], 0.75, 1e-6) << i;
    }
}

TEST(SmoothSurface, QuadsAreFacesOfTheirOwn)
{
    // The roof as quads (each pair of triangles of heightField() merged): the same smoothing,
    // measured faces 0.0245 → 0.0019, ridge band 0.0224 → 0.0024, and the polygons untouched.
    const double step = 0.25;
    const int n = 41;
    const double halfWidth = 0.5 * (n - 1) * step;
    const SurfaceMesh triangles = heightField(n, step, roof, 0.05);
    SurfaceMesh quads = triangles;
    quads.triangles.clear();
    for (size_t t = 0; t < triangles.triangles.size(); t += 2) {
        const openvdb::Vec3I& a = triangles.triangles[t];
        quads.quads.emplace_back(a[0], a[1], a[2], triangles.triangles[t + 1][2]);
    }
    const std::vector<openvdb::Vec4I> polygons = quads.quads;
    const RoofError before = roofError(quads, 1.0, halfWidth, 0.3);
    smoothSurface(quads, settingsFor(2 * step));
    const RoofError after = roofError(quads, 1.0, halfWidth, 0.3);
    EXPECT_LT(after.faces, before.faces / 5) << before.faces << " -> " << after.faces;
    EXPECT_LT(after.ridge, before.ridge / 3) << before.ridge << " -> " << after.ridge;
    EXPECT_EQ(quads.quads, polygons);
    EXPECT_TRUE(quads.triangles.empty());
}

TEST(SmoothSurface, SameBitsForAnyThreadCount)
{
    const SurfaceMesh input = heightField(60, 0.25, roof, 0.05);
    SurfaceMesh one = input, two = input;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        smoothSurface(one, settingsFor(0.5));
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        smoothSurface(two, settingsFor(0.5));
    }
    EXPECT_EQ(one.points, two.points);
    EXPECT_NE(one.points, input.points);
}

TEST(SmoothSurface, ZeroRoundsAndEmptyMeshesAreLeftAsTheyAre)
{
    const SurfaceMesh input = heightField(6, 0.25, roof, 0.05);
    SmoothSettings settings = settingsFor(0.5);
    settings.normalRounds = 0;
    SurfaceMesh mesh = input;
    smoothSurface(mesh, settings);
    EXPECT_EQ(mesh.points, input.points);
    SurfaceMesh empty;
    smoothSurface(empty, settingsFor(0.5));
    EXPECT_TRUE(empty.points.empty());
}

TEST(SmoothSurface, BadSettingsNameThemselves)
{
    const SurfaceMesh mesh = heightField(4, 0.25, roof, 0.0);
    SmoothSettings settings;  // spatialWidth has no default: it is a length
    EXPECT_EQ(message(mesh, settings), "smoothing width must be > 0, got 0");
    settings = settingsFor(0.5);
    settings.normalWidth = -1;
    EXPECT_EQ(message(mesh, settings), "smoothing normal width must be > 0, got -1");
    settings = settingsFor(0.5);
    settings.vertexRounds = -2;
    EXPECT_EQ(message(mesh, settings), "smoothing rounds must be >= 0, got 35 normal and -2 vertex rounds");
}

TEST(SmoothSurface, ExponentialIsWithinOneUlpOfTheTrueOne)
{
    using exp_internal::expNonPositive;
    // The distance in floats between expNonPositive(x) and e^x rounded to float, which double
    // precision gives exactly here (its error is 2^-29 float ulp).
    const auto ulpsOff = [](float x) {
        const float got = expNonPositive(x), want = float(std::exp(double(x)));
        int32_t a, b;
        std::memcpy(&a, &got, sizeof(float));
        std::memcpy(&b, &want, sizeof(float));
        return std::abs(int64_t(a) - int64_t(b));
    };
    int64_t worst = 0;
    float worstAt = 0.0f;
    // Every 7th float in [-1, -2^-24] (where |r| is smallest and the last bits count most),
    // and 2^22 steps across the whole range.
    uint32_t from, to;
    const float minusOne = -1.0f, tiny = -0x1p-24f;
    std::memcpy(&from, &tiny, sizeof(float));
    std::memcpy(&to, &minusOne, sizeof(float));
    for (uint32_t bits = from; bits <= to; bits += 7) {
        float x;
        std::memcpy(&x, &bits, sizeof(float));
        const int64_t off = ulpsOff(x);
        if (off > worst) worst = off, worstAt = x;
    }
    for (int i = 0; i <= (1 << 22); ++i) {
        const float x = exp_internal::kExpLowest * float(i) / float(1 << 22);
        const int64_t off = ulpsOff(x);
        if (off > worst) worst = off, worstAt = x;
    }
    EXPECT_LE(worst, 1) << "at x = " << worstAt;
    EXPECT_EQ(expNonPositive(0.0f), 1.0f);
    EXPECT_EQ(expNonPositive(-0.0f), 1.0f);
    EXPECT_EQ(expNonPositive(-1.0f), float(std::exp(-1.0)));
    // Below the smallest normal result: +0; NaN stays NaN.
    EXPECT_EQ(expNonPositive(-88.0f), 0.0f);
    EXPECT_EQ(expNonPositive(-std::numeric_limits<float>::infinity()), 0.0f);
    EXPECT_TRUE(std::isnan(expNonPositive(std::numeric_limits<float>::quiet_NaN())));
    EXPECT_GT(expNonPositive(-87.3f), 0.0f);
}
