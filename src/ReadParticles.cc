// SPDX-License-Identifier: Apache-2.0
/// @file ReadParticles.cc
/// @brief Stage "read particles": legacy VTK, PLY and raw XYZ files streamed from the file
///        straight into the final arrays; the other formats through ParticleReaders.h.
///
/// The VTK, PLY and XYZ readers never hold the whole file: a FileStream reads it in chunks
/// of kChunkBytes, and large binary arrays (positions, attributes) are read with read(2)
/// directly into the ParticleSet's vectors, then byte-swapped in place if needed. Peak
/// memory is the ParticleSet plus one chunk. Every count in a header is still checked
/// against the bytes left in the file (its size from fstat) before anything is allocated.
/// Pipes and other non-regular files, whose size is unknown, are loaded whole first.
///
/// The parsing itself is FileFormats.cc's, which readMesh() and the fuzz targets use on a
/// buffer: VTK files go through parseVtk() on a FileStream; PLY files through the shared
/// header and skipping code of PlyReaderBase, with vertex records decoded here straight
/// into positions and attributes. So the messages are the same word for word.

#include <nonbloppy/ReadParticles.h>

#include <nonbloppy/Error.h>

#include "FileFormats.h"
#include "ParticleReaders.h"
#include "ReadVdbPoints.h"
#include "ReadVtu.h"
#include "StreamReader.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <new>

#include <unistd.h>

namespace nonbloppy {

namespace {

using namespace io_internal;

/// A native Float32 or Float64 value at @a p as float (valueAsDouble() for the one type pair
/// that PLY positions have, kept here so that the per-value loops can inline it).
inline float
floatValue(const unsigned char* p, ScalarType type)
{
    if (type == ScalarType::Float32) {
        float v;
        std::memcpy(&v, p, 4);
        return v;
    }
    double v;
    std::memcpy(&v, p, 8);
    return float(v);
}

// ------------------------------------------------------------------------------------------
// FileStream

/// A read position in a file, with a bounded buffer of the bytes just ahead of it.
/// Text access (tokens, lines) goes through the buffer; readBytes() copies large binary
/// blocks straight from the file into the caller's memory.
class FileStream final : public ByteInput
{
public:
    explicit FileStream(const std::string& path) : mPath(path)
    {
        const OpenFile file = openFile(path);
        if (file.regular) {
            mFd = file.fd;
            mSize = file.size;
            mBuffer.resize(size_t(std::min<uint64_t>(kChunkBytes, std::max<uint64_t>(mSize, 64))));
        } else {
            // st_size means nothing for pipes and /proc files: hold the whole contents.
            mBuffer = readToEndAndClose(file.fd, path, 0);
            mTail = mBuffer.size();
            mSize = mTail;
            mEof = true;
        }
    }
    ~FileStream() { closeFile(); }
    FileStream(const FileStream&) = delete;
    FileStream& operator=(const FileStream&) = delete;

    uint64_t size() const { return mSize; }
    uint64_t pos() const { return mBufferStart + mHead; }
    uint64_t remaining() const override { return mSize - pos(); }
    bool atEnd() override { return !ensure(1); }
    const char* here() const { return mBuffer.data() + mHead; }
    size_t available() const { return mTail - mHead; }
    void advance(size_t n) { mHead += std::min(n, available()); }

    /// True once at least @a n bytes are buffered at here(); false if the file ends first.
    bool ensure(size_t n)
    {
        while (available() < n) {
            if (!fill()) return false;
        }
        return true;
    }

    /// Copy the next @a n bytes into @a dst; false (having moved to the end) if the file
    /// ends first. Beyond what is buffered, reads go straight from the file into @a dst.
    bool readBytes(unsigned char* dst, size_t n) override
    {
        const size_t buffered = std::min(n, available());
        if (buffered > 0) std::memcpy(dst, here(), buffered);
        mHead += buffered;
        dst += buffered;
        n -= buffered;
        if (n == 0) return true;
        if (n < mBuffer.size() / 2) {
            if (!ensure(n)) {
                mHead = mTail;
                return false;
            }
            std::memcpy(dst, here(), n);
            mHead += n;
            return true;
        }
        // Buffer empty: read directly.
        mBufferStart = pos();
        mHead = mTail = 0;
        while (n > 0) {
            const uint64_t fileLeft = mSize - mBufferStart;
            const size_t want = size_t(std::min<uint64_t>(n, fileLeft));
            if (want == 0) {
                mEof = true;
                return false;
            }
            const ssize_t got = ::read(mFd, dst, want);
            if (got < 0) {
                if (errno == EINTR) continue;
                failRead(mPath, errno);
            }
            if (got == 0) {
                mSize = mBufferStart;  // the file shrank since fstat
                mEof = true;
                return false;
            }
            dst += got;
            n -= size_t(got);
            mBufferStart += uint64_t(got);
        }
        return true;
    }

