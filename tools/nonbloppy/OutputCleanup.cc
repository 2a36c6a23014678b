// SPDX-License-Identifier: Apache-2.0
/// @file OutputCleanup.cc
/// @brief See OutputCleanup.h.

#include "OutputCleanup.h"

#include "BackgroundRemover.h"

#include <cstdio>
#include <filesystem>
#include <system_error>

#include <sys/stat.h>
#include <unistd.h>

namespace nonbloppy_tool {

namespace {

/// The file a writer writes for @a path: symbolic links followed, also to a target that does
/// not exist yet, as the library's writers (and a shell's '>') follow them. A loop of links
/// stops at the 40th, where the writer fails anyway.
std::string writtenFile(const std::string& path)
{
    namespace fs = std::filesystem;
    fs::path target = path;
    for (int links = 0; links < 40; ++links) {
        std::error_code error;
        if (!fs::is_symlink(fs::symlink_status(target, error))) break;
        const fs::path next = fs::read_symlink(target, error);
        if (error) break;
        target = next.is_absolute() ? next : target.parent_path() / next;
    }
    return target.string();
}

} // namespace

void OutputCleanup::willWrite(const std::string& path)
{
    // Undone through the target: removing @a path itself would delete the user's link to a
    // file that did not exist yet and leave the new file behind.
    Output output{writtenFile(path), "", false};
    struct stat existing{};
    if (::stat(output.target.c_str(), &existing) == 0) {
        const std::string backup = output.target + ".nonbloppy-old-" + std::to_string(::getpid());
        if (::link(output.target.c_str(), backup.c_str()) == 0) output.backup = backup;
    }
    mOutputs.push_back(output);
}

void OutputCleanup::keep(BackgroundRemover& remover)
{
    for (const Output& output : mOutputs) {
        if (!output.backup.empty()) remover.remove(output.backup);
    }
    mOutputs.clear();
}

OutputCleanup::~OutputCleanup()
{
    for (const Output& output : mOutputs) {
        if (!output.backup.empty()) {
            // Renaming a link over the same file would leave both names (POSIX).
            struct stat now{}, old{};
            const bool replaced = ::stat(output.target.c_str(), &now) != 0 ||
                                  ::stat(output.backup.c_str(), &old) != 0 || now.st_ino != old.st_ino ||
                                  now.st_dev != old.st_dev;
            if (replaced) {
                std::rename(output.backup.c_str(), output.target.c_str());
            } else {
                ::unlink(output.backup.c_str());
            }
        } else if (output.written) {
            std::remove(output.target.c_str());
        }
    }
}

} // namespace nonbloppy_tool
