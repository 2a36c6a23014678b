// SPDX-License-Identifier: Apache-2.0
/// @file ReadMesh.cc
/// @brief Read OBJ, PLY (with a face element) and legacy VTK POLYDATA meshes.

#include <nonbloppy/ReadMesh.h>

#include <nonbloppy/Error.h>

#include "FileFormats.h"

#include <charconv>
#include <cstring>
#include <limits>
#include <string_view>

#include <unistd.h>

namespace nonbloppy {

namespace {

using namespace io_internal;

/// Appends polygons to a mesh: triangles and quads as they are, larger ones as a fan
/// (v0, vi, vi+1), which is exact for the convex polygons mesh writers produce.
class PolygonSink
{
public:
    PolygonSink(SurfaceMesh& mesh, const std::string& path) : mMesh(mesh), mPath(path) {}

    void add(const uint32_t* corners, size_t n)
    {
        const size_t vertexCount = mMesh.points.size();
        for (size_t i = 0; i < n; ++i) {
            if (corners[i] >= vertexCount) {
                fail(mPath, "polygon " + std::to_string(mPolygon) + " references vertex " +
                    std::to_string(corners[i]) + " but the file has " +
                    std::to_string(vertexCount) + " vertices");
            }
        }
        if (n < 3) {
            fail(mPath, "polygon " + std::to_string(mPolygon) + " has only " +
                std::to_string(n) + " vertices");
        }
        if (n == 3) {
            mMesh.triangles.emplace_back(corners[0], corners[1], corners[2]);
        } else if (n == 4) {
            mMesh.quads.emplace_back(corners[0], corners[1], corners[2], corners[3]);
        } else {
            for (size_t i = 1; i + 1 < n; ++i) {
                mMesh.triangles.emplace_back(corners[0], corners[i], corners[i + 1]);
            }
        }
        ++mPolygon;
    }

    void addAll(const PolygonList& polygons)
    {
        for (size_t i = 0; i < polygons.size(); ++i) {
            add(polygons.indices.data() + polygons.offsets[i],
                polygons.offsets[i + 1] - polygons.offsets[i]);
        }
    }

private:
    SurfaceMesh& mMesh;
    const std::string& mPath;
    size_t mPolygon = 0;
};

std::vector<openvdb::Vec3s>
toVectors(const std::vector<float>& x, const std::vector<float>& y, const std::vector<float>& z)
{
    std::vector<openvdb::Vec3s> vectors(x.size());
    for (size_t i = 0; i < vectors.size(); ++i) vectors[i] = openvdb::Vec3s(x[i], y[i], z[i]);
    return vectors;
}

SurfaceMesh
readPlyMesh(const std::vector<char>& file, const std::string& path)
{
    PlyData ply = parsePly(file.data(), file.size(), path, /*wantFaces=*/true);
    const NumericArray* columns[6] = {};
    const char* names[6] = {"x", "y", "z", "nx", "ny", "nz"};
    for (const NumericArray& property : ply.vertexProperties) {
        for (int i = 0; i < 6; ++i) {
            if (property.name == names[i]) columns[i] = &property;
        }
    }
    SurfaceMesh mesh;
    mesh.points = toVectors(toFloats(*columns[0]), toFloats(*columns[1]), toFloats(*columns[2]));
    if (columns[3] && columns[4] && columns[5]) {
        mesh.normals = toVectors(toFloats(*columns[3]), toFloats(*columns[4]),
            toFloats(*columns[5]));
    }
    PolygonSink(mesh, path).addAll(ply.faces);
    return mesh;
}

SurfaceMesh
readVtkMesh(const std::vector<char>& file, const std::string& path)
{
    VtkData vtk = parseVtk(file.data(), file.size(), path, /*wantPolygons=*/true);
    SurfaceMesh mesh;
    mesh.points = std::move(vtk.points);
    // NORMALS is the standard attribute; some writers store them as a 3-component array.
    const NumericArray* normals = nullptr;
    for (const NumericArray& array : vtk.pointArrays) {
        if (array.kind == "NORMALS" && array.components == 3) {
            normals = &array;
            break;
        }
        if (!normals && array.components == 3 &&
            (array.name == "normals" || array.name == "Normals")) {
            normals = &array;
        }
    }
    if (normals) {
        const std::vector<float> values = toFloats(*normals);
        mesh.normals.resize(values.size() / 3);
        for (size_t i = 0; i < mesh.normals.size(); ++i) {
            mesh.normals[i] = openvdb::Vec3s(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
        }
    }
    PolygonSink(mesh, path).addAll(vtk.polygons);
    return mesh;
}

// ---- OBJ

struct ObjCorner
{
    int64_t vertex = 0;   ///< 0-based after resolving, -1 if absent
    int64_t normal = -1;
};

std::vector<std::string_view>
splitLine(std::string_view line)
{
    std::vector<std::string_view> words;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
        const size_t begin = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
        if (i > begin) words.push_back(line.substr(begin, i - begin));
    }
    return words;
}

class ObjReader
{
public:
    ObjReader(const std::vector<char>& file, const std::string& path)
        : mFile(file), mPath(path) {}

