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
/// then j, then k, each in the input's particle order. The output is binary little-endian PLY
/// with float x y z only; the same input and options give the same bytes on every machine.
/// Written to a temporary file beside OUT and renamed, so OUT is never half-written.

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

const char* const kUsage =
    "usage: nonbloppy_tile IN OUT.ply [--copies N] [--gap G]\n"
    "  IN        particle file (.vtk, .ply, .xyz)\n"
    "  OUT.ply   binary little-endian PLY with N*N*N translated copies of IN\n"
    "  --copies  copies per axis, >= 1 (default 2; 4 -> 64 copies, 8 -> 512 copies)\n"
    "  --gap     distance between neighbouring copies' bounding boxes (default 0.05)\n";

int fail(const std::string& message)
{
    std::cerr << "nonbloppy_tile: " << message << std::endl;
    return 1;
}

void putFloatLE(unsigned char* out, float value)
{
    uint32_t bits;
    std::memcpy(&bits, &value, 4);
    for (int b = 0; b < 4; ++b) out[b] = static_cast<unsigned char>(bits >> (8 * b));
}

int run(int argc, char** argv)
{
    std::vector<std::string> positional;
    long copies = 2;
    double gap = 0.05;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        if (arg == "-h" || arg == "--help") {
            std::cout << kUsage;
            return 0;
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

    // Only the file name, so the bytes do not depend on where the input lies.
    const std::string fileName = std::filesystem::path(inPath).filename().string();
    const uint64_t total = uint64_t(count) * uint64_t(copies * copies * copies);
    const std::string header = "ply\nformat binary_little_endian 1.0\n"
                               "comment nonbloppy_tile " + std::to_string(copies) + "^3 copies of "
                               + fileName + "\nelement vertex " + std::to_string(total)
                               + "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";

    const std::string tempPath = outPath + ".tmp-" + std::to_string(::getpid());
    std::FILE* file = std::fopen(tempPath.c_str(), "wb");
    if (!file) return fail("cannot write " + outPath + ": " + std::strerror(errno));
    bool ok = std::fwrite(header.data(), 1, header.size(), file) == header.size();

    std::vector<unsigned char> buffer(count * 12);
    for (long k = 0; k < copies && ok; ++k)
        for (long j = 0; j < copies && ok; ++j)
            for (long i = 0; i < copies && ok; ++i) {
                const double offset[3] = {i * step[0], j * step[1], k * step[2]};
                for (size_t n = 0; n < count; ++n) {
                    for (int axis = 0; axis < 3; ++axis) {
                        const float value =
                            static_cast<float>(double(particles.positions[n][axis]) + offset[axis]);
                        putFloatLE(&buffer[12 * n + 4 * axis], value);
                    }
                }
                ok = std::fwrite(buffer.data(), 1, buffer.size(), file) == buffer.size();
            }
    const int writeErrno = errno;
    if (std::fclose(file) != 0) ok = false;
    if (!ok || std::rename(tempPath.c_str(), outPath.c_str()) != 0) {
        const int error = ok ? errno : writeErrno;
        std::remove(tempPath.c_str());
        return fail("cannot write " + outPath + ": " + std::strerror(error));
    }
    std::cout << outPath << ": " << total << " particles (" << copies * copies * copies
              << " copies of " << count << ")" << std::endl;
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
