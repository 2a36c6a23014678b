// SPDX-License-Identifier: Apache-2.0
/// @file ReadVtu.cc
/// @brief VTK XML UnstructuredGrid / PolyData particles (`.vtu`, `.vtp`), streamed: the XML
///        through expat in chunks, zlib blocks through zlib, base64 decoded as it arrives.
///
/// Data arrays may be `ascii`, inline `binary` (base64) or `appended` (raw or base64),
/// with `vtkZLibDataCompressor` blocks or uncompressed, UInt32 or UInt64 block headers,
/// either byte order. Nothing holds a whole array's text or bytes on the way: inline arrays
/// are decoded from expat's character-data callbacks straight into the ParticleSet, zlib
/// blocks are inflated from the bytes as they come. At the AppendedData element the parser
/// stops; the raw bytes behind the `_` are never parsed as XML. The closing
/// `</AppendedData>` is found from the end of the file, the rest of the document parsed
/// after it, and then every appended array is read from its offset (raw ones with pread()
/// directly into the final arrays). Peak memory: the particles, one 1 MiB chunk, expat's
/// own buffer, a 64 KiB inflate buffer and, for zlib blocks in base64, one compressed block.
///
/// The messages, and which one a file with several faults gets, are those of the earlier
/// whole-buffer reader (pugixml on the file with the raw appended bytes cut out): faults in
/// locating the appended data first, then XML errors anywhere, then the first fault in
/// document order (Points before PointData within a piece). Errors found inside expat's
/// callbacks are recorded, never thrown through the C parser.

#include "ReadVtu.h"

#include "Decode.h"
#include "FileFormats.h"
#include "ParticleReaders.h"

#include <nonbloppy/Error.h>

#include <expat.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <type_traits>
#include <string_view>
#include <utility>

#include <unistd.h>

namespace nonbloppy {
namespace io_internal {

namespace {

using namespace decode_internal;

/// Piece sizes beyond this are rejected outright (and far smaller ones by the byte checks).
constexpr uint64_t kMaxTuples = uint64_t(1) << 40;

/// Output buffer for zlib blocks that cannot be inflated in place (Float64 positions).
constexpr size_t kInflateBytes = size_t(64) << 10;

/// Base64 decoded per stride before it is handed on (Base64Reader's stride, which the
/// length checks depend on).
constexpr size_t kBase64StrideBytes = 3 * 4096;

/// The element type named @a name in a DataArray's `type` attribute, into @a type;
/// false for names VTK does not define.
bool
vtuScalarType(std::string_view name, ScalarType& type)
{
    static const std::pair<const char*, ScalarType> table[] = {
        {"Int8", ScalarType::Int8}, {"UInt8", ScalarType::UInt8}, {"Int16", ScalarType::Int16},
        {"UInt16", ScalarType::UInt16}, {"Int32", ScalarType::Int32}, {"UInt32", ScalarType::UInt32},
        {"Int64", ScalarType::Int64}, {"UInt64", ScalarType::UInt64},
        {"Float32", ScalarType::Float32}, {"Float64", ScalarType::Float64},
        {"Char", ScalarType::Int8}, {"UChar", ScalarType::UInt8}};
    for (const auto& entry : table) {
        if (name == entry.first) {
            type = entry.second;
            return true;
        }
    }
    return false;
}

/// The value of attribute @a name in expat's name/value list, or @a fallback if absent.
const char*
xmlAttribute(const XML_Char** attributes, const char* name, const char* fallback)
{
    for (size_t i = 0; attributes[i] != nullptr; i += 2) {
        if (std::strcmp(attributes[i], name) == 0) return attributes[i + 1];
    }
    return fallback;
}

/// An integer attribute read leniently, as XML DOM libraries do (and the earlier reader did):
/// leading blanks, a sign, decimal or 0x hex digits, anything after them ignored, no digits
/// giving 0, out-of-range values clamped; @a fallback if the attribute is absent.
int
xmlIntAttribute(const XML_Char** attributes, const char* name, int fallback)
{
    const char* s = xmlAttribute(attributes, name, nullptr);
    if (s == nullptr) return fallback;
    while (*s == ' ' || *s == '\t' || *s == '\r' || *s == '\n') ++s;
    const bool negative = *s == '-';
    if (*s == '-' || *s == '+') ++s;
    uint64_t value = 0;
    bool overflow = false;
    auto accumulate = [&](uint64_t digit, uint64_t base) {
        if (value > (uint64_t(1) << 40)) overflow = true;
        else value = value * base + digit;
    };
    if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        for (s += 2;; ++s) {
            const char c = *s;
            if (c >= '0' && c <= '9') accumulate(uint64_t(c - '0'), 16);
            else if (c >= 'a' && c <= 'f') accumulate(uint64_t(c - 'a' + 10), 16);
            else if (c >= 'A' && c <= 'F') accumulate(uint64_t(c - 'A' + 10), 16);
            else break;
        }
    } else {
        for (; *s >= '0' && *s <= '9'; ++s) accumulate(uint64_t(*s - '0'), 10);
    }
    if (negative) return (overflow || value > uint64_t(INT_MAX) + 1) ? INT_MIN : int(-int64_t(value));
    return (overflow || value > uint64_t(INT_MAX)) ? INT_MAX : int(value);
}

// ------------------------------------------------------------------------------------------
// Input

/// The bytes of a VTU file, read by offset: a memory block, or a regular file read with
/// pread() (a pipe is read whole first, since it cannot be seeked).
class VtuInput
{
public:
    /// @a size bytes at @a data, not copied (they must outlive the input).
    VtuInput(const char* data, size_t size, const std::string& path)
        : mPath(path), mMemory(data), mSize(size) {}

    /// The file @a path; a non-regular one is loaded whole.
    explicit VtuInput(const std::string& path) : mPath(path)
    {
        const OpenFile file = openFile(path);
        if (file.regular) {
            mFd = file.fd;
            mSize = file.size;
        } else {
            mWhole = readToEndAndClose(file.fd, path, 0);
            mMemory = mWhole.data();
            mSize = mWhole.size();
        }
    }

    ~VtuInput()
    {
        if (mFd >= 0) ::close(mFd);
    }
    VtuInput(const VtuInput&) = delete;
    VtuInput& operator=(const VtuInput&) = delete;

    /// The file's size in bytes (fstat's, for a regular file).
    uint64_t size() const { return mSize; }
    /// The name used in messages.
    const std::string& path() const { return mPath; }

    /// Up to @a n bytes at @a offset, fewer only at the end: a pointer into the memory
    /// block, or into @a buffer after reading them from the file.
    size_t view(uint64_t offset, size_t n, std::vector<unsigned char>& buffer,
                const unsigned char*& out)
    {
        if (offset >= mSize) return 0;
        n = size_t(std::min<uint64_t>(n, mSize - offset));
        if (mFd < 0) {
            out = reinterpret_cast<const unsigned char*>(mMemory) + offset;
            return n;
        }
        if (buffer.size() < n) buffer.resize(n);
        out = buffer.data();
        return readAt(offset, buffer.data(), n);
    }

    /// Copy up to @a n bytes at @a offset to @a dst; fewer only if the file ends first.
    size_t readAt(uint64_t offset, unsigned char* dst, size_t n)
    {
        if (offset >= mSize) return 0;
        if (mFd < 0) {
            const size_t step = size_t(std::min<uint64_t>(n, mSize - offset));
            std::memcpy(dst, mMemory + offset, step);
            return step;
        }
        size_t done = 0;
        while (done < n) {
            const ssize_t got = ::pread(mFd, dst + done, std::min<size_t>(n - done, size_t(1) << 30),
                                        off_t(offset + done));
            if (got < 0) {
                if (errno == EINTR) continue;
                failRead(mPath, errno);
            }
            if (got == 0) break;  // the file shrank since fstat
            done += size_t(got);
        }
        return done;
    }

