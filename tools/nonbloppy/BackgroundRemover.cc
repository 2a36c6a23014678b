// SPDX-License-Identifier: Apache-2.0
/// @file BackgroundRemover.cc
/// @brief See BackgroundRemover.h.

#include "BackgroundRemover.h"

#include <system_error>
#include <utility>

#include <unistd.h>

namespace nonbloppy_tool {

BackgroundRemover::~BackgroundRemover()
{
    {
        std::lock_guard<std::mutex> lock(mMutex);
        mStopping = true;
    }
    mWake.notify_one();
    if (mThread.joinable()) mThread.join();
}

void
BackgroundRemover::remove(std::string path)
{
    {
        std::lock_guard<std::mutex> lock(mMutex);
        if (!mThread.joinable()) {
            try {
                mThread = std::thread([this] { serve(); });
            } catch (const std::system_error&) {
                ::unlink(path.c_str());  // no thread to be had: remove it here, as before
                return;
            }
        }
        mQueue.push_back(std::move(path));
    }
    mWake.notify_one();
}

void
BackgroundRemover::serve()
{
    std::unique_lock<std::mutex> lock(mMutex);
    for (;;) {
        mWake.wait(lock, [this] { return mStopping || !mQueue.empty(); });
        if (mQueue.empty()) return;  // stopping, and nothing left
        const std::string path = std::move(mQueue.front());
        mQueue.pop_front();
        lock.unlock();
        ::unlink(path.c_str());
        lock.lock();
    }
}

} // namespace nonbloppy_tool
