// SPDX-License-Identifier: Apache-2.0
#include "TestUtil.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/EstimateParameters.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>

using namespace nonbloppy;
using nonbloppy_test::latticeParticles;

TEST(EstimateParameters, SpacingOfALatticeIsItsStep)
{
    // The count of neighbours is smooth, not exact, on a lattice: measured 0.32% low.
    const auto ball = latticeParticles(0.05, 0.6, [](const openvdb::Vec3d& x) { return x.length() < 0.5; });
    EXPECT_NEAR(estimateSpacing(ball), 0.05, 0.005 * 0.05);
    // Median over a sample, so a few far-away strays do not matter.
    auto withStrays = ball;
    for (int i = 0; i < 20; ++i) withStrays.emplace_back(10.0f + float(i), 0.0f, 0.0f);
    EXPECT_NEAR(estimateSpacing(withStrays), 0.05, 0.005 * 0.05);
}

TEST(EstimateParameters, AnInfiniteCoordinateIsNamedAsSuch)
{
    // It was "particle index cell size must be > 0, got inf", or, with three particles, "all
    // particles are at the same position".
    for (const size_t count : {size_t(3), size_t(10)}) {
        std::vector<openvdb::Vec3f> positions = latticeParticles(0.1, 1.0, [](const openvdb::Vec3d&) { return true; });
        positions.resize(count);
        positions[1][0] = -std::numeric_limits<float>::infinity();
        const std::string message = "non-finite position of particle 1";
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { estimateSpacing(positions); }), message);
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { buildSurface(positions); }), message);
    }
}

TEST(EstimateParameters, TheFirstOfSeveralNonFinitePositionsIsNamed)
{
    // The spacing's first guess scans the positions in parallel pieces: the first bad one
    // is named wherever the pieces start, as the serial loop did.
    std::vector<openvdb::Vec3f> many(200000);
    for (size_t n = 0; n < many.size(); ++n) many[n] = openvdb::Vec3f(float(n % 100), float(n / 100 % 100), float(n / 10000));
    for (size_t n : {size_t(199999), size_t(150000), size_t(64123), size_t(100001)}) {
        many[n][n % 3] = n % 2 ? std::nanf("") : -std::numeric_limits<float>::infinity();
    }
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { estimateSpacing(many); }),
              "non-finite position of particle 64123");
}

TEST(EstimateParameters, LengthsWhoseSquareOverflowsAFloatAreRefused)
{
    // Scaled by 1e20, a lattice gave a mesh of 2.6% of its volume (r_e² = inf in float); by
    // 1e25, none. Up to 1e17 the mesh is the same as at scale 1.
    const auto lattice = [](double scale) {
        std::vector<openvdb::Vec3f> positions =
            latticeParticles(1.0, 5.0, [](const openvdb::Vec3d&) { return true; }, /*jitter=*/0.0);
        for (openvdb::Vec3f& p : positions) p *= float(scale);
        return positions;
    };
    const size_t polygons = buildSurface(lattice(1.0)).mesh.polygonCount();
    ASSERT_GT(polygons, 1000u);
    EXPECT_EQ(buildSurface(lattice(1e17)).mesh.polygonCount(), polygons);
    SurfaceParameters params;
    params.spacing = 1e20;
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { buildSurface(lattice(1e20), params); }),
              "--spacing 1e+20: the radius 2 s = 2e+20 is too large: at most 1e+18 (lengths are squared in single "
              "precision); give the positions in a larger unit");
}

TEST(EstimateParameters, SpacingOfAJitteredLatticeIsItsStep)
{
    // Jitter brings nearest neighbours closer (median 0.9 s) but keeps the volume per particle.
    const auto box = latticeParticles(0.1, 1.0, [](const openvdb::Vec3d&) { return true; }, 0.1);
    EXPECT_NEAR(estimateSpacing(box), 0.1, 0.01 * 0.1);
}

