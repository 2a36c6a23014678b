// SPDX-License-Identifier: Apache-2.0
/// @file StreamReader.h
/// @brief Private: a bounded read buffer over a file or a memory block, optionally
///        inflating gzip on the fly, for the readers that stream into their final arrays
///        (ReadBgeo.cc, ReadTable.cc); and the path-taking entry points of those readers.
///
/// A StreamReader holds one chunk of the data (kChunkBytes; less for a smaller file)
/// plus, for gzip, a quarter chunk of compressed input. The buffer grows beyond a chunk only
/// when a caller asks for one contiguous piece longer than that (a very long text line).
/// Errors are those of loadFile() and decode_internal::gunzip(), word for word.

#ifndef NONBLOPPY_STREAM_READER_H
#define NONBLOPPY_STREAM_READER_H

#include "Decode.h"
#include "FileFormats.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/Particles.h>

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

namespace nonbloppy {
namespace io_internal {

/// Streaming versions of readBgeoParticles(), readTableParticles() and
/// readJsonParticles() (ParticleReaders.h): the same results and messages, but the file is
/// read through a StreamReader instead of being loaded whole first. Pipes and other
/// non-regular files are still loaded whole (they have no size to check counts against).
ParticleSet readBgeoFile(const std::string& path);
ParticleSet readTableFile(const std::string& path);
ParticleSet readJsonFile(const std::string& path);

/// A read position in a file or memory block, with a bounded buffer of the bytes ahead.
class StreamReader
{
public:
    /// Read @a size bytes at @a data (not copied; they must outlive the reader). With
    /// @a inflateGzip, data starting with the gzip magic is inflated as it is read.
    StreamReader(const char* data, size_t size, const std::string& path, bool inflateGzip)
        : mPath(path), mMemory(data), mMemorySize(size), mRawSize(size)
    {
        start(inflateGzip);
    }

    /// Read the file @a path; a pipe or other non-regular file is loaded whole first.
    StreamReader(const std::string& path, bool inflateGzip) : mPath(path)
    {
        const OpenFile file = openFile(path);
        if (file.regular) {
            mFd = file.fd;
            mRawSize = file.size;
        } else {
            // A pipe has no size to check counts against: read it whole.
            mWhole = readToEndAndClose(file.fd, path, 0);
            mMemory = mWhole.data();
            mMemorySize = mRawSize = mWhole.size();
        }
        try {
            start(inflateGzip);
        } catch (...) {
            closeFile();  // the destructor does not run when the constructor throws
            throw;
        }
    }

    ~StreamReader()
    {
        closeFile();
        if (mGzip) inflateEnd(&mZ);
    }
    StreamReader(const StreamReader&) = delete;
    StreamReader& operator=(const StreamReader&) = delete;

    /// True if the input is gzip and is being inflated.
    bool compressed() const { return mGzip; }
    /// Offset of here() in the (inflated) data.
    uint64_t pos() const { return mBufferStart + mHead; }
    /// Bytes left to read; meaningful only if not compressed().
    uint64_t remaining() const { return mRawSize - std::min(mRawSize, pos()); }
    /// Compressed bytes the inflater has not consumed yet.
    uint64_t rawRemaining() const { return mRawSize - mRawPos + (mGzip ? mZ.avail_in : 0); }

    const char* here() const { return mBuffer.data() + mHead; }
    size_t available() const { return mTail - mHead; }
    void advance(size_t n) { mHead += std::min(n, available()); }

    /// True once at least @a n bytes are buffered at here(); false if the data ends first.
    bool ensure(size_t n)
    {
        while (available() < n) {
            if (!fill(n)) return false;
        }
        return true;
    }

    /// Move past @a n bytes; false if the data ends first.
    bool skip(uint64_t n)
    {
        while (n > 0) {
            if (available() == 0 && !fill(1)) return false;
            const size_t step = size_t(std::min<uint64_t>(n, available()));
            mHead += step;
            n -= step;
        }
        return true;
    }

    /// Back to the first byte, as when just made, to read the data again (a file is read
    /// again from disk; memory and a pipe loaded whole are not copied). Not for gzip, whose
    /// inflater has moved on: @throw FileError then. Cost: a seek.
    void rewind()
    {
        if (mGzip) fail(mPath, "cannot read compressed data twice");
        if (mFd >= 0 && ::lseek(mFd, 0, SEEK_SET) != 0) failRead(mPath, errno);
        mRawPos = 0;
        mHead = mTail = 0;
        mBufferStart = 0;
        mPeekUsed = mPeekPos = 0;  // peeked bytes are read again from the file
    }