    /// Offset of the first @a needle at or after @a from, or UINT64_MAX; read in chunks.
    uint64_t findForward(uint64_t from, std::string_view needle)
    {
        std::vector<unsigned char> buffer;
        for (uint64_t start = from; start < mSize;) {
            const unsigned char* bytes = nullptr;
            const size_t n = view(start, kChunkBytes, buffer, bytes);
            if (n == 0) break;
            const std::string_view text(reinterpret_cast<const char*>(bytes), n);
            const size_t hit = text.find(needle);
            if (hit != std::string_view::npos) return start + hit;
            if (start + n >= mSize || n < needle.size()) break;
            start += n - (needle.size() - 1);  // a match may straddle the chunks
        }
        return UINT64_MAX;
    }

    /// Offset of the last @a needle starting at or after @a from, or UINT64_MAX; read
    /// backwards from the end in chunks.
    uint64_t findBackward(uint64_t from, std::string_view needle)
    {
        std::vector<unsigned char> buffer;
        uint64_t end = mSize;
        while (end > from && end - from >= needle.size()) {
            const uint64_t start = std::max<uint64_t>(from, end > kChunkBytes ? end - kChunkBytes : 0);
            const unsigned char* bytes = nullptr;
            const size_t n = view(start, size_t(end - start), buffer, bytes);
            const std::string_view text(reinterpret_cast<const char*>(bytes), n);
            const size_t hit = text.rfind(needle);
            if (hit != std::string_view::npos) return start + hit;
            if (start == from) break;
            end = start + needle.size() - 1;  // a match may straddle the chunks
        }
        return UINT64_MAX;
    }

private:
    const std::string& mPath;
    int mFd = -1;
    std::vector<char> mWhole;         ///< a non-regular file, loaded whole
    const char* mMemory = nullptr;    ///< the memory block (or mWhole)
    uint64_t mSize = 0;
};

// ------------------------------------------------------------------------------------------
// Destinations

/// Where one array's decoded bytes go, in file order: the positions (Float32 stored as they
/// come, Float64 narrowed value by value), an attribute's bytes, or nowhere (an array that
/// is decoded only to report its faults first). Holds indices, not pointers, because later
/// pieces grow the vectors.
class ArraySink
{
public:
    static constexpr int kPositions = -1;
    static constexpr int kDiscard = -2;

    ArraySink() = default;
    /// @param start   first particle (positions) or first byte (attribute) of this array
    /// @param bytes   bytes the file holds for it
    /// @param swap    big-endian values, to be byte-swapped
    ArraySink(ParticleSet& particles, int target, size_t start, ScalarType type, uint64_t bytes,
              bool swap)
        : mParticles(&particles), mTarget(target), mStart(start), mWidth(scalarSize(type)),
          mBytes(bytes), mSwap(swap), mNarrow(target == kPositions && type == ScalarType::Float64)
    {}

    /// Where the next bytes go if they are stored as they come, else nullptr.
    unsigned char* direct()
    {
        if (mTarget == kDiscard || mNarrow) return nullptr;
        return base() + mDone;
    }

    /// @a n bytes were written at direct().
    void commit(size_t n) { mDone += n; }

    /// Store the next @a n bytes.
    void write(const unsigned char* bytes, size_t n)
    {
        if (unsigned char* dst = direct()) {
            std::memcpy(dst, bytes, n);
            mDone += n;
            return;
        }
        if (mTarget == kDiscard) {
            mDone += n;
            return;
        }
        // Float64 positions: a value may be split over two calls.
        float* out = reinterpret_cast<float*>(base());
        while (n > 0) {
            const size_t take = std::min(n, size_t(8) - mCarried);
            std::memcpy(mCarry + mCarried, bytes, take);
            mCarried += take;
            bytes += take;
            n -= take;
            if (mCarried == 8) {
                if (mSwap) std::reverse(mCarry, mCarry + 8);
                double value;
                std::memcpy(&value, mCarry, 8);
                out[mDone / 8] = static_cast<float>(value);
                mDone += 8;
                mCarried = 0;
            }
        }
    }

    /// After the last byte: swap the values that were stored as they came.
    void finish()
    {
        if (mSwap && mTarget != kDiscard && !mNarrow) swapBytes(base(), size_t(mBytes) / mWidth, mWidth);
    }

private:
    /// Where this array's first byte goes (looked up on every call: pieces grow the vectors).
    unsigned char* base()
    {
        if (mTarget == kPositions) return reinterpret_cast<unsigned char*>(mParticles->positions.data() + mStart);
        return mParticles->attributes[size_t(mTarget)].bytes.data() + mStart;
    }

    ParticleSet* mParticles = nullptr;
    int mTarget = kDiscard;
    size_t mStart = 0;
    size_t mWidth = 1;
    uint64_t mBytes = 0;
    uint64_t mDone = 0;
    bool mSwap = false, mNarrow = false;
    unsigned char mCarry[8] = {};
    size_t mCarried = 0;
};

/// The file-wide settings of the VTKFile element that binary arrays depend on.
struct VtuLayout
{
    const std::string* path = nullptr;
    bool bigEndian = false;
    bool uint64Headers = false;
    bool zlib = false;
};

// ------------------------------------------------------------------------------------------
// Binary arrays

/// What a binary array's decoder asks of where its bytes come from: the checks the
/// whole-buffer reader made against the bytes left before each read.
class ByteOrigin
{
public:
    virtual ~ByteOrigin() = default;
    /// Before reading @a count bytes of @a what: fail (or, for text whose length is not
    /// known yet, remember to fail) if fewer can be left.
    virtual void beginRead(uint64_t count, const std::string& what) = 0;
    /// Fail with @a message (or remember to) if fewer than @a count bytes can be left.
    virtual void requireRemaining(uint64_t count, const std::string& message) = 0;
};

/// One binary DataArray — block header and data, uncompressed or zlib blocks — decoded
/// from its bytes as they are pushed, into an ArraySink. It asks for the bytes up to its
/// next check at a time (wanted()), so that the checks happen where the whole-buffer reader
/// made them. Raw compressed bytes are inflated as they come (the block header has already
/// shown they are all there); base64 ones a block at a time, since the text may still end
/// early, and that fault came before any in the block's data.
class BinaryDecoder
{
public:
    /// @param wholeBlocks  collect each compressed block before inflating it
    BinaryDecoder(const VtuLayout& layout, ByteOrigin& origin, ArraySink& sink, uint64_t expected,
                  const std::string& what, bool wholeBlocks)
        : mLayout(layout), mOrigin(origin), mSink(sink), mExpected(expected), mWhat(what),
          mWidth(layout.uint64Headers ? 8 : 4), mWholeBlocks(wholeBlocks)
    {}
    ~BinaryDecoder()
    {
        if (mZlibReady) inflateEnd(&mZ);
    }
    BinaryDecoder(const BinaryDecoder&) = delete;
    BinaryDecoder& operator=(const BinaryDecoder&) = delete;

    /// Begin with the block header (its read check may fail).
    void start()
    {
        mHeaderWant = mLayout.zlib ? 3 * mWidth : mWidth;
        mOrigin.beginRead(mHeaderWant, mWhat);
        mState = State::Header;
    }

    /// True once every byte of the array has been decoded.
    bool done() const { return mState == State::Done; }

    /// Bytes it takes before its next check (0 once done).
    uint64_t wanted() const
    {
        switch (mState) {
        case State::Header:
        case State::Sizes: return mHeaderWant - mHeader.size();
        case State::Data: return mLeft;
        case State::Block: return mBlockLeft;
        case State::Idle:
        case State::Done: break;
        }
        return 0;
    }

    /// For uncompressed data stored as it comes: where the next wanted() bytes go.
    unsigned char* directSpan() { return mState == State::Data ? mSink.direct() : nullptr; }

    /// @a n bytes were written at directSpan().
    void commitDirect(size_t n)
    {
        mSink.commit(n);
        mLeft -= n;
        if (mLeft == 0) mState = State::Done;
    }

