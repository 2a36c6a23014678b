// SPDX-License-Identifier: Apache-2.0
// Inputs the fuzz targets (tests/fuzz/) found, kept in tests/data/fuzz/: each must give a
// one-line FileError, never a crash.

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>

#include <string>

namespace {

std::string
fuzzPath(const std::string& name)
{
    return std::string(NONBLOPPY_TEST_DATA_DIR) + "/fuzz/" + name;
}

std::string
fileErrorOf(const std::string& path)
{
    try {
        nonbloppy::readParticles(path);
    } catch (const nonbloppy::FileError& e) {
        return e.what();
    }
    return "(no FileError)";
}

// fuzz_vdb_points: a .vdb whose stream OpenVDB rejects halfway through a grid (libopenvdb
// leaks a node on that path, upstream); the reader must turn OpenVDB's exception into a
// FileError naming the file.
TEST(FuzzRegressions, VdbCorruptStream)
{
    const std::string path = fuzzPath("vdb_points_corrupt_stream_openvdb_leak.vdb");
    const std::string message = fileErrorOf(path);
    EXPECT_EQ(message.rfind("cannot read .vdb file: ", 0), 0u) << message;
    EXPECT_EQ(message.substr(message.size() - path.size() - 2), "(" + path + ")");
    EXPECT_EQ(message.find('\n'), std::string::npos);
}

} // namespace