    /// For gzip, inflate the rest, keeping nothing: its errors then come first, as when the
    /// whole file was inflated before parsing, and pos() becomes the inflated size.
    void drain()
    {
        if (!mGzip || mGzipFailed) return;
        mHead = mTail;
        while (fill(1)) mHead = mTail;
    }

    /// The next line without its '\n' (a '\r' is kept); false at the end of the data.
    /// The view is valid until the next call on this reader.
    bool line(std::string_view& text)
    {
        if (!ensure(1)) return false;
        size_t length = 0;
        for (;;) {
            const void* newline = std::memchr(here() + length, '\n', available() - length);
            if (newline) {
                length = size_t(static_cast<const char*>(newline) - here());
                text = std::string_view(here(), length);
                mHead += length + 1;
                return true;
            }
            length = available();
            if (!fill(length + 1)) break;
        }
        text = std::string_view(here(), length);
        mHead += length;
        return true;
    }

    /// An input iterator over the bytes (for nlohmann::json::sax_parse); a default-made one
    /// is the end. With @a recentChars, it keeps the last three bytes passed there (the
    /// latest in the low byte): the JSON reader tells "-0" from "0" by them.
    class CharIterator
    {
    public:
        using iterator_category = std::input_iterator_tag;
        using value_type = char;
        using difference_type = std::ptrdiff_t;
        using pointer = const char*;
        using reference = const char&;

        CharIterator() = default;
        explicit CharIterator(StreamReader& reader, uint32_t* recentChars = nullptr)
            : mReader(&reader), mRecent(recentChars) {}
        const char& operator*() const { return *mReader->here(); }
        CharIterator& operator++()
        {
            if (mRecent) *mRecent = ((*mRecent << 8) | static_cast<unsigned char>(*mReader->here())) & 0xffffff;
            ++mReader->mHead;
            return *this;
        }
        bool operator==(const CharIterator& other) const { return atEnd() == other.atEnd(); }
        bool operator!=(const CharIterator& other) const { return !(*this == other); }

    private:
        bool atEnd() const
        {
            return !mReader || (mReader->mHead == mReader->mTail && !mReader->ensure(1));
        }
        StreamReader* mReader = nullptr;
        uint32_t* mRecent = nullptr;
    };

private:
    void closeFile()
    {
        if (mFd >= 0) ::close(mFd);
        mFd = -1;
    }

    /// Up to @a n raw (file or memory) bytes to @a dst; 0 only at the end.
    size_t rawRead(unsigned char* dst, size_t n)
    {
        if (mFd < 0) {
            const size_t step = size_t(std::min<uint64_t>(n, mMemorySize - mRawPos));
            if (step > 0) std::memcpy(dst, mMemory + mRawPos, step);
            mRawPos += step;
            return step;
        }
        for (;;) {
            const ssize_t got = ::read(mFd, dst, std::min<size_t>(n, size_t(1) << 30));
            if (got < 0) {
                if (errno == EINTR) continue;
                failRead(mPath, errno);
            }
            mRawPos += uint64_t(got);
            return size_t(got);
        }
    }

