// SPDX-License-Identifier: Apache-2.0
/// @file WriteMesh.cc
/// @brief Stage "write mesh": OBJ, binary little-endian PLY and legacy binary VTK POLYDATA.
///
/// Each writer formats into a large in-memory chunk that is handed to the stream a few
/// megabytes at a time, instead of one ostream operation per value, and goes through
/// AtomicFile so a failed write never leaves a partial mesh behind. The binary formats have
/// fixed-size records (a vertex, a triangle, a quad), so each batch of records is encoded in
/// parallel straight to its final offset and then written in order; OBJ's lines are formatted
/// in parallel, pieces of lines into strings of their own, written in order: the bytes are
/// the same for any thread count.

#include <nonbloppy/WriteMesh.h>

#include <nonbloppy/Error.h>

#include "AtomicFile.h"
#include "AttributeNames.h"
#include "FileFormats.h"
#include "PolygonIndices.h"
#include "SystemBuffer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <limits>
#include <ostream>
#include <type_traits>
#include <vector>

namespace nonbloppy {

namespace {

/// Writes made from TBB tasks, and the errno of the first that failed, for the caller:
/// errno is per thread, and writeFileAtomically() reports the calling thread's, so a full
/// disk was reported as "Input/output error" whenever the failing write ran on a worker
/// (half the runs at two threads; hostile-input audit).
class TaskWrites
{
public:
    void write(std::ostream& os, const char* data, std::streamsize size)
    {
        os.write(data, size);
        const int error = errno;
        if (!os && error != 0) {
            int none = 0;
            mErrno.compare_exchange_strong(none, error);
        }
    }
    /// In the calling thread once the tasks are done: errno as the failed write left it.
    void restoreErrno() const
    {
        if (const int error = mErrno.load()) errno = error;
    }

private:
    std::atomic<int> mErrno{0};
};

/// Collects output bytes and passes them on to the stream in large chunks.
class ChunkWriter
{
public:
    explicit ChunkWriter(std::ostream& os) : mStream(os) { mBuffer.reserve(kChunk + 4096); }
    ~ChunkWriter() = default;

    void text(const char* s) { mBuffer.append(s); maybeFlush(); }
    void text(const std::string& s) { mBuffer.append(s); maybeFlush(); }
    void maybeFlush()
    {
        if (mBuffer.size() >= kChunk) flush();
    }
    void flush()
    {
        mStream.write(mBuffer.data(), std::streamsize(mBuffer.size()));
        mBuffer.clear();
    }
    /// The stream, with everything collected so far passed on: for writing directly.
    std::ostream& stream()
    {
        flush();
        return mStream;
    }

private:
    static constexpr size_t kChunk = size_t(4) << 20;
    std::ostream& mStream;
    std::string mBuffer;
};

/// The polygons as they will be written: triangles first, then quads (kept or split).
struct PolygonView
{
    const SurfaceMesh& mesh;
    bool keepQuads;

    size_t triangleCount() const
    {
        return mesh.triangles.size() + (keepQuads ? 0 : 2 * mesh.quads.size());
    }
    size_t quadCount() const { return keepQuads ? mesh.quads.size() : 0; }
    size_t polygonCount() const { return triangleCount() + quadCount(); }
    size_t cornerCount() const { return 3 * triangleCount() + 4 * quadCount(); }

    /// The mesh's polygons as written come from its triangles, then its quads: items.
    size_t itemCount() const { return mesh.triangles.size() + mesh.quads.size(); }

