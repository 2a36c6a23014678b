// SPDX-License-Identifier: Apache-2.0
/// @file OutputCleanup.cc
/// @brief See OutputCleanup.h.

#include "OutputCleanup.h"

#include "BackgroundRemover.h"

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include <sys/stat.h>
#include <unistd.h>

namespace nonbloppy_tool {

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

namespace {

/// Link @a target to a new name beside it and return that name ("" if no link could be
/// made): `target.nonbloppy-old-<pid>`, or `.nonbloppy-old-<pid>` in the same directory
/// where that name would be longer than the directory allows (an output name of about 230
/// bytes or more, with the pid's digits), with -2, -3, ... appended while the name is taken
/// (by a killed run of the same pid: containers reuse them). Both cases lost the old file on
/// a failure: the link() failed, and the undo then only removed the new file (bug hunt).
std::string linkBeside(const std::string& target)
{
    const size_t slash = target.rfind('/');
    const std::string directory = slash == std::string::npos ? std::string() : target.substr(0, slash + 1);
    const std::string suffix = "nonbloppy-old-" + std::to_string(::getpid());
    const long maxName = ::pathconf(directory.empty() ? "." : directory.c_str(), _PC_NAME_MAX);
    const size_t limit = maxName > 0 ? size_t(maxName) : 255;
    constexpr size_t kCounterRoom = 4;  // "-100"
    const size_t nameLength = target.size() - directory.size();
    const std::string stem = nameLength + 1 + suffix.size() + kCounterRoom <= limit ? target + "." + suffix
                                                                                     : directory + "." + suffix;
    for (int attempt = 1; attempt <= 100; ++attempt) {
        const std::string name = attempt == 1 ? stem : stem + "-" + std::to_string(attempt);
        if (::link(target.c_str(), name.c_str()) == 0) return name;
        if (errno != EEXIST) break;
    }
    return std::string();
}

} // namespace

void OutputCleanup::willWrite(const std::string& path)
{
    // Undone through the target: removing @a path itself would delete the user's link to a
    // file that did not exist yet and leave the new file behind.
    Output output{writtenFile(path), "", false};
    struct stat existing{};
    if (::stat(output.target.c_str(), &existing) == 0) output.backup = linkBeside(output.target);
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
