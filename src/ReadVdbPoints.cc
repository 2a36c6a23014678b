// SPDX-License-Identifier: Apache-2.0
/// @file ReadVdbPoints.cc
/// @brief Particles from a `.vdb` file holding an openvdb::points::PointDataGrid (as Houdini
///        and OpenVDB's own tools write them): world position from `P`, and every other
///        attribute of a numeric or vector type, by name. Group and string attributes have
///        no ParticleAttribute counterpart and are skipped.
///
/// The bytes are read the way openvdb::io::Stream reads them, grid by grid, from a
/// VdbSource: the open file (readVdbPointsFile(), never opened twice) or a memory block (the
/// fuzz target's bytes, a pipe). Before OpenVDB reads a header, metadata, grid descriptor,
/// transform or a PointDataGrid's tree and leaf buffers, every size in it is checked against
/// the bytes present and against what it describes, and every compressed chunk of the grid
/// is decompressed once (VdbSizeCheck, through a 64 KB window); OpenVDB then reads the same
/// bytes through a 64 KB stream buffer (VdbStreamBuf). So the file is never held whole: peak
/// memory is the PointDataGrid, then the particle arrays made from it. Grids that are not
/// needed are skipped unread when the file says where they end. The particles come in tree
/// order, leaf by leaf: the leaves are converted in parallel, each into its own place, so the
/// order is the same on every run and at any thread count.

#include "ReadVdbPoints.h"

#include "FileFormats.h"
#include "ParticleReaders.h"

#include <nonbloppy/Error.h>

// OpenVDB's point templates must keep default visibility, as src/VisibilityPrelude.h
// explains for the grid types it covers (else openvdb::initialize() crashes).
#pragma GCC visibility push(default)
#include <openvdb/io/Archive.h>
#include <openvdb/io/DelayedLoadMetadata.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/io/io.h>
#include <openvdb/math/Maps.h>
#include <openvdb/openvdb.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/points/StreamCompression.h>
#pragma GCC visibility pop

#include <blosc.h>  // BLOSC_MAX_OVERHEAD
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <istream>
#include <limits>
#include <map>
#include <memory>
#include <streambuf>
#include <sstream>
#include <type_traits>
#include <vector>

#include <unistd.h>

namespace nonbloppy {
namespace io_internal {

namespace {

using openvdb::points::AttributeHandle;
using openvdb::points::PointDataGrid;

using PointLeaf = PointDataGrid::TreeType::LeafNodeType;

/// A PointDataGrid's leaves in tree order, and where each one's points start in the
/// particle arrays (start[n]; start.back() is the point count). The loops below fill each
/// leaf's points in parallel at their place in tree order, so the particles come out in the
/// same order whatever the thread count.
struct PointLeaves
{
    std::vector<const PointLeaf*> leaves;
    std::vector<size_t> start;

    /// Calls @a visit(leaf, first point) for every leaf, leaves in parallel.
    template<typename VisitT>
    void forEach(const VisitT& visit) const
    {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size(), 16),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t n = range.begin(); n < range.end(); ++n) visit(*leaves[n], start[n]);
            });
    }
};

template<typename ValueT, typename StoredT, int ComponentsT>
void
copyAttribute(const PointLeaves& table, size_t arrayIndex, ParticleAttribute& out)
{
    out.components = ComponentsT;
    out.bytes.resize(table.start.back() * ComponentsT * sizeof(StoredT));
    table.forEach([&](const PointLeaf& leaf, size_t first) {
        unsigned char* dst = out.bytes.data() + first * ComponentsT * sizeof(StoredT);
        AttributeHandle<ValueT> handle(leaf.constAttributeArray(arrayIndex));
        for (auto index = leaf.beginIndexAll(); index; ++index) {
            const ValueT value = handle.get(*index);
            StoredT stored[ComponentsT];
            if constexpr (ComponentsT == 1) {
                stored[0] = static_cast<StoredT>(value);
            } else {
                if constexpr (std::is_same_v<ValueT, openvdb::Mat3s> || std::is_same_v<ValueT, openvdb::Mat3d>
                          || std::is_same_v<ValueT, openvdb::Mat4s> || std::is_same_v<ValueT, openvdb::Mat4d>) {
                for (int c = 0; c < ComponentsT; ++c) stored[c] = static_cast<StoredT>(value.asPointer()[c]);  // row-major
            } else {
                for (int c = 0; c < ComponentsT; ++c) stored[c] = static_cast<StoredT>(value[c]);
            }
            }
            std::memcpy(dst, stored, sizeof(stored));
            dst += sizeof(stored);
        }
    });
}

/// @a attributes with runs of scalars "<base>_0", "<base>_1", ... of one type joined into one
/// attribute of that many components (groupColumns()), for each base in @a split (the grid's
/// kSplitAttributesKey): writeParticles() splits so what OpenVDB has no attribute type for
/// (4 floats, say, or 5 integers). Other scalars keep their names, whatever they spell.
std::vector<ParticleAttribute> joinComponents(std::vector<ParticleAttribute> attributes,
                                              const std::vector<std::string>& split)
{
    std::vector<AttributeColumn> columns;
    for (size_t i = 0; i < attributes.size(); ++i) {
        AttributeColumn column{i, attributes[i].name, std::string(), -1, int(attributes[i].type)};
        if (attributes[i].components == 1) {
            column.component = suffixComponentOf(column.name, column.base);
            if (std::find(split.begin(), split.end(), column.base) == split.end()) column.component = -1;
        }
        columns.push_back(std::move(column));
    }
    std::vector<ParticleAttribute> joined;
    for (const ColumnGroup& group : groupColumns(columns)) {
        if (group.columns.size() == 1) {
            joined.push_back(std::move(attributes[group.columns[0]]));
            continue;
        }
        const ParticleAttribute& first = attributes[group.columns[0]];
        ParticleAttribute vector;
        vector.name = group.name;
        vector.type = first.type;
        vector.components = int(group.columns.size());
        const size_t width = scalarSize(first.type), count = first.bytes.size() / width, n = group.columns.size();
        vector.bytes.resize(count * n * width);
        for (size_t c = 0; c < n; ++c) {
            const unsigned char* source = attributes[group.columns[c]].bytes.data();
            for (size_t i = 0; i < count; ++i) std::memcpy(&vector.bytes[(i * n + c) * width], source + i * width, width);
        }
        joined.push_back(std::move(vector));
    }
    return joined;
}

