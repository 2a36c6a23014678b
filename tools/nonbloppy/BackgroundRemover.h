// SPDX-License-Identifier: Apache-2.0
/// @file BackgroundRemover.h
/// @brief Removes files on a thread of its own: dropping the last link to a large file the
///        run has just replaced makes the file system free its blocks, and that wait need not
///        hold up the frame, the next frame or the end of the run.
///
/// @code
/// BackgroundRemover remover;          // no thread until the first remove()
/// remover.remove("mesh.ply.nonbloppy-old-4242");
/// // ... more work ...
/// // ~BackgroundRemover() returns once every queued file is removed.
/// @endcode
///
/// Why: on this project's test machine (ext4 mounted with `discard`), unlinking a 120 MB file
/// written with O_DIRECT blocks for 16-17 ms while using no CPU (`rm` of a `dd oflag=direct`
/// file, strace -T; /usr/bin/time shows 0.00 s of system time). A mesh replacing an earlier
/// run's drops the old one's last link when the run succeeds (OutputCleanup.h), so every
/// re-meshed frame used to wait for that. The thread only waits in the kernel, so it does
/// not count against --threads.

#ifndef NONBLOPPY_TOOL_BACKGROUND_REMOVER_H
#define NONBLOPPY_TOOL_BACKGROUND_REMOVER_H

#include <condition_variable>
#include <deque>
#include <mutex>
#include <string>
#include <thread>

namespace nonbloppy_tool {

/// A queue of files to unlink, served in order by one thread. Thread-safe.
class BackgroundRemover
{
public:
    BackgroundRemover() = default;
    /// Waits until every queued file is removed.
    ~BackgroundRemover();

    BackgroundRemover(const BackgroundRemover&) = delete;
    BackgroundRemover& operator=(const BackgroundRemover&) = delete;

    /// Queue @a path for unlink(2). A failure is ignored, as a failed unlink of the caller's
    /// own would be: the paths given are links the caller made and nobody else relies on.
    /// If the thread cannot be started, @a path is removed before this returns.
    void remove(std::string path);

private:
    void serve();

    std::mutex mMutex;
    std::condition_variable mWake;
    std::deque<std::string> mQueue;
    bool mStopping = false;
    std::thread mThread;
};

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_BACKGROUND_REMOVER_H
