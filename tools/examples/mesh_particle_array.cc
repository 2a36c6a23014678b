// SPDX-License-Identifier: Apache-2.0
// Example: mesh particles held in the program's own array, without copying them into a
// nonbloppy container. Any type with size() and getPos() models the ParticleList concept.
//   usage: example_mesh_particle_array [out.obj]

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/CgroupLimits.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/WriteMesh.h>

#include <tbb/global_control.h>

#include <cstdio>
#include <vector>

// The application's particle storage: packed x, y, z floats.
struct MyParticles
{
    std::vector<float> xyz;
    size_t size() const { return xyz.size() / 3; }
    void getPos(size_t n, openvdb::Vec3R& p) const
    {
        p = openvdb::Vec3R(xyz[3 * n], xyz[3 * n + 1], xyz[3 * n + 2]);
    }
};

int main(int argc, char** argv)
{
    // A ball of radius 1 on a lattice of spacing 0.1: about 4200 particles.
    MyParticles particles;
    for (int i = -10; i <= 10; ++i)
        for (int j = -10; j <= 10; ++j)
            for (int k = -10; k <= 10; ++k)
                if (i * i + j * j + k * k < 100) {
                    particles.xyz.insert(particles.xyz.end(), {0.1f * i, 0.1f * j, 0.1f * k});
                }

    // In a container or batch job, no more workers than its CPU limit grants (TBB alone
    // counts the node's cores); held for as long as the program meshes.
    const nonbloppy::DefaultThreads threads = nonbloppy::defaultThreads();
    const tbb::global_control workers(tbb::global_control::max_allowed_parallelism, size_t(threads.threads));

    try {
        nonbloppy::SurfaceParameters params;  // unset lengths derive from the spacing
        params.iterations = 2;
        const nonbloppy::SurfaceResult result = nonbloppy::buildSurface(particles, params);

        const nonbloppy::MeshMeasures measures = nonbloppy::measureMesh(result.mesh);
        std::printf("%zu particles -> %zu vertices, %zu polygons, closed %s, volume %.3f "
                    "(ball of N s^3: %.3f), spacing %.3f, %.0f ms\n",
                    particles.size(), measures.vertices, measures.polygons,
                    measures.closed ? "yes" : "no", measures.volume,
                    double(particles.size()) * 1e-3, result.parameters.spacing,
                    1e3 * result.timings.total());
        if (argc > 1) nonbloppy::writeMesh(result.mesh, argv[1]);
        return measures.closed && measures.manifold ? 0 : 1;
    } catch (const nonbloppy::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