    /// Move @a n bytes ahead (callers check remaining() first).
    void skipBytes(uint64_t n) override
    {
        const uint64_t target = std::min(pos() + n, mSize);
        if (target <= mBufferStart + mTail) {
            mHead = size_t(target - mBufferStart);
            return;
        }
        mBufferStart = target;
        mHead = mTail = 0;
        if (::lseek(mFd, off_t(target), SEEK_SET) < 0) failRead(mPath, errno);
    }

    void skipSpace() override
    {
        for (;;) {
            while (mHead < mTail && isSpace(mBuffer[mHead])) ++mHead;
            if (mHead < mTail || !fill()) return;
        }
    }

    /// The next run of non-space characters (empty at the end of the file). The view is
    /// valid until the next call on this stream.
    std::string_view token() override
    {
        skipSpace();
        size_t length = 0;
        for (;;) {
            while (mHead + length < mTail && !isSpace(mBuffer[mHead + length])) ++length;
            if (mHead + length < mTail || !fill()) break;
        }
        const std::string_view text(mBuffer.data() + mHead, length);
        mHead += length;
        return text;
    }

    /// The rest of the current line without its line break; moves past the '\n'.
    std::string line() override
    {
        size_t length = 0;
        bool found = false;
        for (;;) {
            const void* newline =
                std::memchr(mBuffer.data() + mHead + length, '\n', mTail - mHead - length);
            if (newline) {
                length = size_t(static_cast<const char*>(newline) - (mBuffer.data() + mHead));
                found = true;
                break;
            }
            length = mTail - mHead;
            if (!fill()) break;
        }
        size_t end = length;
        if (end > 0 && mBuffer[mHead + end - 1] == '\r') --end;
        std::string text(mBuffer.data() + mHead, end);
        mHead += length + (found ? 1 : 0);
        return text;
    }

    /// True if the next non-space text is the word @a word (case-insensitive). Moves nothing.
    bool peekWord(std::string_view word) override
    {
        size_t i = 0;
        for (;; ++i) {
            if (!ensure(i + 1)) return false;
            if (!isSpace(here()[i])) break;
        }
        for (size_t j = 0; j < word.size(); ++j) {
            if (!ensure(i + j + 1) || toLower(here()[i + j]) != toLower(word[j])) return false;
        }
        return !ensure(i + word.size() + 1) || isSpace(here()[i + word.size()]);
    }

    bool skipLineStartingWith(std::string_view word, bool skipSpaceFirst) override
    {
        if (skipSpaceFirst) skipSpace();
        if (remaining() >= word.size() && ensure(word.size()) &&
            iequals(std::string_view(here(), word.size()), word)) {
            line();
            return true;
        }
        return false;
    }

private:
    void closeFile()
    {
        if (mFd >= 0) ::close(mFd);
        mFd = -1;
    }

    /// Read more of the file behind the buffered bytes; false at the end of the file.
    bool fill()
    {
        if (mEof) return false;
        if (mHead > 0) {
            std::memmove(mBuffer.data(), mBuffer.data() + mHead, mTail - mHead);
            mBufferStart += mHead;
            mTail -= mHead;
            mHead = 0;
        }
        if (mTail == mBuffer.size()) mBuffer.resize(mBuffer.size() * 2);
        const uint64_t fileLeft = mSize - (mBufferStart + mTail);
        const size_t want = size_t(std::min<uint64_t>(mBuffer.size() - mTail, fileLeft));
        if (want == 0) {
            mEof = true;
            return false;
        }
        for (;;) {
            const ssize_t got = ::read(mFd, mBuffer.data() + mTail, want);
            if (got < 0) {
                if (errno == EINTR) continue;
                failRead(mPath, errno);
            }
            if (got == 0) {
                mSize = mBufferStart + mTail;  // the file shrank since fstat
                mEof = true;
                return false;
            }
            mTail += size_t(got);
            return true;
        }
    }

