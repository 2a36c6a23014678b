// SPDX-License-Identifier: Apache-2.0
/// @file UnwrittenVector.h
/// @brief Private helper: a std::vector whose resize() leaves new elements of trivial types
///        unwritten, for large buffers that a parallel loop fills next.
///
/// std::vector::resize() value-initialises, which for floats and Vec3s is a serial memset
/// that also takes every page fault of a new buffer on one thread. With this allocator the
/// parallel loop that fills the buffer touches its pages first, on all threads.
/// @code
/// UnwrittenVector<openvdb::Vec3s> copy(points.size());   // no memset
/// tbb::parallel_for(..., [&](range) { copy[i] = points[i]; ... });
/// @endcode

#ifndef NONBLOPPY_UNWRITTEN_VECTOR_H
#define NONBLOPPY_UNWRITTEN_VECTOR_H

#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace nonbloppy {
namespace memory_internal {

/// std::allocator, except that resize() leaves new elements of trivial types unwritten
/// (default- rather than value-initialised).
template<typename T>
struct UnwrittenAllocator : std::allocator<T>
{
    template<typename U>
    struct rebind
    {
        using other = UnwrittenAllocator<U>;
    };
    UnwrittenAllocator() = default;
    template<typename U>
    UnwrittenAllocator(const UnwrittenAllocator<U>&) noexcept {}
    template<typename U>
    void construct(U* p) noexcept
    {
        ::new (static_cast<void*>(p)) U;
    }
    template<typename U, typename... Args>
    void construct(U* p, Args&&... args)
    {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

template<typename T>
using UnwrittenVector = std::vector<T, UnwrittenAllocator<T>>;

} // namespace memory_internal
} // namespace nonbloppy

#endif // NONBLOPPY_UNWRITTEN_VECTOR_H