ParticleSet
convertGrid(const PointDataGrid& grid, const std::string& path)
{
    ParticleSet particles;
    auto firstLeaf = grid.tree().cbeginLeaf();
    if (!firstLeaf) return particles;
    const openvdb::points::AttributeSet::Descriptor& descriptor =
        firstLeaf->attributeSet().descriptor();
    const size_t positionIndex = descriptor.find("P");
    if (positionIndex == openvdb::points::AttributeSet::INVALID_POS) {
        fail(path, "PointDataGrid '" + printable(grid.getName()) + "' has no P attribute");
    }
    // Every leaf must share the descriptor (OpenVDB guarantees it for grids it wrote; a
    // corrupt file might not, and the handles below would then read the wrong arrays).
    // Checked in parallel, reported for the first such leaf in tree order.
    PointLeaves table;
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) table.leaves.push_back(leaf.getLeaf());
    enum : uint8_t { kSound, kDecreasingOffsets, kOtherDescriptor, kBadArray };
    std::vector<uint8_t> problem(table.leaves.size(), kSound);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, table.leaves.size(), 64),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                const PointLeaf& leaf = *table.leaves[n];
                // A voxel's points are those from the previous voxel's offset up to its own; a
                // decreasing offset would make the index iterators below visit more points than
                // pointCount() (the last offset) says, past the arrays and the output.
                for (openvdb::Index v = 1; v < PointLeaf::SIZE && problem[n] == kSound; ++v) {
                    if (leaf.getValue(v) < leaf.getValue(v - 1)) problem[n] = kDecreasingOffsets;
                }
                if (problem[n] == kSound && !(leaf.attributeSet().descriptor() == descriptor)) {
                    problem[n] = kOtherDescriptor;
                }
                for (size_t a = 0; a < descriptor.size() && problem[n] == kSound; ++a) {
                    const openvdb::points::AttributeArray* array = leaf.attributeSet().getConst(a);
                    if (!array || (array->size() != leaf.pointCount() && !array->isUniform())) problem[n] = kBadArray;
                }
            }
        });
    const std::string gridName = printable(grid.getName());
    for (const uint8_t found : problem) {
        if (found == kDecreasingOffsets) fail(path, "corrupt point offsets in PointDataGrid '" + gridName + "'");
        if (found == kOtherDescriptor) fail(path, "leaves of PointDataGrid '" + gridName + "' have different attributes");
        if (found == kBadArray) fail(path, "corrupt attribute array in PointDataGrid '" + gridName + "'");
    }
    table.start.assign(table.leaves.size() + 1, 0);
    for (size_t n = 0; n < table.leaves.size(); ++n) table.start[n + 1] = table.start[n] + table.leaves[n]->pointCount();
    const uint64_t count = table.start.back();

    requireMemoryForParticles(path, count, sizeof(openvdb::Vec3f));
    particles.positions.resize(size_t(count));
    const openvdb::math::Transform& transform = grid.transform();
    table.forEach([&](const PointLeaf& leaf, size_t first) {
        AttributeHandle<openvdb::Vec3f> handle(leaf.constAttributeArray(positionIndex));
        openvdb::Vec3f* out = particles.positions.data() + first;
        for (auto index = leaf.beginIndexAll(); index; ++index) {
            const openvdb::Vec3d voxel = index.getCoord().asVec3d();
            const openvdb::Vec3d world = transform.indexToWorld(voxel + openvdb::Vec3d(handle.get(*index)));
            *out++ = openvdb::Vec3f(world);
        }
    });

    // Attributes in the order the descriptor numbers them.
    std::vector<std::pair<size_t, std::string>> arrays;
    for (const auto& entry : descriptor.map()) arrays.emplace_back(entry.second, entry.first);
    std::sort(arrays.begin(), arrays.end());
    for (const auto& [arrayIndex, name] : arrays) {
        if (arrayIndex == positionIndex) continue;
        const openvdb::points::AttributeArray& array = firstLeaf->constAttributeArray(arrayIndex);
        if (openvdb::points::isGroup(array)) {
            // Groups share bit arrays named "__group0", ...; the descriptor names each group.
            continue;
        }
        if (openvdb::points::isString(array)) {
            particles.skipped.push_back("string attribute '" + name + "'");
            continue;
        }
        const std::string valueType = descriptor.valueType(arrayIndex);
        ParticleAttribute attribute;
        attribute.name = name;
        if (valueType == "float") { attribute.type = ScalarType::Float32; copyAttribute<float, float, 1>(table, arrayIndex, attribute); }
        else if (valueType == "double") { attribute.type = ScalarType::Float64; copyAttribute<double, double, 1>(table, arrayIndex, attribute); }
        else if (valueType == "int8") { attribute.type = ScalarType::Int8; copyAttribute<int8_t, int8_t, 1>(table, arrayIndex, attribute); }
        else if (valueType == "int16") { attribute.type = ScalarType::Int16; copyAttribute<int16_t, int16_t, 1>(table, arrayIndex, attribute); }
        else if (valueType == "int32") { attribute.type = ScalarType::Int32; copyAttribute<int32_t, int32_t, 1>(table, arrayIndex, attribute); }
        else if (valueType == "int64") { attribute.type = ScalarType::Int64; copyAttribute<int64_t, int64_t, 1>(table, arrayIndex, attribute); }
        else if (valueType == "bool") { attribute.type = ScalarType::UInt8; copyAttribute<bool, uint8_t, 1>(table, arrayIndex, attribute); }
        else if (valueType == "vec3s") { attribute.type = ScalarType::Float32; copyAttribute<openvdb::Vec3f, float, 3>(table, arrayIndex, attribute); }
        else if (valueType == "vec3d") { attribute.type = ScalarType::Float64; copyAttribute<openvdb::Vec3d, double, 3>(table, arrayIndex, attribute); }
        else if (valueType == "vec3i") { attribute.type = ScalarType::Int32; copyAttribute<openvdb::Vec3i, int32_t, 3>(table, arrayIndex, attribute); }
        else if (valueType == "quats") { attribute.type = ScalarType::Float32; copyAttribute<openvdb::math::Quats, float, 4>(table, arrayIndex, attribute); }
        else if (valueType == "quatd") { attribute.type = ScalarType::Float64; copyAttribute<openvdb::math::Quatd, double, 4>(table, arrayIndex, attribute); }
        else if (valueType == "mat3s") { attribute.type = ScalarType::Float32; copyAttribute<openvdb::Mat3s, float, 9>(table, arrayIndex, attribute); }
        else if (valueType == "mat3d") { attribute.type = ScalarType::Float64; copyAttribute<openvdb::Mat3d, double, 9>(table, arrayIndex, attribute); }
        else if (valueType == "mat4s") { attribute.type = ScalarType::Float32; copyAttribute<openvdb::Mat4s, float, 16>(table, arrayIndex, attribute); }
        else if (valueType == "mat4d") { attribute.type = ScalarType::Float64; copyAttribute<openvdb::Mat4d, double, 16>(table, arrayIndex, attribute); }
        else continue;  // a type registered after OpenVDB 10's own (which are all above)
        particles.attributes.push_back(std::move(attribute));
    }
    std::vector<std::string> split;
    if (const auto listed = grid.getMetadata<openvdb::StringMetadata>(kSplitAttributesKey)) {
        std::istringstream words(listed->value());
        for (std::string word; words >> word;) split.push_back(word);
    }
    particles.attributes = joinComponents(std::move(particles.attributes), split);
    for (const auto& group : descriptor.groupMap()) particles.skipped.push_back("group '" + group.first + "'");
    return particles;
}

// ------------------------------------------------------------------------------------------
// Where the bytes come from

/// The bytes of a .vdb file by position: a block in memory (the fuzz target's input, a pipe
/// read whole) or an open regular file, read with pread() so that the walk and OpenVDB's
/// stream can each keep their own position in it.
class VdbSource
{
public:
    VdbSource(const char* data, size_t size, const std::string& path)
        : mMemory(data), mSize(size), mPath(path) {}
    /// @a fd stays the caller's to close.
    VdbSource(int fd, uint64_t size, const std::string& path) : mFd(fd), mSize(size), mPath(path) {}

    uint64_t size() const { return mSize; }
    /// The whole block, or nullptr for a file.
    const char* memory() const { return mMemory; }

    /// Copy the @a n bytes at @a pos (pos + n <= size()) to @a out.
    /// @throw FileError "cannot read <path>: <reason>", or the truncated-stream error if the
    ///        file shrank since its size was taken.
    void read(uint64_t pos, char* out, size_t n) const
    {
        if (mMemory) {
            std::memcpy(out, mMemory + pos, n);
            return;
        }
        while (n > 0) {
            const ssize_t got = ::pread(mFd, out, n, off_t(pos));
            if (got < 0) {
                if (errno == EINTR) continue;
                failRead(mPath, errno);
            }
            if (got == 0) fail(mPath, "cannot read .vdb file: truncated stream");
            out += got;
            pos += uint64_t(got);
            n -= size_t(got);
        }
    }

private:
    const char* mMemory = nullptr;
    int mFd = -1;
    uint64_t mSize = 0;
    const std::string& mPath;
};

/// A window onto a VdbSource for the walk (VdbSizeCheck): the bytes asked for, and up to
/// kWindowBytes after them, read at once. A request longer than that (a long string, a
/// compressed chunk: at most a page of 1 MB in files OpenVDB writes) widens the window.
class VdbWindow
{
public:
    explicit VdbWindow(const VdbSource& source) : mSource(source) {}

    /// The @a n bytes at @a pos (pos + n <= size()), valid until the next call.
    const unsigned char* bytes(uint64_t pos, size_t n)
    {
        if (const char* memory = mSource.memory()) {
            return reinterpret_cast<const unsigned char*>(memory + pos);
        }
        if (pos < mStart || pos + n > mStart + mLength) {
            const size_t length = size_t(std::min<uint64_t>(std::max(n, kWindowBytes), mSource.size() - pos));
            if (mBuffer.size() < length) mBuffer.resize(length);
            mSource.read(pos, mBuffer.data(), length);
            mStart = pos;
            mLength = length;
        }
        return reinterpret_cast<const unsigned char*>(mBuffer.data()) + (pos - mStart);
    }

    uint64_t size() const { return mSource.size(); }

private:
    static constexpr size_t kWindowBytes = size_t(1) << 16;
    const VdbSource& mSource;
    std::vector<char> mBuffer;
    uint64_t mStart = 0;
    size_t mLength = 0;
};