    /// Call op(const uint32_t* corners, int n) for the written polygons of item @a i, in
    /// order: a triangle, a quad kept, or the two triangles of a quad split.
    template<typename OpT>
    void forEachOf(size_t i, OpT op) const
    {
        const auto [corners, count] = polygon_indices_internal::cornersOf(mesh, i);
        if (count == 3 || keepQuads) {
            op(corners, count);
            return;
        }
        const uint32_t second[3] = {corners[0], corners[2], corners[3]};
        op(corners, 3);
        op(second, 3);
    }
};

/// Stores @a value's bytes (4 or 8) at @a at in the given byte order; returns the next
/// position.
template<bool BigEndian, typename T>
inline char* putBytes(char* at, T value)
{
    static_assert(sizeof(T) == 4 || sizeof(T) == 8, "4- or 8-byte values only");
    std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t> bits;
    std::memcpy(&bits, &value, sizeof(T));
    if ((__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__) != BigEndian) {
        if constexpr (sizeof(T) == 4) bits = __builtin_bswap32(bits);
        else bits = __builtin_bswap64(bits);
    }
    std::memcpy(at, &bits, sizeof(T));
    return at + sizeof(T);
}

/// The type @a attribute's values are stored as: Float32 for floats; for integers the
/// narrowest that holds every one exactly, Int32 or (VTK: Int64, PLY: UInt32 or Float64).
ScalarType
storedType(const MeshAttribute& attribute, bool vtk)
{
    if (!attribute.integer) return ScalarType::Float32;
    const auto range = std::minmax_element(attribute.integers.begin(), attribute.integers.end());
    const int64_t lowest = attribute.integers.empty() ? 0 : *range.first;
    const int64_t highest = attribute.integers.empty() ? 0 : *range.second;
    const ScalarType ply = io_internal::plyIntegerType(lowest, highest);
    return vtk && ply != ScalarType::Int32 ? ScalarType::Int64 : ply;
}

/// Stores element @a i of @a attribute as @a type (storedType()) at @a at; returns the next
/// position.
template<bool BigEndian>
inline char* putValue(char* at, const MeshAttribute& attribute, size_t i, ScalarType type)
{
    switch (type) {
    case ScalarType::Float32: return putBytes<BigEndian>(at, attribute.values[i]);
    case ScalarType::Int32: return putBytes<BigEndian>(at, int32_t(attribute.integers[i]));
    case ScalarType::UInt32: return putBytes<BigEndian>(at, uint32_t(attribute.integers[i]));
    case ScalarType::Int64: return putBytes<BigEndian>(at, attribute.integers[i]);
    default: return putBytes<BigEndian>(at, double(attribute.integers[i]));
    }
}

/// Writes @a count records of @a recordBytes each, record i encoded by
/// encode(i, char* record): batches of about 8 MB are encoded in parallel into one of two
/// buffers while the batch before is written from the other (a TBB task, so --threads holds),
/// in order, so the bytes do not depend on the thread count. Peak extra memory: 16 MB, mapped
/// for the call (see SystemBuffer.h).
/// Writing one batch after encoding it left the threads idle during each write, which copies
/// the batch into the file's buffer and waits for the disk: on the 64x benchmark mesh (119 MB)
/// the writes took 0.073 s and the encoding 0.037 s, one after the other.
template<typename EncodeT>
void
writeRecords(ChunkWriter& out, size_t count, size_t recordBytes, const EncodeT& encode)
{
    if (count == 0) return;
    std::ostream& os = out.stream();
    constexpr size_t kBatchBytes = size_t(8) << 20;
    const size_t perBatch = std::max<size_t>(1, kBatchBytes / recordBytes);
    memory_internal::SystemBuffer batches[2];
    batches[0] = memory_internal::SystemBuffer(std::min(count, perBatch) * recordBytes);
    if (count > perBatch) batches[1] = memory_internal::SystemBuffer(perBatch * recordBytes);
    tbb::task_group writing;
    TaskWrites writes;
    try {
        for (size_t first = 0, k = 0; first < count; first += perBatch, ++k) {
            const size_t n = std::min(perBatch, count - first);
            char* batch = batches[k % 2].data();
            tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 8192), [&](const tbb::blocked_range<size_t>& r) {
                for (size_t i = r.begin(); i < r.end(); ++i) encode(first + i, batch + i * recordBytes);
            });
            writing.wait();  // the batch before is written: its buffer is free for the next
            writing.run([&os, &writes, batch, bytes = std::streamsize(n * recordBytes)] {
                writes.write(os, batch, bytes);
            });
        }
        writing.wait();
        writes.restoreErrno();
    } catch (...) {
        writing.wait();  // the buffers outlive the write in flight
        throw;
    }
}

