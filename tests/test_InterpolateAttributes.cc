// SPDX-License-Identifier: Apache-2.0
// Tests for interpolateAttributes(): a constant field comes back exactly, a linear field
// f(r) = A·r + b comes back as A·t_i + b with t_i the kernel-weighted mean position
// (computed here by brute force over every particle), the result does not depend on the
// thread count, and the attributes reach PLY and VTK files.

#include "TestUtil.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/InterpolateAttributes.h>
#include <nonbloppy/Kernel.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/WriteMesh.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

using namespace nonbloppy;

const openvdb::Mat3d kA(0.5, -1.0, 2.0, 3.0, 0.25, -0.75, 1.5, 1.0, -2.0);
const openvdb::Vec3d kB(0.1, -0.2, 0.3);
constexpr double kSpacing = 0.1;

/// Ids past 2^24 (where floats skip integers) and past 2^32, as a big simulation's are.
constexpr int64_t kFirstId = int64_t(1) << 40;

/// A jittered ball of particles with a constant scalar "c" = 2.5 (float32), a linear
/// vector field "f" = A·r + b (float64) and an int64 "id" = kFirstId + particle number.
ParticleSet
ballWithFields()
{
    ParticleSet particles;
    particles.positions = nonbloppy_test::latticeParticles(kSpacing, 0.6,
        [](const openvdb::Vec3d& x) { return x.length() < 0.5; }, 0.2);
    std::vector<float> c(particles.size(), 2.5f);
    std::vector<double> f;
    std::vector<int64_t> id;
    for (size_t j = 0; j < particles.size(); ++j) {
        const openvdb::Vec3d v = kA * openvdb::Vec3d(particles.positions[j]) + kB;
        f.insert(f.end(), {v[0], v[1], v[2]});
        id.push_back(kFirstId + int64_t(j));
    }
    particles.attributes.push_back(ParticleAttribute::of("c", 1, c));
    particles.attributes.push_back(ParticleAttribute::of("f", 3, f));
    particles.attributes.push_back(ParticleAttribute::of("id", 1, id));
    return particles;
}

struct Fixture
{
    ParticleSet particles = ballWithFields();
    SurfaceMesh mesh;
    double radius = 0;

    Fixture()
    {
        SurfaceParameters params;
        params.spacing = kSpacing;
        SurfaceResult result = buildSurface(particles.positions, params);
        mesh = std::move(result.mesh);
        radius = result.parameters.effectiveRadius;
        EXPECT_GT(mesh.points.size(), 500u) << "the ball's surface";
        mesh.points.push_back(openvdb::Vec3s(5.0f, 5.0f, 5.0f));  // no particle in reach
        if (!mesh.normals.empty()) mesh.normals.push_back(openvdb::Vec3s(0.0f, 0.0f, 1.0f));
    }
};

TEST(InterpolateAttributes, ConstantFieldComesBackExactly)
{
    Fixture fx;
    ASSERT_GT(fx.mesh.points.size(), 100u);
    interpolateAttributes(fx.mesh, fx.particles, {"c"}, fx.radius);
    ASSERT_EQ(fx.mesh.attributes.size(), 1u);
    const MeshAttribute& c = fx.mesh.attributes[0];
    EXPECT_EQ(c.name, "c");
    EXPECT_EQ(c.components, 1);
    ASSERT_EQ(c.values.size(), fx.mesh.points.size());
    for (size_t i = 0; i + 1 < c.values.size(); ++i) ASSERT_EQ(c.values[i], 2.5f) << "vertex " << i;
    EXPECT_EQ(c.values.back(), 0.0f);  // the far vertex
}

TEST(InterpolateAttributes, VerticesPastIntCellNumbersGetNoValue)
{
    // A vertex more than 2^31 index cells out, beyond the particles in +x: the search box's
    // near corner was left unclipped, its cell number wrapped to INT_MIN, and the search
    // walked 2^31 cells for minutes (API review). One also 2^31 cells out in -y, and one in
    // both directions at once.
    Fixture fx;
    const float far = float(3.0 * double(std::numeric_limits<int>::max()) * fx.radius);  // cells of r_e/2
    fx.mesh.points.push_back(openvdb::Vec3s(far, 0.0f, 0.0f));
    fx.mesh.points.push_back(openvdb::Vec3s(0.0f, -far, 0.0f));
    fx.mesh.points.push_back(openvdb::Vec3s(far, -far, far));
    if (!fx.mesh.normals.empty()) fx.mesh.normals.resize(fx.mesh.points.size(), openvdb::Vec3s(0.0f, 0.0f, 1.0f));
    interpolateAttributes(fx.mesh, fx.particles, {"c"}, fx.radius);
    const std::vector<float>& c = fx.mesh.attributes.at(0).values;
    ASSERT_EQ(c.size(), fx.mesh.points.size());
    EXPECT_EQ(c[0], 2.5f);
    for (size_t i = c.size() - 4; i < c.size(); ++i) EXPECT_EQ(c[i], 0.0f) << "vertex " << i;
}

