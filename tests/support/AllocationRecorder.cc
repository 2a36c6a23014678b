// SPDX-License-Identifier: Apache-2.0
/// @file AllocationRecorder.cc
/// @brief largestAllocationDuring(), and the global operator new it records through.

#include "AllocationRecorder.h"

#include <cstdlib>
#include <new>

namespace {

// Recording happens on the armed thread only, and only while it is armed.
thread_local bool tRecordAllocations = false;
thread_local size_t tLargestAllocation = 0;

void*
recordedAllocation(std::size_t size) noexcept
{
    if (tRecordAllocations && size > tLargestAllocation) tLargestAllocation = size;
    return std::malloc(size == 0 ? 1 : size);
}

} // namespace

// Every non-aligned form is replaced, so all of them pair malloc with free (AddressSanitizer
// checks that allocation and deallocation functions match); aligned forms stay the library's.
void*
operator new(std::size_t size)
{
    if (void* p = recordedAllocation(size)) return p;
    throw std::bad_alloc();
}

void*
operator new[](std::size_t size)
{
    if (void* p = recordedAllocation(size)) return p;
    throw std::bad_alloc();
}

void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return recordedAllocation(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return recordedAllocation(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace nonbloppy_test {

size_t
largestAllocationDuring(const std::function<void()>& work)
{
    struct Disarm  // on every way out, a throw from @a work included
    {
        ~Disarm() { tRecordAllocations = false; }
    } disarm;
    tLargestAllocation = 0;
    tRecordAllocations = true;
    work();
    return tLargestAllocation;
}

} // namespace nonbloppy_test