    SurfaceMesh read()
    {
        std::vector<openvdb::Vec3s> fileNormals;
        std::vector<uint32_t> cornerVertices;
        std::vector<int64_t> cornerNormals;
        std::vector<size_t> faceOffsets{0};
        bool anyCornerNormal = false;
        struct ForwardReference
        {
            size_t line;
            int64_t vertex;  ///< 0-based
        };
        std::vector<ForwardReference> forwardReferences;  // in file order

        size_t pos = 0;
        while (pos < mFile.size()) {
            const char* begin = mFile.data() + pos;
            const void* newline = std::memchr(begin, '\n', mFile.size() - pos);
            const size_t length = newline
                ? size_t(static_cast<const char*>(newline) - begin) : mFile.size() - pos;
            pos += length + 1;
            ++mLineNumber;
            const std::string_view line(begin, length);
            // OBJ is text: a NUL byte means another kind of file, which the statements it
            // does not know would otherwise read as an empty mesh.
            if (std::memchr(line.data(), '\0', line.size())) failAtLine("binary data, not OBJ text,");
            if (line.size() < 2) continue;
            if (line[0] == 'v' && (line[1] == ' ' || line[1] == '\t')) {
                mMesh.points.push_back(readVector(line));
            } else if (line[0] == 'v' && line[1] == 'n' && line.size() > 2 &&
                       (line[2] == ' ' || line[2] == '\t')) {
                fileNormals.push_back(readVector(line));
            } else if (line[0] == 'f' && (line[1] == ' ' || line[1] == '\t')) {
                const std::vector<std::string_view> words = splitLine(line.substr(1));
                // Said at its line: "polygon 4 has only 2 vertices" left the reader to count
                // the faces before it.
                if (words.size() < 3) failAtLine("face with " + std::to_string(words.size()) + " vertices (at least 3)");
                int64_t highest = -1;
                for (std::string_view word : words) {
                    ObjCorner corner = readCorner(word, mMesh.points.size(), fileNormals.size());
                    cornerVertices.push_back(uint32_t(corner.vertex));
                    cornerNormals.push_back(corner.normal);
                    anyCornerNormal = anyCornerNormal || corner.normal >= 0;
                    highest = std::max(highest, corner.vertex);
                }
                faceOffsets.push_back(cornerVertices.size());
                // A vertex not yet read may still come later in the file; if it never does,
                // the face's line is named (polygon numbers mean nothing to an OBJ's reader).
                if (highest >= int64_t(mMesh.points.size())) forwardReferences.push_back({mLineNumber, highest});
            }
            // vt, o, g, s, usemtl, mtllib, comments: nothing a SurfaceMesh keeps.
        }

        for (const ForwardReference& reference : forwardReferences) {
            if (reference.vertex < int64_t(mMesh.points.size())) continue;
            mLineNumber = reference.line;
            failAtLine("vertex index " + std::to_string(reference.vertex + 1) + " out of range (the file has " +
                       std::to_string(mMesh.points.size()) + " vertices)");
        }

        // OBJ normals belong to face corners; SurfaceMesh has one normal per vertex.
        if (anyCornerNormal) {
            mMesh.normals.assign(mMesh.points.size(), openvdb::Vec3s(0.0f));
            for (size_t i = 0; i < cornerVertices.size(); ++i) {
                if (cornerNormals[i] < 0) continue;
                if (size_t(cornerNormals[i]) >= fileNormals.size() ||
                    cornerVertices[i] >= mMesh.points.size()) continue;  // checked below
                mMesh.normals[cornerVertices[i]] = fileNormals[size_t(cornerNormals[i])];
            }
        } else if (!fileNormals.empty() && fileNormals.size() == mMesh.points.size()) {
            mMesh.normals = std::move(fileNormals);
        }

        PolygonList polygons;
        polygons.offsets = std::move(faceOffsets);
        polygons.indices = std::move(cornerVertices);
        PolygonSink(mMesh, mPath).addAll(polygons);
        return std::move(mMesh);
    }

private:
    [[noreturn]] void failAtLine(const std::string& what) const
    {
        fail(mPath, what + " at line " + std::to_string(mLineNumber));
    }