    /// Take the next @a n bytes, at most wanted().
    void push(const unsigned char* bytes, size_t n)
    {
        switch (mState) {
        case State::Header:
        case State::Sizes:
            mHeader.insert(mHeader.end(), bytes, bytes + n);
            if (mHeader.size() < mHeaderWant) return;
            if (mState == State::Header) onHeader();
            else onBlockSizes();
            return;
        case State::Data:
            mSink.write(bytes, n);
            mLeft -= n;
            if (mLeft == 0) mState = State::Done;
            return;
        case State::Block:
            mBlockLeft -= n;
            if (!mWholeBlocks) {
                inflateSome(bytes, n);
            } else {
                mBlockBytes.insert(mBlockBytes.end(), bytes, bytes + n);
                if (mBlockLeft > 0) return;
                for (size_t done = 0; done < mBlockBytes.size();) {
                    const size_t step = std::min(mBlockBytes.size() - done, size_t(1) << 30);
                    inflateSome(mBlockBytes.data() + done, step);
                    done += step;
                }
                mBlockBytes.clear();
            }
            if (mBlockLeft == 0) endBlock();
            return;
        case State::Idle:
        case State::Done: return;
        }
    }

private:
    enum class State { Idle, Header, Sizes, Data, Block, Done };

    /// Throw FileError "<message> (<path>)".
    [[noreturn]] void failHere(const std::string& message) const { fail(*mLayout.path, message); }

    /// Header word @a index, in the file's byte order and header width.
    uint64_t headerWord(size_t index) const
    {
        unsigned char word[8];
        std::memcpy(word, mHeader.data() + index * mWidth, mWidth);
        if (mLayout.bigEndian) std::reverse(word, word + mWidth);
        if (mWidth == 4) {
            uint32_t v;
            std::memcpy(&v, word, 4);
            return v;
        }
        uint64_t v;
        std::memcpy(&v, word, 8);
        return v;
    }

    /// The first header words are in: size checks, then the data or the block sizes.
    void onHeader()
    {
        if (!mLayout.zlib) {
            const uint64_t bytes = headerWord(0);
            if (bytes != mExpected) {
                failHere(mWhat + " holds " + std::to_string(bytes) + " bytes, expected " +
                         std::to_string(mExpected));
            }
            mOrigin.requireRemaining(bytes, "truncated data in " + mWhat);
            mOrigin.beginRead(bytes, mWhat);
            mLeft = bytes;
            mState = bytes == 0 ? State::Done : State::Data;
            return;
        }
        mBlocks = headerWord(0);
        mBlockSize = headerWord(1);
        mLastSize = headerWord(2);
        const uint64_t sizeBytes = mBlocks > UINT64_MAX / mWidth / 2 ? UINT64_MAX / 2 : mBlocks * mWidth;
        mOrigin.requireRemaining(sizeBytes, "truncated block header in " + mWhat);
        mOrigin.beginRead(sizeBytes, mWhat);
        mHeaderWant = 3 * mWidth + sizeBytes;
        mState = State::Sizes;
        if (mBlocks == 0) onBlockSizes();
    }

    /// The compressed block sizes are in: check the totals, then start block 0.
    void onBlockSizes()
    {
        mTotal = 0;
        uint64_t compressedTotal = 0;
        if (mBlocks > 0) {
            if (mLastSize > mBlockSize || mBlockSize > kMaxTuples) {
                failHere("corrupt block header in " + mWhat);
            }
            mTotal = (mBlocks - 1) * mBlockSize + (mLastSize == 0 ? mBlockSize : mLastSize);
        }
        for (uint64_t b = 0; b < mBlocks; ++b) compressedTotal += headerWord(3 + size_t(b));
        if (mTotal != mExpected) {
            failHere(mWhat + " holds " + std::to_string(mTotal) + " bytes, expected " +
                     std::to_string(mExpected));
        }
        mOrigin.requireRemaining(compressedTotal, "truncated data in " + mWhat);
        mBlock = 0;
        mProduced = 0;
        startBlock();
    }

    /// Check block mBlock's sizes and prepare to inflate it (or finish after the last).
    void startBlock()
    {
        if (mBlock == mBlocks) {
            mState = State::Done;
            return;
        }
        mCompressed = headerWord(3 + size_t(mBlock));
        mBlockOut = (mBlock + 1 == mBlocks && mLastSize != 0) ? mLastSize : mBlockSize;
        // Each block fits in what is left of the array (this also catches products above
        // that overflowed), and deflate cannot have packed it tighter than its ratio.
        if (mBlockOut > mTotal - mProduced || mCompressed > (uint64_t(1) << 48)
            || mBlockOut > mCompressed * kMaxInflateRatio + 64) {
            failHere("corrupt block header in " + mWhat);
        }
        mOrigin.beginRead(mCompressed, mWhat);
        if (!mZlibReady) {
            if (inflateInit(&mZ) != Z_OK) failHere("cannot initialise zlib");
            mZlibReady = true;
        } else if (inflateReset(&mZ) != Z_OK) {
            failHere("cannot initialise zlib");
        }
        mBlockLeft = mCompressed;
        mBlockProduced = 0;
        mBlockEnded = false;
        mState = State::Block;
        if (mBlockLeft == 0) endBlock();
    }

    /// Inflate the next @a n compressed bytes of the current block into the sink; output
    /// beyond the block's declared size is never produced.
    void inflateSome(const unsigned char* bytes, size_t n)
    {
        if (mBlockEnded) return;  // bytes after the end of the zlib stream are not read
        mZ.next_in = const_cast<Bytef*>(bytes);
        mZ.avail_in = uInt(n);
        unsigned char spare = 0;
        for (;;) {
            const uint64_t room = mBlockOut - mBlockProduced;
            unsigned char* direct = mSink.direct();
            if (direct == nullptr && mBuffer.empty()) mBuffer.resize(kInflateBytes);
            unsigned char* out = direct ? direct : mBuffer.data();
            const size_t capacity = direct ? size_t(std::min<uint64_t>(room, UINT_MAX))
                                           : size_t(std::min<uint64_t>(room, kInflateBytes));
            mZ.next_out = capacity > 0 ? out : &spare;  // zlib wants an address even for 0 bytes
            mZ.avail_out = uInt(capacity);
            const int status = inflate(&mZ, Z_NO_FLUSH);
            const size_t produced = capacity - mZ.avail_out;
            if (direct) mSink.commit(produced);
            else mSink.write(mBuffer.data(), produced);
            mBlockProduced += produced;
            if (status == Z_STREAM_END) {
                mBlockEnded = true;
                return;
            }
            if (status == Z_DATA_ERROR || status == Z_NEED_DICT) {
                failHere("corrupt compressed data in block " + std::to_string(mBlock) + " of " + mWhat +
                         (mZ.msg ? ": " + std::string(mZ.msg) : std::string()));
            }
            // Out of input or output, or zlib gave up: endBlock() then finds it incomplete.
            if (status != Z_OK) return;
            if (mZ.avail_in == 0) return;
        }
    }

    /// All compressed bytes of the block are in: it must have ended at its declared size.
    void endBlock()
    {
        if (!mBlockEnded || mBlockProduced != mBlockOut || mCompressed > UINT_MAX || mBlockOut > UINT_MAX) {
            failHere("compressed block " + std::to_string(mBlock) + " of " + mWhat +
                     " does not inflate to its declared " + std::to_string(mBlockOut) + " bytes");
        }
        mProduced += mBlockOut;
        ++mBlock;
        startBlock();
    }

    const VtuLayout& mLayout;
    ByteOrigin& mOrigin;
    ArraySink& mSink;
    uint64_t mExpected;
    std::string mWhat;
    size_t mWidth;
    bool mWholeBlocks;

    State mState = State::Idle;
    std::vector<unsigned char> mHeader;  ///< block header words received so far
    uint64_t mHeaderWant = 0;            ///< header bytes to collect before the next step
    uint64_t mLeft = 0;                  ///< uncompressed data bytes still to come