/// The std::streambuf OpenVDB reads from: the memory block itself, or a file through a
/// buffer of kBufferBytes (reads longer than that go straight into the caller's memory).
/// Seekable, read-only.
class VdbStreamBuf : public std::streambuf
{
public:
    explicit VdbStreamBuf(const VdbSource& source) : mSource(source)
    {
        if (const char* memory = source.memory()) {
            char* begin = const_cast<char*>(memory);  // a get area only: never written
            setg(begin, begin, begin + source.size());
        } else {
            mBuffer.resize(kBufferBytes);
            setg(mBuffer.data(), mBuffer.data(), mBuffer.data());
        }
    }

protected:
    int_type underflow() override
    {
        if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
        if (!fill()) return traits_type::eof();
        return traits_type::to_int_type(*gptr());
    }

    std::streamsize xsgetn(char* out, std::streamsize count) override
    {
        std::streamsize done = 0;
        while (done < count) {
            if (gptr() == egptr()) {
                const uint64_t pos = position();
                const uint64_t rest = uint64_t(count - done);
                if (!mSource.memory() && rest >= kBufferBytes) {
                    const size_t n = size_t(std::min(rest, mSource.size() - pos));
                    if (n == 0) break;
                    mSource.read(pos, out + done, n);
                    done += std::streamsize(n);
                    mStart = pos + n;
                    setg(mBuffer.data(), mBuffer.data(), mBuffer.data());
                    continue;
                }
                if (!fill()) break;
            }
            const std::streamsize n = std::min<std::streamsize>(count - done, egptr() - gptr());
            std::memcpy(out + done, gptr(), size_t(n));
            setg(eback(), gptr() + n, egptr());
            done += n;
        }
        return done;
    }

    pos_type seekoff(off_type offset, std::ios_base::seekdir dir, std::ios_base::openmode which) override
    {
        const off_type base = dir == std::ios_base::beg ? 0
                            : dir == std::ios_base::cur ? off_type(position()) : off_type(mSource.size());
        return seekpos(pos_type(base + offset), which);
    }

    pos_type seekpos(pos_type target, std::ios_base::openmode which) override
    {
        const off_type pos = off_type(target);
        if (!(which & std::ios_base::in) || pos < 0 || uint64_t(pos) > mSource.size()) {
            return pos_type(off_type(-1));
        }
        const uint64_t buffered = uint64_t(egptr() - eback());
        if (uint64_t(pos) >= mStart && uint64_t(pos) <= mStart + buffered) {
            setg(eback(), eback() + (uint64_t(pos) - mStart), egptr());
        } else {
            mStart = uint64_t(pos);
            setg(mBuffer.data(), mBuffer.data(), mBuffer.data());
        }
        return target;
    }

private:
    uint64_t position() const { return mStart + uint64_t(gptr() - eback()); }

    /// The next bytes of the file into the buffer; false at the end (or for memory, whose
    /// get area is all of it).
    bool fill()
    {
        if (mSource.memory()) return false;
        const uint64_t pos = position();
        const size_t n = size_t(std::min<uint64_t>(kBufferBytes, mSource.size() - pos));
        if (n == 0) return false;
        mSource.read(pos, mBuffer.data(), n);
        mStart = pos;
        setg(mBuffer.data(), mBuffer.data(), mBuffer.data() + n);
        return true;
    }

    static constexpr uint64_t kBufferBytes = uint64_t(1) << 16;
    const VdbSource& mSource;
    std::vector<char> mBuffer;
    uint64_t mStart = 0;  ///< file position of eback()
};

// ------------------------------------------------------------------------------------------
// Reading the stream with every size OpenVDB would trust checked first

/// Checks the parts of a .vdb stream in which OpenVDB (io::Stream, MetaMap, GridDescriptor,
/// math::Transform) allocates as much as a number in the file says before reading the bytes:
/// string lengths (util/Name.h readString), metadata values (StringMetadata, UnknownMetadata,
/// io::DelayedLoadMetadata) and the grid count. Each size must fit in the bytes left, so a
/// crafted header cannot make libopenvdb allocate gigabytes before it fails. It walks the same
/// bytes OpenVDB will read next; the caller positions it from the stream (seek()).
///
/// For a PointDataGrid it also walks the tree's topology (root, internal and leaf nodes),
/// where every node's values come as a chunk whose size io::bloscFromStream/unzipFromStream
/// allocate before reading, and then every leaf's buffers (pointLeafBuffers(): attribute
/// descriptors, array metadata, page headers, pages, point offsets), where OpenVDB also
/// asserts on sizes it did not check. Every compressed chunk in there (Blosc, or zlib in a
/// topology) is decompressed into a scratch buffer and must give the bytes it should:
/// OpenVDB throws on corrupt data, and leaks when it does. The whole grid is walked before
/// OpenVDB reads any of it.
class VdbSizeCheck
{
public:
    VdbSizeCheck(const VdbSource& source, const std::string& path)
        : mBytes(source), mSize(source.size()), mPath(path) {}

    void seek(size_t pos) { mPos = std::min<uint64_t>(pos, mSize); }
    size_t pos() const { return mPos; }

    /// The header io::Archive::readHeader() reads; returns the file format version.
    uint32_t header()
    {
        static const unsigned char kMagic[8] = {0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0};
        if (mSize < 8 || std::memcmp(mBytes.bytes(0, 8), kMagic, 8) != 0) corrupt("not a VDB file");
        mPos = 8;
        const uint32_t version = load<uint32_t>("header");
        // PointDataGrids came with file format 223 or later; the per-grid compression
        // flags (222) are the oldest layout walked here.
        if (version < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) {
            corrupt("unsupported file format version " + std::to_string(version) +
                    " (point data grids need 223 or later)");
        }
        // OpenVDB reads newer versions after a warning on stderr, as if they were its own.
        if (version > openvdb::OPENVDB_FILE_VERSION) {
            corrupt("unsupported file format version " + std::to_string(version) + " (OpenVDB " +
                    openvdb::getLibraryVersionString() + " reads up to " +
                    std::to_string(openvdb::OPENVDB_FILE_VERSION) + ")");
        }
        skip(4 + 4, "header");  // library major, minor
        mHasGridOffsets = load<uint8_t>("header") != 0;
        // The UUID as text, 8-4-4-4-12 hex digits (boost::uuids' stream format).
        need(36, "header");
        const unsigned char* uuid = here(36);
        for (size_t i = 0; i < 36; ++i) {
            const char c = char(uuid[i]);
            const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
            if (dash ? c != '-' : !std::isxdigit(static_cast<unsigned char>(c))) corrupt("bad UUID in header");
        }
        mPos += 36;
        return version;
    }

    /// The grid count (io::Archive::readGridCount()), refused if that many grids cannot fit.
    uint32_t gridCount()
    {
        const uint32_t count = load<uint32_t>("grid count");
        // A grid takes at least its descriptor (three strings and three offsets).
        if (count > left() / 36) corrupt("grid count " + std::to_string(int32_t(count)) + " does not fit in the file");
        return count;
    }

    /// A MetaMap (MetaMap::readMeta): count, then name, type name and value per item.
    /// @a owner is "the file" or "grid '<name>'".
    void metaMap(const std::string& owner)
    {
        const uint32_t count = load<uint32_t>("metadata of " + owner);
        // An item takes at least 12 bytes (two string lengths and a value size).
        if (count > left() / 12) {
            // Mostly a cut-off file (hostile-input audit: "claims 1 items" did not say so).
            corrupt("truncated or corrupt metadata of " + owner + ": it claims " + std::to_string(count) +
                    (count == 1 ? " item" : " items") + ", at least 12 bytes each, and " + std::to_string(left()) +
                    " bytes are left");
        }
        for (uint32_t i = 0; i < count; ++i) {
            const std::string name = string("a metadata name of " + owner);
            const std::string item = "metadata '" + printable(name) + "' of " + owner;
            const std::string type = string("type name of " + item);
            const uint32_t bytes = load<uint32_t>(item);
            if (bytes > left()) {
                corrupt(item + " claims " + std::to_string(bytes) + " bytes, " +
                        std::to_string(left()) + " left");
            }
            const size_t valueStart = mPos;
            if (type == openvdb::io::DelayedLoadMetadata::staticTypeName()) {
                delayedLoadValue(bytes, item);
            } else if (type != openvdb::StringMetadata::staticTypeName()
                       && openvdb::Metadata::isRegisteredType(type)) {
                // TypedMetadata<T> reads sizeof(T) bytes whatever the size says.
                const uint32_t expected = openvdb::Metadata::createMetadata(type)->size();
                if (bytes != expected) {
                    corrupt(item + " of type " + printable(type) + " has " + std::to_string(bytes) +
                            " bytes, expected " + std::to_string(expected));
                }
            }
            // Strings and unknown types are read as the size says.
            mPos = std::max(mPos, valueStart + bytes);
        }
    }

