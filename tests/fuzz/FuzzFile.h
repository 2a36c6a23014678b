// SPDX-License-Identifier: Apache-2.0
/// @file FuzzFile.h
/// @brief For the targets whose reader takes a path (readParticles() streams legacy VTK, PLY
///        and XYZ from the file): the input written to a tmpfs file with the extension that
///        selects the reader, one file per process, removed at exit.

#ifndef NONBLOPPY_FUZZ_FILE_H
#define NONBLOPPY_FUZZ_FILE_H

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <unistd.h>

namespace nonbloppy_fuzz {

inline std::string&
inputPath()
{
    static std::string path;
    return path;
}

/// Write @a size bytes to /dev/shm/nonbloppy-fuzz-<pid><extension> and return the path.
inline const std::string&
writeInput(const uint8_t* bytes, size_t size, const char* extension)
{
    std::string& path = inputPath();
    if (path.empty()) {
        path = "/dev/shm/nonbloppy-fuzz-" + std::to_string(getpid()) + extension;
        std::atexit([] { std::remove(inputPath().c_str()); });
    }
    FILE* file = std::fopen(path.c_str(), "wb");
    if (!file || (size > 0 && std::fwrite(bytes, 1, size, file) != size) || std::fclose(file) != 0) {
        std::perror(path.c_str());
        std::abort();
    }
    return path;
}

} // namespace nonbloppy_fuzz

#endif // NONBLOPPY_FUZZ_FILE_H
