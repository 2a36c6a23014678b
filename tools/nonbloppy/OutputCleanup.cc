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

void OutputCleanup::willWrite(const std::string& path)
{
    Output output{path, path, "", false};
    std::error_code error;
    if (std::filesystem::exists(path, error)) {
        const std::filesystem::path target = std::filesystem::canonical(path, error);
        if (!error) {
            output.target = target.string();
            const std::string backup = output.target + ".nonbloppy-old-" + std::to_string(::getpid());
            if (::link(output.target.c_str(), backup.c_str()) == 0) output.backup = backup;
        }
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
            std::remove(output.path.c_str());
        }
    }
}

} // namespace nonbloppy_tool
