// SPDX-License-Identifier: Apache-2.0
/// @file tile_particles.cc
/// @brief `nonbloppy_tile IN OUT.ply --copies N`: a large test frame made of N×N×N disjoint
///        copies of a real one, for memory and speed measurements (never committed: generate it).
///
///     nonbloppy_tile tests/data/dam_break_frame_23_24389_particles.vtk /tmp/dam512.ply --copies 8
///
/// Copy (i, j, k) is the input translated by (i·(Δx + gap), j·(Δy + gap), k·(Δz + gap)), where
/// Δ is the extent of the input's bounding box and gap defaults to 0.05 (the spacing of the
/// repository's dam-break frames), so copies never touch. Copies are written with i fastest,
/// then j, then k, each in the input's particle order. The output is written by
/// writeParticles(): binary little-endian PLY, float x y z and, with --attributes, each of the
/// input's attributes in its type, every copy holding the input's values (ids repeat from copy
/// to copy); the same input and options give the same bytes on every machine, and OUT is
/// never half-written.

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/WriteParticles.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>


namespace {

const char* const kUsage =
    "usage: nonbloppy_tile IN OUT.ply [--copies N] [--gap G] [--attributes]\n"
    "  IN        particle file (.vtk, .ply, .xyz)\n"
    "  OUT.ply   binary little-endian PLY with N*N*N translated copies of IN\n"
    "  --copies  copies per axis, >= 1 (default 2; 4 -> 64 copies, 8 -> 512 copies)\n"
    "  --gap     distance between neighbouring copies' bounding boxes (default 0.05)\n"
    "  --attributes  keep the input's attributes (each copy holds the input's values)\n";

int fail(const std::string& message)
{
    std::cerr << "nonbloppy_tile: " << message << std::endl;
    return 1;
}

int run(int argc, char** argv)
{
    std::vector<std::string> positional;
    long copies = 2;
    double gap = 0.05;
    bool keepAttributes = false;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        if (arg == "-h" || arg == "--help") {
            std::cout << kUsage;
            return 0;
        }
        if (arg == "--attributes") {
            keepAttributes = true;
            continue;
        }
        if (arg == "--copies" || arg == "--gap") {
            if (a + 1 >= argc) return fail(arg + " needs a value");
            const std::string value = argv[++a];
            char* end = nullptr;
            errno = 0;
            if (arg == "--copies") {
                copies = std::strtol(value.c_str(), &end, 10);
                if (errno || *end || end == value.c_str() || copies < 1 || copies > 64) {
                    return fail("--copies must be an integer in [1,64], got '" + value + "'");
                }
            } else {
                gap = std::strtod(value.c_str(), &end);
                if (errno || *end || end == value.c_str() || !(gap >= 0.0)) {
                    return fail("--gap must be a number >= 0, got '" + value + "'");
                }
            }
            continue;
        }
        if (arg.size() > 1 && arg[0] == '-') return fail("unknown option " + arg);
        positional.push_back(arg);
    }
    if (positional.size() != 2) {
        std::cerr << kUsage;
        return 2;
    }
    const std::string& inPath = positional[0];
    const std::string& outPath = positional[1];
    if (outPath.size() < 4 || outPath.compare(outPath.size() - 4, 4, ".ply") != 0) {
        return fail("output must be a .ply file (" + outPath + ")");
    }

    const nonbloppy::ParticleSet particles = nonbloppy::readParticles(inPath);
    const size_t count = particles.size();
    if (count == 0) return fail("no particles in " + inPath);

    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (const openvdb::Vec3f& p : particles.positions) {
        for (int axis = 0; axis < 3; ++axis) {
            lo[axis] = std::min(lo[axis], double(p[axis]));
            hi[axis] = std::max(hi[axis], double(p[axis]));
        }
    }
    double step[3];
    for (int axis = 0; axis < 3; ++axis) step[axis] = hi[axis] - lo[axis] + gap;

    const size_t copyCount = size_t(copies * copies * copies);
    const uint64_t total = uint64_t(count) * copyCount;
    nonbloppy::ParticleSet tiled;
    tiled.positions.reserve(size_t(total));
    for (long k = 0; k < copies; ++k)
        for (long j = 0; j < copies; ++j)
            for (long i = 0; i < copies; ++i) {
                const double offset[3] = {i * step[0], j * step[1], k * step[2]};
                for (const openvdb::Vec3f& p : particles.positions) {
                    tiled.positions.emplace_back(float(double(p[0]) + offset[0]), float(double(p[1]) + offset[1]),
                                                 float(double(p[2]) + offset[2]));
                }
            }
    if (keepAttributes) {
        for (const nonbloppy::ParticleAttribute& attribute : particles.attributes) {
            nonbloppy::ParticleAttribute copy = attribute;
            copy.bytes.clear();
            copy.bytes.reserve(attribute.bytes.size() * copyCount);
            for (size_t c = 0; c < copyCount; ++c) {
                copy.bytes.insert(copy.bytes.end(), attribute.bytes.begin(), attribute.bytes.end());
            }
            tiled.attributes.push_back(std::move(copy));
        }
    }
    nonbloppy::writeParticles(tiled, outPath);
    std::cout << outPath << ": " << total << " particles (" << copyCount << " copies of " << count
              << (keepAttributes ? ", with their attributes" : "") << ")" << std::endl;
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        return fail(e.what());
    }
}