TEST(EstimateParameters, SpacingOfASheetIsTheNearestNeighbourDistance)
{
    // Two layers: no particle is surrounded, so the median nearest-neighbour distance it is.
    const auto sheet = latticeParticles(0.1, 1.0, [](const openvdb::Vec3d& x) { return x[2] > -0.05 && x[2] < 0.15; }, 0.1);
    const double spacing = estimateSpacing(sheet);
    EXPECT_GT(spacing, 0.085);
    EXPECT_LT(spacing, 0.095);
}

TEST(EstimateParameters, SpacingOfAFlatSheetAndOfALineIsTheirStep)
{
    // Exactly flat (or straight): the bounding box has no volume (or area), so the first
    // guess comes from the area (or length) per particle.
    std::vector<openvdb::Vec3f> sheet, line;
    for (int i = 0; i < 60; ++i) {
        for (int j = 0; j < 60; ++j) sheet.emplace_back(0.05f * float(i), 0.05f * float(j), 1.0f);
        line.emplace_back(2.0f, 0.05f * float(i), 1.0f);
    }
    EXPECT_NEAR(estimateSpacing(sheet), 0.05, 1e-6);
    EXPECT_NEAR(estimateSpacing(line), 0.05, 1e-6);
}

TEST(EstimateParameters, SpacingOfMicrometreParticlesIsEstimatedOnCellsOpenVdbAccepts)
{
    // A lattice spaced 1 µm, in metres: its first guess (1e-6) is below OpenVDB's smallest
    // cell, so the estimate's index uses that smallest cell; the spacing is still found.
    const auto box = latticeParticles(1e-6, 1e-5, [](const openvdb::Vec3d&) { return true; });
    EXPECT_NEAR(estimateSpacing(box), 1e-6, 0.005 * 1e-6);  // the smooth count: within 0.5% on lattices
}

TEST(EstimateParameters, SpacingOfSplishSplashFramesIsTheirVolumePerParticle)
{
    // SPlisHSPlasH gives each particle of radius r the volume 0.8·(2r)³: s = 0.0464 for
    // r = 0.025; the median nearest-neighbour distance of these frames is 0.0393 and 0.0437.
    for (const char* name : {"dam_break_frame_23_24389_particles.vtk", "bunny_frame_14_7705_particles.vtk"}) {
        const ParticleSet frame = readParticles(nonbloppy_test::dataPath(name));
        EXPECT_NEAR(estimateSpacing(frame.positions), 0.0464, 0.0008) << name;
    }
    // Scattered particles have no inside: their nearest-neighbour distance, not their spread.
    const ParticleSet spray = readParticles(nonbloppy_test::dataPath("free_particles_125_particles.vtk"));
    EXPECT_NEAR(estimateSpacing(spray.positions), 0.795, 0.001);
}

TEST(EstimateParameters, SpacingNeedsTwoDistinctParticles)
{
    try {
        estimateSpacing({openvdb::Vec3f(1.0f)});
        FAIL() << "one particle accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "cannot estimate the particle spacing from 1 particle; give --spacing or "
                               "--radius, --threshold and --voxel-size");
    }
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([] { estimateSpacing({}); }),
              "cannot estimate the particle spacing from no particles; give --spacing or --radius, --threshold and "
              "--voxel-size");
    const std::vector<openvdb::Vec3f> onePlace(5, openvdb::Vec3f(1.0f));
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { estimateSpacing(onePlace); }),
              "cannot estimate the particle spacing: all particles are at the same position");
}

TEST(EstimateParameters, SpacingOfParticlesStackedInThreesIsRefused)
{
    // Distinct positions, but each one three times: every nearest neighbour is at distance 0.
    std::vector<openvdb::Vec3f> stacked;
    for (const openvdb::Vec3f& p : latticeParticles(0.1, 0.5, [](const openvdb::Vec3d&) { return true; })) {
        stacked.insert(stacked.end(), 3, p);
    }
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { estimateSpacing(stacked); }),
              "cannot estimate the particle spacing: most particles sit on top of another one; give --spacing");
}