/// The polygons of @a polygons as fixed-size records: the triangles, then the quads (one
/// quad record each, or two triangle records when split). Each corner is a 4-byte int;
/// PLY starts a polygon with a one-byte corner count, VTK with a 4-byte one.
template<bool BigEndian, typename CountT>
void
writePolygonRecords(ChunkWriter& out, const PolygonView& polygons)
{
    const SurfaceMesh& mesh = polygons.mesh;
    static_assert(sizeof(CountT) == 1 || sizeof(CountT) == 4, "one- or four-byte counts");
    auto putPolygon = [](char* at, const uint32_t* corners, int n) {
        if constexpr (sizeof(CountT) == 1) {
            *at++ = char(n);
        } else {
            at = putBytes<BigEndian>(at, CountT(n));
        }
        for (int i = 0; i < n; ++i) at = putBytes<BigEndian>(at, int32_t(corners[i]));
        return at;
    };
    const size_t triangleBytes = sizeof(CountT) + 3 * 4, quadBytes = sizeof(CountT) + 4 * 4;
    writeRecords(out, mesh.triangles.size(), triangleBytes, [&](size_t i, char* at) {
        const openvdb::Vec3I& t = mesh.triangles[i];
        const uint32_t corners[3] = {t[0], t[1], t[2]};
        putPolygon(at, corners, 3);
    });
    if (polygons.keepQuads) {
        writeRecords(out, mesh.quads.size(), quadBytes, [&](size_t i, char* at) {
            const openvdb::Vec4I& q = mesh.quads[i];
            const uint32_t corners[4] = {q[0], q[1], q[2], q[3]};
            putPolygon(at, corners, 4);
        });
    } else {
        writeRecords(out, mesh.quads.size(), 2 * triangleBytes, [&](size_t i, char* at) {
            const openvdb::Vec4I& q = mesh.quads[i];
            const uint32_t first[3] = {q[0], q[1], q[2]};
            const uint32_t second[3] = {q[0], q[2], q[3]};
            putPolygon(putPolygon(at, first, 3), second, 3);
        });
    }
}

/// A mesh with out-of-range indices would produce a file every reader rejects.
void
validateMesh(const SurfaceMesh& mesh, const std::string& path)
{
    const size_t vertexCount = mesh.points.size();
    if (!mesh.normals.empty() && mesh.normals.size() != vertexCount) {
        throw ParameterError("mesh has " + std::to_string(mesh.normals.size()) +
            " normals for " + std::to_string(vertexCount) + " vertices (" + path + ")");
    }
    for (const MeshAttribute& attribute : mesh.attributes) {
        if (attribute.components < 1 || attribute.size() != vertexCount * size_t(attribute.components)) {
            throw ParameterError("mesh attribute '" + attribute.name + "' has " +
                std::to_string(attribute.size()) + " values for " +
                std::to_string(vertexCount) + " vertices of " +
                std::to_string(attribute.components) + " components (" + path + ")");
        }
        if (attribute.integer ? !attribute.values.empty() : !attribute.integers.empty()) {
            throw ParameterError("mesh attribute '" + attribute.name + "' has " +
                (attribute.integer ? "float values but is marked integer" : "integers but is not marked integer") +
                " (" + path + ")");
        }
    }
    const std::string badIndex = polygon_indices_internal::firstBadIndex(mesh);
    if (!badIndex.empty()) throw ParameterError(badIndex + " (" + path + ")");
}