    /// A GridDescriptor (GridDescriptor::read): unique name, type, instance parent, offsets.
    /// Returns the grid's name; @a instance (if given) says whether it names a parent whose
    /// tree it shares (a grid copied with GridBase::copy(), written once); @a pointDataGrid
    /// (if given), whether its type is PointDataGrid's.
    std::string gridDescriptor(uint32_t version, bool* instance = nullptr, bool* pointDataGrid = nullptr)
    {
        const std::string name = string("grid name");
        const std::string grid = "grid '" + printable(name) + "'";
        const std::string type = string("type name of " + grid);
        if (pointDataGrid) *pointDataGrid = type == PointDataGrid::gridType();
        std::string parent;
        if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) parent = string("instance parent of " + grid);
        if (instance) *instance = !parent.empty();
        skip(3 * 8, grid + " descriptor");
        return name;
    }

    bool hasGridOffsets() const { return mHasGridOffsets; }

    /// What io::Archive::readGrid() reads before the tree: compression flags, the grid's
    /// MetaMap and transform; then, for a PointDataGrid, the tree's topology.
    void grid(const std::string& name, bool pointDataGrid, uint32_t version)
    {
        const std::string grid = "grid '" + printable(name) + "'";
        const uint32_t compression = load<uint32_t>(grid + " compression flags");
        metaMap(grid);
        transform(grid);
        if (!pointDataGrid) return;
        // Before multi-pass I/O, a PointDataGrid's leaves were read in one pass that leaves
        // their attribute arrays half-read; OpenVDB itself never wrote such files.
        if (version < openvdb::OPENVDB_FILE_VERSION_MULTIPASS_IO) {
            corrupt(grid + " is a point data grid in file format " + std::to_string(version) +
                    " (point data grids need 224 or later)");
        }
        mLeafCount = 0;
        pointTreeTopology(compression, "tree of " + grid);
        pointLeafBuffers(grid);
    }

    /// Grid::readBuffers() of a PointDataGrid (PointDataLeafNode::readBuffers): a pass count,
    /// then every leaf once per pass, in tree order:
    ///   0          each leaf's voxel buffer size (2 bytes);
    ///   1          a header byte and an attribute descriptor (until one is marked as shared
    ///              by all leaves that follow), then the metadata of each attribute array;
    ///   2 .. A+1   attribute a - 2: the page headers of its paged arrays;
    ///   A+2        the voxel values (point offsets);
    ///   A+3 .. 2A+2  attribute a - A - 3: its data (pages, or the array's own bytes).
    /// OpenVDB trusts every size in there: it allocates what a descriptor, an array or a page
    /// header says, asserts (and so aborts the process, Debian building libopenvdb with
    /// assertions) on a zero page size or on an array running past its page, and copies
    /// arrays out of pages without checking that they are as long as the array. So each size
    /// is checked here against the bytes left and against what the array must hold (its size,
    /// stride and storage type), every leaf and every page, before OpenVDB reads any of it.
    /// One pass over the bytes: Blosc chunks are checked by their 16-byte headers, then
    /// decompressed (bloscChunk()), since OpenVDB leaks when it throws on corrupt data.
    void pointLeafBuffers(const std::string& grid)
    {
        const std::string what = "leaf buffers of " + grid;
        const uint16_t passes = load<uint16_t>(what);
        skip(2 * mLeafCount, what);  // pass 0

        // Pass 1: descriptors and array metadata. A header with bit 0 set makes its leaf's
        // descriptor the one of every later leaf (none of them stores one); bit 1 announces a
        // block of bytes to skip, which OpenVDB reads into a vector of that size. The arrays
        // of all leaves go into one vector, leaf after leaf (firstArray[leaf] is where each
        // leaf's start).
        std::vector<ArrayLayout> arrays;
        std::vector<size_t> firstArray;
        firstArray.reserve(size_t(mLeafCount) + 1);
        std::shared_ptr<const LeafDescriptor> descriptor;
        bool shared = false;
        size_t attributes = 0;  // the most attributes of a leaf
        for (uint64_t leaf = 0; leaf < mLeafCount; ++leaf) {
            const auto where = [&] { return "leaf " + std::to_string(leaf) + " of " + grid; };
            if (!shared) {
                const uint8_t header = load<uint8_t>(where);
                if (header > 3) {
                    corrupt("unknown header flags " + std::to_string(header) + " in " + where());
                }
                descriptor = attributeDescriptor("attribute descriptor of " + where());
                if (header & 2) {
                    const uint64_t bytes = load<uint64_t>(where);
                    if (bytes > left()) {
                        corrupt("block to skip in " + where() + " claims " + std::to_string(bytes) +
                                " bytes, " + std::to_string(left()) + " left");
                    }
                    mPos += size_t(bytes);
                }
                shared = header & 1;
            }
            attributes = std::max(attributes, descriptor->storageBytes.size());
            firstArray.push_back(arrays.size());
            for (size_t a = 0; a < descriptor->storageBytes.size(); ++a) {
                arrays.push_back(arrayMetadata(descriptor->storageBytes[a], [&] {
                    return "attribute '" + printable(descriptor->names[a]) + "' of " + where();
                }));
            }
        }
        firstArray.push_back(arrays.size());
        const auto arrayOf = [&](uint64_t leaf, size_t a) -> ArrayLayout* {
            const size_t first = firstArray[size_t(leaf)];
            return a < firstArray[size_t(leaf) + 1] - first ? &arrays[first + a] : nullptr;
        };
        // Passes beyond the attributes read nothing; fewer would leave arrays unread. (A tree
        // without leaves is written with no passes.)
        if (mLeafCount > 0 && passes < 4 + 2 * attributes) {
            corrupt(what + " come in " + std::to_string(passes) + " passes; leaves with " +
                    std::to_string(attributes) + " attributes need " +
                    std::to_string(4 + 2 * attributes));
        }

        // Passes 2 .. A+1: the page headers, attribute by attribute. A paged attribute's
        // arrays are packed into pages in leaf order (compression::PagedInputStream): a new
        // page header comes when the last page is used up, and each array takes its bytes
        // from the current page. Every array must lie inside its page (OpenVDB asserts it),
        // and every page must be used up, else the data pass would not read it and the arrays
        // in it would be copied from a page that was never loaded.
        std::vector<std::vector<PageLayout>> pages(attributes);
        for (size_t a = 0; a < attributes; ++a) {
            uint64_t used = 0, pageBytes = 0;
            for (uint64_t leaf = 0; leaf < mLeafCount; ++leaf) {
                ArrayLayout* array = arrayOf(leaf, a);
                if (!array || !array->paged) continue;
                const auto where = [&] {
                    return "attribute " + std::to_string(a) + " of leaf " + std::to_string(leaf) +
                           " of " + grid;
                };
                if (used == pageBytes) {
                    pages[a].push_back(pageHeader([&] { return "page header of " + where(); }));
                    pageBytes = pages[a].back().uncompressedBytes;
                    used = 0;
                }
                array->page = pages[a].size() - 1;
                if (array->bytes > pageBytes - used) {
                    corrupt("array of " + std::to_string(array->bytes) + " bytes in " + where() +
                            " runs past its page (" + std::to_string(pageBytes - used) +
                            " bytes left in it)");
                }
                used += array->bytes;
            }
            if (used != pageBytes) {
                corrupt("last page of attribute " + std::to_string(a) + " in " + what + " holds " +
                        std::to_string(pageBytes) + " bytes, its arrays " + std::to_string(used));
            }
        }

        // Pass A+2: each leaf's value mask and point offsets (io::readCompressedValues for
        // PointDataIndex32: a 16-bit size, 0xffff for 2048 raw bytes, else a Blosc chunk).
        for (uint64_t leaf = 0; leaf < mLeafCount; ++leaf) {
            const auto where = [&] {
                return "point offsets of leaf " + std::to_string(leaf) + " of " + grid;
            };
            skip(64, where);
            const uint16_t bytes = load<uint16_t>(where);
            if (bytes == std::numeric_limits<uint16_t>::max()) skip(2048, where);
            else bloscChunk(bytes, 2048, where);
        }

        // Passes A+3 .. 2A+2: the data, attribute by attribute, leaf by leaf. A paged array
        // reads its page when it is the first array in it.
        for (size_t a = 0; a < attributes; ++a) {
            size_t nextPage = 0;
            for (uint64_t leaf = 0; leaf < mLeafCount; ++leaf) {
                const ArrayLayout* array = arrayOf(leaf, a);
                if (!array) continue;
                const auto where = [&] {
                    return "attribute " + std::to_string(a) + " of leaf " + std::to_string(leaf) +
                           " of " + grid;
                };
                if (array->paged) {
                    if (array->page == nextPage) {
                        pageData(pages[a][nextPage++], [&] { return "page of " + where(); });
                    }
                    continue;
                }
                // TypedAttributeArray::readBuffers(): a non-uniform array says whether it is
                // Blosc-compressed; raw bytes become the array as they are.
                const auto data = [&] { return "data of " + where(); };
                const bool blosc = !array->uniform && load<uint8_t>(data) == 1;
                if (blosc) {
                    bloscChunk(array->bytes, array->expectedBytes, data);
                } else {
                    if (array->bytes != array->expectedBytes) {
                        corrupt(data() + " has " + std::to_string(array->bytes) + " bytes, expected " +
                                std::to_string(array->expectedBytes));
                    }
                    skip(array->bytes, data);
                }
            }
        }
    }

    /// What a leaf's later passes need to know of its attribute descriptor.
    struct LeafDescriptor
    {
        std::vector<std::string> names;     ///< by attribute index
        std::vector<size_t> storageBytes;   ///< sizeof(StorageType) of each attribute's array
    };

    /// AttributeSet::Descriptor::read(): the attribute count (OpenVDB sizes a vector by it),
    /// the type and codec names, the names with their indices, the groups, a MetaMap.
    /// Every type must be a registered attribute type (AttributeSet::readMetadata creates the
    /// arrays by it), and the names must number the attributes 0..n-1, each once: the reader
    /// looks arrays up by these indices.
    std::shared_ptr<const LeafDescriptor> attributeDescriptor(const std::string& descriptor)
    {
        const uint64_t attributes = load<uint64_t>(descriptor);
        // An attribute takes a type, a codec and a name (three string lengths) and an index.
        if (attributes > left() / 20) {
            corrupt(descriptor + " claims " + std::to_string(attributes) + " attributes");
        }
        auto result = std::make_shared<LeafDescriptor>();
        result->names.resize(size_t(attributes));
        result->storageBytes.resize(size_t(attributes));
        for (uint64_t a = 0; a < attributes; ++a) {
            const std::string type = string("type name in " + descriptor);
            const std::string codec = string("codec name in " + descriptor);
            result->storageBytes[a] = storageBytes({type, codec}, descriptor);
        }
        std::vector<bool> named(size_t(attributes), false);
        for (uint64_t a = 0; a < attributes; ++a) {
            const std::string name = string("attribute name in " + descriptor);
            const uint64_t index = load<uint64_t>(descriptor);
            if (index >= attributes || named[index]) {
                corrupt("attribute '" + printable(name) + "' in " + descriptor + " has index " +
                        std::to_string(index) + " (" + std::to_string(attributes) + " attributes)");
            }
            named[index] = true;
            result->names[index] = name;
        }
        const uint64_t groups = load<uint64_t>(descriptor);
        if (groups > left() / 12) corrupt(descriptor + " claims " + std::to_string(groups) + " groups");
        for (uint64_t g = 0; g < groups; ++g) {
            string("group name in " + descriptor);
            skip(8, descriptor);
        }
        metaMap(descriptor);
        return result;
    }

    /// sizeof(StorageType) of the attribute array type @a type (value type, codec), from an
    /// array of one value made by OpenVDB's registry; remembered per type.
    size_t storageBytes(const openvdb::NamePair& type, const std::string& descriptor)
    {
        const auto known = mStorageBytes.find(type);
        if (known != mStorageBytes.end()) return known->second;
        if (!openvdb::points::AttributeArray::isRegistered(type)) {
            corrupt("unknown attribute type '" + printable(type.first) + "' with codec '" +
                    printable(type.second) + "' in " + descriptor);
        }
        const size_t bytes = openvdb::points::AttributeArray::create(type, 1)->storageTypeSize();
        mStorageBytes.emplace(type, bytes);
        return bytes;
    }

    /// One attribute array of one leaf, as TypedAttributeArray::readMetadata() leaves it.
    struct ArrayLayout
    {
        uint64_t bytes = 0;          ///< bytes of data: paged or raw, the array itself
        uint64_t expectedBytes = 0;  ///< what the array holds: its data size × storage size
        bool paged = false;
        bool uniform = false;
        size_t page = 0;             ///< paged: index of its page among the attribute's pages
    };

    /// TypedAttributeArray::readMetadata(): a byte count (including the 2 flag bytes and the
    /// 4-byte size that follow), flags, serialization flags, size, and the stride (or total
    /// size) when strided. The array's data is its data size (1 if uniform; size × stride,
    /// or the total size when the stride varies, as OpenVDB's 32-bit dataSize() computes it)
    /// times @a storageBytes; a paged array's byte count must say exactly that, since it is
    /// all OpenVDB copies out of the page for it.
    template<typename WhatT>
    ArrayLayout arrayMetadata(size_t storageBytes, const WhatT& where)
    {
        using openvdb::points::AttributeArray;
        const auto metadata = [&] { return "metadata of " + where(); };
        const uint64_t bytes = load<uint64_t>(metadata);
        const uint8_t flags = load<uint8_t>(metadata);
        const uint8_t serialization = load<uint8_t>(metadata);
        const uint32_t size = load<uint32_t>(metadata);
        if (bytes < 6) corrupt(where() + " claims " + std::to_string(bytes) + " bytes, less than its header");
        // Flags from 0x20 up are not OpenVDB's (0x20 is its own "partially read" state).
        if (flags >= AttributeArray::PARTIALREAD) {
            corrupt(where() + " has unknown flags " + std::to_string(flags));
        }
        if (serialization >= 2 * AttributeArray::WRITEPAGED) {
            corrupt(where() + " has unknown serialization flags " + std::to_string(serialization));
        }
        uint32_t strideOrTotal = 1;
        if (serialization & AttributeArray::WRITESTRIDED) strideOrTotal = load<uint32_t>(metadata);
        ArrayLayout array;
        array.bytes = bytes - 6;
        array.paged = serialization & AttributeArray::WRITEPAGED;
        array.uniform = serialization & AttributeArray::WRITEUNIFORM;
        const bool constantStride = flags & AttributeArray::CONSTANTSTRIDE;
        if (size == 0 || strideOrTotal == 0 || (!constantStride && strideOrTotal < size)) {
            corrupt(where() + " has size " + std::to_string(size) + " and " +
                    (constantStride ? "stride " : "total size ") + std::to_string(strideOrTotal));
        }
        const uint64_t values = array.uniform ? 1
                              : constantStride ? uint64_t(size) * strideOrTotal : strideOrTotal;
        if (values > std::numeric_limits<uint32_t>::max()) {
            corrupt(where() + " has " + std::to_string(size) + " values of stride " +
                    std::to_string(strideOrTotal) + ", more than 2^32");
        }
        array.expectedBytes = values * storageBytes;
        if (array.paged && array.bytes != array.expectedBytes) {
            corrupt(where() + " claims " + std::to_string(array.bytes) + " bytes, expected " +
                    std::to_string(array.expectedBytes) + " for " + std::to_string(values) +
                    " values of " + std::to_string(storageBytes) + " bytes");
        }
        return array;
    }

    /// A page of a paged attribute (compression::Page): compressed size and, if it is
    /// positive (Blosc), the uncompressed size; a negative size means that many raw bytes.
    struct PageLayout
    {
        int32_t compressedBytes = 0;
        uint64_t uncompressedBytes = 0;
    };

    /// compression::Page::readHeader(), which asserts that neither size is 0.
    template<typename WhatT>
    PageLayout pageHeader(const WhatT& where)
    {
        PageLayout page;
        page.compressedBytes = int32_t(load<uint32_t>(where));
        if (page.compressedBytes > 0) {
            const int32_t uncompressed = int32_t(load<uint32_t>(where));
            if (uncompressed <= 0) {
                corrupt(where() + " gives uncompressed size " + std::to_string(uncompressed));
            }
            page.uncompressedBytes = uint64_t(uncompressed);
        } else if (page.compressedBytes == 0 || page.compressedBytes == std::numeric_limits<int32_t>::min()) {
            corrupt(where() + " gives compressed size " + std::to_string(page.compressedBytes));
        } else {
            page.uncompressedBytes = uint64_t(-int64_t(page.compressedBytes));
        }
        return page;
    }

    /// compression::Page::readBuffers(): the page's bytes, raw or one Blosc chunk.
    template<typename WhatT>
    void pageData(const PageLayout& page, const WhatT& where)
    {
        if (page.compressedBytes < 0) skip(page.uncompressedBytes, where);
        else bloscChunk(uint64_t(page.compressedBytes), page.uncompressedBytes, where);
    }

    /// A Blosc chunk of @a bytes that must decompress to @a uncompressed bytes. Blosc trusts
    /// its 16-byte header (uncompressed size at byte 4, block size at 8, compressed size at
    /// 12): OpenVDB allocates twice the uncompressed size it gives and copies the array out
    /// of that, and Blosc reads as many bytes as its compressed size says, so both must agree
    /// with the sizes the file gave OpenVDB. (OpenVDB pads inputs shorter than
    /// compression::BLOSC_PAD_BYTES to that length with zeros before compressing them.)
    /// Blosc's codecs do not compress more than 1032:1 (deflate's limit; OpenVDB writes LZ4,
    /// at most about 255:1), which bounds what a small file can make OpenVDB allocate.
    /// A tree's topology is read by io::bloscFromStream, which neither pads nor accepts
    /// padding (@a padded false).
    ///
    /// The chunk is then decompressed into a scratch buffer, as OpenVDB will decompress it,
    /// and must give exactly the bytes its header says: sizes cannot tell corrupt data, and
    /// OpenVDB leaks when it throws on it (in the topology, RootNode::readTopology holds the
    /// new child node in a raw pointer, 270 KB and its subtree; in the leaf buffers, the
    /// pages and page handles of PagedInputStream). At most a page (1 MB) at a time.
    template<typename WhatT>
    void bloscChunk(uint64_t bytes, uint64_t uncompressed, const WhatT& where, bool padded = true)
    {
        need(bytes, where);
        if (bytes < 16) {
            corrupt("Blosc chunk of " + std::to_string(bytes) + " bytes in " + describe(where) +
                    " is shorter than its header");
        }
        uint32_t header[3];
        std::memcpy(header, here(16) + 4, sizeof(header));
        const uint64_t pad = uint64_t(openvdb::compression::BLOSC_PAD_BYTES);
        padded = padded && header[0] == pad && uncompressed <= pad;
        // Blosc divides by the block size and allocates by it; it writes 1 for no bytes.
        if ((header[0] != uncompressed && !padded) || header[2] != bytes || header[1] == 0
            || header[1] > std::max<uint32_t>(header[0], 1)) {
            corrupt("Blosc chunk in " + describe(where) + " says " + std::to_string(header[0]) + " bytes from " +
                    std::to_string(header[2]) + " in blocks of " + std::to_string(header[1]) +
                    "; expected " + std::to_string(uncompressed) + " bytes from " + std::to_string(bytes));
        }
        if (uncompressed / 1032 > bytes) {
            corrupt("Blosc chunk in " + describe(where) + " claims " + std::to_string(uncompressed) +
                    " bytes from " + std::to_string(bytes) + ", more than 1032:1");
        }
        // A bare 16-byte header of no bytes (a node without active values) is what
        // io::bloscFromStream accepts and compression::bloscDecompress would not.
        if (header[0] > 0) {
            // compression::bloscDecompress wants room for Blosc's overhead after the bytes.
            mScratch.resize(std::max(mScratch.size(), size_t(header[0]) + BLOSC_MAX_OVERHEAD));
            try {
                openvdb::compression::bloscDecompress(mScratch.data(), size_t(uncompressed),
                    size_t(header[0]) + BLOSC_MAX_OVERHEAD, reinterpret_cast<const char*>(here(size_t(bytes))));
            } catch (const openvdb::Exception&) {
                corrupt("corrupt Blosc chunk in " + describe(where) + ": it does not decompress to the " +
                        std::to_string(header[0]) + " bytes its header gives");
            }
        }
        mPos += size_t(bytes);
    }

    /// math::Transform::read(): the map's type name, then its fields (a frustum map nests
    /// a second map).
    void transform(const std::string& grid)
    {
        using namespace openvdb::math;
        const std::string what = "transform of " + grid;
        for (;;) {
            const std::string map = string(what);
            if (map == NonlinearFrustumMap::mapType()) {
                skip(6 * 8 + 2 * 8, what);  // bounding box, taper, depth
                continue;
            }
            // The fields each map type's read() reads: Mat4d, or Vec3d translation and the
            // five Vec3d of a scale.
            const uint64_t bytes =
                (map == AffineMap::mapType() || map == UnitaryMap::mapType()) ? 16 * 8
                : (map == ScaleMap::mapType() || map == UniformScaleMap::mapType()) ? 5 * 24
                : (map == ScaleTranslateMap::mapType() || map == UniformScaleTranslateMap::mapType()) ? 6 * 24
                : map == TranslationMap::mapType() ? 24 : 0;
            if (bytes == 0) corrupt("unknown map type '" + printable(map) + "' in " + what);
            skip(bytes, what);
            return;
        }
    }

    /// Tree::readTopology() of a PointDataGrid (5-4-3 tree of 4-byte PointDataIndex32):
    /// buffer count, root background, tiles, then each child's subtree.
    void pointTreeTopology(uint32_t compression, const std::string& what)
    {
        // Trees of more than one buffer are gone from OpenVDB; it would warn on stderr and
        // read on as if there were one.
        const uint32_t buffers = load<uint32_t>(what);
        if (buffers != 1) corrupt(what + " has " + std::to_string(buffers) + " buffers; point grids have 1");
        // Leaves are made with the background as their value, and a PointDataLeafNode
        // asserts that it is 0 (its values are point offsets), aborting the process.
        const uint32_t background = load<uint32_t>(what);
        if (background != 0) {
            corrupt(what + " has background " + std::to_string(background) + "; point grids need 0");
        }
        const uint32_t tiles = load<uint32_t>(what);
        const uint32_t children = load<uint32_t>(what);
        if (tiles > left() / 17) {
            corrupt(what + " claims " + std::to_string(tiles) + " root tiles in " +
                    std::to_string(left()) + " bytes");
        }
        skip(uint64_t(tiles) * 17, what);  // origin, value, active flag
        // A root child takes its origin and two 4096-byte masks at least.
        if (children > left() / (12 + 8192)) {
            corrupt(what + " claims " + std::to_string(children) + " root children in " +
                    std::to_string(left()) + " bytes");
        }
        // RootNode keeps its children in a map by origin and reads their buffers in that
        // order; OpenVDB writes them in it. Out of order (or twice, which replaces the first),
        // the leaf buffers would belong to other leaves than the ones walked here.
        std::array<int32_t, 3> previous{};
        for (uint32_t i = 0; i < children; ++i) {
            std::array<int32_t, 3> origin;
            for (int32_t& xyz : origin) xyz = load<int32_t>(what);
            if (i > 0 && !(previous < origin)) {
                corrupt("root children of " + what + " are not in order: (" + coord(origin) +
                        ") after (" + coord(previous) + ")");
            }
            previous = origin;
            internalNode(5, compression, what);
        }
    }

    static std::string coord(const std::array<int32_t, 3>& xyz)
    {
        return std::to_string(xyz[0]) + ", " + std::to_string(xyz[1]) + ", " + std::to_string(xyz[2]);
    }

    /// InternalNode::readTopology(): child and value masks, the values, then the children
    /// (level 4 nodes below a level 5 node; leaves, of which the topology is a 64-byte
    /// value mask, below a level 4 node).
    void internalNode(int log2Dim, uint32_t compression, const std::string& what)
    {
        const size_t maskBytes = (size_t(1) << (3 * log2Dim)) / 8;
        need(2 * maskBytes, what);
        const unsigned char* masks = here(2 * maskBytes);
        const size_t childCount = bitCount(masks, maskBytes);
        const size_t activeCount = bitCount(masks + maskBytes, maskBytes);
        mPos += 2 * maskBytes;
        compressedValues(size_t(1) << (3 * log2Dim), activeCount, maskBytes, compression, what);
        for (size_t c = 0; c < childCount; ++c) {
            if (log2Dim == 5) internalNode(4, compression, what);
            else skip(64, what);
        }
        if (log2Dim == 4) mLeafCount += childCount;
    }

    /// io::readCompressedValues() of @a count 4-byte values: a flag saying what follows,
    /// up to two inactive values, a selection mask, then the (active) values as one chunk.
    void compressedValues(size_t count, size_t activeCount, size_t maskBytes,
                          uint32_t compression, const std::string& what)
    {
        const int8_t flag = load<int8_t>(what);
        if (flag == 2 || flag == 4 || flag == 5) skip(flag == 5 ? 8 : 4, what);
        if (flag == 3 || flag == 4 || flag == 5) skip(maskBytes, what);
        if ((compression & openvdb::io::COMPRESS_ACTIVE_MASK) && flag != 6) count = activeCount;
        const uint64_t bytes = uint64_t(count) * 4;
        if (!(compression & (openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ZIP))) {
            skip(bytes, what);
            return;
        }
        // io::bloscFromStream / unzipFromStream: an int64 size, negative for raw bytes.
        const int64_t chunk = load<int64_t>(what);
        if (chunk <= 0) {
            if (uint64_t(0) - uint64_t(chunk) != bytes) {
                corrupt("uncompressed chunk of " + std::to_string(uint64_t(0) - uint64_t(chunk)) +
                        " bytes in " + what + ", expected " + std::to_string(bytes));
            }
            skip(bytes, what);
            return;
        }
        if (uint64_t(chunk) > left()) {
            corrupt("compressed chunk in " + what + " claims " + std::to_string(chunk) +
                    " bytes, " + std::to_string(left()) + " left");
        }
        // Blosc takes precedence over zip (io::readData); Blosc reads as much as its own
        // header says, whatever the chunk size said.
        if (compression & openvdb::io::COMPRESS_BLOSC) {
            bloscChunk(uint64_t(chunk), bytes, what, /*padded=*/false);
        } else {
            zipChunk(here(size_t(chunk)), size_t(chunk), size_t(bytes), what);
            mPos += size_t(chunk);
        }
    }

    /// io::unzipFromStream() of a chunk of node values (at most 32^3 values of 4 bytes): it
    /// is inflated into a scratch buffer first and must give exactly @a bytes, for the
    /// reason bloscChunk() gives (OpenVDB throws on it inside RootNode::readTopology).
    void zipChunk(const unsigned char* chunk, size_t chunkBytes, size_t bytes, const std::string& what)
    {
        mScratch.resize(std::max(mScratch.size(), bytes));
        uLongf inflated = uLongf(bytes);
        const int status = uncompress(reinterpret_cast<Bytef*>(mScratch.data()), &inflated,
                                      chunk, uLong(chunkBytes));
        if (status != Z_OK) {
            corrupt("corrupt zlib chunk in " + what + " (" + zError(status) + ")");
        }
        if (inflated != bytes) {
            corrupt("zlib chunk in " + what + " inflates to " + std::to_string(inflated) +
                    " bytes, expected " + std::to_string(bytes));
        }
    }

    static size_t bitCount(const unsigned char* bytes, size_t size)
    {
        size_t n = 0;
        for (size_t i = 0; i < size; ++i) n += size_t(__builtin_popcount(bytes[i]));
        return n;
    }

    /// The readers below name what they read for the error message with @a what: a string,
    /// or (in the per-leaf walk, run for every leaf) a callable returning one, called only
    /// when there is an error to report.
    ///
    /// An integer of type @a T as the file stores it (OpenVDB writes the host's byte order,
    /// little-endian on every platform it supports). Also used for the grid count.
    template<typename T, typename WhatT>
    T load(const WhatT& what)
    {
        static_assert(std::is_integral_v<T>, "load<T>() reads integers");
        need(sizeof(T), what);
        T value;
        std::memcpy(&value, here(sizeof(T)), sizeof(T));
        mPos += sizeof(T);
        return value;
    }

    size_t left() const { return mSize - mPos; }

    [[noreturn]] void corrupt(const std::string& what) const
    {
        fail(mPath, "cannot read .vdb file: " + what);
    }