TEST(EstimateParameters, CalibratedThresholdPutsAFlatSurfaceHalfASpacingOutside)
{
    // A slab 8 layers thick, wide enough that its middle is flat; top layer at z = 0.
    const double spacing = 0.1;
    auto slab = latticeParticles(spacing, 1.6, [](const openvdb::Vec3d& x) {
        return std::abs(x[0]) <= 1.5 && std::abs(x[1]) <= 1.5 && x[2] <= 1e-9 && x[2] >= -0.75;
    });
    SurfaceParameters params;
    params.iterations = 0;
    const SurfaceResult result = buildSurface(slab, params);
    EXPECT_NEAR(result.parameters.spacing, spacing, 0.005 * spacing);
    EXPECT_DOUBLE_EQ(result.parameters.effectiveRadius, 2 * result.parameters.spacing);
    EXPECT_DOUBLE_EQ(result.parameters.voxelSize, result.parameters.spacing / 2);
    EXPECT_DOUBLE_EQ(result.parameters.threshold, calibrateThreshold(2.0));
    const auto [meanHeight, count] = nonbloppy_test::meanTopHeight(result.mesh.points);
    ASSERT_GT(count, 50);
    // The calibration lands the flat top within 0.0001 s of s/2 (measured).
    EXPECT_NEAR(meanHeight, spacing / 2, 0.005 * spacing);
}

TEST(EstimateParameters, ThresholdGrowsWithTheRadius)
{
    EXPECT_GT(calibrateThreshold(3.0), calibrateThreshold(2.0));
    EXPECT_GT(calibrateThreshold(2.0), 0.0);
    for (const auto& [ratioGiven, spelled] : {std::pair<double, const char*>{0.5, "0.5"}, {0.4, "0.4"}}) {
        const double ratio = ratioGiven;  // C++17 lambdas cannot capture a structured binding
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { calibrateThreshold(ratio); }),
                  std::string("--radius must exceed half the particle spacing to calibrate --threshold, got ") +
                      spelled + " spacings");
    }
    const std::string tooLarge = "--radius must be at most 32 particle spacings to calibrate --threshold, got 32.5 "
                                 "spacings; give --threshold";
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([] { calibrateThreshold(32.5); }), tooLarge);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([] { calibrateRelaxedThreshold(32.5, 0.3, 2); }), tooLarge);
    // Just above half a spacing the kernel reached no sample: both returned r_0 = 0, and
    // buildSurface() meshed nothing without a word.
    for (const auto& [ratioGiven, spelled] : {std::pair<double, const char*>{0.5000001, "0.5"}, {0.501, "0.501"}}) {
        const double ratio = ratioGiven;  // as above
        const std::string message = std::string("--radius is too small to calibrate --threshold: at ") + spelled +
                                    " spacings the density where the surface belongs is 0; give a larger --radius "
                                    "or --threshold";
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { calibrateThreshold(ratio); }), message);
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { calibrateRelaxedThreshold(ratio, 0.3, 2); }),
                  message);
    }
    EXPECT_GT(calibrateThreshold(0.51), 0.0);
    EXPECT_GT(calibrateRelaxedThreshold(0.51, 0.3, 2), 0.0);
}

