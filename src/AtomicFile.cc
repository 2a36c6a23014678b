// SPDX-License-Identifier: Apache-2.0
/// @file AtomicFile.cc
/// @brief Temporary-file-and-rename writing (see AtomicFile.h).

#include "AtomicFile.h"
#include "SystemBuffer.h"

#include <nonbloppy/Error.h>

#include <algorithm>
#include <condition_variable>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <new>
#include <streambuf>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#if defined(__linux__)
#include <linux/magic.h>
#include <sys/vfs.h>
#endif

namespace nonbloppy {

namespace {

[[noreturn]] void
throwWriteError(const std::string& path, int errorNumber)
{
    throw FileError("cannot write " + path + ": " + std::strerror(errorNumber));
}

/// The mode a file created with open(path, O_CREAT, 0666) would get. mkstemp() creates
/// 0600 files, which would make every output unreadable for other users of a render farm.
/// The umask is read from /proc because umask() can only be queried by changing it, which
/// is not thread-safe.
mode_t
newFileMode(const std::string& path)
{
    struct stat existing;
    if (::stat(path.c_str(), &existing) == 0) return existing.st_mode & 07777;

    mode_t mask = 022;
    if (std::FILE* status = std::fopen("/proc/self/status", "r")) {
        char line[256];
        while (std::fgets(line, sizeof(line), status)) {
            if (std::strncmp(line, "Umask:", 6) == 0) {
                mask = mode_t(std::strtoul(line + 6, nullptr, 8));
                break;
            }
        }
        std::fclose(status);
    }
    return 0666 & ~mask;
}

/// A std::streambuf writing a file with O_DIRECT: bytes collect in a 4 MiB buffer aligned to
/// 4096 bytes; a full buffer goes to a writer thread, which writes it (whole blocks at
/// block-aligned offsets, as O_DIRECT requires on every Linux file system) while the caller
/// fills the second buffer. finish() waits for that thread, writes the whole blocks left and
/// then the last partial block with O_DIRECT cleared.
///
/// Why a thread: a direct write returns only when the device has the data (2.5 ms per
/// buffer here, 70 ms for the 64x benchmark mesh), and the caller's encoding and copying
/// would wait for it. The bytes and their order are the same; an error of the writer
/// thread fails the next buffer handed over, or finish(), with its errno.
class DirectFileBuf : public std::streambuf
{
public:
    DirectFileBuf() = default;
    ~DirectFileBuf() override
    {
        stopWriter();
        if (mFd >= 0) ::close(mFd);
    }
    DirectFileBuf(const DirectFileBuf&) = delete;
    DirectFileBuf& operator=(const DirectFileBuf&) = delete;

    /// Open @a path (it exists) for writing with O_DIRECT. False if that is refused, or if
    /// its two blocks cannot be mapped.
    bool open(const std::string& path)
    {
#if defined(O_DIRECT)
        try {
            for (memory_internal::SystemBuffer& buffer : mBuffers) {
                buffer = memory_internal::SystemBuffer(kBufferBytes);  // page-aligned
            }
        } catch (const std::bad_alloc&) {
            return false;  // no room for the blocks: the caller writes through the page cache
        }
        mFd = ::open(path.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC | O_DIRECT);
        if (mFd < 0) return false;
        setp(mBuffers[0].data(), mBuffers[0].data() + kBufferBytes);
        return true;
#else
        (void)path;
        return false;
#endif
    }

    /// Write what is left and close the file. False with errno set on failure.
    bool finish()
    {
        bool ok = waitForWriter();
        stopWriter();
        char* buffer = pbase();
        const size_t size = size_t(pptr() - pbase());
        const size_t whole = size & ~(kAlignment - 1);
        ok = ok && writeAll(buffer, whole) && (size == whole || (stopDirect() && writeAll(buffer + whole, size - whole)));
        const int error = errno;
        setp(buffer, buffer + kBufferBytes);
        const int fd = mFd;
        mFd = -1;
        if (::close(fd) != 0) ok = false;
        else errno = error;
        return ok;
    }

protected:
    int_type overflow(int_type ch) override
    {
        if (!flushBuffer()) return traits_type::eof();
        if (!traits_type::eq_int_type(ch, traits_type::eof())) {
            *pptr() = traits_type::to_char_type(ch);
            pbump(1);
        }
        return traits_type::not_eof(ch);
    }

    std::streamsize xsputn(const char* data, std::streamsize count) override
    {
        std::streamsize done = 0;
        while (done < count) {
            if (pptr() == epptr() && !flushBuffer()) return done;
            const std::streamsize room = std::min<std::streamsize>(epptr() - pptr(), count - done);
            std::memcpy(pptr(), data + done, size_t(room));
            pbump(int(room));
            done += room;
        }
        return done;
    }

private:
    static constexpr size_t kAlignment = 4096;
    static constexpr size_t kBufferBytes = size_t(4) << 20;

