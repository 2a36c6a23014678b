// SPDX-License-Identifier: Apache-2.0
// Example: mesh a particle file and save a .vdb holding the density grid and the surface
// as a narrow-band level set (nonbloppy::meshToLevelSet), for Houdini or vdb_view.
//   usage: example_mesh_to_vdb [particles.vtk [out.vdb]]

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/MeshToLevelSet.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/WriteVdb.h>

#include <openvdb/tools/Interpolation.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv)
{
    const char* dataDir = std::getenv("NONBLOPPY_TEST_DATA_DIR");
    const char* outDir = std::getenv("NONBLOPPY_EXAMPLE_OUT");
    const std::string input = argc > 1 ? argv[1]
        : std::string(dataDir ? dataDir : "tests/data") + "/dam_break_frame_23_24389_particles.vtk";
    const std::string output = argc > 2 ? argv[2] : std::string(outDir ? outDir : ".") + "/dam_break.vdb";

    try {
        openvdb::initialize();
        const nonbloppy::ParticleSet particles = nonbloppy::readParticles(input);
        const nonbloppy::SurfaceResult result = nonbloppy::buildSurface(particles);
        const nonbloppy::SurfaceMesh& mesh = result.mesh;

        // The surface as a signed distance field on the density's voxels, 3 voxels each side
        // (world-space vertices; negative inside, as OpenVDB's level sets are).
        const double voxelSize = result.parameters.voxelSize;
        openvdb::FloatGrid::Ptr surface = nonbloppy::meshToLevelSet(mesh, voxelSize, 3.0f);

        // The level set passes through the mesh: its distance is within a voxel at every vertex.
        openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(*surface);
        size_t off = 0;
        for (const openvdb::Vec3s& v : mesh.points) {
            if (!(std::abs(sampler.wsSample(openvdb::Vec3d(v))) < voxelSize)) ++off;
        }

        nonbloppy::writeVdb({result.density, surface}, output);
        std::printf("%s: %zu particles -> density (%zu active voxels), surface level set "
                    "(%zu active voxels, %zu of %zu vertices more than a voxel off it) in %s\n",
                    input.c_str(), particles.size(), size_t(result.density->activeVoxelCount()),
                    size_t(surface->activeVoxelCount()), off, mesh.points.size(), output.c_str());
        return !mesh.points.empty() && off == 0 ? 0 : 1;
    } catch (const nonbloppy::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