TEST(InterpolateAttributes, LinearFieldGivesTheFieldAtTheWeightedMean)
{
    Fixture fx;
    interpolateAttributes(fx.mesh, fx.particles, {"f"}, fx.radius);
    const MeshAttribute& f = fx.mesh.attributes.at(0);
    ASSERT_EQ(f.components, 3);
    ASSERT_EQ(f.values.size(), 3 * fx.mesh.points.size());
    const float re = float(fx.radius);
    size_t checked = 0;
    for (size_t i = 0; i < fx.mesh.points.size(); ++i) {
        // t_i by brute force over every particle, with the kernel's weights.
        const openvdb::Vec3f v = fx.mesh.points[i];
        openvdb::Vec3d sum(0.0);
        double weights = 0.0;
        for (const openvdb::Vec3f& p : fx.particles.positions) {
            const float w = mpsWeightSquared((v - p).lengthSqr(), re);
            sum += double(w) * openvdb::Vec3d(p);
            weights += w;
        }
        if (weights == 0.0) {
            for (int a = 0; a < 3; ++a) EXPECT_EQ(f.values[3 * i + a], 0.0f);
            continue;
        }
        const openvdb::Vec3d expected = kA * (sum / weights) + kB;
        for (int a = 0; a < 3; ++a) {
            ASSERT_NEAR(f.values[3 * i + a], expected[a], 2e-5) << "vertex " << i << " axis " << a;
        }
        ++checked;
    }
    EXPECT_EQ(checked, fx.mesh.points.size() - 1);
}

TEST(InterpolateAttributes, IntegersTakeTheNearestParticlesValue)
{
    // An id is a name, not a quantity: the weighted mean of ids 17 and 18 named no particle.
    // Each vertex gets the id of the nearest particle within r_e, exactly (past 2^40, where
    // a float holds every 131072nd integer only), by brute force.
    Fixture fx;
    interpolateAttributes(fx.mesh, fx.particles, {"id", "c"}, fx.radius);
    const MeshAttribute& id = fx.mesh.attributes.at(0);
    ASSERT_EQ(id.name, "id");
    ASSERT_TRUE(id.integer);  // writeMesh() stores it as integers
    ASSERT_EQ(id.integers.size(), fx.mesh.points.size());
    EXPECT_TRUE(id.values.empty());
    const float re = float(fx.radius);
    size_t betweenTwoIds = 0;
    for (size_t i = 0; i < fx.mesh.points.size(); ++i) {
        const openvdb::Vec3f v = fx.mesh.points[i];
        float nearestSqr = re * re;
        int32_t nearest = -1;
        double weights = 0.0, weightedIds = 0.0;
        for (size_t j = 0; j < fx.particles.size(); ++j) {
            const float d2 = (v - fx.particles.positions[j]).lengthSqr();
            const float w = mpsWeightSquared(d2, re);
            if (w == 0.0f) continue;
            weights += w;
            weightedIds += double(w) * double(j);  // the particle number: the mean of ids, less kFirstId
            if (nearest < 0 || d2 < nearestSqr) {
                nearestSqr = d2;
                nearest = int32_t(j);
            }
        }
        if (nearest < 0) {
            EXPECT_EQ(id.integers[i], 0) << "vertex " << i;
            continue;
        }
        ASSERT_EQ(id.integers[i], kFirstId + nearest) << "vertex " << i;
        betweenTwoIds += std::floor(weightedIds / weights) != weightedIds / weights;
    }
    // The mean would have given values between ids at almost every vertex.
    EXPECT_GT(betweenTwoIds, fx.mesh.points.size() / 2);
    // A float attribute beside it is still a weighted mean.
    for (size_t i = 0; i + 1 < fx.mesh.points.size(); ++i) ASSERT_EQ(fx.mesh.attributes.at(1).values[i], 2.5f);
    EXPECT_FALSE(fx.mesh.attributes.at(1).integer);
    EXPECT_TRUE(fx.mesh.attributes.at(1).integers.empty());
}