private:
    template<typename WhatT>
    static std::string describe(const WhatT& what)
    {
        if constexpr (std::is_invocable_v<const WhatT&>) return what();
        else return std::string(what);
    }

    template<typename WhatT>
    void need(uint64_t bytes, const WhatT& what) const
    {
        if (bytes > left()) corrupt("truncated " + describe(what));
    }
    template<typename WhatT>
    void skip(uint64_t bytes, const WhatT& what)
    {
        need(bytes, what);
        mPos += size_t(bytes);
    }
    template<typename WhatT>
    std::string string(const WhatT& what)
    {
        const uint32_t length = load<uint32_t>(what);
        if (length > left()) {
            corrupt(describe(what) + " claims " + std::to_string(length) + " bytes, " +
                    std::to_string(left()) + " left");
        }
        std::string text(reinterpret_cast<const char*>(here(length)), length);
        mPos += length;
        return text;
    }

    /// io::DelayedLoadMetadata::readValue(): a leaf count, then a mask of one byte per leaf
    /// and optionally a compressed size of 8 bytes per leaf, each raw or Blosc-compressed.
    /// OpenVDB sizes its arrays from the count and from the Blosc headers.
    void delayedLoadValue(uint32_t bytes, const std::string& item)
    {
        if (bytes == 0) return;
        const uint32_t count = load<uint32_t>(item);
        // A leaf takes far more than one byte of the file.
        if (count > mSize) corrupt(item + " claims " + std::to_string(count) + " leaves");
        for (int array = 0; array < 2; ++array) {
            const uint64_t width = array == 0 ? 1 : 8;
            const uint32_t compressed = load<uint32_t>(item);
            if (array == 1 && compressed == std::numeric_limits<uint32_t>::max()) break;
            if (compressed == 0) {
                skip(uint64_t(count) * width, item);
                continue;
            }
            // A Blosc chunk starts with a 16-byte header whose bytes 4..7 hold the
            // uncompressed size (little-endian). OpenVDB's bloscCompress() pads arrays
            // shorter than 128 bytes to 128 before compressing them.
            if (compressed < 16 || compressed > left()) corrupt("bad compressed array in " + item);
            uint32_t uncompressed;
            std::memcpy(&uncompressed, here(16) + 4, 4);
            constexpr uint64_t kBloscPadBytes = 128;
            const uint64_t arrayBytes = uint64_t(count) * width;
            if (uncompressed != arrayBytes && !(arrayBytes < kBloscPadBytes && uncompressed == kBloscPadBytes)) {
                corrupt("bad compressed array in " + item);
            }
            mPos += compressed;
        }
    }

    /// The @a n bytes at the read position (need() has checked them), valid until the next
    /// read.
    const unsigned char* here(size_t n) { return mBytes.bytes(mPos, n); }

    VdbWindow mBytes;
    uint64_t mSize;
    size_t mPos = 0;
    const std::string& mPath;
    bool mHasGridOffsets = false;
    uint64_t mLeafCount = 0;  ///< leaves in the topology walked last
    std::vector<char> mScratch;  ///< decompressed chunks (bloscChunk(), zipChunk())
    /// sizeof(StorageType) per attribute array type seen (storageBytes())
    std::map<openvdb::NamePair, size_t> mStorageBytes;
};