    /// Hand the full buffer to the writer thread (started on first use) and go on in the
    /// other one; false (errno set) if the writer failed on an earlier buffer.
    bool flushBuffer()
    {
        if (!waitForWriter()) return false;
        char* full = pbase();
        const size_t size = size_t(pptr() - pbase());
        {
            std::lock_guard<std::mutex> lock(mMutex);
            mPending = full;
            mPendingSize = size;
        }
        if (!mWriter.joinable()) mWriter = std::thread([this] { writerLoop(); });
        mChanged.notify_all();
        char* next = full == mBuffers[0].data() ? mBuffers[1].data() : mBuffers[0].data();
        setp(next, next + kBufferBytes);
        return true;
    }

    /// Wait until the writer thread holds no buffer; false (errno set) if it failed.
    bool waitForWriter()
    {
        std::unique_lock<std::mutex> lock(mMutex);
        mChanged.wait(lock, [this] { return mPending == nullptr; });
        if (mWriterError != 0) {
            errno = mWriterError;
            return false;
        }
        return true;
    }

    void writerLoop()
    {
        std::unique_lock<std::mutex> lock(mMutex);
        for (;;) {
            mChanged.wait(lock, [this] { return mPending != nullptr || mStopping; });
            if (!mPending) return;  // stopping, nothing left
            const char* data = mPending;
            const size_t size = mPendingSize;
            lock.unlock();
            const bool ok = mWriterError == 0 && writeAll(data, size);  // after an error: skip
            const int error = errno;
            lock.lock();
            if (!ok && mWriterError == 0) mWriterError = error ? error : EIO;
            mPending = nullptr;
            mChanged.notify_all();
        }
    }

    /// End the writer thread (after the buffer it holds, if any).
    void stopWriter()
    {
        if (!mWriter.joinable()) return;
        {
            std::lock_guard<std::mutex> lock(mMutex);
            mStopping = true;
        }
        mChanged.notify_all();
        mWriter.join();
    }

    /// Clear O_DIRECT (once): the following writes go through the page cache.
    bool stopDirect()
    {
        if (mBuffered) return true;
        mBuffered = true;
#if defined(O_DIRECT)
        const int flags = ::fcntl(mFd, F_GETFL);
        return flags >= 0 && ::fcntl(mFd, F_SETFL, flags & ~O_DIRECT) == 0;
#else
        return true;
#endif
    }

    /// Write @a size bytes, retrying on EINTR. A direct write the file system rejects
    /// (EINVAL: stricter alignment than 4096) or cuts short (which leaves the offset
    /// unaligned) is finished through the page cache.
    bool writeAll(const char* data, size_t size)
    {
        while (size > 0) {
            const ssize_t written = ::write(mFd, data, size);
            if (written < 0) {
                if (errno == EINTR) continue;
                if (errno == EINVAL && !mBuffered) {
                    if (!stopDirect()) return false;
                    continue;
                }
                return false;
            }
            if (written == 0) {
                errno = EIO;
                return false;
            }
            data += written;
            size -= size_t(written);
            if (size > 0 && !stopDirect()) return false;
        }
        return true;
    }

    int mFd = -1;
    memory_internal::SystemBuffer mBuffers[2];  ///< mapped, not from malloc (see SystemBuffer.h)
    bool mBuffered = false;  ///< O_DIRECT cleared: after a rejected or short write, or for the tail

