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

namespace nonbloppy {
namespace machine_memory_internal {

/// The memory this process can use, in bytes: the machine's physical memory, or less where
/// a limit on its address space or data segment (ulimit -v, -d) says so; 0 if unknown.
/// Cost: three system calls.
inline double usableMemoryBytes()
{
    const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGE_SIZE);
    double usable = pages > 0 && pageSize > 0 ? double(pages) * double(pageSize) : 0.0;
    for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
        struct rlimit limit{};
        if (::getrlimit(resource, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
            usable = usable > 0.0 ? std::min(usable, double(limit.rlim_cur)) : double(limit.rlim_cur);
        }
    }
    return usable;
}

} // namespace machine_memory_internal
} // namespace nonbloppy

#endif // NONBLOPPY_MACHINE_MEMORY_H