    /// Up to @a n data bytes (inflated for gzip) to @a dst; 0 only at the end.
    size_t produce(unsigned char* dst, size_t n)
    {
        if (mPeekUsed > 0) {
            // The bytes read to look for the gzip magic come first.
            const size_t step = std::min(n, mPeekUsed - mPeekPos);
            std::memcpy(dst, mRawBuffer.data() + mPeekPos, step);
            mPeekPos += step;
            if (mPeekPos == mPeekUsed) {
                mPeekUsed = mPeekPos = 0;
                std::vector<unsigned char>().swap(mRawBuffer);
            }
            return step;
        }
        if (!mGzip) return rawRead(dst, n);
        if (mGzipEnded) return 0;
        n = std::min<size_t>(n, std::numeric_limits<uInt>::max());
        for (;;) {
            if (mZ.avail_in == 0) {
                if (mFd < 0) {
                    // Inflate straight from the memory block.
                    const size_t step = size_t(std::min<uint64_t>(mMemorySize - mRawPos,
                                                                  std::numeric_limits<uInt>::max()));
                    mZ.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(mMemory + mRawPos));
                    mZ.avail_in = uInt(step);
                    mRawPos += step;
                } else {
                    mZ.next_in = mRawBuffer.data();
                    mZ.avail_in = uInt(rawRead(mRawBuffer.data(), mRawBuffer.size()));
                }
            }
            const uInt inBefore = mZ.avail_in;
            mZ.next_out = dst;
            mZ.avail_out = uInt(n);
            const int status = inflate(&mZ, Z_NO_FLUSH);
            const size_t produced = n - mZ.avail_out;
            mInflated += produced;
            if (mInflated > mRawSize * decode_internal::kMaxInflateRatio + 4096) {
                gzipFail("corrupt gzip data: expands beyond deflate's limits");
            }
            if (status == Z_STREAM_END) {
                mGzipEnded = true;
                return produced;
            }
            if (status == Z_BUF_ERROR && inBefore == 0) gzipFail("truncated gzip data");
            if (status != Z_OK && status != Z_BUF_ERROR) {
                gzipFail("corrupt gzip data: " +
                         (mZ.msg ? std::string(mZ.msg) : "error " + std::to_string(status)));
            }
            if (produced > 0) return produced;
        }
    }

    [[noreturn]] void gzipFail(const std::string& message)
    {
        mGzipFailed = true;
        fail(mPath, message);
    }

    /// Read more data behind the buffered bytes, with room for at least @a want bytes in
    /// all; false at the end of the data.
    bool fill(size_t want)
    {
        if (mHead > 0) {
            std::memmove(mBuffer.data(), mBuffer.data() + mHead, mTail - mHead);
            mBufferStart += mHead;
            mTail -= mHead;
            mHead = 0;
        }
        // A small file gets a buffer of its size, not a whole chunk.
        size_t size = mGzip ? kChunkBytes
                            : size_t(std::min<uint64_t>(std::max<uint64_t>(mRawSize, 64), kChunkBytes));
        while (size < want) size *= 2;
        if (size > mBuffer.size()) mBuffer.resize(size);
        const size_t got = produce(reinterpret_cast<unsigned char*>(mBuffer.data()) + mTail,
                                   mBuffer.size() - mTail);
        mTail += got;
        return got > 0;
    }

    void start(bool inflateGzip)
    {
        if (!inflateGzip) return;
        char magic[2];
        size_t have = 0;
        if (mFd < 0) {
            have = size_t(std::min<uint64_t>(2, mMemorySize));
            if (have > 0) std::memcpy(magic, mMemory, have);
        } else {
            mRawBuffer.resize(size_t(std::min<uint64_t>(std::max<uint64_t>(mRawSize, 64), kChunkBytes / 4)));
            mPeekUsed = rawRead(mRawBuffer.data(), mRawBuffer.size());
            have = std::min<size_t>(2, mPeekUsed);
            if (have > 0) std::memcpy(magic, mRawBuffer.data(), have);
        }
        if (!decode_internal::isGzip(magic, have)) return;  // produce() hands out the peeked bytes
        if (inflateInit2(&mZ, 16 + MAX_WBITS) != Z_OK) fail(mPath, "cannot initialise zlib");
        mGzip = true;
        if (mFd >= 0) {
            mZ.next_in = mRawBuffer.data();
            mZ.avail_in = uInt(mPeekUsed);
            mPeekUsed = 0;
        }
    }

    const std::string& mPath;
    int mFd = -1;
    std::vector<char> mWhole;            ///< a non-regular file, loaded whole
    const char* mMemory = nullptr;       ///< the memory block (or mWhole)
    size_t mMemorySize = 0;
    uint64_t mRawSize = 0;               ///< file or memory size
    uint64_t mRawPos = 0;                ///< raw bytes taken from the file or memory

    std::vector<char> mBuffer;           ///< data; the unread bytes are [mHead, mTail)
    size_t mHead = 0, mTail = 0;
    uint64_t mBufferStart = 0;           ///< data offset of mBuffer[0]

    std::vector<unsigned char> mRawBuffer;  ///< compressed input, or the peeked first bytes
    size_t mPeekUsed = 0, mPeekPos = 0;     ///< peeked bytes not yet handed out (not gzip)

    bool mGzip = false, mGzipEnded = false, mGzipFailed = false;
    z_stream mZ{};
    uint64_t mInflated = 0;
};

} // namespace io_internal
} // namespace nonbloppy

#endif // NONBLOPPY_STREAM_READER_H
