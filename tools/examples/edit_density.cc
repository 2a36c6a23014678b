// SPDX-License-Identifier: Apache-2.0
// Example: read a density grid written by another tool (a .vdb), erase a box from it,
// extract the surface again and relax it against the particles that remain.
//   usage: example_edit_density [density.vdb particles.vtk]
// Without arguments it first writes such a .vdb itself, from the dam-break test frame.

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/RelaxVertices.h>
#include <nonbloppy/WriteVdb.h>

#include <cstdio>
#include <cstdlib>
#include <string>

// The particles outside a world box, as a ParticleList over the caller's set: no copy.
struct ParticlesOutside
{
    const nonbloppy::ParticleSet& all;
    std::vector<size_t> kept;
    ParticlesOutside(const nonbloppy::ParticleSet& set, const openvdb::BBoxd& box) : all(set)
    {
        for (size_t n = 0; n < set.size(); ++n) {
            if (!box.isInside(openvdb::Vec3d(set.positions[n]))) kept.push_back(n);
        }
    }
    size_t size() const { return kept.size(); }
    void getPos(size_t n, openvdb::Vec3R& xyz) const { all.getPos(kept[n], xyz); }
};

int main(int argc, char** argv)
{
    const char* dataDir = std::getenv("NONBLOPPY_TEST_DATA_DIR");
    const char* outDir = std::getenv("NONBLOPPY_EXAMPLE_OUT");
    std::string vdbPath = std::string(outDir ? outDir : ".") + "/other_tool_density.vdb";
    std::string particlePath =
        std::string(dataDir ? dataDir : "tests/data") + "/dam_break_frame_23_24389_particles.vtk";
    try {
        openvdb::initialize();
        if (argc > 2) {
            vdbPath = argv[1];
            particlePath = argv[2];
        } else {  // stand-in for the other tool
            nonbloppy::writeVdb({nonbloppy::buildSurface(nonbloppy::readParticles(particlePath)).density}, vdbPath);
        }
        const nonbloppy::ParticleSet particles = nonbloppy::readParticles(particlePath);

        openvdb::io::File file(vdbPath);
        file.open();
        openvdb::FloatGrid::Ptr density = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
        file.close();
        if (!density) throw nonbloppy::FileError("no float grid \"density\" in " + vdbPath);
        // nonbloppy stores its parameters on the grid; another tool's grid may need them given.
        const double threshold = density->metaValue<double>("threshold");
        const double radius = density->metaValue<double>("effective_radius");

        // Erase the upper half (in y) of the fluid's bounding box: those voxels become background.
        const openvdb::CoordBBox active = density->evalActiveVoxelBoundingBox();
        openvdb::CoordBBox erase = active;
        erase.min().y() = (active.min().y() + active.max().y()) / 2;
        density->tree().fill(erase, density->background(), /*active=*/false);
        density->tree().prune();
        const openvdb::BBoxd worldErase = density->transform().indexToWorld(erase);

        nonbloppy::SurfaceMesh mesh = nonbloppy::extractSurface(*density, threshold);
        const ParticlesOutside remaining(particles, worldErase);
        const nonbloppy::ParticleIndex index = nonbloppy::buildParticleIndex(remaining, 0.5 * radius);
        nonbloppy::RelaxSettings relax;
        relax.effectiveRadius = radius;
        nonbloppy::relaxVertices(mesh, index, relax);
        nonbloppy::computeNormals(mesh);

        const nonbloppy::MeshMeasures measures = nonbloppy::measureMesh(mesh);
        const openvdb::Coord size = erase.dim();
        std::printf("%s: erased %d×%d×%d voxels; %zu of %zu particles remain; mesh %zu vertices, "
                    "%zu polygons, closed %s, volume %.4f\n", vdbPath.c_str(), size.x(), size.y(), size.z(),
                    remaining.size(), particles.size(), measures.vertices, measures.polygons,
                    measures.closed ? "yes" : "no", measures.volume);
        return measures.closed && measures.volume > 0.0 ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
