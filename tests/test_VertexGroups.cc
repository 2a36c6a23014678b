// SPDX-License-Identifier: Apache-2.0
// Tests for the private vertex grouping the relaxation and the attribute interpolation share
// (src/VertexGroups.h): every vertex in reach lands in exactly one group, the group of its
// cell, in a fixed order whatever the thread count; a group's candidate particles are exactly
// those within the radius of its box, in the order gathered.

#include "../src/Cancellation.h"
#include "../src/ParticleIndexImpl.h"
#include "../src/VertexGroups.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace {

using namespace nonbloppy;
using vertex_groups_internal::groupVerticesByCell;

/// @a count points uniform in [-1, 1]^3 (fixed seed).
std::vector<openvdb::Vec3s> randomPoints(size_t count, unsigned seed)
{
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    std::vector<openvdb::Vec3s> points(count);
    for (openvdb::Vec3s& p : points) p = openvdb::Vec3s(uniform(random), uniform(random), uniform(random));
    return points;
}

struct Groups
{
    memory_internal::UnwrittenVector<uint32_t> order;
    std::vector<size_t> groupStart;
};

Groups groupsOf(const std::vector<openvdb::Vec3s>& points, double groupSize)
{
    Groups groups;
    cancellation_internal::CancelPoll poll(nullptr, "group vertices");
    groupVerticesByCell(points, groupSize, groups.order, groups.groupStart, poll);
    return groups;
}

TEST(VertexGroups, EveryVertexInTheGroupOfItsCellInCellOrder)
{
    constexpr double kGroupSize = 0.3;
    std::vector<openvdb::Vec3s> points = randomPoints(20000, 7);
    // Out of reach: NaN, infinite, and beyond 2^30 group cells; left out of every group.
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const float far = float(2.0 * double(1 << 30) * kGroupSize);
    points[5] = openvdb::Vec3s(nan, 0.0f, 0.0f);
    points[6] = openvdb::Vec3s(0.0f, -inf, 0.0f);
    points[7] = openvdb::Vec3s(0.0f, 0.0f, far);
    const Groups groups = groupsOf(points, kGroupSize);

    ASSERT_EQ(groups.order.size(), points.size() - 3);
    ASSERT_EQ(groups.groupStart.front(), 0u);
    ASSERT_EQ(groups.groupStart.back(), groups.order.size());
    std::vector<int> seen(points.size(), 0);
    openvdb::Coord previousCell;
    for (size_t g = 0; g + 1 < groups.groupStart.size(); ++g) {
        const size_t begin = groups.groupStart[g], end = groups.groupStart[g + 1];
        ASSERT_LT(begin, end) << "group " << g << " is empty";
        const openvdb::Coord cell = particle_index_internal::cellOf(openvdb::Vec3d(points[groups.order[begin]]), kGroupSize);
        if (g > 0) ASSERT_LT(previousCell, cell) << "groups in cell order, one per cell";
        previousCell = cell;
        for (size_t n = begin; n < end; ++n) {
            const uint32_t vertex = groups.order[n];
            ++seen[vertex];
            EXPECT_EQ(particle_index_internal::cellOf(openvdb::Vec3d(points[vertex]), kGroupSize), cell);
            if (n > begin) EXPECT_LT(groups.order[n - 1], vertex) << "a group's vertices in vertex order";
        }
    }
    for (size_t i = 0; i < points.size(); ++i) EXPECT_EQ(seen[i], (i >= 5 && i <= 7) ? 0 : 1) << "vertex " << i;
}

TEST(VertexGroups, SameGroupsForAnyThreadCount)
{
    // Enough vertices for the radix sort's chunks to be cut differently by the threads.
    const std::vector<openvdb::Vec3s> points = randomPoints(300000, 11);
    Groups one;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = groupsOf(points, 0.05);
    }
    const Groups many = groupsOf(points, 0.05);
    EXPECT_TRUE(one.order == many.order);
    EXPECT_TRUE(one.groupStart == many.groupStart);
    EXPECT_GT(one.groupStart.size(), 10000u);
}

TEST(VertexGroups, CandidatesAreTheParticlesWithinTheRadiusOfTheBox)
{
    const std::vector<openvdb::Vec3s> particles = randomPoints(5000, 3);
    const openvdb::Vec3f boxMin(-0.2f, 0.1f, -0.05f), boxMax(0.1f, 0.3f, 0.0f);
    constexpr float kRadius = 0.25f;
    vertex_groups_internal::GroupCandidates<4, /*kWithSlots=*/true> candidates;
    // Two runs of slots, as the particle index hands them over; a third is empty.
    candidates.gather(particles, 0, 3000, boxMin, boxMax, kRadius * kRadius);
    candidates.gather(particles, 3000, 3000, boxMin, boxMax, kRadius * kRadius);
    candidates.gather(particles, 3000, 5000, boxMin, boxMax, kRadius * kRadius);
    const size_t kept = candidates.count;
    std::vector<uint32_t> expected;
    size_t borderline = 0;
    for (uint32_t k = 0; k < particles.size(); ++k) {
        openvdb::Vec3d outside(0.0);
        for (int a = 0; a < 3; ++a) {
            const double p = particles[k][a];
            outside[a] = std::max({0.0, double(boxMin[a]) - p, p - double(boxMax[a])});
        }
        const double distance = outside.length();
        borderline += std::abs(distance - kRadius) < 1e-6;
        if (distance < kRadius) expected.push_back(k);
    }
    ASSERT_EQ(borderline, 0u) << "a particle too near the radius for a double reference";
    ASSERT_EQ(kept, expected.size());
    EXPECT_GT(kept, 100u);
    EXPECT_LT(kept, particles.size() / 2);
    for (size_t n = 0; n < kept; ++n) {
        const uint32_t k = expected[n];
        ASSERT_EQ(candidates.slots[n], k) << "candidate " << n;
        EXPECT_EQ(candidates.x[n], particles[k][0]);
        EXPECT_EQ(candidates.y[n], particles[k][1]);
        EXPECT_EQ(candidates.z[n], particles[k][2]);
    }
    // Padding to whole lanes with a position beyond the radius of every point of the box.
    candidates.pad(boxMax[0] + 4.0f * kRadius);
    EXPECT_EQ(candidates.count % 4, 0u);
    EXPECT_LT(candidates.count, kept + 4);
    for (size_t n = kept; n < candidates.count; ++n) {
        const openvdb::Vec3f padding(candidates.x[n], candidates.y[n], candidates.z[n]);
        EXPECT_GT((padding - boxMax).length(), kRadius);
        EXPECT_GT((padding - boxMin).length(), kRadius);
    }
    candidates.clear();
    EXPECT_EQ(candidates.count, 0u);
}

} // namespace
