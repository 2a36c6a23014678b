// SPDX-License-Identifier: Apache-2.0
// cropParticles(): the particles inside a box, in their order, with their attributes.
#include "TestUtil.h"

#include <nonbloppy/CropParticles.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

namespace {

using nonbloppy::cropParticles;
using openvdb::BBoxd;
using openvdb::Vec3d;

std::string errorOf(const BBoxd& box)
{
    try {
        cropParticles(nonbloppy::ParticleSet(), box);
    } catch (const nonbloppy::ParameterError& e) {
        return e.what();
    }
    return "";
}

TEST(CropParticles, KeepsTheParticlesInsideTheBoxInTheirOrderWithTheirAttributes)
{
    // The real dam-break frame cut at x = 0: every particle with x <= 0 is kept, in file
    // order, each with its own id (the ids count the particles in file order) and velocity.
    const nonbloppy::ParticleSet frame =
        nonbloppy::readParticles(nonbloppy_test::dataPath("dam_break_frame_23_24389_particles.vtk"));
    const BBoxd half(Vec3d(-10.0, -10.0, -10.0), Vec3d(0.0, 10.0, 10.0));
    const nonbloppy::ParticleSet cropped = cropParticles(frame, half);
    size_t expected = 0;
    const nonbloppy::ParticleAttribute* ids = frame.findAttribute("id");
    const nonbloppy::ParticleAttribute* velocities = frame.findAttribute("velocity");
    ASSERT_TRUE(ids && velocities);
    const nonbloppy::ParticleAttribute* keptIds = cropped.findAttribute("id");
    const nonbloppy::ParticleAttribute* keptVelocities = cropped.findAttribute("velocity");
    ASSERT_TRUE(keptIds && keptVelocities);
    EXPECT_EQ(keptIds->type, ids->type);
    EXPECT_EQ(keptVelocities->components, 3);
    for (size_t n = 0; n < frame.size(); ++n) {
        if (!(frame.positions[n].x() <= 0.0f)) continue;
        ASSERT_LT(expected, cropped.size());
        EXPECT_EQ(cropped.positions[expected], frame.positions[n]);
        EXPECT_EQ(keptIds->asDouble(expected), ids->asDouble(n));
        for (int c = 0; c < 3; ++c) EXPECT_EQ(keptVelocities->asDouble(expected, c), velocities->asDouble(n, c));
        ++expected;
    }
    EXPECT_EQ(cropped.size(), expected);
    EXPECT_GT(expected, 1000u);
    EXPECT_LT(expected, frame.size() - 1000);
    EXPECT_EQ(keptIds->size(), expected);
    // A box around everything keeps the frame as it is.
    const nonbloppy::ParticleSet all = cropParticles(frame, BBoxd(Vec3d(-1e30), Vec3d(1e30)));
    EXPECT_EQ(all.positions, frame.positions);
    EXPECT_EQ(all.attributes[0].bytes, frame.attributes[0].bytes);
    EXPECT_EQ(all.attributes[1].bytes, frame.attributes[1].bytes);
}

TEST(CropParticles, TheBoxsFacesAreInsideAndNanIsNowhere)
{
    nonbloppy::ParticleSet particles;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    particles.positions = {{0, 0, 0}, {1, 1, 1}, {1.0000001f, 0.5f, 0.5f}, {nan, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}};
    particles.skipped = {"unnamed column 1"};
    const nonbloppy::ParticleSet cropped = cropParticles(particles, BBoxd(Vec3d(0.0), Vec3d(1.0)));
    EXPECT_EQ(cropped.positions, (std::vector<openvdb::Vec3f>{{0, 0, 0}, {1, 1, 1}, {0.5f, 0.5f, 0.5f}}));
    EXPECT_EQ(cropped.skipped, particles.skipped);
    // A box of zero extent keeps what lies on it; none inside is an empty set, not an error.
    EXPECT_EQ(cropParticles(particles, BBoxd(Vec3d(1.0), Vec3d(1.0))).size(), 1u);
    EXPECT_EQ(cropParticles(particles, BBoxd(Vec3d(2.0), Vec3d(3.0))).size(), 0u);
}

TEST(CropParticles, TheSameParticlesAtAnyThreadCount)
{
    // More particles than four blocks (65,536 each), so that blocks are counted and copied apart.
    constexpr size_t kBlock = 65536;
    nonbloppy::ParticleSet particles;
    std::vector<int32_t> ids;
    for (int n = 0; n < 300000; ++n) {
        particles.positions.emplace_back(float(n % 97), float(n % 89), float(n % 83));
        ids.push_back(n);
    }
    particles.attributes.push_back(nonbloppy::ParticleAttribute::of("id", 1, ids));
    const BBoxd box(Vec3d(10.0, 20.0, 0.0), Vec3d(60.0, 50.0, 41.5));
    nonbloppy::ParticleSet one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = cropParticles(particles, box);
    }
    const nonbloppy::ParticleSet many = cropParticles(particles, box);
    EXPECT_EQ(one.positions, many.positions);
    EXPECT_EQ(one.attributes[0].bytes, many.attributes[0].bytes);
    // And the ids kept rise: the order is the input's.
    for (size_t n = 1; n < many.size(); ++n) ASSERT_LT(many.attributes[0].asDouble(n - 1), many.attributes[0].asDouble(n));
    size_t inside = 0;
    for (const openvdb::Vec3f& p : particles.positions) {
        inside += p.x() >= 10 && p.x() <= 60 && p.y() >= 20 && p.y() <= 50 && p.z() <= 41.5f;
    }
    EXPECT_EQ(many.size(), inside);
    EXPECT_GT(particles.size(), 4 * kBlock);
}

