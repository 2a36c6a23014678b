// SPDX-License-Identifier: Apache-2.0
/// @file Decode.cc
/// @brief gzip/zlib through zlib, a small base64 decoder, byte swapping.

#include "Decode.h"

#include "FileFormats.h"

#include <zlib.h>

#include <algorithm>
#include <limits>

namespace nonbloppy {
namespace decode_internal {

using io_internal::fail;

bool
isGzip(const char* data, size_t size)
{
    return size >= 2 && static_cast<unsigned char>(data[0]) == 0x1f
        && static_cast<unsigned char>(data[1]) == 0x8b;
}

std::vector<char>
gunzip(const char* data, size_t size, const std::string& path)
{
    z_stream stream{};
    if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) fail(path, "cannot initialise zlib");
    std::vector<char> out;
    // Grow geometrically; deflate's ratio bounds the total, so no input can ask for more
    // than ~1032 times its own size.
    out.resize(std::min<size_t>(size * 4 + 1024, size_t(1) << 26));
    size_t produced = 0;
    size_t consumed = 0;
    int status = Z_OK;
    while (true) {
        if (produced == out.size()) {
            if (out.size() > size * kMaxInflateRatio + 4096) {
                inflateEnd(&stream);
                fail(path, "corrupt gzip data: expands beyond deflate's limits");
            }
            out.resize(out.size() * 2);
        }
        const size_t inChunk = std::min<size_t>(size - consumed, std::numeric_limits<uInt>::max());
        const size_t outChunk = std::min<size_t>(out.size() - produced, std::numeric_limits<uInt>::max());
        stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data + consumed));
        stream.avail_in = uInt(inChunk);
        stream.next_out = reinterpret_cast<Bytef*>(out.data() + produced);
        stream.avail_out = uInt(outChunk);
        status = inflate(&stream, Z_NO_FLUSH);
        consumed += inChunk - stream.avail_in;
        produced += outChunk - stream.avail_out;
        if (status == Z_STREAM_END) break;
        if (status == Z_BUF_ERROR && consumed == size) {
            inflateEnd(&stream);
            fail(path, "truncated gzip data");
        }
        if (status != Z_OK && status != Z_BUF_ERROR) {
            const std::string message = stream.msg ? stream.msg : "error " + std::to_string(status);
            inflateEnd(&stream);
            fail(path, "corrupt gzip data: " + message);
        }
    }
    inflateEnd(&stream);
    out.resize(produced);
    return out;
}

void
inflateZlib(const unsigned char* data, size_t size, size_t expectedSize,
            std::vector<unsigned char>& out, const std::string& what, const std::string& path)
{
    const size_t start = out.size();
    out.resize(start + expectedSize);
    z_stream stream{};
    if (inflateInit(&stream) != Z_OK) fail(path, "cannot initialise zlib");
    stream.next_in = const_cast<Bytef*>(data);
    stream.avail_in = uInt(std::min<size_t>(size, std::numeric_limits<uInt>::max()));
    stream.next_out = out.data() + start;
    stream.avail_out = uInt(std::min<size_t>(expectedSize, std::numeric_limits<uInt>::max()));
    const int status = inflate(&stream, Z_FINISH);
    const size_t produced = expectedSize - stream.avail_out;
    const std::string message = stream.msg ? stream.msg : "";
    inflateEnd(&stream);
    if (status != Z_STREAM_END || produced != expectedSize
        || size > std::numeric_limits<uInt>::max() || expectedSize > std::numeric_limits<uInt>::max()) {
        if (status == Z_DATA_ERROR || status == Z_NEED_DICT) {
            fail(path, "corrupt compressed data in " + what + (message.empty() ? "" : ": " + message));
        }
        fail(path, "compressed " + what + " does not inflate to its declared " +
             std::to_string(expectedSize) + " bytes");
    }
}

namespace {


} // namespace

bool
Base64Reader::decodeQuantum()
{
    int values[4];
    int n = 0;
    while (n < 4 && mPos < mText.size()) {
        const unsigned char c = static_cast<unsigned char>(mText[mPos++]);
        const int v = base64Value(c);
        if (v == 65) continue;
        if (v == 255) {
            fail(mPath, "invalid base64 character '" + io_internal::printable(std::string_view(
                reinterpret_cast<const char*>(&c), 1)) + "' at offset " + std::to_string(mPos - 1));
        }
        values[n++] = v;
    }
    if (n == 0) return false;
    if (n < 4) fail(mPath, "truncated base64 data");
    // "xx==" gives one byte, "xxx=" two, "xxxx" three; '=' may appear only at the end.
    int data = 4;
    while (data > 0 && values[data - 1] == 64) --data;
    for (int i = 0; i < data; ++i) {
        if (values[i] == 64) fail(mPath, "misplaced base64 padding at offset " + std::to_string(mPos - 1));
    }
    if (data < 2) fail(mPath, "misplaced base64 padding at offset " + std::to_string(mPos - 1));
    for (int i = data; i < 4; ++i) values[i] = 0;
    const uint32_t bits = (uint32_t(values[0]) << 18) | (uint32_t(values[1]) << 12)
                          | (uint32_t(values[2]) << 6) | uint32_t(values[3]);
    mPending.push_back(static_cast<unsigned char>(bits >> 16));
    if (data >= 3) mPending.push_back(static_cast<unsigned char>(bits >> 8));
    if (data >= 4) mPending.push_back(static_cast<unsigned char>(bits));
    return true;
}

void
Base64Reader::readAll(std::vector<unsigned char>& out)
{
    out.insert(out.end(), mPending.begin() + ptrdiff_t(mPendingPos), mPending.end());
    mPending.clear();
    mPendingPos = 0;
    while (decodeQuantum()) {
        if (mPending.size() >= 3 * 4096) {
            out.insert(out.end(), mPending.begin(), mPending.end());
            mPending.clear();
        }
    }
    out.insert(out.end(), mPending.begin(), mPending.end());
    mPending.clear();
}

void
Base64Reader::read(size_t count, std::vector<unsigned char>& out, const std::string& what)
{
    if (count > maxRemaining()) fail(mPath, "truncated base64 data in " + what);
    out.reserve(out.size() + count);
    while (count > 0) {
        if (mPendingPos == mPending.size()) {
            mPending.clear();
            mPendingPos = 0;
            // Decode straight through in big strides when nothing is pending.
            while (mPending.size() < std::min<size_t>(count, 3 * 4096) && decodeQuantum()) {}
            if (mPending.empty()) fail(mPath, "truncated base64 data in " + what);
        }
        const size_t take = std::min(count, mPending.size() - mPendingPos);
        out.insert(out.end(), mPending.begin() + ptrdiff_t(mPendingPos),
                   mPending.begin() + ptrdiff_t(mPendingPos + take));
        mPendingPos += take;
        count -= take;
    }
}

std::vector<unsigned char>
decodeBase64(std::string_view text, const std::string& path, const std::string& /*what*/)
{
    Base64Reader reader(text, path);
    std::vector<unsigned char> out;
    reader.readAll(out);
    return out;
}

void
swapBytes(unsigned char* data, size_t count, size_t width)
{
    if (width <= 1) return;
    for (size_t i = 0; i < count; ++i) std::reverse(data + i * width, data + (i + 1) * width);
}

} // namespace decode_internal
} // namespace nonbloppy