    const std::string& mPath;
    int mFd = -1;
    std::vector<char> mBuffer;
    size_t mHead = 0, mTail = 0;   ///< the unread buffered bytes are mBuffer[mHead, mTail)
    uint64_t mBufferStart = 0;     ///< file offset of mBuffer[0]
    uint64_t mSize = 0;            ///< file size
    bool mEof = false;
};

// ------------------------------------------------------------------------------------------
// Legacy VTK

/// The particle part of a legacy VTK file: POINTS and the POINT_DATA arrays, read straight
/// into their final arrays by parseVtk(); cells, CELL_DATA, lookup tables and METADATA are
/// skipped.
ParticleSet
readVtkParticles(const std::string& path)
{
    FileStream stream(path);
    VtkData vtk = parseVtk(stream, path, /*wantPolygons=*/false);
    ParticleSet particles;
    particles.positions = std::move(vtk.points);
    particles.skipped = std::move(vtk.skippedSections);  // a mesh's polygons, say
    particles.attributes.reserve(vtk.pointArrays.size());
    for (NumericArray& array : vtk.pointArrays) {
        ParticleAttribute attribute;
        attribute.name = std::move(array.name);
        attribute.type = array.type;
        attribute.components = array.components;
        attribute.bytes = std::move(array.bytes);
        particles.attributes.push_back(std::move(attribute));
    }
    return particles;
}

// ------------------------------------------------------------------------------------------
// PLY

/// Where one vertex property goes: a position axis, a component of an attribute, or
/// nowhere (lists).
struct PlyColumn
{
    int axis = -1;                      ///< 0, 1, 2 for x, y, z
    ParticleAttribute* attribute = nullptr;
    size_t component = 0;               ///< of attribute
    size_t width = 0;                   ///< bytes per value

    /// Where vertex @a i's value goes.
    unsigned char* destination(size_t i) const
    {
        return attribute->bytes.data() + (i * size_t(attribute->components) + component) * width;
    }
};

/// The vertex element of a PLY file, read straight into a ParticleSet: x, y, z as
/// positions, every other scalar property an attribute, those spelling the components of
/// a vector (<name>_x,_y,_z or <name>_0,_1,..., as writeParticles() writes them, of one
/// type) one attribute of that many components (groupColumns()).
class PlyReader : public PlyReaderBase
{
public:
    PlyReader(FileStream& stream, const std::string& path)
        : PlyReaderBase(stream, path), mStream(stream) {}