/// io::Stream's reading, grid by grid, with VdbSizeCheck run on each part before OpenVDB
/// reads it; stops at the first PointDataGrid. (io::Archive's protected readers are the
/// same ones io::Stream uses.)
class CheckedVdbStream : public openvdb::io::Archive
{
public:
    /// The grids read, the last of them the first PointDataGrid if there is one.
    openvdb::GridPtrVec read(const VdbSource& source, const std::string& path)
    {
        const uint64_t size = source.size();
        VdbSizeCheck check(source, path);
        VdbStreamBuf buffer(source);
        std::istream is(&buffer);
        // OpenVDB does not check its reads: past the end it would go on with uninitialised
        // sizes. A short read throws instead.
        is.exceptions(std::ios::failbit | std::ios::badbit);
        auto position = [&]() -> size_t {
            const std::streamoff pos = is ? std::streamoff(is.tellg()) : std::streamoff(-1);
            if (pos < 0 || size_t(pos) > size) check.corrupt("truncated stream");
            return size_t(pos);
        };
        auto expectAt = [&](size_t pos, const char* what) {
            const size_t read = position();
            if (read != pos) {
                check.corrupt(std::string("unexpected layout of ") + what + " (OpenVDB read up to byte " +
                              std::to_string(read) + ", the check walked up to " + std::to_string(pos) + ")");
            }
        };

        const uint32_t version = check.header();
        readHeader(is);
        expectAt(check.pos(), "the header");
        openvdb::io::StreamMetadata::Ptr streamMetadata(new openvdb::io::StreamMetadata);
        openvdb::io::setStreamMetadataPtr(is, streamMetadata, /*transfer=*/false);
        openvdb::io::setVersion(is, libraryVersion(), fileVersion());
        openvdb::io::setDataCompression(is, compression());

        check.metaMap("the file");
        openvdb::MetaMap fileMetadata;
        fileMetadata.readMeta(is);
        expectAt(check.pos(), "the file metadata");

        const uint32_t gridCount = check.gridCount();
        readGridCount(is);

        openvdb::GridPtrVec grids;
        NamedGridMap namedGrids;
        bool pointsRead = false;  // the first PointDataGrid, the only one read
        for (uint32_t i = 0; i < gridCount; ++i) {
            check.seek(position());
            check.gridDescriptor(version);
            openvdb::io::GridDescriptor descriptor;
            descriptor.read(is);
            expectAt(check.pos(), "a grid descriptor");
            if (!openvdb::GridBase::isRegistered(descriptor.gridType())) {
                check.corrupt("unknown grid type '" + printable(descriptor.gridType()) + "'");
            }
            openvdb::GridBase::Ptr grid = openvdb::GridBase::createGrid(descriptor.gridType());
            const bool pointDataGrid = descriptor.gridType() == PointDataGrid::gridType();
            // Other grids are not needed, nor point grids after the first: where the file says
            // where they end, skip them unread (only their names and types are kept, for the
            // error message and ParticleSet::skipped).
            if ((!pointDataGrid || pointsRead) && check.hasGridOffsets() && descriptor.getEndPos() > 0
                && uint64_t(descriptor.getEndPos()) >= check.pos()
                && uint64_t(descriptor.getEndPos()) <= size) {
                grid->setName(descriptor.gridName());
                grids.push_back(grid);
                is.seekg(descriptor.getEndPos());
                continue;
            }
            // An instance shares its parent's tree; the file stores none for it.
            check.grid(descriptor.uniqueName(), pointDataGrid && !descriptor.isInstance(), version);
            grid->setSaveFloatAsHalf(descriptor.saveFloatAsHalf());
            readGrid(grid, descriptor, is);
            if (pointDataGrid && !descriptor.isInstance()) expectAt(check.pos(), "a point data grid");
            grids.push_back(grid);
            namedGrids[descriptor.uniqueName()] = grid;
            connectInstance(descriptor, namedGrids);
            if (openvdb::gridConstPtrCast<PointDataGrid>(grid)) {
                pointsRead = true;
                if (!check.hasGridOffsets()) break;  // the rest could only be found by reading it
            }
        }
        return grids;
    }
};

