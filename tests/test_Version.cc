// SPDX-License-Identifier: Apache-2.0
// Version macros, the run-time version() and the CMake project version agree.

#include <nonbloppy/Version.h>

#include <gtest/gtest.h>

#include <string>

TEST(Version, RuntimeMatchesHeaderAndProject)
{
    EXPECT_EQ(std::string(nonbloppy::version()), NONBLOPPY_VERSION_STRING);
    EXPECT_EQ(std::string(NONBLOPPY_VERSION_STRING), NONBLOPPY_PROJECT_VERSION);
    const std::string fromParts = std::to_string(NONBLOPPY_VERSION_MAJOR) + "." +
        std::to_string(NONBLOPPY_VERSION_MINOR) + "." + std::to_string(NONBLOPPY_VERSION_PATCH);
    EXPECT_EQ(fromParts, NONBLOPPY_VERSION_STRING);
}