TEST(CropParticles, BadBoxesAreRefusedNamingTheBound)
{
    EXPECT_EQ(errorOf(BBoxd(Vec3d(0.0, 2.0, 0.0), Vec3d(1.0, 1.0, 1.0))),
              "particle box: its minimum y 2 exceeds its maximum 1");
    EXPECT_EQ(errorOf(BBoxd(Vec3d(0.0, 0.0, 1.0000001), Vec3d(1.0, 1.0, 1.0))),
              "particle box: its minimum z 1.0000001 exceeds its maximum 1");
    EXPECT_EQ(errorOf(BBoxd(Vec3d(std::nan(""), 0.0, 0.0), Vec3d(1.0))),
              "particle box: its minimum x is nan, not a finite number");
    EXPECT_EQ(errorOf(BBoxd(Vec3d(0.0), Vec3d(1.0, INFINITY, 1.0))),
              "particle box: its maximum y is inf, not a finite number");
    EXPECT_EQ(errorOf(BBoxd(Vec3d(0.0), Vec3d(1.0))), "");
    // An attribute that does not hold one value per particle, as writeParticles() refuses it:
    // too few values, a stray byte past the last value, no components.
    nonbloppy::ParticleSet particles;
    particles.positions = {{0, 0, 0}, {1, 1, 1}};
    const auto cropError = [&](const nonbloppy::ParticleAttribute& attribute) {
        particles.attributes = {attribute};
        try {
            cropParticles(particles, BBoxd(Vec3d(0.0), Vec3d(1.0)));
        } catch (const nonbloppy::ParameterError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_EQ(cropError(nonbloppy::ParticleAttribute::of("id", 1, std::vector<int32_t>{7})),
              "attribute 'id' does not hold one value per particle");
    nonbloppy::ParticleAttribute stray = nonbloppy::ParticleAttribute::of("id", 1, std::vector<int32_t>{7, 8});
    stray.bytes.push_back(0);
    EXPECT_EQ(cropError(stray), "attribute 'id' does not hold one value per particle");
    nonbloppy::ParticleAttribute none = nonbloppy::ParticleAttribute::of("id", 1, std::vector<int32_t>{7, 8});
    none.components = 0;
    EXPECT_EQ(cropError(none), "attribute 'id' has 0 components, at least 1 needed");
    EXPECT_EQ(cropError(nonbloppy::ParticleAttribute::of("id", 1, std::vector<int32_t>{7, 8})), "");
}

} // namespace