    uint64_t mBlocks = 0, mBlockSize = 0, mLastSize = 0, mTotal = 0;
    uint64_t mBlock = 0;                 ///< current zlib block
    uint64_t mProduced = 0;              ///< bytes inflated by the blocks before it
    uint64_t mCompressed = 0, mBlockOut = 0, mBlockLeft = 0, mBlockProduced = 0;
    bool mBlockEnded = false;
    bool mZlibReady = false;
    z_stream mZ{};
    std::vector<unsigned char> mBuffer;  ///< inflate output that is not stored as it comes
    std::vector<unsigned char> mBlockBytes;  ///< the compressed block, with mWholeBlocks
};

/// A check on the length of a text that is still arriving: it must reach @a chars
/// characters, or the array fails with @a message.
struct LengthRequirement
{
    uint64_t chars;
    std::string message;
};

/// The checks an array's text must pass once its length is known, and the first error met
/// while decoding it, which counts only if the checks before it pass: the whole-buffer
/// reader checked the text's length before decoding, so a text too short for a read fails
/// with the length message even if it also holds a bad value.
class TextChecks
{
public:
    explicit TextChecks(const std::string& path) : mPath(path) {}

    /// Characters seen so far (all of them once the text has ended).
    uint64_t length() const { return mLength; }
    /// True once a fault has been kept for later: decoding has stopped.
    bool stopped() const { return !mDeferred.empty(); }

    /// @a n more characters arrived; throws the kept fault once the checks before it pass.
    void grow(uint64_t n)
    {
        mLength += n;
        while (!mRequirements.empty() && mRequirements.front().chars <= mLength) {
            mRequirements.erase(mRequirements.begin());
        }
        if (mRequirements.empty() && !mDeferred.empty()) throw FileError(mDeferred);
    }

    /// The text must reach @a chars characters.
    void require(uint64_t chars, std::string message)
    {
        if (chars > mLength) mRequirements.push_back({chars, std::move(message)});
    }

    /// A fault found while decoding: thrown now if the checks before it pass, else kept.
    void failed(const FileError& error)
    {
        if (mRequirements.empty()) throw error;
        mDeferred = error.what();
    }

    /// The text has ended: throw the first failed check, else the kept fault.
    void finish()
    {
        for (const LengthRequirement& requirement : mRequirements) {
            if (requirement.chars > mLength) fail(mPath, requirement.message);
        }
        if (!mDeferred.empty()) throw FileError(mDeferred);
    }

private:
    const std::string& mPath;
    uint64_t mLength = 0;
    std::vector<LengthRequirement> mRequirements;  ///< in the order they were made
    std::string mDeferred;
};

/// A base64 text (an inline `binary` DataArray, or appended base64 from an array's offset
/// on) decoded into a BinaryDecoder as it arrives, in pieces of any size. Decodes only the
/// 4-character quanta the decoder needs, so positions and leftovers at each check are those
/// of decode_internal::Base64Reader, and with them the messages.
class Base64Feeder final : public ByteOrigin
{
public:
    /// @param knownLength  the text's length if known (appended), else UINT64_MAX
    Base64Feeder(const VtuLayout& layout, ArraySink& sink, uint64_t expected, const std::string& what,
                 uint64_t knownLength)
        : mPath(*layout.path), mWhat(what), mChecks(*layout.path),
          mKnown(knownLength != UINT64_MAX), mDecoder(layout, *this, sink, expected, what, true)
    {
        if (mKnown) mChecks.grow(knownLength);
    }

    /// Start decoding (the header's read check may fail).
    void start()
    {
        try {
            mDecoder.start();
        } catch (const FileError& error) {
            mChecks.failed(error);
        }
    }

    /// True once the array is complete; the rest of the text is not looked at.
    bool done() const { return mDecoder.done(); }

    /// The next @a n characters of the text.
    void feed(const char* text, size_t n)
    {
        if (!mKnown) mChecks.grow(n);
        if (mChecks.stopped()) return;
        try {
            decode(text, n);
        } catch (const FileError& error) {
            mChecks.failed(error);
        }
    }

    /// The text has ended: fail as Base64Reader would if the array is incomplete.
    void finish()
    {
        mChecks.finish();
        if (mDecoder.done()) return;
        if (mQuantumSize > 0) fail(mPath, "truncated base64 data");
        fail(mPath, "truncated base64 data in " + mWhat);
    }

    /// Base64Reader::read()'s check: @a count bytes must be decodable from what is left.
    void beginRead(uint64_t count, const std::string& what) override
    {
        requireRemaining(count, "truncated base64 data in " + what);
    }

    /// Fail now (known length) or once the text has ended (inline) if fewer than @a count
    /// bytes could be decoded from the rest of the text.
    void requireRemaining(uint64_t count, const std::string& message) override
    {
        // Base64Reader::maxRemaining(): 3 bytes per 4 characters left, plus 3, plus the
        // bytes of its last decoding stride.
        const uint64_t slack = 3 + mStride;
        if (count <= slack) return;
        const uint64_t quanta = (count - slack) / 3 + ((count - slack) % 3 != 0);
        const uint64_t chars = quanta > (UINT64_MAX - mPos) / 4 ? UINT64_MAX : mPos + 4 * quanta;
        if (chars <= mChecks.length()) return;
        if (mKnown) fail(mPath, message);
        mChecks.require(chars, message);
    }

private:
    /// Decode @a n characters, handing the decoder the bytes it wants.
    void decode(const char* text, size_t n)
    {
        size_t i = 0;
        for (;;) {
            const uint64_t want = mDecoder.wanted();
            if (want == 0) return;
            if (mPendingPos < mPendingSize) {
                const size_t take = size_t(std::min<uint64_t>(want, mPendingSize - mPendingPos));
                mDecoder.push(mPending + mPendingPos, take);
                mPendingPos += take;
                continue;
            }
            if (i == n) return;
            if (mStride >= mStrideTarget) {
                // Base64Reader decodes up to a stride of what the read still wants at a time.
                mStride = 0;
                mStrideTarget = size_t(std::min<uint64_t>(want, kBase64StrideBytes));
            }
            size_t produced = 0;
            while (mStride < mStrideTarget && i < n) {
                const unsigned char c = static_cast<unsigned char>(text[i++]);
                ++mPos;
                const int v = base64Value(c);
                if (v == 65) continue;
                if (v == 255) {
                    fail(mPath, "invalid base64 character '" + printable(std::string_view(
                        reinterpret_cast<const char*>(&c), 1)) + "' at offset " + std::to_string(mPos - 1));
                }
                mQuantum[mQuantumSize++] = v;
                if (mQuantumSize == 4) {
                    const size_t bytes = decodeQuantum(mBatch + produced);
                    produced += bytes;
                    mStride += bytes;
                    mQuantumSize = 0;
                }
            }
            const size_t take = size_t(std::min<uint64_t>(produced, want));
            if (take > 0) mDecoder.push(mBatch, take);
            // The last quantum may give up to two bytes more than wanted: keep them.
            mPendingSize = produced - take;
            mPendingPos = 0;
            std::memcpy(mPending, mBatch + take, mPendingSize);
        }
    }

    /// The bytes of the complete quantum in mQuantum, written to @a out; their count.
    size_t decodeQuantum(unsigned char* out)
    {
        // "xx==" gives one byte, "xxx=" two, "xxxx" three; '=' may appear only at the end.
        int data = 4;
        while (data > 0 && mQuantum[data - 1] == 64) --data;
        for (int k = 0; k < data; ++k) {
            if (mQuantum[k] == 64) fail(mPath, "misplaced base64 padding at offset " + std::to_string(mPos - 1));
        }
        if (data < 2) fail(mPath, "misplaced base64 padding at offset " + std::to_string(mPos - 1));
        for (int k = data; k < 4; ++k) mQuantum[k] = 0;
        const uint32_t bits = (uint32_t(mQuantum[0]) << 18) | (uint32_t(mQuantum[1]) << 12)
                              | (uint32_t(mQuantum[2]) << 6) | uint32_t(mQuantum[3]);
        out[0] = static_cast<unsigned char>(bits >> 16);
        if (data >= 3) out[1] = static_cast<unsigned char>(bits >> 8);
        if (data >= 4) out[2] = static_cast<unsigned char>(bits);
        return size_t(data - 1);
    }