    ParticleSet read()
    {
        readHeader();
        for (size_t e = 0; e < mElements.size(); ++e) {
            const PlyElement& element = mElements[e];
            if (element.name != "vertex") {
                skipElement(element);
                continue;
            }
            readVertices(element);
            // The other elements (a mesh's faces) are not read, only named. Data after the
            // vertices (more rows than the header counts) was dropped silently: it is checked
            // where nothing but empty elements follows (MeshLab writes point clouds with
            // "element face 0"); a list element's size is known only by reading it.
            bool last = true;
            for (size_t other = 0; other < mElements.size(); ++other) {
                if (other == e || mElements[other].count == 0) continue;
                mData.skipped.push_back("element '" + mElements[other].name + "'");
                last = last && other < e;
            }
            if (last) {
                mInput.skipSpace();
                if (!mInput.atEnd()) {
                    fail(mPath, "PLY file has " + std::to_string(mInput.remaining()) +
                                " bytes more than its header declares (element vertex " + std::to_string(element.count) + ")");
                }
            }
            return std::move(mData);
        }
        fail(mPath, "PLY file has no vertex element");
    }

private:
    void readVertices(const PlyElement& element)
    {
        const std::string section = "PLY vertex element";
        requireAxes(element);
        requireRoom(element, section);
        const size_t count = size_t(element.count);

        // Lay out the destinations first: positions, and the attributes the other scalar
        // properties form.
        std::vector<PlyColumn> columns(element.properties.size());
        std::vector<AttributeColumn> attributeColumns;
        for (size_t p = 0; p < element.properties.size(); ++p) {
            const PlyProperty& property = element.properties[p];
            if (property.isList) {
                mData.skipped.push_back("list property '" + property.name + "'");
                continue;
            }
            PlyColumn& column = columns[p];
            column.width = scalarSize(property.type);
            column.axis = axisOf(property.name);
            if (column.axis < 0) {
                AttributeColumn attributeColumn{p, property.name, std::string(), -1, int(property.type)};
                attributeColumn.component = suffixComponentOf(property.name, attributeColumn.base);
                attributeColumns.push_back(std::move(attributeColumn));
            } else if (property.type != ScalarType::Float32 &&
                       property.type != ScalarType::Float64) {
                fail(mPath, "PLY property '" + property.name + "' must be float or double");
            }
        }
        uint64_t bytesPerParticle = sizeof(openvdb::Vec3f);
        for (const AttributeColumn& column : attributeColumns) {
            bytesPerParticle += scalarSize(element.properties[column.index].type);
        }
        requireMemoryForParticles(mPath, count, bytesPerParticle);
        mData.positions.resize(count);
        const std::vector<ColumnGroup> groups = groupColumns(attributeColumns);
        mData.attributes.reserve(groups.size());  // the columns point into it
        for (const ColumnGroup& group : groups) {
            const PlyProperty& first = element.properties[attributeColumns[group.columns[0]].index];
            ParticleAttribute attribute;
            attribute.name = group.name;
            attribute.type = first.type;
            attribute.components = int(group.columns.size());
            attribute.bytes.resize(count * group.columns.size() * scalarSize(first.type));
            mData.attributes.push_back(std::move(attribute));
            for (size_t c = 0; c < group.columns.size(); ++c) {
                PlyColumn& column = columns[attributeColumns[group.columns[c]].index];
                column.attribute = &mData.attributes.back();
                column.component = c;
            }
        }

        bool hasList = false;
        for (const PlyProperty& property : element.properties) hasList = hasList || property.isList;
        if (isPackedFloatXyz(element)) {
            // x y z float and nothing else: the file's bytes are the position array's.
            mReader->readInto(3 * count, ScalarType::Float32, section,
                reinterpret_cast<unsigned char*>(mData.positions.data()));
        } else if (mReader->binary() && !hasList) {
            readFixedRecords(element, columns, section);
        } else {
            readRecordByRecord(element, columns, section);
        }
    }

    static int axisOf(const std::string& name)
    {
        return name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : -1;
    }

    bool isPackedFloatXyz(const PlyElement& element) const
    {
        const std::vector<PlyProperty>& p = element.properties;
        return mReader->binary() && p.size() == 3 && p[0].name == "x" && p[1].name == "y" &&
            p[2].name == "z" && !p[0].isList && !p[1].isList && !p[2].isList &&
            p[0].type == ScalarType::Float32 && p[1].type == ScalarType::Float32 &&
            p[2].type == ScalarType::Float32;
    }

    /// Binary records of one size: decoded a buffered block (up to kChunkBytes) of whole
    /// records at a time, the block's records in parallel (each writes its own particle's
    /// values only), every value copied at its width known at compile time. 64x benchmark
    /// input with the dam-break frame's id and velocity (28-byte records, 44 MB): 0.079 s
    /// with a memcpy of run-time width per value, one record after the other.
    void readFixedRecords(const PlyElement& element, const std::vector<PlyColumn>& columns,
                          const std::string& section)
    {
        size_t recordSize = 0;
        std::vector<size_t> offsets;  // of each column's value in a record
        for (const PlyColumn& column : columns) {
            offsets.push_back(recordSize);
            recordSize += column.width;
        }
        const bool swap = mReader->swaps();
        const size_t count = size_t(element.count);
        std::vector<openvdb::Vec3f>& positions = mData.positions;
        for (size_t i = 0; i < count;) {
            if (!mStream.ensure(recordSize)) fail(mPath, "truncated " + section);
            const size_t block = std::min(count - i, mStream.available() / recordSize);
            const unsigned char* records = reinterpret_cast<const unsigned char*>(mStream.here());
            tbb::parallel_for(tbb::blocked_range<size_t>(0, block, 4096), [&](const tbb::blocked_range<size_t>& range) {
                for (size_t r = range.begin(); r < range.end(); ++r) {
                    const unsigned char* record = records + r * recordSize;
                    for (size_t p = 0; p < columns.size(); ++p) {
                        const PlyColumn& column = columns[p];
                        const unsigned char* from = record + offsets[p];
                        switch (column.width) {
                        case 1: decodeValue<1>(column, from, i + r, swap, positions); break;
                        case 2: decodeValue<2>(column, from, i + r, swap, positions); break;
                        case 4: decodeValue<4>(column, from, i + r, swap, positions); break;
                        default: decodeValue<8>(column, from, i + r, swap, positions); break;
                        }
                    }
                }
            });
            i += block;
            mStream.advance(block * recordSize);
        }
    }