TEST(EstimateParameters, AnIndexOfAnyCellSizeServesTheEstimate)
{
    // resolveParametersIndexed() searches the caller's index instead of building its own:
    // the samples are spread over that index's slots, so s moves in its last digits only.
    const ParticleSet frame = readParticles(nonbloppy_test::dataPath("dam_break_frame_23_24389_particles.vtk"));
    SurfaceParameters params;
    params.effectiveRadius = 0.1;
    const ResolvedParameters own = resolveParameters(params, frame.positions);
    for (const double cellSize : {0.02, 0.05, 0.3}) {
        const ParticleIndex index = ParticleIndex::build(frame.positions, cellSize);
        const ResolvedParameters shared = resolveParametersIndexed(params, index);
        EXPECT_NEAR(shared.spacing, own.spacing, 1e-3 * own.spacing) << "cell " << cellSize;
        EXPECT_NEAR(shared.threshold, own.threshold, 3e-3 * own.threshold) << "cell " << cellSize;
        EXPECT_DOUBLE_EQ(shared.voxelSize, 0.5 * shared.spacing);
        EXPECT_DOUBLE_EQ(shared.effectiveRadius, 0.1);
    }
    // buildSurface() with r_e given indexes first (cells of r_e / 2) and estimates through
    // that index, bit for bit; its stages say so in their order.
    const SurfaceResult built = buildSurface(frame.positions, params);
    const ResolvedParameters expected =
        resolveParametersIndexed(params, ParticleIndex::build(frame.positions, 0.5 * 0.1));
    EXPECT_EQ(built.parameters.spacing, expected.spacing);
    EXPECT_EQ(built.parameters.threshold, expected.threshold);
    ASSERT_GE(built.timings.entries.size(), 2u);
    EXPECT_EQ(built.timings.entries[0].stage, "index particles");
    EXPECT_EQ(built.timings.entries[1].stage, "estimate parameters");
    // Without r_e the estimate comes first: r_e, hence the index's cells, depend on it.
    const SurfaceResult estimated = buildSurface(frame.positions, SurfaceParameters());
    EXPECT_EQ(estimated.timings.entries[0].stage, "estimate parameters");
    EXPECT_EQ(estimated.parameters.spacing, resolveParameters(SurfaceParameters(), frame.positions).spacing);
    // A bad r_e is refused by the parameter check, not by the index.
    SurfaceParameters bad;
    bad.effectiveRadius = -0.1;
    try {
        buildSurface(frame.positions, bad);
        ADD_FAILURE() << "negative radius accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "--radius must be > 0, got -0.1");
    }
}