TEST(InterpolateAttributes, OfEquallyNearParticlesTheFirstGivesItsValue)
{
    // A vertex halfway between two particles: the first in the input gives every component
    // of a vector integer attribute, whichever order the index keeps them in.
    for (const bool swapped : {false, true}) {
        SCOPED_TRACE(swapped);
        ParticleSet particles;
        particles.positions = {openvdb::Vec3f(0.1f, 0.0f, 0.0f), openvdb::Vec3f(-0.1f, 0.0f, 0.0f),
                               openvdb::Vec3f(0.0f, 0.3f, 0.0f)};
        std::vector<int16_t> cell{7, 8, 9, 3, 2, 1, 5, 5, 5};
        if (swapped) std::swap(particles.positions[0], particles.positions[1]);
        particles.attributes.push_back(ParticleAttribute::of("cell", 3, cell));
        SurfaceMesh mesh;
        mesh.points = {openvdb::Vec3s(0.0f, 0.0f, 0.0f), openvdb::Vec3s(0.0f, 0.29f, 0.0f)};
        interpolateAttributes(mesh, particles, {"cell"}, 0.5);
        const std::vector<int64_t>& values = mesh.attributes.at(0).integers;
        EXPECT_EQ(values, (std::vector<int64_t>{7, 8, 9, 5, 5, 5}));  // the first particle, either way
    }
}

TEST(InterpolateAttributes, SameBytesForAnyThreadCount)
{
    Fixture fx;
    SurfaceMesh one = fx.mesh, many = fx.mesh;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        interpolateAttributes(one, fx.particles, {"all"}, fx.radius);
    }
    interpolateAttributes(many, fx.particles, {"all"}, fx.radius);
    ASSERT_EQ(one.attributes.size(), 3u);
    for (size_t a = 0; a < 3; ++a) {
        EXPECT_EQ(one.attributes[a].name, many.attributes[a].name);
        EXPECT_TRUE(one.attributes[a].values == many.attributes[a].values) << one.attributes[a].name;
        EXPECT_TRUE(one.attributes[a].integers == many.attributes[a].integers) << one.attributes[a].name;
    }
}

TEST(InterpolateAttributes, NamesAndErrors)
{
    Fixture fx;
    EXPECT_EQ(resolveAttributeNames(fx.particles, {"all"}), (std::vector<std::string>{"c", "f", "id"}));
    EXPECT_EQ(resolveAttributeNames(fx.particles, {"id", "c", "id"}), (std::vector<std::string>{"id", "c"}));
    try {
        interpolateAttributes(fx.mesh, fx.particles, {"velocity"}, fx.radius);
        FAIL() << "no exception";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "unknown attribute 'velocity'; the particles have: c, f, id");
    }
    ParticleSet bare;
    bare.positions = fx.particles.positions;
    try {
        interpolateAttributes(fx.mesh, bare, {"velocity"}, fx.radius);
        FAIL() << "no exception";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "unknown attribute 'velocity'; the particles have no attributes");
    }
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { interpolateAttributes(fx.mesh, fx.particles, {"c"}, 0.0); }),
              "--radius must be > 0, got 0");
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { interpolateAttributes(fx.mesh, fx.particles, {"c"}, 2e18); }),
              "--radius 2e+18 is too large: at most 1e+18 (lengths are squared in single precision); give the "
              "positions in a larger unit");

    // A uint64 past int64 (a hash, say) has no place in the 64-bit signed integers.
    std::vector<uint64_t> hashes(fx.particles.size(), 5);
    hashes[3] = std::numeric_limits<uint64_t>::max();
    fx.particles.attributes.push_back(ParticleAttribute::of("h", 1, hashes));
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { interpolateAttributes(fx.mesh, fx.particles, {"h"}, fx.radius); }),
              "attribute 'h' holds 18446744073709551615, above 9223372036854775807, the largest integer a mesh "
              "attribute holds");
    hashes.assign(hashes.size(), uint64_t(std::numeric_limits<int64_t>::max()));  // the largest that fits
    fx.particles.attributes.back() = ParticleAttribute::of("h", 1, hashes);
    interpolateAttributes(fx.mesh, fx.particles, {"h"}, fx.radius);
    EXPECT_EQ(fx.mesh.attributes.back().integers.at(0), std::numeric_limits<int64_t>::max());

    // A caller's attribute of no countable shape was "has 0 values for N particles".
    fx.particles.attributes.back().components = -1;
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { interpolateAttributes(fx.mesh, fx.particles, {"h"}, fx.radius); }),
              "attribute 'h' has -1 components, at least 1 needed");
    fx.particles.attributes.back().components = 1;
    fx.particles.attributes.back().type = ScalarType(17);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { interpolateAttributes(fx.mesh, fx.particles, {"h"}, fx.radius); }),
              "attribute 'h' has the unknown scalar type 17");
}

/// Counts start() and end() calls; says stop from the start of the stage when @a stop.
struct CountingInterrupter : openvdb::util::NullInterrupter
{
    explicit CountingInterrupter(bool stopInStage) : stop(stopInStage) {}
    void start(const char* name) override
    {
        ++starts;
        stage = name ? name : "";
    }
    void end() override { ++ends; }
    bool wasInterrupted(int = -1) override { return stop && starts > 0; }
    bool stop;
    int starts = 0, ends = 0;
    std::string stage;
};