/// checkVdbLayout() of @a source.
void checkLayout(const VdbSource& source, const std::string& path)
{
    VdbSizeCheck check(source, path);
    const uint64_t size = source.size();
    const uint32_t version = check.header();
    check.metaMap("the file");
    const uint32_t gridCount = check.gridCount();
    for (uint32_t i = 0; i < gridCount; ++i) {
        bool instance = false, pointDataGrid = false;
        const std::string name = check.gridDescriptor(version, &instance, &pointDataGrid);
        const size_t gridStart = check.pos();
        // The descriptor ends with three offsets: grid, blocks, end of the grid.
        check.seek(gridStart - 24);
        const int64_t gridPosition = check.load<int64_t>("grid descriptor");
        const int64_t blockPosition = check.load<int64_t>("grid descriptor");
        const int64_t end = check.load<int64_t>("grid descriptor");
        if (!check.hasGridOffsets()) {
            // Written to a stream: the next grid starts where this one's tree ends, which
            // only reading the tree finds.
            check.grid(name, /*pointDataGrid=*/false, version);
            return;
        }
        if (end < int64_t(gridStart)) {
            // io::File patches the offsets in once a grid is written: a cut-off write leaves 0.
            check.corrupt("truncated or corrupt grid '" + printable(name) + "' (its end offset " + std::to_string(end) +
                          " lies before its start " + std::to_string(gridStart) + ")");
        }
        if (uint64_t(end) > size) {
            check.corrupt("truncated grid '" + printable(name) + "' (it ends at byte " + std::to_string(end) +
                          ", the file has " + std::to_string(size) + ")");
        }
        // io::File reads the grid from its grid offset (where the walk below starts, right
        // after the descriptor) and seeks to its block offset: one pointing elsewhere made
        // it read past the end of the file into uninitialised lengths (gigabytes, minutes).
        // An instance stores no tree, so io::Archive leaves its block offset 0 (a file with
        // one was refused: bug hunt).
        const bool blocksInside = blockPosition >= int64_t(gridStart) && blockPosition <= end;
        if (gridPosition != int64_t(gridStart) || !(blocksInside || (instance && blockPosition == 0))) {
            check.corrupt("corrupt grid '" + printable(name) + "' (its grid and block offsets " +
                          std::to_string(gridPosition) + " and " + std::to_string(blockPosition) +
                          " do not lie between its start " + std::to_string(gridStart) + " and end " +
                          std::to_string(end) + ")");
        }
        // A PointDataGrid's leaves are walked too: OpenVDB asserts (aborts) on a page size of
        // 0 or an array past its page, when io::File reads them or, delay-loaded, when they
        // are first touched ('inspect' of tests/data/fuzz/vdb_points_*_assert.vdb: exit 134).
        check.grid(name, pointDataGrid && !instance, version);
        if (check.pos() > uint64_t(end)) check.corrupt("grid '" + printable(name) + "' overruns its end offset");
        check.seek(size_t(end));
    }
}