TEST(EstimateParameters, ResolveReportsWhatWasGivenAndChecksRanges)
{
    const auto ball = latticeParticles(0.05, 0.3, [](const openvdb::Vec3d& x) { return x.length() < 0.25; });
    SurfaceParameters params;
    params.effectiveRadius = 0.2;
    const ResolvedParameters resolved = resolveParameters(params, ball);
    EXPECT_TRUE(resolved.effectiveRadiusGiven);
    EXPECT_FALSE(resolved.spacingGiven);
    EXPECT_FALSE(resolved.thresholdGiven);
    EXPECT_DOUBLE_EQ(resolved.effectiveRadius, 0.2);
    EXPECT_DOUBLE_EQ(resolved.voxelSize, 0.5 * resolved.spacing);
    EXPECT_NEAR(resolved.spacing, 0.05, 0.005 * 0.05);
    // The default (Method::Faithful) calibrates r_0 for the relaxed surface, with the steps
    // capped at s/2 as the relaxation caps them; the paper's for the blob.
    EXPECT_DOUBLE_EQ(resolved.threshold,
                     calibrateRelaxedThreshold(0.2 / resolved.spacing, kDefaultBlend, kDefaultIterations, nullptr,
                                               kDefaultMaxStepOverSpacing));
    SurfaceParameters paper = params;
    paper.method = Method::Paper;
    EXPECT_DOUBLE_EQ(resolveParameters(paper, ball).threshold, calibrateThreshold(0.2 / resolved.spacing));

    const auto expectMessage = [&](SurfaceParameters bad, const char* message) {
        try {
            resolveParameters(bad, ball);
            ADD_FAILURE() << "accepted: " << message;
        } catch (const ParameterError& e) {
            EXPECT_STREQ(e.what(), message);
        }
    };
    SurfaceParameters bad;
    bad.effectiveRadius = 0.0;
    expectMessage(bad, "--radius must be > 0, got 0");
    bad = SurfaceParameters();
    bad.voxelSize = -1.0;
    expectMessage(bad, "--voxel-size must be > 0, got -1");
    bad = SurfaceParameters();
    bad.blend = 1.5;
    expectMessage(bad, "--blend must lie in [0,1], got 1.5");
    // A value that six digits would print as the limit it broke is printed exactly (bug hunt:
    // "--blend must lie in [0,1], got 1").
    bad.blend = 1.0000001;
    expectMessage(bad, "--blend must lie in [0,1], got 1.0000001");
    bad = SurfaceParameters();
    bad.adaptivity = -1e-9;
    expectMessage(bad, "--adaptivity must lie in [0,1], got -1e-09");
    bad.adaptivity = 1.0000001;
    expectMessage(bad, "--adaptivity must lie in [0,1], got 1.0000001");
    bad = SurfaceParameters();
    bad.threshold = 3.4028236e38;
    expectMessage(bad, "--threshold must be a positive number within float's range (the density grid's values), "
                       "got 3.4028236e+38");
    bad = SurfaceParameters();
    bad.effectiveRadius = 0.1;
    bad.voxelSize = 0.1000001;
    expectMessage(bad, "--voxel-size 0.1000001 is too large for --radius 0.1: at least one voxel per radius");
    bad.effectiveRadius = 0.09999996;  // both print as 0.1 with six digits
    bad.voxelSize = 0.09999997;
    expectMessage(bad, "--voxel-size 0.09999997 is too large for --radius 0.09999996: at least one voxel per radius");
    bad = SurfaceParameters();
    bad.spacing = 0.0000299999;
    expectMessage(bad, "--spacing 2.99999e-05: the voxel size 0.5 s = 1.499995e-05 is below 1.5e-05, the smallest "
                       "OpenVDB accepts: give the positions in a smaller unit");
    bad = SurfaceParameters();
    bad.iterations = -1;
    expectMessage(bad, "--iterations must be >= 0, got -1");
    bad = SurfaceParameters();
    bad.spacing = 0.05;
    bad.voxelSize = 0.0001;
    // Lengths set by the given spacing are named as such, and checked before the particles.
    expectMessage(bad, "--spacing 0.05: --voxel-size 0.0001 is too small for the radius 2 s = 0.1: at most 32 "
                       "voxels per radius");
    // Checked before r_0 is calibrated, which at r_e = 1000 s would take hours.
    bad = SurfaceParameters();
    bad.spacing = 0.05;
    bad.effectiveRadius = 50.0;
    expectMessage(bad, "--spacing 0.05: the voxel size 0.5 s = 0.025 is too small for --radius 50: at most 32 "
                       "voxels per radius");
    // Wider than r_e: particles between voxel centres would be lost (at 64 r_e, all of them).
    SurfaceParameters wide;
    wide.spacing = 0.05;
    wide.voxelSize = 6.4;
    expectMessage(wide, "--spacing 0.05: --voxel-size 6.4 is too large for the radius 2 s = 0.1: at least one "
                        "voxel per radius");
    // The voxel size derived (s/2), the radius given: both are named.
    SurfaceParameters narrow;
    narrow.spacing = 0.05;
    narrow.effectiveRadius = 0.001;
    expectMessage(narrow, "--spacing 0.05: the voxel size 0.5 s = 0.025 is too large for --radius 0.001: at least "
                          "one voxel per radius");
    // The spacing estimated, the voxel size derived from it: named as such, with the estimate.
    narrow.spacing.reset();
    expectMessage(narrow, "--spacing 0.0498381 (estimated): the voxel size 0.5 s = 0.0249191 is too large for "
                          "--radius 0.001: at least one voxel per radius");
    wide.voxelSize = 0.1;  // one voxel per radius: accepted
    EXPECT_NO_THROW(resolveParameters(wide, ball));
    bad.voxelSize = 2.0;
    expectMessage(bad, "--radius must be at most 32 particle spacings to calibrate --threshold, got 1000 "
                       "spacings; give --threshold");
    bad.effectiveRadius = 1.65;
    bad.voxelSize = 0.06;
    expectMessage(bad, "--radius must be at most 32 particle spacings to calibrate --threshold, got 33 "
                       "spacings; give --threshold");
    bad.threshold = 1.0;  // given: nothing to calibrate, any width
    EXPECT_DOUBLE_EQ(resolveParameters(bad, ball).threshold, 1.0);
    // The volume correction's target N·s³ overflows (radius, voxel size and threshold given:
    // a spacing that large would set a radius beyond 1e18, and calibrate nothing).
    bad = SurfaceParameters();
    bad.spacing = 1e300;
    bad.effectiveRadius = 1.0;
    bad.voxelSize = 0.5;
    bad.threshold = 1.0;
    expectMessage(bad, "--spacing 1e+300 is too large: the fluid's volume N s^3 (N = 485) is not a finite number");
    // Below OpenVDB's smallest voxel and index cell (positions in metres, spacing 1 µm).
    bad = SurfaceParameters();
    bad.spacing = 1e-6;
    expectMessage(bad, "--spacing 1e-06: the voxel size 0.5 s = 5e-07 is below 1.5e-05, the smallest OpenVDB "
                       "accepts: give the positions in a smaller unit");
    bad.voxelSize = 2e-5;
    bad.effectiveRadius = 2e-5;
    expectMessage(bad, "--radius 2e-05 is below 3e-05, the smallest OpenVDB accepts: give the positions in a "
                       "smaller unit");
    try {
        resolveParameters(SurfaceParameters(), {});
        ADD_FAILURE() << "no particles accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "no particles to mesh");
    }
}

