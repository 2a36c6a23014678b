// SPDX-License-Identifier: Apache-2.0
// Consumer of the installed package: meshes particles held in the program's own array type
// through the ParticleList concept (size(), getPos()) and checks the result.
// Exit status 0 on success; prints what failed otherwise.

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/CgroupLimits.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/Version.h>

#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstring>

namespace {

/// The application's own particle storage: separate coordinate arrays, doubles.
struct SoaParticles
{
    std::vector<double> x, y, z;
    size_t size() const { return x.size(); }
    void getPos(size_t n, openvdb::Vec3R& xyz) const { xyz = openvdb::Vec3R(x[n], y[n], z[n]); }
};

int failures = 0;
void check(bool ok, const char* what)
{
    std::printf("%s: %s\n", ok ? "ok  " : "FAIL", what);
    if (!ok) ++failures;
}

} // namespace

int main()
{
    check(std::strcmp(nonbloppy::version(), NONBLOPPY_VERSION_STRING) == 0,
          "library version equals header version");

    // Meshed with no more workers than a container's CPU limit grants, as a studio's tool would.
    const nonbloppy::DefaultThreads threads = nonbloppy::defaultThreads();
    check(threads.threads >= 1, "defaultThreads() gives at least one worker");
    tbb::global_control workers(tbb::global_control::max_allowed_parallelism, size_t(threads.threads));

    // One particle: the density r_e/d − 1 equals r_0 at d = r_e/(1 + r_0), a sphere.
    const double re = 1.0, r0 = 1.0, h = 0.05;
    SoaParticles one;
    one.x = {0.25}; one.y = {-0.5}; one.z = {2.0};
    nonbloppy::SurfaceParameters params;
    params.spacing = 0.5;
    params.effectiveRadius = re;
    params.threshold = r0;
    params.voxelSize = h;
    params.iterations = 0;  // relaxation would shrink the sphere by (1 − c)^t
    params.method = nonbloppy::Method::Paper;  // the plain method: no volume correction
    const nonbloppy::SurfaceResult result = nonbloppy::buildSurface(one, params);

    const double expected = re / (1.0 + r0);
    double minR = 1e30, maxR = 0.0;
    const openvdb::Vec3d centre(0.25, -0.5, 2.0);
    for (const openvdb::Vec3s& p : result.mesh.points) {
        const double r = (openvdb::Vec3d(p) - centre).length();
        minR = std::min(minR, r);
        maxR = std::max(maxR, r);
    }
    std::printf("one particle: %zu vertices, radius in [%.4f, %.4f], expected %.4f\n",
                result.mesh.points.size(), minR, maxR, expected);
    check(!result.mesh.points.empty(), "one particle gives a mesh");
    check(std::abs(minR - expected) < 0.2 * h && std::abs(maxR - expected) < 0.2 * h,
          "vertices lie on the sphere r_e/(1 + r_0)");
    const nonbloppy::MeshMeasures measures = nonbloppy::measureMesh(result.mesh);
    check(measures.closed && measures.manifold, "the sphere is closed and manifold");
    const double sphereVolume = 4.0 / 3.0 * M_PI * expected * expected * expected;
    check(std::abs(measures.volume - sphereVolume) < 0.02 * sphereVolume,
          "enclosed volume within 2% of the sphere's");
    check(result.mesh.normals.size() == result.mesh.points.size(), "one normal per vertex");

    // Errors cross the library boundary as nonbloppy exceptions.
    bool caught = false;
    try {
        nonbloppy::SurfaceParameters bad = params;
        bad.blend = 1.5;
        nonbloppy::buildSurface(one, bad);
    } catch (const nonbloppy::ParameterError& e) {
        caught = std::strstr(e.what(), "blend") != nullptr;
    }
    check(caught, "ParameterError caught from the library, naming the parameter");

    std::printf("%s\n", failures == 0 ? "consumer: all checks passed" : "consumer: FAILED");
    return failures == 0 ? 0 : 1;
}