TEST(InterpolateAttributes, AStopOrAnErrorEndsTheAnnouncedStage)
{
    Fixture fx;
    CountingInterrupter stopping(true);
    try {
        interpolateAttributes(fx.mesh, fx.particles, {"c"}, fx.radius, &stopping);
        FAIL() << "no exception";
    } catch (const CancelledError& e) {
        EXPECT_STREQ(e.what(), "interrupted during interpolate attributes");
    }
    EXPECT_EQ(stopping.stage, "interpolate attributes");
    EXPECT_EQ(stopping.starts, 1);
    EXPECT_EQ(stopping.ends, 1);
    EXPECT_TRUE(fx.mesh.attributes.empty()) << "a stop leaves the mesh as it was";

    // Refused while indexing the particles, after the stage began: it still ends.
    ParticleSet far = fx.particles;
    far.positions[7] = openvdb::Vec3f(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
    CountingInterrupter counting(false);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>(
                  [&] { interpolateAttributes(fx.mesh, far, {"c"}, fx.radius, &counting); }),
              "non-finite position of particle 7");
    EXPECT_EQ(counting.starts, 1);
    EXPECT_EQ(counting.ends, 1);

    // Refused before the stage begins: nothing announced.
    ParticleSet shortAttribute = fx.particles;
    shortAttribute.attributes[0].bytes.resize(sizeof(float));
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>(
                  [&] { interpolateAttributes(fx.mesh, shortAttribute, {"c"}, fx.radius, &counting); }),
              "attribute 'c' has 1 values for " + std::to_string(fx.particles.size()) + " particles");
    EXPECT_EQ(counting.starts, 1);
    EXPECT_EQ(counting.ends, 1);
}

TEST(InterpolateAttributes, AnAttributeOfTheSameNameIsReplacedEvenWithoutVertices)
{
    Fixture fx;
    SurfaceMesh empty;
    interpolateAttributes(empty, fx.particles, {"c", "f"}, fx.radius);
    interpolateAttributes(empty, fx.particles, {"c"}, fx.radius);  // used to append a second "c"
    ASSERT_EQ(empty.attributes.size(), 2u);
    EXPECT_EQ(empty.attributes[0].name, "c");
    EXPECT_EQ(empty.attributes[1].name, "f");
    EXPECT_EQ(empty.attributes[1].components, 3);
    EXPECT_TRUE(empty.attributes[0].values.empty());

    interpolateAttributes(fx.mesh, fx.particles, {"c"}, fx.radius);
    interpolateAttributes(fx.mesh, fx.particles, {"c", "id"}, fx.radius);
    ASSERT_EQ(fx.mesh.attributes.size(), 2u);
    EXPECT_EQ(fx.mesh.attributes[0].name, "c");
    EXPECT_EQ(fx.mesh.attributes[1].name, "id");
}

TEST(InterpolateAttributes, WrittenAsPlyPropertiesAndVtkPointData)
{
    Fixture fx;
    interpolateAttributes(fx.mesh, fx.particles, {"c", "f"}, fx.radius);
    std::string dir = ::testing::TempDir() + "nonbloppy_attr_XXXXXX";
    ASSERT_NE(mkdtemp(dir.data()), nullptr);
    writeMesh(fx.mesh, dir + "/m.ply");
    writeMesh(fx.mesh, dir + "/m.vtk");

    // Both files read back as particle files, whose attributes are the vertex data. PLY
    // holds the vector as properties f_x, f_y, f_z, which read back as one vector.
    EXPECT_NE(nonbloppy_test::readBytes(dir + "/m.ply").find("property float c\nproperty float f_x\nproperty float f_y\n"
                                            "property float f_z\n"), std::string::npos);
    const ParticleSet ply = readParticles(dir + "/m.ply");
    ASSERT_EQ(ply.size(), fx.mesh.points.size());
    ASSERT_NE(ply.findAttribute("c"), nullptr);
    const ParticleAttribute* plyF = ply.findAttribute("f");
    ASSERT_NE(plyF, nullptr);
    EXPECT_EQ(plyF->components, 3);
    const ParticleSet vtk = readParticles(dir + "/m.vtk");
    const ParticleAttribute* f = vtk.findAttribute("f");
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(f->components, 3);
    const MeshAttribute& meshF = fx.mesh.attributes[1];
    for (size_t i = 0; i < fx.mesh.points.size(); ++i) {
        EXPECT_EQ(float(ply.findAttribute("c")->asDouble(i)), fx.mesh.attributes[0].values[i]);
        for (int a = 0; a < 3; ++a) {
            EXPECT_EQ(float(plyF->asDouble(i, a)), meshF.values[3 * i + a]);
            EXPECT_EQ(float(f->asDouble(i, a)), meshF.values[3 * i + a]);
        }
    }
    EXPECT_EQ(std::system(("rm -rf '" + dir + "'").c_str()), 0);
}

} // namespace