    const std::string& mPath;
    std::string mWhat;
    TextChecks mChecks;
    bool mKnown;
    BinaryDecoder mDecoder;
    uint64_t mPos = 0;                      ///< characters consumed by decoding
    int mQuantum[4] = {};                   ///< a quantum split between two pieces
    int mQuantumSize = 0;
    unsigned char mBatch[kBase64StrideBytes + 3];
    size_t mStride = 0, mStrideTarget = 0;  ///< bytes decoded in the current stride, its goal
    unsigned char mPending[3] = {};         ///< decoded beyond what was wanted
    size_t mPendingSize = 0, mPendingPos = 0;
};

/// Raw appended bytes of one array, read by offset from the input into a BinaryDecoder;
/// uncompressed data goes straight from the file into the final array.
class RawFeeder final : public ByteOrigin
{
public:
    /// The array's bytes start at @a start in @a input; @a size bytes of appended data
    /// are left from there.
    RawFeeder(VtuInput& input, uint64_t start, uint64_t size, const VtuLayout& layout,
              ArraySink& sink, uint64_t expected, const std::string& what)
        : mInput(input), mStart(start), mSize(size), mPath(*layout.path), mWhat(what),
          mDecoder(layout, *this, sink, expected, what, false)
    {}

    /// Decode the whole array.
    void run()
    {
        mDecoder.start();
        std::vector<unsigned char> buffer;
        while (!mDecoder.done()) {
            const uint64_t want = mDecoder.wanted();
            const size_t n = size_t(std::min<uint64_t>(want, kChunkBytes));
            if (unsigned char* dst = mDecoder.directSpan()) {
                const size_t step = size_t(std::min<uint64_t>(want, size_t(1) << 30));
                if (mInput.readAt(mStart + mPos, dst, step) != step) truncated();
                mPos += step;
                mDecoder.commitDirect(step);
                continue;
            }
            const unsigned char* bytes = nullptr;
            if (mInput.view(mStart + mPos, n, buffer, bytes) != n) truncated();
            mPos += n;
            mDecoder.push(bytes, n);
        }
    }

    /// The raw source's read check: @a count bytes must be left in the appended data.
    void beginRead(uint64_t count, const std::string& what) override
    {
        if (count > mSize - mPos) fail(mPath, "truncated appended data in " + what);
    }

    /// Fail with @a message unless @a count bytes are left in the appended data.
    void requireRemaining(uint64_t count, const std::string& message) override
    {
        if (count > mSize - mPos) fail(mPath, message);
    }

private:
    /// The file ended before its size said (it shrank while being read).
    [[noreturn]] void truncated() const { fail(mPath, "truncated appended data in " + mWhat); }

    VtuInput& mInput;
    uint64_t mStart, mSize;
    uint64_t mPos = 0;
    const std::string& mPath;
    std::string mWhat;
    BinaryDecoder mDecoder;
};

// ------------------------------------------------------------------------------------------
// ASCII arrays

/// A native value of @a T parsed from the whole of @a word into @a out; false if it is not one.
template<typename T>
bool
parseNumber(std::string_view word, unsigned char* out)
{
    if constexpr (std::is_floating_point_v<T>) {
        double value;
        if (!parseDoubleRefusingOverflow(word, value)) return false;
        const T narrowed = static_cast<T>(value);
        std::memcpy(out, &narrowed, sizeof(T));
        return true;
    } else {
        T value;
        const char* begin = word.data();
        if (!word.empty() && word[0] == '+') ++begin;
        const auto result = std::from_chars(begin, word.data() + word.size(), value);
        if (result.ec != std::errc() || result.ptr != word.data() + word.size()) return false;
        std::memcpy(out, &value, sizeof(T));
        return true;
    }
}

/// parseNumber() for the run-time @a type.
bool
parseTyped(std::string_view word, ScalarType type, unsigned char* out)
{
    switch (type) {
    case ScalarType::Int8: return parseNumber<int8_t>(word, out);
    case ScalarType::UInt8: return parseNumber<uint8_t>(word, out);
    case ScalarType::Int16: return parseNumber<int16_t>(word, out);
    case ScalarType::UInt16: return parseNumber<uint16_t>(word, out);
    case ScalarType::Int32: return parseNumber<int32_t>(word, out);
    case ScalarType::UInt32: return parseNumber<uint32_t>(word, out);
    case ScalarType::Int64: return parseNumber<int64_t>(word, out);
    case ScalarType::UInt64: return parseNumber<uint64_t>(word, out);
    case ScalarType::Float32: return parseNumber<float>(word, out);
    case ScalarType::Float64: return parseNumber<double>(word, out);
    }
    return false;
}

/// An `ascii` DataArray's text parsed value by value as it arrives into an ArraySink; only
/// a value split between two pieces of text is copied.
class AsciiFeeder
{
public:
    AsciiFeeder(const std::string& path, ArraySink& sink, uint64_t values, ScalarType type,
                const std::string& what)
        : mPath(path), mSink(sink), mValues(values), mType(type), mWidth(scalarSize(type)),
          mWhat(what), mChecks(path)
    {
        // Every value takes at least one character and one separator.
        if (values > 1) mChecks.require(2 * (values - 1), "truncated ascii data in " + what);
    }

    /// The next @a n characters of the text.
    void feed(const char* text, size_t n)
    {
        mChecks.grow(n);
        if (mChecks.stopped()) return;
        size_t i = 0;
        while (i < n && mDone < mValues && !mChecks.stopped()) {
            if (isBlank(text[i])) {
                if (!mToken.empty()) {
                    parse(mToken);
                    mToken.clear();
                }
                ++i;
                continue;
            }
            const size_t start = i;
            while (i < n && !isBlank(text[i])) ++i;
            if (i == n) {
                mToken.append(text + start, n - start);  // may go on in the next piece
            } else if (mToken.empty()) {
                parse(std::string_view(text + start, i - start));
            } else {
                mToken.append(text + start, i - start);
                parse(mToken);
                mToken.clear();
            }
        }
        // Past the declared count only blanks may follow: a value more means the count (or
        // the array) is wrong, and was dropped without a word.
        if (mDone == mValues && mToken.empty()) {
            mExtra = mExtra || std::any_of(text + i, text + n, [](char c) { return !isBlank(c); });
        }
    }

    /// The text has ended: fail if it was too short or too long, or held a bad value.
    void finish()
    {
        if (!mToken.empty() && mDone < mValues && !mChecks.stopped()) parse(mToken);
        mChecks.finish();
        if (mDone < mValues) fail(mPath, "truncated ascii data in " + mWhat);
        if (mExtra) fail(mPath, "more than the " + std::to_string(mValues) + " declared values in " + mWhat);
    }

private:
    /// The separators of ascii arrays (as the whole-buffer reader had them).
    static bool isBlank(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

    /// One value into the sink, or a "bad value" fault.
    void parse(std::string_view word)
    {
        unsigned char value[8];
        if (!parseTyped(word, mType, value)) {
            try {
                fail(mPath, "bad value '" + printable(word) + "' in " + mWhat);
            } catch (const FileError& error) {
                mChecks.failed(error);
            }
            return;
        }
        mSink.write(value, mWidth);
        ++mDone;
    }

    const std::string& mPath;
    ArraySink& mSink;
    uint64_t mValues;
    ScalarType mType;
    size_t mWidth;
    std::string mWhat;
    TextChecks mChecks;
    uint64_t mDone = 0;
    bool mExtra = false;  ///< a value after the last declared one
    std::string mToken;  ///< a value split between two pieces of text
};

// ------------------------------------------------------------------------------------------
// The document

/// The SAX side of the reader: expat's callbacks build the ParticleSet as the document goes
/// by. Faults are recorded with a sequence number in document order (Points reserved ahead
/// of the PointData of its piece) and the lowest one wins, so the message is the one the
/// whole-buffer reader, which checked in that order, gave.
class VtuReader
{
public:
    VtuReader(VtuInput& input, size_t feedBytes)
        : mInput(input), mPath(input.path()), mFeedBytes(std::max<size_t>(feedBytes, 1))
    {
        mLayout.path = &mPath;
    }