/// Writes @a count text items, item i appended to a std::string by format(i, std::string&):
/// pieces of kItemsPerPiece items go through a TBB pipeline, formatted in parallel, each into
/// a string of its own, and written in order as they come, so the bytes do not depend on the
/// thread count. Peak extra memory: one string per token, two tokens per thread (about
/// 170 KB of OBJ lines each).
/// One thread formatting the whole text was most of an OBJ write: on the 64x benchmark mesh
/// (403 MB of text) the write stage took 0.76 s of a 2.01 s run. Written a piece at a time,
/// the file's own writer (AtomicFile: direct writes on a thread of its own) works while the
/// next pieces are formatted; batches of 32 pieces, each written after the next was
/// formatted, left the disk idle meanwhile (one thread 0.85 s against 0.56-0.61 s, two
/// 0.44-0.47 s against 0.40-0.43 s). Pieces of 1024 and 16384 lines, or 4 and 8 tokens per
/// thread, were no faster (the disk's time varies by ±0.1 s between runs).
template<typename FormatT>
void
writeTextItems(ChunkWriter& out, size_t count, const FormatT& format)
{
    if (count == 0) return;
    std::ostream& os = out.stream();
    constexpr size_t kItemsPerPiece = 4096;
    const size_t pieceCount = (count + kItemsPerPiece - 1) / kItemsPerPiece;
    // A piece holds its token from formatting to writing, so piece p + tokens never shares
    // piece p's string while p is in flight.
    const size_t tokens = 2 * size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    std::vector<std::string> texts(tokens);
    size_t next = 0;
    TaskWrites writes;
    tbb::parallel_pipeline(tokens,
        tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
            [&](tbb::flow_control& control) -> size_t {
                if (next == pieceCount) control.stop();
                return next++;
            })
        & tbb::make_filter<size_t, size_t>(tbb::filter_mode::parallel,
            [&](size_t piece) {
                std::string& text = texts[piece % tokens];
                text.clear();
                const size_t begin = piece * kItemsPerPiece, end = std::min(begin + kItemsPerPiece, count);
                for (size_t i = begin; i < end; ++i) format(i, text);
                return piece;
            })
        & tbb::make_filter<size_t, void>(tbb::filter_mode::serial_in_order,
            [&](size_t piece) {
                const std::string& text = texts[piece % tokens];
                writes.write(os, text.data(), std::streamsize(text.size()));
            }));
    writes.restoreErrno();
}

/// Appends @a value as the shortest decimal text that reads back as exactly it.
inline char* putNumber(char* at, float value)
{
    return std::to_chars(at, at + 32, value).ptr;
}
inline char* putNumber(char* at, uint64_t value)
{
    return std::to_chars(at, at + 24, value).ptr;
}

/// Appends the OBJ line "<tag> x y z" for @a v (tag "v" or "vn") to @a text.
inline void appendVectorLine(std::string& text, const char* tag, const openvdb::Vec3s& v)
{
    char line[128];
    char* at = line;
    while (*tag) *at++ = *tag++;
    for (int a = 0; a < 3; ++a) {
        *at++ = ' ';
        at = putNumber(at, v[a]);
    }
    *at++ = '\n';
    text.append(line, size_t(at - line));
}

/// Appends the OBJ face line of the @a n corners (0-based) to @a text, each corner "i" or,
/// @a withNormals, "i//i" (1-based).
inline void appendFaceLine(std::string& text, const uint32_t* corners, int n, bool withNormals)
{
    char line[4 * 48 + 2];
    char* at = line;
    *at++ = 'f';
    for (int i = 0; i < n; ++i) {
        const uint64_t oneBased = uint64_t(corners[i]) + 1;
        *at++ = ' ';
        at = putNumber(at, oneBased);
        if (withNormals) {
            *at++ = '/';
            *at++ = '/';
            at = putNumber(at, oneBased);
        }
    }
    *at++ = '\n';
    text.append(line, size_t(at - line));
}

void
writeObj(const SurfaceMesh& mesh, const PolygonView& polygons, std::ostream& os)
{
    ChunkWriter out(os);
    out.text("# nonbloppy surface mesh\n");
    writeTextItems(out, mesh.points.size(), [&](size_t i, std::string& text) {
        appendVectorLine(text, "v", mesh.points[i]);
    });
    writeTextItems(out, mesh.normals.size(), [&](size_t i, std::string& text) {
        appendVectorLine(text, "vn", mesh.normals[i]);
    });
    const bool withNormals = !mesh.normals.empty();
    writeTextItems(out, polygons.itemCount(), [&](size_t i, std::string& text) {
        polygons.forEachOf(i, [&](const uint32_t* corners, int n) { appendFaceLine(text, corners, n, withNormals); });
    });
    out.flush();
}

/// Whether the PLY and VTK writers declare normals: when the mesh has them, and when it has
/// no vertices, so that a sequence's empty frames (before the fluid arrives, say) declare
/// the columns its other frames have (a pipeline's meshes have normals).
bool declaresNormals(const SurfaceMesh& mesh)
{
    return !mesh.normals.empty() || mesh.points.empty();
}

