// SPDX-License-Identifier: Apache-2.0
/// @file SystemBuffer.h
/// @brief Private helper: a byte buffer mapped straight from the system (mmap, so aligned to
///        a page) and handed back to it on destruction (munmap).
///
/// For the writers' multi-megabyte transient buffers (WriteMesh.cc's 8 MB batches, the
/// direct-I/O writer's 4 MiB blocks). From malloc they would come from the calling thread's
/// arena, and a thread other than the main one keeps its arena's free top resident:
/// malloc_trim() shrinks only the main heap's top, and main() sets a trim threshold above
/// any thread heap. A sequence writes each frame on a thread of its own while the next one
/// is meshed (tools/nonbloppy/BatchRun.cc), and three 195k-particle frames then peaked at
/// 133-148 MiB against 113-123 when written on the main thread; with these buffers, as before.
/// @code
/// SystemBuffer batch(8 << 20);   // throws std::bad_alloc when the system has no room
/// encodeInto(batch.data());
/// @endcode

#ifndef NONBLOPPY_SYSTEM_BUFFER_H
#define NONBLOPPY_SYSTEM_BUFFER_H

#include <cstddef>
#include <new>
#include <utility>

#include <sys/mman.h>

namespace nonbloppy {
namespace memory_internal {

/// @a bytes of zeroed, page-aligned memory of its own mapping. Move-only.
/// Cost: one mmap() and one munmap(); each page is faulted in on first touch.
class SystemBuffer
{
public:
    SystemBuffer() = default;
    explicit SystemBuffer(size_t bytes) : mSize(bytes)
    {
        if (bytes == 0) return;
        void* memory = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (memory == MAP_FAILED) throw std::bad_alloc();
        mData = static_cast<char*>(memory);
    }
    ~SystemBuffer()
    {
        if (mData) ::munmap(mData, mSize);
    }
    SystemBuffer(SystemBuffer&& other) noexcept
        : mData(std::exchange(other.mData, nullptr)), mSize(std::exchange(other.mSize, 0)) {}
    SystemBuffer& operator=(SystemBuffer&& other) noexcept
    {
        std::swap(mData, other.mData);
        std::swap(mSize, other.mSize);
        return *this;
    }
    SystemBuffer(const SystemBuffer&) = delete;
    SystemBuffer& operator=(const SystemBuffer&) = delete;

    char* data() const { return mData; }
    size_t size() const { return mSize; }

private:
    char* mData = nullptr;
    size_t mSize = 0;
};

} // namespace memory_internal
} // namespace nonbloppy

#endif // NONBLOPPY_SYSTEM_BUFFER_H
