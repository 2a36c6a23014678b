// SPDX-License-Identifier: Apache-2.0
// Example: mesh a particle file and save a .vdb holding the density grid and the surface
// as a narrow-band level set (openvdb::tools::meshToVolume), for Houdini or vdb_view.
//   usage: example_mesh_to_vdb [particles.vtk [out.vdb]]

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/WriteVdb.h>

#include <openvdb/tools/MeshToVolume.h>

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

        // The surface as a signed distance field on the density's voxels, 3 voxels each side.
        // Our polygons face outwards, as meshToVolume expects; a triangle is a Vec4I whose
        // last index is INVALID_IDX.
        std::vector<openvdb::Vec4I> polygons(mesh.quads);
        for (const openvdb::Vec3I& t : mesh.triangles) {
            polygons.emplace_back(t[0], t[1], t[2], openvdb::util::INVALID_IDX);
        }
        openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec4I> adapter(
            mesh.points, polygons);
        openvdb::FloatGrid::Ptr surface = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
            adapter, result.density->transform(), 3.0f, 3.0f);
        surface->setName("surface");
        surface->setGridClass(openvdb::GRID_LEVEL_SET);

        nonbloppy::writeVdb({result.density, surface}, output);
        std::printf("%s: %zu particles -> density (%zu active voxels), surface level set "
                    "(%zu active voxels) in %s\n", input.c_str(), particles.size(),
                    size_t(result.density->activeVoxelCount()), size_t(surface->activeVoxelCount()),
                    output.c_str());
        return surface->activeVoxelCount() > 0 ? 0 : 1;
    } catch (const nonbloppy::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