    /// The particles, or the FileError the file deserves.
    ParticleSet read()
    {
        std::string xmlError = parse(0, mInput.size(), std::string());
        if (!mAppendedSeen) {
            if (!xmlError.empty()) {
                failIfMisplacedAppendedData();
                throw FileError(xmlError);
            }
        } else {
            const uint64_t start = locateAppendedData(mAppendedTagEnd);
            mAppendedStart = start;
            // The rest of the document after </AppendedData>, inside the elements still open.
            std::string prefix;
            for (const std::string& name : mNames) prefix += "<" + name + ">";
            xmlError = parse(mAppendedStart + mAppendedSize, mInput.size(), prefix);
            if (!xmlError.empty()) throw FileError(xmlError);
        }
        readAppendedArrays();
        if (mErrorSeq != UINT64_MAX) throw FileError(mError);
        return std::move(mParticles);
    }

private:
    enum class Kind { Other, Root, Grid, Piece, Points, PointData, Array };

    /// One DataArray being decoded from its text.
    struct InlineArray
    {
        uint64_t seq = 0;
        std::string mismatch;  ///< fault to report once it is decoded (pieces disagree)
        std::unique_ptr<ArraySink> sink;
        std::unique_ptr<AsciiFeeder> ascii;
        std::unique_ptr<Base64Feeder> base64;
    };

    /// One appended DataArray, read after the document.
    struct AppendedArray
    {
        uint64_t seq = 0;
        std::string what, offset, mismatch;
        uint64_t expected = 0;
        std::unique_ptr<ArraySink> sink;
    };

    /// The Piece being read.
    struct Piece
    {
        bool valid = false;
        uint64_t count = 0;
        size_t positionOffset = 0;
        uint64_t seqPoints = 0;
        bool pointsSeen = false, pointsArraySeen = false, pointDataSeen = false;
        size_t attributeIndex = 0;
    };

    // -- faults

    /// Keep @a message (a whole FileError text) if it is the first in document order.
    void record(uint64_t seq, const std::string& message)
    {
        if (seq < mErrorSeq) {
            mErrorSeq = seq;
            mError = message;
        }
    }

    /// record() "<what> (<path>)".
    void raise(uint64_t seq, const std::string& what) { record(seq, what + " (" + mPath + ")"); }

    /// Run @a body, recording its FileError under @a seq; anything else stops the parser
    /// and is rethrown after it (exceptions must not cross expat's C frames).
    template<typename BodyT>
    bool guarded(uint64_t seq, BodyT&& body)
    {
        try {
            body();
            return true;
        } catch (const FileError& error) {
            record(seq, error.what());
        } catch (...) {
            if (!mFatal) mFatal = std::current_exception();
            XML_StopParser(mParser, XML_FALSE);
        }
        return false;
    }

    // -- parsing

    /// Parse bytes [@a begin, @a end) of the input (after @a prefix, which produces no
    /// events); "" or the XML error message.
    std::string parse(uint64_t begin, uint64_t end, const std::string& prefix)
    {
        std::unique_ptr<std::remove_pointer_t<XML_Parser>, void (*)(XML_Parser)> parser(
            XML_ParserCreate("UTF-8"), XML_ParserFree);
        if (!parser) throw std::bad_alloc();
        mParser = parser.get();
        XML_SetUserData(mParser, this);
        XML_SetElementHandler(mParser, &VtuReader::onStart, &VtuReader::onEnd);
        XML_SetCharacterDataHandler(mParser, &VtuReader::onText);
        const uint64_t shift = begin - std::min<uint64_t>(begin, prefix.size());
        auto errorText = [&] {
            // Expat gives -1 when it has no position (an empty document).
            const XML_Index at = XML_GetCurrentByteIndex(mParser);
            return "XML error at byte " + std::to_string(shift + uint64_t(std::max<XML_Index>(at, 0))) +
                   ": " + XML_ErrorString(XML_GetErrorCode(mParser)) + " (" + mPath + ")";
        };
        if (!prefix.empty()) {
            mQuiet = true;
            const XML_Status status = XML_Parse(mParser, prefix.data(), int(prefix.size()), XML_FALSE);
            mQuiet = false;
            if (status != XML_STATUS_OK) return errorText();
        }
        std::vector<unsigned char> buffer;
        uint64_t offset = begin;
        do {
            const unsigned char* bytes = nullptr;
            const size_t n = offset < end ? mInput.view(offset, size_t(std::min<uint64_t>(mFeedBytes, end - offset)), buffer, bytes) : 0;
            offset += n;
            const bool last = n == 0 || offset >= end;
            const XML_Status status =
                XML_Parse(mParser, reinterpret_cast<const char*>(bytes), int(n), last ? XML_TRUE : XML_FALSE);
            if (mFatal) std::rethrow_exception(mFatal);
            if (status == XML_STATUS_ERROR) {
                if (XML_GetErrorCode(mParser) == XML_ERROR_ABORTED && mStopped) {
                    mStopped = false;
                    return std::string();
                }
                return errorText();
            }
            if (last) break;
        } while (true);
        return std::string();
    }

    /// expat's callbacks, forwarded to the reader they were registered with.
    static void XMLCALL onStart(void* self, const XML_Char* name, const XML_Char** attributes)
    {
        static_cast<VtuReader*>(self)->startElement(name, attributes);
    }
    static void XMLCALL onEnd(void* self, const XML_Char* name)
    {
        static_cast<VtuReader*>(self)->endElement(name);
    }
    static void XMLCALL onText(void* self, const XML_Char* text, int length)
    {
        static_cast<VtuReader*>(self)->text(text, size_t(length));
    }

    /// An element starts: recognise the VTKFile / grid / Piece / Points / PointData /
    /// DataArray path the reader uses (first grid, first Points and PointData per piece),
    /// start its checks and decoders, or stop at AppendedData.
    void startElement(const char* name, const XML_Char** attributes)
    {
        if (mQuiet) return;
        const Kind parent = mKinds.empty() ? Kind::Other : mKinds.back();
        Kind kind = Kind::Other;
        const std::string_view element(name);
        if (mKinds.empty()) {
            kind = Kind::Root;
            guarded(nextSeq(), [&] { startRoot(name, attributes); });
        } else if (element == "AppendedData" && !mAppendedSeen) {
            mAppendedSeen = true;
            mAppendedTagEnd = uint64_t(XML_GetCurrentByteIndex(mParser)) + uint64_t(XML_GetCurrentByteCount(mParser));
            // Any attribute saying base64 (as the earlier reader looked for "base64" in the tag).
            for (size_t i = 0; attributes[i] != nullptr; i += 2) {
                if (std::strcmp(attributes[i + 1], "base64") == 0) mAppendedBase64 = true;
            }
            mStopped = true;
            XML_StopParser(mParser, XML_FALSE);
        } else if (parent == Kind::Root && mRootValid && !mGridSeen && element == mType) {
            kind = Kind::Grid;
            mGridSeen = true;
        } else if (parent == Kind::Grid && element == "Piece") {
            kind = Kind::Piece;
            startPiece(attributes);
        } else if (parent == Kind::Piece && mPiece.valid && element == "Points" && !mPiece.pointsSeen) {
            kind = Kind::Points;
            mPiece.pointsSeen = true;
        } else if (parent == Kind::Points && element == "DataArray" && !mPiece.pointsArraySeen) {
            mPiece.pointsArraySeen = true;
            if (mPiece.count > 0 && mPiece.seqPoints < mErrorSeq) {
                kind = Kind::Array;
                guarded(mPiece.seqPoints, [&] { startPoints(attributes); });
            }
        } else if (parent == Kind::Piece && mPiece.valid && element == "PointData" && !mPiece.pointDataSeen) {
            kind = Kind::PointData;
            mPiece.pointDataSeen = true;
        } else if (parent == Kind::PointData && element == "DataArray") {
            const uint64_t seq = nextSeq();
            if (seq < mErrorSeq) {
                kind = Kind::Array;
                guarded(seq, [&] { startAttribute(seq, attributes); });
            }
        }
        mKinds.push_back(kind);
        mNames.emplace_back(name);
    }