    /// Particle @a i's value of @a column, @a kWidth bytes at @a from (byte-swapped if
    /// @a swap), into its position or attribute.
    template<size_t kWidth>
    static void decodeValue(const PlyColumn& column, const unsigned char* from, size_t i,
                            bool swap, std::vector<openvdb::Vec3f>& positions)
    {
        unsigned char value[kWidth];
        std::memcpy(value, from, kWidth);
        if (swap) std::reverse(value, value + kWidth);
        // Positions are float or double (checked), so their width tells their type.
        if constexpr (kWidth == 4) {
            if (column.axis >= 0) {
                std::memcpy(&positions[i][column.axis], value, 4);
                return;
            }
        } else if constexpr (kWidth == 8) {
            if (column.axis >= 0) {
                double position;
                std::memcpy(&position, value, 8);
                positions[i][column.axis] = float(position);
                return;
            }
        }
        std::memcpy(column.destination(i), value, kWidth);
    }

    /// Text records, or binary ones with list properties: one value at a time.
    void readRecordByRecord(const PlyElement& element, const std::vector<PlyColumn>& columns,
                            const std::string& section)
    {
        const size_t count = size_t(element.count);
        for (size_t i = 0; i < count; ++i) {
            for (size_t p = 0; p < element.properties.size(); ++p) {
                const PlyProperty& property = element.properties[p];
                const PlyColumn& column = columns[p];
                if (property.isList) {
                    skipList(property, section);
                } else if (column.axis >= 0) {
                    unsigned char value[8];
                    mReader->readInto(1, property.type, section, value);
                    mData.positions[i][column.axis] = floatValue(value, property.type);
                } else {
                    mReader->readInto(1, property.type, section, column.destination(i));
                }
            }
        }
    }

