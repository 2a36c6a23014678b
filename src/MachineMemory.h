// SPDX-License-Identifier: Apache-2.0
/// @file MachineMemory.h
/// @brief Private: how much memory this process can have, so that a stage whose data
///        cannot fit is refused with a message naming its parameters before it allocates,
///        instead of ending in std::bad_alloc ("out of memory") or the kernel's OOM killer.

#ifndef NONBLOPPY_MACHINE_MEMORY_H
#define NONBLOPPY_MACHINE_MEMORY_H

#include <nonbloppy/Error.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>

namespace nonbloppy {
namespace machine_memory_internal {

/// The first number in the file @a path, or -1 if it holds none (missing, or "max").
inline double numberInFile(const std::string& path)
{
    double value = -1.0;
    if (FILE* file = std::fopen(path.c_str(), "r")) {
        if (std::fscanf(file, "%lf", &value) != 1) value = -1.0;
        std::fclose(file);
    }
    return value;
}

/// The value of @a key in a cgroup memory.stat file @a path ("inactive_file 123"), or 0.
inline double statInFile(const std::string& path, const std::string& key)
{
    double value = 0.0;
    if (FILE* file = std::fopen(path.c_str(), "r")) {
        char name[256];
        double number = 0.0;
        while (std::fscanf(file, "%255s %lf", name, &number) == 2) {
            if (key == name) {
                value = number;
                break;
            }
        }
        std::fclose(file);
    }
    return value;
}

/// What the process's memory cgroup lets it still take, in bytes, as a batch scheduler
/// (Slurm, Kubernetes) limits it: the limit less the usage, not counting the inactive page
/// cache, which the kernel reclaims first (files read or written before). cgroup v2
/// memory.max, memory.current and memory.stat, or v1 memory.limit_in_bytes,
/// memory.usage_in_bytes and memory.stat, under the path /proc/self/cgroup names (or the
/// mount's root, as inside a container); -1 without a limit.
inline double cgroupHeadroomBytes()
{
    std::string unified, memoryV1;
    bool hasV1 = false;
    if (FILE* cgroups = std::fopen("/proc/self/cgroup", "r")) {
        char line[4096];
        while (std::fgets(line, sizeof(line), cgroups)) {
            std::string text(line);
            if (!text.empty() && text.back() == '\n') text.pop_back();
            if (text.compare(0, 3, "0::") == 0) unified = text.substr(3);
            const size_t at = text.find(":memory:");
            if (at != std::string::npos) {
                hasV1 = true;
                memoryV1 = text.substr(at + 8);
            }
        }
        std::fclose(cgroups);
    }
    // A v1 memory controller governs where there is one; else the unified (v2) hierarchy.
    const std::string root = hasV1 ? "/sys/fs/cgroup/memory" : "/sys/fs/cgroup";
    const std::string path = hasV1 ? memoryV1 : unified;
    const char* limitName = hasV1 ? "/memory.limit_in_bytes" : "/memory.max";
    const char* usageName = hasV1 ? "/memory.usage_in_bytes" : "/memory.current";
    const char* inactiveKey = hasV1 ? "total_inactive_file" : "inactive_file";
    for (const std::string& dir : {root + path, root}) {
        const double limit = numberInFile(dir + limitName), usage = numberInFile(dir + usageName);
        // v2 writes no limit as "max", v1 as a page-rounded 2^63.
        if (!(limit > 0.0) || limit > 1e18 || !(usage >= 0.0)) continue;
        const double inactive = statInFile(dir + "/memory.stat", inactiveKey);
        return std::max(0.0, limit - std::max(0.0, usage - inactive));
    }
    return -1.0;
}

/// @a bytes for a message, three significant digits in the largest unit that keeps the
/// number at 1 or more: "512 kB", "131 MB", "3.35 GB", "960 GB" (a refusal under a small
/// ulimit said "0.00131 GB").
inline std::string formatBytes(double bytes)
{
    static const char* const kUnits[] = {"bytes", "kB", "MB", "GB", "TB", "PB"};
    int unit = 0;
    while (unit < 5 && bytes >= 999.5) {
        bytes /= 1000.0;
        ++unit;
    }
    char text[48];
    std::snprintf(text, sizeof(text), "%.3g %s", bytes, kUnits[unit]);
    return text;
}

/// The memory this process can still take, in bytes: the machine's physical memory, or less
/// where ulimit -v or -d or the memory cgroup says so, minus what is held now, measured as
/// each limit counts it (its resident set against the
/// machine's memory, its address space against ulimit -v, its data against ulimit -d); -1
/// if unknown. Concurrent work in the process (frames meshed side by side) is counted as far
/// as it has got. Cost: reads of /proc/self/statm, /proc/self/cgroup and three cgroup files.
inline double memoryHeadroomBytes()
{
    const long pageSize = ::sysconf(_SC_PAGE_SIZE);
    unsigned long sizePages = 0, residentPages = 0, shared = 0, text = 0, lib = 0, dataPages = 0;
    if (FILE* statm = std::fopen("/proc/self/statm", "r")) {
        if (std::fscanf(statm, "%lu %lu %lu %lu %lu %lu", &sizePages, &residentPages, &shared, &text, &lib,
                        &dataPages) != 6) {
            sizePages = residentPages = dataPages = 0;
        }
        std::fclose(statm);
    }
    const double page = pageSize > 0 ? double(pageSize) : 0.0;
    const long physicalPages = ::sysconf(_SC_PHYS_PAGES);
    double headroom = physicalPages > 0 && page > 0.0 ? (double(physicalPages) - double(residentPages)) * page : -1.0;
    const std::pair<int, unsigned long> limits[] = {{RLIMIT_AS, sizePages}, {RLIMIT_DATA, dataPages}};
    for (const auto& [resource, usedPages] : limits) {
        struct rlimit limit{};
        if (::getrlimit(resource, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
            const double left = std::max(0.0, double(limit.rlim_cur) - double(usedPages) * page);
            headroom = headroom >= 0.0 ? std::min(headroom, left) : left;
        }
    }
    const double cgroup = cgroupHeadroomBytes();
    if (cgroup >= 0.0) headroom = headroom >= 0.0 ? std::min(headroom, cgroup) : cgroup;
    return headroom;
}

/// Throw ParameterError("<need>, more than the 2.7 GB this process can still take: <advice>")
/// if @a bytes exceed memoryHeadroomBytes(); nothing where the headroom is unknown. The check
/// of every stage whose memory grows with its input, made before it allocates.
/// @a describe() is called only then, and returns {need, advice}: what would take the bytes
/// ("smoothing the surface (N polygons) would take another 146 MB") and what to give instead.
template<typename DescribeT>
void requireHeadroom(double bytes, DescribeT&& describe)
{
    const double headroom = memoryHeadroomBytes();
    if (!(headroom >= 0.0) || !(bytes > headroom)) return;
    const std::pair<std::string, std::string> needAndAdvice = describe();
    throw ParameterError(needAndAdvice.first + ", more than the " + formatBytes(headroom)
                         + " this process can still take: " + needAndAdvice.second);
}

} // namespace machine_memory_internal
} // namespace nonbloppy

#endif // NONBLOPPY_MACHINE_MEMORY_H