    /// An element ends: finish an inline array, or make the end-of-piece, grid and root
    /// checks.
    void endElement(const char*)
    {
        if (mQuiet || mKinds.empty()) return;
        const Kind kind = mKinds.back();
        mKinds.pop_back();
        mNames.pop_back();
        if (kind == Kind::Array && mArray.sink) {
            InlineArray array = std::move(mArray);
            mArray = InlineArray();
            guarded(array.seq, [&] {
                if (array.ascii) array.ascii->finish();
                if (array.base64) array.base64->finish();
                array.sink->finish();
                if (!array.mismatch.empty()) fail(mPath, array.mismatch);
            });
        } else if (kind == Kind::Piece && mPiece.valid) {
            if (mPiece.count > 0 && !mPiece.pointsArraySeen) raise(mPiece.seqPoints, "piece without Points");
            const uint64_t seq = nextSeq();
            if (!mFirstPiece && mPiece.attributeIndex != mParticles.attributes.size()) {
                raise(seq, "pieces have different point data");
            }
            mFirstPiece = false;
            mPiece = Piece();
        } else if (kind == Kind::Grid) {
            if (mFirstPiece) raise(nextSeq(), "no Piece in " + mType);
        } else if (kind == Kind::Root) {
            if (mRootValid && !mGridSeen) raise(nextSeq(), "no " + mType + " element");
        }
    }

    /// Character data: fed to the inline array being read, if it is its direct text.
    void text(const char* data, size_t length)
    {
        if (mQuiet || mKinds.empty() || mKinds.back() != Kind::Array || !mArray.sink) return;
        const bool ok = guarded(mArray.seq, [&] {
            if (mArray.ascii) mArray.ascii->feed(data, length);
            else if (mArray.base64) mArray.base64->feed(data, length);
        });
        if (!ok) mArray = InlineArray();  // the fault is recorded; skip the rest of its text
    }

    /// The next sequence number, in document order.
    uint64_t nextSeq() { return mNextSeq++; }

    /// The VTKFile element: type, byte order, header width and compressor.
    void startRoot(const char* name, const XML_Char** attributes)
    {
        if (std::strcmp(name, "VTKFile") != 0) fail(mPath, "no VTKFile element");
        mType = xmlAttribute(attributes, "type", "");
        if (mType != "UnstructuredGrid" && mType != "PolyData") {
            fail(mPath, "unsupported VTKFile type '" + printable(mType) +
                 "'; expected UnstructuredGrid or PolyData");
        }
        const std::string byteOrder = xmlAttribute(attributes, "byte_order", "LittleEndian");
        if (byteOrder != "LittleEndian" && byteOrder != "BigEndian") {
            fail(mPath, "unknown byte_order '" + printable(byteOrder) + "'");
        }
        mLayout.bigEndian = byteOrder == "BigEndian";
        const std::string headerType = xmlAttribute(attributes, "header_type", "UInt32");
        if (headerType != "UInt32" && headerType != "UInt64") {
            fail(mPath, "unsupported header_type '" + printable(headerType) + "'");
        }
        mLayout.uint64Headers = headerType == "UInt64";
        const std::string compressor = xmlAttribute(attributes, "compressor", "");
        if (!compressor.empty() && compressor != "vtkZLibDataCompressor") {
            fail(mPath, "unsupported compressor '" + printable(compressor) +
                 "'; only vtkZLibDataCompressor is read");
        }
        mLayout.zlib = !compressor.empty();
        mRootValid = true;
    }

    /// A Piece of the grid: its NumberOfPoints.
    void startPiece(const XML_Char** attributes)
    {
        mPiece = Piece();
        const uint64_t seq = nextSeq();
        mPiece.seqPoints = nextSeq();
        if (seq > mErrorSeq) return;
        const char* countText = xmlAttribute(attributes, "NumberOfPoints", "");
        uint64_t count = 0;
        const auto result = std::from_chars(countText, countText + std::strlen(countText), count);
        if (result.ec != std::errc() || *result.ptr != '\0' || count > kMaxTuples) {
            raise(seq, "bad NumberOfPoints '" + printable(countText) + "'");
            return;
        }
        mPiece.valid = true;
        mPiece.count = count;
        mPiece.positionOffset = mParticles.positions.size();
        // A PolyData's polygons, lines and strips are not read: listed, as the legacy VTK
        // reader lists its sections (bug hunt: a .vtp mesh was converted without a word).
        if (mType == "PolyData") {
            for (const char* cells : {"Polys", "Lines", "Strips"}) {
                const std::string text = xmlAttribute(attributes, ("NumberOf" + std::string(cells)).c_str(), "0");
                const std::string item = std::string(cells) + " section";
                if (text != "0" && !text.empty() &&
                    std::find(mParticles.skipped.begin(), mParticles.skipped.end(), item) == mParticles.skipped.end()) {
                    mParticles.skipped.push_back(item);
                }
            }
        }
    }

    /// The piece's first Points DataArray (NumberOfPoints > 0).
    void startPoints(const XML_Char** attributes)
    {
        ScalarType type;
        const char* typeName = xmlAttribute(attributes, "type", "");
        if (!vtuScalarType(typeName, type) || (type != ScalarType::Float32 && type != ScalarType::Float64)) {
            fail(mPath, "Points must be Float32 or Float64, got '" + printable(typeName) + "'");
        }
        if (xmlIntAttribute(attributes, "NumberOfComponents", 1) != 3) fail(mPath, "Points must have 3 components");
        startArray(mPiece.seqPoints, attributes, type, 3, "Points", ArraySink::kPositions, std::string());
    }

    /// A PointData DataArray: an attribute, created by the first piece and extended by
    /// the others, which must list the same arrays.
    void startAttribute(uint64_t seq, const XML_Char** attributes)
    {
        const std::string name = xmlAttribute(attributes, "Name", "");
        const std::string what = "'" + printable(name) + "'";
        ScalarType type;
        const char* typeName = xmlAttribute(attributes, "type", "");
        if (std::strcmp(typeName, "String") == 0) {
            // Names and labels have no place in an attribute: left out (its text and any
            // appended block are not read) and said, as a .vdb's strings are. It was refused.
            if (mFirstPiece) mParticles.skipped.push_back("string array '" + name + "'");
            return;
        }
        if (!vtuScalarType(typeName, type)) {
            fail(mPath, "unsupported type '" + printable(typeName) + "' of " + what);
        }
        const int components = xmlIntAttribute(attributes, "NumberOfComponents", 1);
        if (components < 1 || components > kMaxFileComponents) fail(mPath, "bad NumberOfComponents of " + what);
        const size_t index = mPiece.attributeIndex++;
        int target = int(index);
        std::string mismatch;
        if (mFirstPiece) {
            ParticleAttribute attribute;
            attribute.name = name;
            attribute.type = type;
            attribute.components = components;
            mParticles.attributes.push_back(std::move(attribute));
        } else if (index >= mParticles.attributes.size() || mParticles.attributes[index].name != name
                   || mParticles.attributes[index].type != type
                   || mParticles.attributes[index].components != components) {
            mismatch = "pieces have different point data (" + what + ")";
            target = ArraySink::kDiscard;
        }
        if (mPiece.count == 0) {
            if (!mismatch.empty()) fail(mPath, mismatch);
            return;
        }
        startArray(seq, attributes, type, components, what, target, mismatch);
    }