/// The names the writer of extension @a ext (lower case, with the dot) gives the mesh's
/// attributes, one per attribute in order: in the particle writers' alphabet, distinct from
/// one another and from the format's own columns (PLY: x, y, z and, with normals, nx, ny,
/// nz; VTK: the NORMALS array "normals"). Empty for `.obj`, which has no place for them.
std::vector<std::string>
attributeNamesFor(const SurfaceMesh& mesh, const std::string& ext)
{
    using namespace attribute_names_internal;
    std::vector<NamedAttribute> attributes;
    for (const MeshAttribute& a : mesh.attributes) attributes.emplace_back(a.name, a.components);
    const bool withNormals = declaresNormals(mesh);
    if (ext == ".ply") {
        return uniqueNames(attributes, headerWord, plyColumns, [withNormals](const std::string& column) {
            return column == "x" || column == "y" || column == "z"
                || (withNormals && (column == "nx" || column == "ny" || column == "nz"));
        }, io_internal::suffixComponentOf);
    }
    if (ext == ".vtk") {
        return uniqueNames(attributes, headerWord, wholeColumn,
                           [withNormals](const std::string& column) { return withNormals && column == "normals"; });
    }
    return std::vector<std::string>(mesh.attributes.size());
}

void
requireInt32(size_t value, const char* what, const std::string& path)
{
    if (value > size_t(std::numeric_limits<int32_t>::max())) {
        throw FileError(std::string("too many ") + what + " for 32-bit indices (" + path + ")");
    }
}

void
writePly(const SurfaceMesh& mesh, const PolygonView& polygons, const std::string& path,
         std::ostream& os)
{
    requireInt32(mesh.points.size(), "vertices", path);
    const bool withNormals = declaresNormals(mesh);
    ChunkWriter out(os);
    out.text("ply\nformat binary_little_endian 1.0\ncomment written by nonbloppy\n");
    out.text("element vertex " + std::to_string(mesh.points.size()) + "\n");
    out.text("property float x\nproperty float y\nproperty float z\n");
    if (withNormals) out.text("property float nx\nproperty float ny\nproperty float nz\n");
    const std::vector<std::string> names = attributeNamesFor(mesh, ".ply");
    std::vector<ScalarType> types(mesh.attributes.size());
    size_t vertexBytes = withNormals ? 24 : 12;
    for (size_t i = 0; i < mesh.attributes.size(); ++i) {
        types[i] = storedType(mesh.attributes[i], /*vtk=*/false);
        vertexBytes += scalarSize(types[i]) * size_t(mesh.attributes[i].components);
        for (const std::string& column : attribute_names_internal::plyColumns(names[i], mesh.attributes[i].components)) {
            out.text(std::string("property ") + io_internal::plyTypeName(types[i]) + " " + column + "\n");
        }
    }
    out.text("element face " + std::to_string(polygons.polygonCount()) + "\n");
    out.text("property list uchar int vertex_indices\nend_header\n");
    writeRecords(out, mesh.points.size(), vertexBytes, [&](size_t i, char* at) {
        for (int axis = 0; axis < 3; ++axis) at = putBytes<false>(at, float(mesh.points[i][axis]));
        if (withNormals) {
            for (int axis = 0; axis < 3; ++axis) at = putBytes<false>(at, float(mesh.normals[i][axis]));
        }
        for (size_t a = 0; a < mesh.attributes.size(); ++a) {
            const MeshAttribute& attribute = mesh.attributes[a];
            const size_t first = i * size_t(attribute.components);
            for (int c = 0; c < attribute.components; ++c) at = putValue<false>(at, attribute, first + size_t(c), types[a]);
        }
    });
    writePolygonRecords</*BigEndian=*/false, uint8_t>(out, polygons);
    out.flush();
}