    // The writer thread and the buffer it holds. mFd, mBuffered and writeAll() belong to
    // the writer thread while it holds a buffer, to the caller otherwise.
    std::thread mWriter;
    std::mutex mMutex;
    std::condition_variable mChanged;
    const char* mPending = nullptr;  ///< handed to the writer thread, not yet written
    size_t mPendingSize = 0;
    int mWriterError = 0;            ///< errno of the writer thread's first failure
    bool mStopping = false;
};

/// Run @a writeContents on a stream over @a buffer, then @a finish it; errors as
/// writeFileAtomically() documents.
template<typename FinishT>
void writeThrough(std::streambuf& buffer, const std::string& path,
                  const std::function<void(std::ostream&)>& writeContents, FinishT finish)
{
    errno = 0; // so a stream failure reports its own cause, not a stale one
    std::ostream os(&buffer);
    try {
        writeContents(os);
    } catch (const Error&) {
        throw; // already one line naming what went wrong (e.g. cancelled)
    } catch (const std::exception& e) {
        throw FileError("cannot write " + path + ": " + e.what());
    }
    os.flush();
    if (!os) throwWriteError(path, errno ? errno : EIO);
    if (!finish()) throwWriteError(path, errno ? errno : EIO);
}

} // namespace

bool
directIoSuitable(const std::string& path)
{
#if defined(__linux__) && defined(O_DIRECT)
    struct statfs info;
    if (::statfs(path.c_str(), &info) != 0) return false;
    switch (static_cast<unsigned long>(info.f_type)) {
    case EXT4_SUPER_MAGIC:  // also ext2 and ext3
    case XFS_SUPER_MAGIC:
    case BTRFS_SUPER_MAGIC:
        return true;
    default:
        return false;
    }
#else
    (void)path;
    return false;
#endif
}

namespace {

/// @a path with symbolic links followed to the file they name (which need not exist yet),
/// as a shell redirection or cp writes through a link. Replacing the link itself would
/// silently detach whatever it was meant to update.
/// @throw FileError naming @a path after 40 links (a loop), as open() would fail.
std::string followSymlinks(const std::string& path)
{
    namespace fs = std::filesystem;
    fs::path target = path;
    for (int links = 0;; ++links) {
        std::error_code error;
        if (!fs::is_symlink(fs::symlink_status(target, error))) return target.string();
        if (links == 40) throwWriteError(path, ELOOP);
        const fs::path next = fs::read_symlink(target, error);
        if (error) throwWriteError(path, error.value());
        target = next.is_absolute() ? next : target.parent_path() / next;
    }
}

/// mkstemp() pattern of the temporary file for @a target: `target.tmp-XXXXXX`, or, when
/// that name would be longer than the directory allows (a legal name of 245 or more bytes),
/// `.tmp-XXXXXX` in the same directory. Both match the `*.tmp-*` of the cleanup advice.
std::string temporaryPattern(const std::string& target)
{
    constexpr const char* kSuffix = ".tmp-XXXXXX";
    const size_t slash = target.rfind('/');
    const std::string directory = slash == std::string::npos ? "." : target.substr(0, slash + 1);
    const size_t nameLength = target.size() - (slash == std::string::npos ? 0 : slash + 1);
    const long maxName = ::pathconf(directory.c_str(), _PC_NAME_MAX);
    const size_t limit = maxName > 0 ? size_t(maxName) : 255;
    if (nameLength + std::strlen(kSuffix) <= limit) return target + kSuffix;
    return (slash == std::string::npos ? std::string() : target.substr(0, slash + 1)) + kSuffix;
}

/// @throw FileError unless @a target (symbolic links followed) is missing or a regular file:
/// renaming over a device, FIFO or socket would replace the node itself (as root, /dev/null
/// or /dev/full), and over a directory fails only after all the work.
void requireRegularOrMissing(const std::string& path, const std::string& target)
{
    struct stat status{};
    if (::stat(target.c_str(), &status) != 0 || S_ISREG(status.st_mode)) return;
    if (S_ISDIR(status.st_mode)) throwWriteError(path, EISDIR);
    throw FileError("cannot write " + path + ": not a regular file");
}

} // namespace

AtomicFile::AtomicFile(const std::string& path)
    : mPath(path), mTarget(followSymlinks(path))
{
    requireRegularOrMissing(mPath, mTarget);
    std::string pattern = temporaryPattern(mTarget);
    std::vector<char> name(pattern.begin(), pattern.end());
    name.push_back('\0');
    const int fd = ::mkstemp(name.data());
    if (fd < 0) throwWriteError(mPath, errno);
    ::close(fd);
    mTempPath = name.data();
}

AtomicFile::~AtomicFile()
{
    if (!mCommitted && !mTempPath.empty()) ::unlink(mTempPath.c_str());
}

void
AtomicFile::commit()
{
    if (mCommitted) return;
    if (::chmod(mTempPath.c_str(), newFileMode(mTarget)) != 0 ||
        ::rename(mTempPath.c_str(), mTarget.c_str()) != 0)
    {
        const int errorNumber = errno;
        ::unlink(mTempPath.c_str());
        mTempPath.clear();
        throwWriteError(mPath, errorNumber);
    }
    mCommitted = true;
}

bool
writeFileAtomically(const std::string& path,
                    const std::function<void(std::ostream&)>& writeContents,
                    size_t expectedBytes)
{
    AtomicFile file(path);
    if (expectedBytes >= kDirectIoMinBytes && directIoSuitable(file.tempPath())) {
        DirectFileBuf direct;
        if (direct.open(file.tempPath())) {
            writeThrough(direct, path, writeContents, [&] { return direct.finish(); });
            file.commit();
            return true;
        }
    }
    std::filebuf buffer;
    errno = 0;
    if (!buffer.open(file.tempPath(), std::ios::out | std::ios::binary | std::ios::trunc)) {
        throwWriteError(path, errno ? errno : EIO);
    }
    writeThrough(buffer, path, writeContents, [&] { return buffer.close() != nullptr; });
    file.commit();
    return false;
}

} // namespace nonbloppy