/// @a read(VdbSource) over the file @a path: a regular file through pread(); anything else
/// (a pipe, which cannot be read twice: walk, then OpenVDB) read whole first.
template<typename ReadT>
auto withVdbSource(const std::string& path, ReadT&& read)
{
    const OpenFile file = openFile(path);
    if (!file.regular) {
        const std::vector<char> data = readToEndAndClose(file.fd, path, 0);
        return read(VdbSource(data.data(), data.size(), path));
    }
    struct FdCloser { int fd; ~FdCloser() { ::close(fd); } } closer{file.fd};
    return read(VdbSource(file.fd, file.size, path));
}

/// The first PointDataGrid of @a source, converted.
ParticleSet
readVdbPoints(const VdbSource& source, const std::string& path)
{
    openvdb::initialize();
    openvdb::GridPtrVec grids;
    try {
        grids = CheckedVdbStream().read(source, path);
        for (size_t g = 0; g < grids.size(); ++g) {
            if (const auto points = openvdb::gridConstPtrCast<PointDataGrid>(grids[g])) {
                ParticleSet particles = convertGrid(*points, path);
                // Only the first is read; the others are said (bug hunt: a second grid's
                // particles were left out of a mesh without a word).
                for (size_t other = g + 1; other < grids.size(); ++other) {
                    if (openvdb::gridConstPtrCast<PointDataGrid>(grids[other])) {
                        particles.skipped.push_back("point grid '" + printable(grids[other]->getName()) + "'");
                    }
                }
                return particles;
            }
        }
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        fail(path, "corrupt .vdb file: it asks for more memory than there is");
    } catch (const std::ios_base::failure&) {
        fail(path, "cannot read .vdb file: truncated stream");
    } catch (const std::exception& e) {
        fail(path, "cannot read .vdb file: " + printable(e.what(), std::string::npos));
    }
    fail(path, "no PointDataGrid in this .vdb file (grids: " +
         [&] {
             std::string names;
             for (const auto& grid : grids) {
                 if (!names.empty()) names += ", ";
                 names += printable(grid->getName()) + " " + grid->valueType();
             }
             return names.empty() ? std::string("none") : names;
         }() + "); a density cache holds no particles to read");
}

} // namespace

ParticleSet
readVdbPointsParticles(const char* data, size_t size, const std::string& path)
{
    return readVdbPoints(VdbSource(data, size, path), path);
}

void
checkVdbLayout(const std::string& path)
{
    withVdbSource(path, [&](const VdbSource& source) { checkLayout(source, path); });
}

ParticleSet
readVdbPointsFile(const std::string& path)
{
    return withVdbSource(path, [&](const VdbSource& source) { return readVdbPoints(source, path); });
}

} // namespace io_internal
} // namespace nonbloppy