    /// Check a DataArray's size against the file, make room for it and start decoding it
    /// (inline) or note it for later (appended).
    void startArray(uint64_t seq, const XML_Char** attributes, ScalarType type, int components,
                    const std::string& what, int target, const std::string& mismatch)
    {
        const uint64_t tuples = mPiece.count;
        const size_t width = scalarSize(type);
        const uint64_t expected = tuples * uint64_t(components) * width;
        const uint64_t fileSize = mInput.size();
        // No encoding packs data tighter than deflate's ratio; that bounds all arrays together
        // too, since pieces could otherwise decode the same appended bytes again and again.
        mDecodedBytes += expected;
        if (expected > fileSize * kMaxInflateRatio + 1024
            || mDecodedBytes > fileSize * kMaxInflateRatio + 1024) {
            fail(mPath, "truncated " + what + ": the file is too small for " + std::to_string(tuples) +
                 " tuples");
        }
        const std::string format = xmlAttribute(attributes, "format", "ascii");
        if (format == "ascii") {
            // The text lies in the file; checked here so nothing is allocated for more.
            if (tuples * uint64_t(components) > fileSize / 2 + 1) fail(mPath, "truncated ascii data in " + what);
        } else if (format != "binary" && format != "appended") {
            fail(mPath, "unknown format '" + printable(format) + "' of " + what);
        }

        size_t start = 0;
        if (target == ArraySink::kPositions) {
            start = mPiece.positionOffset;
            requireMemoryForParticles(mPath, mPiece.positionOffset + tuples, sizeof(openvdb::Vec3f));
            mParticles.positions.resize(mPiece.positionOffset + size_t(tuples));
        } else if (target >= 0) {
            std::vector<unsigned char>& bytes = mParticles.attributes[size_t(target)].bytes;
            start = bytes.size();
            bytes.resize(start + size_t(expected));
        }
        auto sink = std::make_unique<ArraySink>(mParticles, target, start, type, expected,
                                                mLayout.bigEndian && format != "ascii");
        if (format == "appended") {
            AppendedArray array;
            array.seq = seq;
            array.what = what;
            array.offset = xmlAttribute(attributes, "offset", "");
            array.mismatch = mismatch;
            array.expected = expected;
            array.sink = std::move(sink);
            mAppended.push_back(std::move(array));
            return;
        }
        mArray = InlineArray();
        mArray.seq = seq;
        mArray.mismatch = mismatch;
        mArray.sink = std::move(sink);
        if (format == "ascii") {
            mArray.ascii = std::make_unique<AsciiFeeder>(mPath, *mArray.sink, tuples * uint64_t(components),
                                                         type, what);
        } else {
            mArray.base64 = std::make_unique<Base64Feeder>(mLayout, *mArray.sink, expected, what, UINT64_MAX);
            mArray.base64->start();
        }
    }

    // -- appended data

    /// Where the appended bytes lie, from the end of the AppendedData start tag at
    /// @a tagEnd: after white space and '_', up to the last </AppendedData> of the file.
    uint64_t locateAppendedData(uint64_t tagEnd)
    {
        uint64_t underscore = tagEnd;
        unsigned char c = 0;
        for (;; ++underscore) {
            if (mInput.readAt(underscore, &c, 1) != 1) fail(mPath, "AppendedData does not start with '_'");
            if (c != ' ' && c != '\n' && c != '\r' && c != '\t') break;
        }
        if (c != '_') fail(mPath, "AppendedData does not start with '_'");
        const uint64_t close = mInput.findBackward(underscore + 1, "</AppendedData>");
        if (close == UINT64_MAX) fail(mPath, "truncated AppendedData (no </AppendedData>)");
        mAppendedSize = close - underscore - 1;
        return underscore + 1;
    }

    /// For a document with an XML error before any AppendedData element: the faults the
    /// earlier reader found first by looking for "<AppendedData" in the text.
    void failIfMisplacedAppendedData()
    {
        const uint64_t tag = mInput.findForward(0, "<AppendedData");
        if (tag == UINT64_MAX) return;
        const uint64_t tagEnd = mInput.findForward(tag, ">");
        if (tagEnd == UINT64_MAX) fail(mPath, "truncated AppendedData tag");
        locateAppendedData(tagEnd + 1);
    }

    /// Read every appended array that comes before the first fault, in document order.
    void readAppendedArrays()
    {
        std::vector<unsigned char> buffer;
        for (AppendedArray& array : mAppended) {
            if (array.seq >= mErrorSeq) continue;
            try {
                readAppendedArray(array, buffer);
            } catch (const FileError& error) {
                record(array.seq, error.what());
            }
        }
    }

    /// One appended array from its offset into its final place.
    void readAppendedArray(AppendedArray& array, std::vector<unsigned char>& buffer)
    {
        if (!mAppendedSeen) fail(mPath, array.what + " is appended but there is no AppendedData");
        const char* offsetText = array.offset.c_str();
        uint64_t offset = 0;
        const auto result = std::from_chars(offsetText, offsetText + array.offset.size(), offset);
        if (result.ec != std::errc() || *result.ptr != '\0') {
            fail(mPath, "bad offset '" + printable(array.offset) + "' of " + array.what);
        }
        if (offset > mAppendedSize) fail(mPath, "offset of " + array.what + " lies beyond the appended data");
        const uint64_t start = mAppendedStart + offset;
        const uint64_t size = mAppendedSize - offset;
        if (!mAppendedBase64) {
            RawFeeder(mInput, start, size, mLayout, *array.sink, array.expected, array.what).run();
        } else {
            Base64Feeder feeder(mLayout, *array.sink, array.expected, array.what, size);
            feeder.start();
            for (uint64_t pos = 0; pos < size && !feeder.done();) {
                const unsigned char* bytes = nullptr;
                const size_t n = mInput.view(start + pos, size_t(std::min<uint64_t>(kChunkBytes, size - pos)),
                                             buffer, bytes);
                if (n == 0) break;
                feeder.feed(reinterpret_cast<const char*>(bytes), n);
                pos += n;
            }
            feeder.finish();
        }
        array.sink->finish();
        if (!array.mismatch.empty()) fail(mPath, array.mismatch);
    }

    VtuInput& mInput;
    const std::string& mPath;
    size_t mFeedBytes;
    VtuLayout mLayout;
    ParticleSet mParticles;

    XML_Parser mParser = nullptr;
    bool mQuiet = false;             ///< feeding the synthetic prefix: no events
    bool mStopped = false;           ///< stopped at the AppendedData element on purpose
    std::exception_ptr mFatal;       ///< a non-FileError exception from a callback
    std::vector<Kind> mKinds;        ///< the open elements
    std::vector<std::string> mNames;

    bool mRootValid = false, mGridSeen = false, mFirstPiece = true;
    std::string mType;
    Piece mPiece;
    InlineArray mArray;
    std::vector<AppendedArray> mAppended;
    uint64_t mDecodedBytes = 0;      ///< all arrays so far

    bool mAppendedSeen = false, mAppendedBase64 = false;
    uint64_t mAppendedTagEnd = 0, mAppendedStart = 0, mAppendedSize = 0;

    uint64_t mNextSeq = 0;
    uint64_t mErrorSeq = UINT64_MAX;
    std::string mError;
};

} // namespace

ParticleSet
readVtuBuffer(const char* data, size_t size, const std::string& path, size_t feedBytes)
{
    VtuInput input(data, size, path);
    return VtuReader(input, feedBytes).read();
}

ParticleSet
readVtuParticles(const char* data, size_t size, const std::string& path)
{
    return readVtuBuffer(data, size, path, kChunkBytes);
}

ParticleSet
readVtuFile(const std::string& path)
{
    VtuInput input(path);
    return VtuReader(input, kChunkBytes).read();
}

} // namespace io_internal
} // namespace nonbloppy
