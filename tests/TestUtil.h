// SPDX-License-Identifier: Apache-2.0
/// @file TestUtil.h
/// @brief Particle sets with known answers, file helpers and a scratch-directory fixture,
///        shared by the tests.

#ifndef NONBLOPPY_TEST_UTIL_H
#define NONBLOPPY_TEST_UTIL_H

#include <nonbloppy/Particles.h>

#include <openvdb/openvdb.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

/// NONBLOPPY_TEST_ASAN is defined when the tests are built with AddressSanitizer (GCC's
/// __SANITIZE_ADDRESS__, clang's __has_feature), whose quarantine keeps freed memory: tests
/// that measure memory skip themselves there.
#if defined(__SANITIZE_ADDRESS__)
#define NONBLOPPY_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define NONBLOPPY_TEST_ASAN 1
#endif
#endif

namespace nonbloppy_test {

inline std::string dataPath(const std::string& name)
{
    return std::string(NONBLOPPY_TEST_DATA_DIR) + "/" + name;
}

/// The whole content of the file @a path ("" if it cannot be read).
inline std::string readBytes(const std::string& path)
{
    std::ifstream is(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>());
}

/// Writes @a bytes as the whole content of @a path; a failed write fails the test.
inline void writeBytes(const std::string& path, const std::string& bytes)
{
    std::ofstream os(path, std::ios::binary | std::ios::trunc);
    os.write(bytes.data(), std::streamsize(bytes.size()));
    if (!os.good()) ADD_FAILURE() << "cannot write " << path;
}

/// The attribute @a name of @a particles; throws std::runtime_error (failing the test) if
/// there is none.
inline const nonbloppy::ParticleAttribute& attribute(const nonbloppy::ParticleSet& particles,
                                                     const std::string& name)
{
    const nonbloppy::ParticleAttribute* found = particles.findAttribute(name);
    if (!found) throw std::runtime_error("no attribute " + name);
    return *found;
}

/// The message of the exception @a ExceptionT that @a f throws ("" if it throws none).
template<typename ExceptionT>
std::string messageOf(const std::function<void()>& f)
{
    try {
        f();
    } catch (const ExceptionT& e) {
        return e.what();
    }
    return "";
}

/// A fresh, empty directory per test (under ::testing::TempDir()), removed afterwards.
class ScratchDirTest : public ::testing::Test
{
protected:
    void SetUp() override
    {
        std::string pattern = ::testing::TempDir() + "nonbloppy_test_XXXXXX";
        ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
        mDir = pattern;
    }
    void TearDown() override
    {
        std::error_code ec;
        std::filesystem::remove_all(mDir, ec);
    }
    std::string dir() const { return mDir; }
    /// @a name inside the test's directory.
    std::string path(const std::string& name) const { return mDir + "/" + name; }
    /// Write @a bytes to @a name inside the test's directory; returns its path.
    std::string write(const std::string& name, const std::string& bytes) const
    {
        writeBytes(path(name), bytes);
        return path(name);
    }

private:
    std::string mDir;
};

/// The mean height z of the mesh vertices @a points above the patch |x|, |y| < halfWidth
/// with z > 0 (the top face of a slab centred on the z axis), and how many vertices that is.
inline std::pair<double, int> meanTopHeight(const std::vector<openvdb::Vec3s>& points,
                                            double halfWidth = 0.5)
{
    double heightSum = 0.0;
    int count = 0;
    for (const openvdb::Vec3s& p : points) {
        if (std::abs(p[0]) < halfWidth && std::abs(p[1]) < halfWidth && p[2] > 0.0f) {
            heightSum += p[2];
            ++count;
        }
    }
    return {count > 0 ? heightSum / count : 0.0, count};
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

/// @a bytes in base64 (RFC 4648, '=' padding); with @a wrap a newline after every 76
/// characters, as VTK's writers break long inline arrays.
inline std::string base64(const std::string& bytes, bool wrap = false)
{
    static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve(bytes.size() / 3 * 4 + bytes.size() / 57 + 8);
    for (size_t i = 0; i < bytes.size(); i += 3) {
        uint32_t bits = uint32_t(static_cast<unsigned char>(bytes[i])) << 16;
        if (i + 1 < bytes.size()) bits |= uint32_t(static_cast<unsigned char>(bytes[i + 1])) << 8;
        if (i + 2 < bytes.size()) bits |= uint32_t(static_cast<unsigned char>(bytes[i + 2]));
        out += alphabet[(bits >> 18) & 63];
        out += alphabet[(bits >> 12) & 63];
        out += i + 1 < bytes.size() ? alphabet[(bits >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? alphabet[bits & 63] : '=';
        if (wrap && (i / 3 + 1) % 19 == 0) out += '\n';
    }
    return out;
}

} // namespace nonbloppy_test

#endif // NONBLOPPY_TEST_UTIL_H