TEST(EstimateParameters, AnInfiniteStepCapResolvesToNoCap)
{
    const auto ball = latticeParticles(0.05, 0.3, [](const openvdb::Vec3d& x) { return x.length() < 0.25; });
    SurfaceParameters params;
    params.maxStep = std::numeric_limits<double>::infinity();
    const ResolvedParameters infinite = resolveParameters(params, ball);
    params.maxStep = 0.0;
    const ResolvedParameters none = resolveParameters(params, ball);
    EXPECT_EQ(infinite.maxStep, 0.0);
    EXPECT_EQ(infinite.threshold, none.threshold);
    params.maxStep = -0.5;
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { resolveParameters(params, ball); }),
              "--max-step must be >= 0 (0 or inf: no cap), got -0.5");
}

TEST(EstimateParameters, LengthsDerivedFromTheEstimateAreNamedAsSuch)
{
    // Positions in metres of a fluid with 1 µm spacing: the voxel size s/2 is below OpenVDB's
    // smallest. The message named "--voxel-size", an option never given.
    const auto tiny = latticeParticles(1e-6, 6e-6, [](const openvdb::Vec3d& x) { return x.length() < 5e-6; });
    const std::string message = nonbloppy_test::messageOf<ParameterError>(
        [&] { resolveParameters(SurfaceParameters(), tiny); });
    const double spacing = estimateSpacing(tiny);
    EXPECT_NEAR(spacing, 1e-6, 0.01e-6);
    const auto printed = [](double value) {  // as the messages print numbers
        std::ostringstream out;
        out << value;
        return out.str();
    };
    EXPECT_EQ(message, "--spacing " + printed(spacing) + " (estimated): the voxel size 0.5 s = " +
                           printed(0.5 * spacing) +
                           " is below 1.5e-05, the smallest OpenVDB accepts: give the positions in a smaller unit");
    // A given spacing and radius too far apart to calibrate the threshold: known without
    // particles, so checkParameters() refuses them; a given threshold needs no calibration.
    SurfaceParameters wide;
    wide.spacing = 0.05;
    wide.effectiveRadius = 1.65;
    wide.voxelSize = 0.06;
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { checkParameters(wide); }),
              "--radius must be at most 32 particle spacings to calibrate --threshold, got 33 spacings; give "
              "--threshold");
    wide.threshold = 1.0;
    EXPECT_NO_THROW(checkParameters(wide));
}

TEST(EstimateParameters, EnumeratorsOutOfRangeAreRefused)
{
    // An integer cast to Method ran as neither variant (the Paper mesh without the Paper
    // threshold); one cast to VolumeOffset ran as Convex.
    SurfaceParameters params;
    params.method = static_cast<Method>(7);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { checkParameters(params); }),
              "method must be Paper or Faithful, got 7");
    params.method = Method::Faithful;
    params.volumeOffset = static_cast<VolumeOffset>(-1);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { checkParameters(params); }),
              "volume offset must be Uniform or Convex, got -1");
    params.volumeOffset = VolumeOffset::Uniform;
    EXPECT_NO_THROW(checkParameters(params));
}