    openvdb::Vec3s readVector(std::string_view line) const
    {
        const std::vector<std::string_view> words = splitLine(line);
        if (words.size() < 4) failAtLine("expected three coordinates");
        openvdb::Vec3s v;
        for (int i = 0; i < 3; ++i) {
            if (!parseWhole(words[size_t(i) + 1], v[i])) {
                failAtLine("bad number '" + printable(words[size_t(i) + 1]) + "'");
            }
        }
        return v;
    }

    /// 1-based or negative (relative) OBJ index → 0-based.
    int64_t resolveIndex(std::string_view text, size_t count, const char* what) const
    {
        int64_t index = 0;
        const char* end = text.data() + text.size();
        const auto result = std::from_chars(text.data(), end, index);
        if (text.empty() || result.ec != std::errc() || result.ptr != end || index == 0) {
            failAtLine(std::string("bad ") + what + " index '" + printable(text) + "'");
        }
        if (index < 0) {
            if (uint64_t(-(index + 1)) >= count) {
                failAtLine(std::string(what) + " index " + std::to_string(index) + " out of range");
            }
            return int64_t(count) + index;
        }
        if (index > int64_t(std::numeric_limits<uint32_t>::max())) {
            failAtLine(std::string(what) + " index " + std::to_string(index) + " out of range");
        }
        return index - 1;
    }

    ObjCorner readCorner(std::string_view word, size_t vertexCount, size_t normalCount) const
    {
        // v, v/vt, v//vn or v/vt/vn
        ObjCorner corner;
        const size_t slash = word.find('/');
        corner.vertex = resolveIndex(word.substr(0, slash), vertexCount, "vertex");
        if (slash != std::string_view::npos) {
            const size_t second = word.find('/', slash + 1);
            if (second != std::string_view::npos && second + 1 < word.size()) {
                corner.normal = resolveIndex(word.substr(second + 1), normalCount, "normal");
            }
        }
        return corner;
    }

    const std::vector<char>& mFile;
    const std::string& mPath;
    size_t mLineNumber = 0;
    SurfaceMesh mMesh;
};

} // namespace

SurfaceMesh
readMesh(const std::string& path)
{
    const std::string ext = requireMeshExtension(path);  // the formats writeMesh() writes
    const std::vector<char> file = loadFile(path);
    if (ext == ".obj") return ObjReader(file, path).read();
    if (ext == ".ply") return readPlyMesh(file, path);
    return readVtkMesh(file, path);
}

bool
declaresPolygons(const std::string& path)
{
    const std::string ext = lowerExtension(path);
    if (ext != ".ply" && ext != ".vtk") {
        // Nothing to read, but a file that cannot be opened is said to be so (a missing
        // .obj was declared a mesh).
        ::close(openFile(path).fd);
        return ext == ".obj";
    }
    // A PLY header says it all: the vertex data after it (gigabytes, maybe) is not read.
    const std::vector<char> file = ext == ".ply" ? loadFileThrough(path, "end_header") : loadFile(path);
    return ext == ".ply" ? plyDeclaresFaces(file.data(), file.size(), path)
                         : vtkDeclaresPolygons(file.data(), file.size(), path);
}

} // namespace nonbloppy
