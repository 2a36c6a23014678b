// SPDX-License-Identifier: Apache-2.0
/// @file TestUtil.h
/// @brief Particle sets with known answers, shared by the tests.

#ifndef NONBLOPPY_TEST_UTIL_H
#define NONBLOPPY_TEST_UTIL_H

#include <openvdb/openvdb.h>

#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace nonbloppy_test {

inline std::string dataPath(const std::string& name)
{
    return std::string(NONBLOPPY_TEST_DATA_DIR) + "/" + name;
}

/// Lattice points of spacing @a spacing inside @a inside (a predicate on world positions),
/// searched over [-extent, extent]³, each moved by up to jitter·spacing with a fixed seed.
inline std::vector<openvdb::Vec3f> latticeParticles(double spacing, double extent,
                                                    const std::function<bool(const openvdb::Vec3d&)>& inside,
                                                    double jitter = 0.0, unsigned seed = 7)
{
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> offset(-jitter * spacing, jitter * spacing);
    std::vector<openvdb::Vec3f> positions;
    const int n = int(std::ceil(extent / spacing));
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
            for (int k = -n; k <= n; ++k) {
                const openvdb::Vec3d x(i * spacing, j * spacing, k * spacing);
                if (!inside(x)) continue;
                openvdb::Vec3d p = x;
                if (jitter > 0.0) p += openvdb::Vec3d(offset(random), offset(random), offset(random));
                positions.emplace_back(p);
            }
    return positions;
}

} // namespace nonbloppy_test

#endif // NONBLOPPY_TEST_UTIL_H
