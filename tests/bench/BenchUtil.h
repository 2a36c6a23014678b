// SPDX-License-Identifier: Apache-2.0
/// @file BenchUtil.h
/// @brief Inputs for the measurement programs: a real frame tiled n×n×n times in memory.

#ifndef NONBLOPPY_BENCH_UTIL_H
#define NONBLOPPY_BENCH_UTIL_H

#include <nonbloppy/ReadParticles.h>

#include <openvdb/openvdb.h>

#include <chrono>
#include <string>
#include <vector>

namespace nonbloppy_bench {

/// The particles of @a path repeated on an n×n×n grid of copies, each offset by 1.25× the
/// frame's bounding box so that copies never touch (1.56 M particles for the dam-break
/// frame with n = 4). @a jitter moves every copy by that fraction of the box (a moving fluid).
inline std::vector<openvdb::Vec3f> tiledFrame(const std::string& path, int n, double jitter = 0.0)
{
    const nonbloppy::ParticleSet frame = nonbloppy::readParticles(path);
    openvdb::BBoxd box;
    for (const openvdb::Vec3f& p : frame.positions) box.expand(openvdb::Vec3d(p));
    const openvdb::Vec3d step = 1.25 * box.extents();
    std::vector<openvdb::Vec3f> tiled;
    tiled.reserve(frame.size() * size_t(n * n * n));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                const openvdb::Vec3d offset(i * step[0], j * step[1], k * step[2]);
                const openvdb::Vec3d shift = jitter * box.extents() * double((i + 2 * j + 3 * k) % 5);
                for (const openvdb::Vec3f& p : frame.positions) {
                    tiled.emplace_back(openvdb::Vec3d(p) + offset + shift);
                }
            }
    return tiled;
}

inline double secondsSince(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace nonbloppy_bench

#endif // NONBLOPPY_BENCH_UTIL_H