    FileStream& mStream;   ///< the input, for whole-record access
    ParticleSet mData;
};

// ------------------------------------------------------------------------------------------
// XYZ

ParticleSet
readXyzParticles(const std::string& path)
{
    FileStream stream(path);
    if (stream.size() % 12 != 0) {
        fail(path, "XYZ file size " + std::to_string(stream.size()) +
            " is not a multiple of 12 bytes (three float32 per particle)");
    }
    requireMemoryForParticles(path, stream.size() / 12, sizeof(openvdb::Vec3f));
    ParticleSet particles;
    particles.positions.resize(size_t(stream.size() / 12));
    static_assert(sizeof(openvdb::Vec3f) == 12, "Vec3f must be three packed floats");
    unsigned char* bytes = reinterpret_cast<unsigned char*>(particles.positions.data());
    if (!stream.readBytes(bytes, particles.positions.size() * 12)) {
        // The file shrank while it was read; report what is left, as the size check would.
        fail(path, "XYZ file size " + std::to_string(stream.size()) +
            " is not a multiple of 12 bytes (three float32 per particle)");
    }
    if (kHostIsBigEndian) swapInPlace(bytes, 3 * particles.positions.size(), 4);
    return particles;
}

const char* const kParticleExtensions =
    ".vtk, .vtu, .vtp, .ply, .xyz, .bgeo, .vdb, .csv, .txt or .json";

/// The extension before @a ext, the lower-case extension @a path ends with ("x.bgeo.gz",
/// ".gz": ".bgeo"); "" if there is none.
std::string innerExtension(const std::string& path, const std::string& ext)
{
    return io_internal::lowerExtension(path.substr(0, path.size() - ext.size()));
}

/// The extension that picks @a path's reader, lower case: lowerExtension(), except that
/// ".bgeo" is also picked by `.bhclassic` (Houdini 12 and later write the classic layout
/// under that name; their own `.bgeo` is JSON-based) and by the gzipped `.bgeo.gz` and
/// `.bhclassic.gz` (the reader tells gzip from the bytes, and refuses JSON inside, as a
/// `.bgeo.gz` from Houdini 12 or later holds).
std::string readerExtension(const std::string& path)
{
    const std::string ext = io_internal::lowerExtension(path);
    if (ext == ".gz") {
        const std::string inner = innerExtension(path, ext);
        if (inner == ".bgeo" || inner == ".bhclassic") return ".bgeo";
    }
    return ext == ".bhclassic" ? ".bgeo" : ext;
}

/// What to do with a Houdini geometry file nonbloppy does not read, said after the
/// unknown-extension error; empty for other names. Houdini's default cache, `.bgeo.sc`, is
/// JSON-based geometry compressed with Blosc, and `.geo`/`.hclassic` are ASCII.
std::string houdiniAdvice(const std::string& path)
{
    const std::string ext = io_internal::lowerExtension(path);
    const std::string inner = ext == ".sc" || ext == ".gz" ? innerExtension(path, ext) : ext;
    if (inner != ".bgeo" && inner != ".bhclassic" && inner != ".geo" && inner != ".hclassic") return std::string();
    return std::string(ext == ".sc" ? ": Houdini's Blosc-compressed geometry is not read" : ": Houdini's ASCII geometry is not read")
           + "; export it from Houdini as .bhclassic (classic binary geometry; renaming does not convert it)";
}

/// The reader for the lower-case extension @a ext, which isParticleFile() accepted.
ParticleSet
readParticlesByExtension(const std::string& path, const std::string& ext)
{
    if (ext == ".vtk") return readVtkParticles(path);
    if (ext == ".ply") {
        FileStream stream(path);
        return PlyReader(stream, path).read();
    }
    if (ext == ".xyz") return readXyzParticles(path);
    if (ext == ".bgeo") return readBgeoFile(path);
    if (ext == ".csv" || ext == ".txt") return readTableFile(path);
    if (ext == ".json") return readJsonFile(path);
    if (ext == ".vtu" || ext == ".vtp") return readVtuFile(path);
    // .vdb: walked and checked through a window, then read by OpenVDB from the file.
    return readVdbPointsFile(path);
}

} // namespace

ParticleSet
readParticles(const std::string& path)
{
    using namespace io_internal;
    requireParticleFile(path);
    const std::string ext = readerExtension(path);

    ParticleSet particles;
    // The readers refuse before allocating what a file's header or size announces beyond the
    // memory left (requireMemoryForParticles()); text read row by row (CSV, JSON) announces
    // nothing, so its growth can still run out: said here with the file's name, not as a bare
    // "out of memory" (whatever was read is freed by then).
    try {
        particles = readParticlesByExtension(path, ext);
    } catch (const std::bad_alloc&) {
        fail(path, "out of memory while reading the particles");
    }

    // Later stages hash positions into voxels; one NaN would poison the whole grid.

    for (size_t i = 0; i < particles.positions.size(); ++i) {
        const openvdb::Vec3f& p = particles.positions[i];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
            throw ParameterError("non-finite position of particle " + std::to_string(i) +
                " (" + path + ")");
        }
    }
    return particles;
}

bool
isParticleFile(const std::string& path)
{
    const std::string ext = readerExtension(path);
    return ext == ".vtk" || ext == ".ply" || ext == ".xyz" || ext == ".bgeo" || ext == ".vtu"
        || ext == ".vtp" || ext == ".csv" || ext == ".txt" || ext == ".json" || ext == ".vdb";
}

void
requireParticleFile(const std::string& path)
{
    using namespace io_internal;
    const std::string ext = readerExtension(path);
    if (ext.empty()) {
        throw FileError("particle file name has no extension (" + path +
            "); expected " + kParticleExtensions);
    }
    if (!isParticleFile(path)) {
        const std::string advice = houdiniAdvice(path);
        throw FileError("unknown particle file extension '" + ext + "' (" + path + ")" +
            (advice.empty() ? std::string("; expected ") + kParticleExtensions : advice));
    }
}

} // namespace nonbloppy
