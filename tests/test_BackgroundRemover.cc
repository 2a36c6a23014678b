// SPDX-License-Identifier: Apache-2.0
/// @file test_BackgroundRemover.cc
/// @brief The tool's background file remover (tools/nonbloppy/BackgroundRemover.h): every
///        queued file is gone once the remover is, whoever queued it; failures are ignored.

#include "BackgroundRemover.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using nonbloppy_tool::BackgroundRemover;

class BackgroundRemoverTest : public ::testing::Test
{
protected:
    void SetUp() override
    {
        mDir = fs::temp_directory_path() / ("nonbloppy_remover_" + std::to_string(::getpid()));
        fs::remove_all(mDir);
        fs::create_directories(mDir);
    }
    void TearDown() override { fs::remove_all(mDir); }

    /// A new file named @a name in the test's directory, holding @a bytes bytes.
    std::string file(const std::string& name, size_t bytes = 4096) const
    {
        const fs::path path = mDir / name;
        std::ofstream(path, std::ios::binary) << std::string(bytes, 'x');
        return path.string();
    }
    size_t filesLeft() const
    {
        return size_t(std::distance(fs::directory_iterator(mDir), fs::directory_iterator()));
    }

    fs::path mDir;
};

TEST_F(BackgroundRemoverTest, EveryQueuedFileIsGoneOnceTheRemoverIs)
{
    std::vector<std::string> paths;
    for (int i = 0; i < 50; ++i) paths.push_back(file("f" + std::to_string(i), size_t(i) << 12));
    const std::string kept = file("kept");
    {
        BackgroundRemover remover;
        for (const std::string& path : paths) remover.remove(path);
    }
    for (const std::string& path : paths) EXPECT_FALSE(fs::exists(path)) << path;
    EXPECT_TRUE(fs::exists(kept));
    EXPECT_EQ(filesLeft(), 1u);
}

TEST_F(BackgroundRemoverTest, ConcurrentCallersAndMissingFilesAreServed)
{
    // Frame jobs hand over their replaced outputs at the same time; a path that is already
    // gone is skipped without stopping the queue behind it.
    {
        BackgroundRemover remover;
        std::vector<std::thread> callers;
        for (int c = 0; c < 4; ++c) {
            callers.emplace_back([&, c] {
                for (int i = 0; i < 25; ++i) {
                    remover.remove((mDir / ("missing" + std::to_string(c))).string());
                    remover.remove(file("c" + std::to_string(c) + "_" + std::to_string(i)));
                }
            });
        }
        for (std::thread& caller : callers) caller.join();
    }
    EXPECT_EQ(filesLeft(), 0u);
}

} // namespace
