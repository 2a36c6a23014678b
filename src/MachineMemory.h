// SPDX-License-Identifier: Apache-2.0
/// @file MachineMemory.h
/// @brief Private: how much memory this process can have, so that a stage whose data
///        cannot fit is refused with a message naming its parameters before it allocates,
///        instead of ending in std::bad_alloc ("out of memory") or the kernel's OOM killer.

#ifndef NONBLOPPY_MACHINE_MEMORY_H
#define NONBLOPPY_MACHINE_MEMORY_H

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <utility>

namespace nonbloppy {
namespace machine_memory_internal {

/// The memory this process can still take, in bytes: the machine's physical memory, or less
/// where ulimit -v or -d says so, minus what the process holds now, measured as each limit
/// counts it (its resident set against the
/// machine's memory, its address space against ulimit -v, its data against ulimit -d); -1
/// if unknown. Concurrent work in the process (frames meshed side by side) is counted as far
/// as it has got. Cost: a read of /proc/self/statm and three system calls.
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
    return headroom;
}

} // namespace machine_memory_internal
} // namespace nonbloppy

#endif // NONBLOPPY_MACHINE_MEMORY_H