void
writeVtk(const SurfaceMesh& mesh, const PolygonView& polygons, const std::string& path,
         std::ostream& os)
{
    requireInt32(mesh.points.size(), "vertices", path);
    requireInt32(polygons.polygonCount() + polygons.cornerCount(), "polygon corners", path);
    ChunkWriter out(os);
    out.text("# vtk DataFile Version 3.0\nnonbloppy surface mesh\nBINARY\nDATASET POLYDATA\n");
    out.text("POINTS " + std::to_string(mesh.points.size()) + " float\n");
    auto putVec3 = [](char* at, const openvdb::Vec3s& v) {
        for (int axis = 0; axis < 3; ++axis) at = putBytes<true>(at, float(v[axis]));
    };
    writeRecords(out, mesh.points.size(), 12, [&](size_t i, char* at) { putVec3(at, mesh.points[i]); });
    out.text("\nPOLYGONS " + std::to_string(polygons.polygonCount()) + " " +
        std::to_string(polygons.polygonCount() + polygons.cornerCount()) + "\n");
    writePolygonRecords</*BigEndian=*/true, int32_t>(out, polygons);
    out.text("\n");
    const bool withNormals = declaresNormals(mesh);
    if (withNormals || !mesh.attributes.empty()) {
        out.text("POINT_DATA " + std::to_string(mesh.points.size()) + "\n");
    }
    if (withNormals) {
        out.text("NORMALS normals float\n");
        writeRecords(out, mesh.normals.size(), 12, [&](size_t i, char* at) { putVec3(at, mesh.normals[i]); });
        out.text("\n");
    }
    // Vectors as VECTORS, 1, 2 and 4 components as SCALARS, anything else as a FIELD array.
    const std::vector<std::string> names = attributeNamesFor(mesh, ".vtk");
    for (size_t i = 0; i < mesh.attributes.size(); ++i) {
        const MeshAttribute& attribute = mesh.attributes[i];
        const std::string& name = names[i];
        const ScalarType stored = storedType(attribute, /*vtk=*/true);
        const std::string type = io_internal::vtkTypeName(stored);
        if (attribute.components == 3) {
            out.text("VECTORS " + name + " " + type + "\n");
        } else if (attribute.components <= 4) {
            out.text("SCALARS " + name + " " + type + " " + std::to_string(attribute.components) +
                "\nLOOKUP_TABLE default\n");
        } else {
            out.text("FIELD FieldData 1\n" + name + " " + std::to_string(attribute.components) +
                " " + std::to_string(mesh.points.size()) + " " + type + "\n");
        }
        writeRecords(out, attribute.size(), scalarSize(stored),
                     [&](size_t i, char* at) { putValue<true>(at, attribute, i, stored); });
        out.text("\n");
    }
    out.flush();
}

} // namespace

std::vector<std::string>
writtenAttributeNames(const SurfaceMesh& mesh, const std::string& path)
{
    return attributeNamesFor(mesh, io_internal::requireMeshExtension(path));
}

std::vector<std::string>
roundedAttributes(const SurfaceMesh& mesh, const std::string& path)
{
    const std::string ext = io_internal::requireMeshExtension(path);
    std::vector<std::string> rounded;
    if (ext != ".ply") return rounded;  // VTK has vtktypeint64; OBJ leaves attributes out
    for (const MeshAttribute& a : mesh.attributes) {
        if (a.integer && !std::all_of(a.integers.begin(), a.integers.end(), io_internal::exactInDouble)) {
            rounded.push_back(a.name);
        }
    }
    return rounded;
}

void
writeMesh(const SurfaceMesh& mesh, const std::string& path, const MeshWriteSettings& settings)
{
    const std::string ext = io_internal::requireMeshExtension(path);
    validateMesh(mesh, path);
    if (ext != ".obj") {  // OBJ drops the attributes
        for (const MeshAttribute& a : mesh.attributes) io_internal::requireFileComponents(a.name, a.components, " (" + path + ")");
    }
    const PolygonView polygons{mesh, settings.keepQuads};
    // A lower bound of every format's size: binary positions and corner indices.
    const size_t expectedBytes = mesh.points.size() * sizeof(openvdb::Vec3s) + polygons.cornerCount() * 4;
    writeFileAtomically(path, [&](std::ostream& os) {
        if (ext == ".obj") writeObj(mesh, polygons, os);
        else if (ext == ".ply") writePly(mesh, polygons, path, os);
        else writeVtk(mesh, polygons, path, os);
    }, settings.directIo ? expectedBytes : 0);
}

bool
isMeshFile(const std::string& path)
{
    return io_internal::isMeshExtension(io_internal::lowerExtension(path));
}

void
requireMeshFile(const std::string& path)
{
    io_internal::requireMeshExtension(path);
}

} // namespace nonbloppy
