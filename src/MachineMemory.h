// SPDX-License-Identifier: Apache-2.0
/// @file MachineMemory.h
/// @brief Private: how much memory this process can have, so that a stage whose data
///        cannot fit is refused with a message naming its parameters before it allocates,
///        instead of ending in std::bad_alloc ("out of memory") or the kernel's OOM killer.

#ifndef NONBLOPPY_MACHINE_MEMORY_H
#define NONBLOPPY_MACHINE_MEMORY_H

#include <nonbloppy/CgroupLimits.h>
#include <nonbloppy/Error.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>

namespace nonbloppy {
namespace machine_memory_internal {

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
/// machine's memory, its address space against ulimit -v, its data against ulimit -d, and
/// cgroupMemoryHeadroomBytes(), which counts every cgroup up to the root); -1 if unknown.
/// Concurrent work in the process (frames meshed side by side) is counted as far as it has
/// got. Cost: reads of /proc/self/statm, /proc/self/cgroup and three files per cgroup level.
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
    if (const std::optional<double> cgroup = cgroupMemoryHeadroomBytes())
        headroom = headroom >= 0.0 ? std::min(headroom, *cgroup) : *cgroup;
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
