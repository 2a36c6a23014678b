// SPDX-License-Identifier: Apache-2.0
/// @file AllocationRecorder.h
/// @brief The largest single operator new request a piece of work makes on its thread: how
///        the tests show that a reader refuses a hostile count before allocating for it.
///        AllocationRecorder.cc replaces the global operator new of the test binary.

#ifndef NONBLOPPY_TEST_ALLOCATION_RECORDER_H
#define NONBLOPPY_TEST_ALLOCATION_RECORDER_H

#include <cstddef>
#include <functional>

namespace nonbloppy_test {

/// Run @a work and return the largest single operator new request made on this thread
/// while it ran (allocations of other threads are not seen). Exceptions from @a work
/// propagate, with recording switched off.
size_t largestAllocationDuring(const std::function<void()>& work);

} // namespace nonbloppy_test

#endif // NONBLOPPY_TEST_ALLOCATION_RECORDER_H
