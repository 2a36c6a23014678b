// SPDX-License-Identifier: Apache-2.0
/// @file InspectCommand.cc
/// @brief `nonbloppy inspect FILE [--json]`: what a .vdb, mesh or particle file holds, in the
///        manner of vdb_print (one line per grid) and pbrt's `plytool info`.

#include "Commands.h"
#include "Json.h"
#include "UsageError.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/EstimateParameters.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/Mesh.h>
#include <nonbloppy/Particles.h>
#include <nonbloppy/ReadMesh.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/ReadVdb.h>

#include <openvdb/openvdb.h>
#include <openvdb/points/PointCount.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/tools/Count.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <limits>
#include <memory>
#include <new>
#include <optional>
#include <sstream>
#include <type_traits>
#include <string>
#include <vector>

#include <sys/stat.h>

namespace nonbloppy_tool {

namespace {

// ---------------------------------------------------------------------------------------
// A small JSON writer: objects and arrays, indented two spaces, strings escaped.

class JsonWriter
{
public:
    void beginObject(const char* key = nullptr) { open(key, '{'); }
    void endObject() { close('}'); }
    void beginArray(const char* key = nullptr) { open(key, '['); }
    void endArray() { close(']'); }

    /// A value already in JSON syntax.
    void raw(const char* key, const std::string& json)
    {
        item(key);
        mOut << json;
    }
    void string(const char* key, const std::string& value) { raw(key, jsonString(value)); }
    void number(const char* key, double value) { raw(key, jsonNumber(value)); }
    void integer(const char* key, long long value) { raw(key, std::to_string(value)); }
    void boolean(const char* key, bool value) { raw(key, value ? "true" : "false"); }
    void vec3(const char* key, double x, double y, double z)
    {
        raw(key, "[" + jsonNumber(x) + ", " + jsonNumber(y) + ", " + jsonNumber(z) + "]");
    }

    /// "bbox": {"min": [...], "max": [...]}, or null when there is no point.
    void boundingBox(const std::optional<std::pair<openvdb::Vec3d, openvdb::Vec3d>>& bbox)
    {
        if (!bbox) {
            raw("bbox", "null");
            return;
        }
        beginObject("bbox");
        vec3("min", bbox->first.x(), bbox->first.y(), bbox->first.z());
        vec3("max", bbox->second.x(), bbox->second.y(), bbox->second.z());
        endObject();
    }

    std::string str() const { return mOut.str() + "\n"; }

private:
    void item(const char* key)
    {
        if (!mFirst.empty()) {
            if (!mFirst.back()) mOut << ",";
            mFirst.back() = false;
            mOut << "\n" << std::string(2 * mFirst.size(), ' ');
        }
        if (key) mOut << jsonString(key) << ": ";
    }
    void open(const char* key, char bracket)
    {
        item(key);
        mOut << bracket;
        mFirst.push_back(true);
    }
    void close(char bracket)
    {
        const bool empty = mFirst.back();
        mFirst.pop_back();
        if (!empty) mOut << "\n" << std::string(2 * mFirst.size(), ' ');
        mOut << bracket;
    }

    std::ostringstream mOut;
    std::vector<bool> mFirst; ///< per open container: no item written yet
};

// ---------------------------------------------------------------------------------------
// Helpers

std::string formatVec3(double x, double y, double z)
{
    return "(" + formatNumber(x) + ", " + formatNumber(y) + ", " + formatNumber(z) + ")";
}

std::string formatCoord(const openvdb::Coord& c)
{
    return "(" + std::to_string(c.x()) + "," + std::to_string(c.y()) + "," + std::to_string(c.z())
           + ")";
}

/// Bounding box of @a points (min, max); nullopt for none.
template<typename Vec3T>
std::optional<std::pair<openvdb::Vec3d, openvdb::Vec3d>> boundingBox(const std::vector<Vec3T>& points)
{
    if (points.empty()) return std::nullopt;
    openvdb::Vec3d lo(std::numeric_limits<double>::infinity()), hi(-lo);
    for (const Vec3T& p : points) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], double(p[a]));
            hi[a] = std::max(hi[a], double(p[a]));
        }
    }
    return std::make_pair(lo, hi);
}

void printRow(const std::string& label, const std::string& value)
{
    char line[64];
    std::snprintf(line, sizeof(line), "  %-16s ", label.c_str());
    std::cout << line << value << "\n";
}

// ---------------------------------------------------------------------------------------
// Particle files

/// What inspect says of one attribute: its name, type and components, and per component the
/// smallest and largest value that is finite, with the count of values that are not (NaN or
/// infinite, which a simulation that blew up writes). The values themselves are not kept.
struct AttributeSummary
{
    std::string name;
    nonbloppy::ScalarType type = nonbloppy::ScalarType::Float32;
    int components = 1;
    /// Per component, the shortest text that reads back as the value (integers exact, floats
    /// in their own type's digits), valid JSON; empty where no value is finite (or none).
    std::vector<std::string> low, high;
    size_t nonFinite = 0;
};

/// Whether @a a orders before @a b, -0 before +0: std::min of the two equal zeros keeps
/// whichever came first, and the parallel reduction's order depends on the threads.
template<typename T>
bool before(T a, T b)
{
    if constexpr (std::is_floating_point_v<T>) return a < b || (a == b && std::signbit(a) && !std::signbit(b));
    return a < b;
}

/// The per-component range of @a a's values, stored as T (its type). Cost: one pass over the
/// values, in parallel over particles; the result does not depend on the order.
template<typename T>
void summarizeValues(const nonbloppy::ParticleAttribute& a, AttributeSummary& summary)
{
    const auto lower = [](T x, T y) { return before(y, x) ? y : x; };
    const auto higher = [](T x, T y) { return before(x, y) ? y : x; };
    const size_t components = size_t(std::max(1, a.components));
    const size_t count = a.bytes.size() / sizeof(T) / components;
    struct Range
    {
        std::vector<T> low, high;
        std::vector<bool> any;
        size_t nonFinite = 0;
    };
    const auto empty = [&] { return Range{std::vector<T>(components), std::vector<T>(components), std::vector<bool>(components), 0}; };
    const Range range = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, count, 65536), empty(),
        [&](const tbb::blocked_range<size_t>& particles, Range r) {
            for (size_t i = particles.begin(); i < particles.end(); ++i) {
                for (size_t c = 0; c < components; ++c) {
                    T v;
                    std::memcpy(&v, a.bytes.data() + (i * components + c) * sizeof(T), sizeof(T));
                    if constexpr (std::is_floating_point_v<T>) {
                        if (!std::isfinite(v)) {
                            ++r.nonFinite;
                            continue;
                        }
                    }
                    if (!r.any[c]) {
                        r.low[c] = r.high[c] = v;
                        r.any[c] = true;
                    } else {
                        r.low[c] = lower(r.low[c], v);
                        r.high[c] = higher(r.high[c], v);
                    }
                }
            }
            return r;
        },
        [&](Range r, const Range& other) {
            for (size_t c = 0; c < components; ++c) {
                if (!other.any[c]) continue;
                r.low[c] = r.any[c] ? lower(r.low[c], other.low[c]) : other.low[c];
                r.high[c] = r.any[c] ? higher(r.high[c], other.high[c]) : other.high[c];
                r.any[c] = true;
            }
            r.nonFinite += other.nonFinite;
            return r;
        });
    summary.nonFinite = range.nonFinite;
    for (size_t c = 0; c < components; ++c) {
        // int8 and uint8 print as numbers, not characters.
        using Printed = std::conditional_t<std::is_integral_v<T> && sizeof(T) == 1, int, T>;
        summary.low.push_back(range.any[c] ? shortestText(Printed(range.low[c])) : std::string());
        summary.high.push_back(range.any[c] ? shortestText(Printed(range.high[c])) : std::string());
    }
}

AttributeSummary summarize(const nonbloppy::ParticleAttribute& a)
{
    AttributeSummary summary{a.name, a.type, a.components, {}, {}, 0};
    using nonbloppy::ScalarType;
    switch (a.type) {
    case ScalarType::Int8: summarizeValues<int8_t>(a, summary); break;
    case ScalarType::UInt8: summarizeValues<uint8_t>(a, summary); break;
    case ScalarType::Int16: summarizeValues<int16_t>(a, summary); break;
    case ScalarType::UInt16: summarizeValues<uint16_t>(a, summary); break;
    case ScalarType::Int32: summarizeValues<int32_t>(a, summary); break;
    case ScalarType::UInt32: summarizeValues<uint32_t>(a, summary); break;
    case ScalarType::Int64: summarizeValues<int64_t>(a, summary); break;
    case ScalarType::UInt64: summarizeValues<uint64_t>(a, summary); break;
    case ScalarType::Float32: summarizeValues<float>(a, summary); break;
    case ScalarType::Float64: summarizeValues<double>(a, summary); break;
    }
    return summary;
}

std::vector<AttributeSummary> summarize(const std::vector<nonbloppy::ParticleAttribute>& attributes)
{
    std::vector<AttributeSummary> summaries;
    for (const nonbloppy::ParticleAttribute& a : attributes) summaries.push_back(summarize(a));
    return summaries;
}

/// The name of component @a c of @a components: x, y, z for three, else its number.
std::string componentName(size_t c, int components)
{
    return components == 3 ? std::string(1, char('x' + c)) : std::to_string(c);
}

/// One row per attribute: "velocity  float32 x3  x -1.5 .. 2.25, y 0 .. 1, z -3 .. 3",
/// "id  uint32  0 .. 24388", then ", 12 not finite" where values are NaN or infinite.
void printAttributes(const std::vector<AttributeSummary>& attributes)
{
    if (attributes.empty()) {
        printRow("attributes", "none");
        return;
    }
    bool first = true;
    for (const AttributeSummary& a : attributes) {
        std::string text = a.name + "  " + nonbloppy::scalarTypeName(a.type);
        if (a.components != 1) text += " x" + std::to_string(a.components);
        std::string ranges;
        for (size_t c = 0; c < a.low.size(); ++c) {
            if (a.low[c].empty()) continue;
            if (!ranges.empty()) ranges += ", ";
            if (a.components != 1) ranges += componentName(c, a.components) + " ";
            ranges += a.low[c] + " .. " + a.high[c];
        }
        if (a.nonFinite > 0) ranges += std::string(ranges.empty() ? "" : ", ") + std::to_string(a.nonFinite) + " not finite";
        if (!ranges.empty()) text += "  " + ranges;
        printRow(first ? "attributes" : "", text);
        first = false;
    }
}

/// The "attributes" array of the JSON report: {"name", "type", "components", "min", "max",
/// "non_finite"} each; "min" and "max" hold a number per component, null where none is
/// finite.
void writeAttributes(JsonWriter& w, const std::vector<AttributeSummary>& attributes)
{
    w.beginArray("attributes");
    for (const AttributeSummary& a : attributes) {
        w.beginObject();
        w.string("name", a.name);
        w.string("type", nonbloppy::scalarTypeName(a.type));
        w.integer("components", a.components);
        const auto list = [](const std::vector<std::string>& values) {
            std::string json = "[";
            for (size_t c = 0; c < values.size(); ++c) json += (c ? ", " : "") + (values[c].empty() ? "null" : values[c]);
            return json + "]";
        };
        w.raw("min", list(a.low));
        w.raw("max", list(a.high));
        w.integer("non_finite", static_cast<long long>(a.nonFinite));
        w.endObject();
    }
    w.endArray();
}

int inspectParticles(const std::string& path, const nonbloppy::ParticleSet& particles, bool json)
{
    const auto bbox = boundingBox(particles.positions);
    std::optional<double> spacing;
    std::string spacingNote;
    if (particles.size() < 2) {
        spacingNote = "needs two particles";
    } else {
        try {
            spacing = nonbloppy::estimateSpacing(particles.positions);
        } catch (const nonbloppy::Error& e) {
            spacingNote = e.what();
        }
    }

    if (json) {
        JsonWriter w;
        w.beginObject();
        w.string("file", path);
        w.string("type", "particles");
        w.integer("particles", static_cast<long long>(particles.size()));
        w.boundingBox(bbox);
        if (spacing) w.number("spacing", *spacing);
        else w.raw("spacing", "null");
        writeAttributes(w, summarize(particles.attributes));
        w.beginArray("not_read");
        for (const std::string& skipped : particles.skipped) w.string(nullptr, skipped);
        w.endArray();
        w.endObject();
        std::cout << w.str();
        return 0;
    }

    std::cout << path << ": particle file\n";
    printRow("particles", std::to_string(particles.size()));
    if (bbox) {
        printRow("bounding box", formatPoint<float>(bbox->first) + " -> " + formatPoint<float>(bbox->second));
    }
    // estimateSpacing() does not say which of its two measures it gave: name both.
    printRow("spacing", spacing ? formatNumber(*spacing) + " (estimated: volume per particle inside the fluid, "
                                                           "or the median neighbour distance where no particle is surrounded)"
                                : "- (" + spacingNote + ")");
    printAttributes(summarize(particles.attributes));
    if (!particles.skipped.empty()) printRow("not read", joinedSkipped(particles));
    std::cout.flush();
    return 0;
}

// ---------------------------------------------------------------------------------------
// Meshes

/// The vertex attributes of the mesh file @a path (PLY properties, VTK point data; OBJ has
/// none) other than its normals, as the particle readers see them. Cost: a second read of
/// the file, as particles. Unknown (nullopt) where the particle readers refuse the file
/// (a NaN vertex, say) that readMesh() read.
std::optional<std::vector<AttributeSummary>> meshVertexAttributes(const std::string& path,
                                                                  const nonbloppy::SurfaceMesh& mesh)
{
    const std::string ext = lowerExtension(path);
    if (ext != ".ply" && ext != ".vtk") return std::vector<AttributeSummary>();
    std::vector<nonbloppy::ParticleAttribute> attributes;
    try {
        attributes = nonbloppy::readParticles(path).attributes;
    } catch (const nonbloppy::Error&) {
        return std::nullopt;
    }
    // An empty mesh declares normals too (writeMesh()), with none to read back.
    if (!mesh.normals.empty() || mesh.points.empty()) {
        // PLY normals are the properties nx, ny, nz; a VTK file's are the array readMesh()
        // took for them, whatever its name (a NORMALS section, or an array called normals or
        // Normals): the first of three components that holds the same values.
        if (ext == ".ply") {
            attributes.erase(std::remove_if(attributes.begin(), attributes.end(),
                                            [](const nonbloppy::ParticleAttribute& a) {
                                                return a.name == "nx" || a.name == "ny" || a.name == "nz";
                                            }),
                             attributes.end());
        } else {
            const auto holdsTheNormals = [&](const nonbloppy::ParticleAttribute& a) {
                if (a.components != 3 || a.size() != mesh.normals.size()) return false;
                for (size_t n = 0; n < a.size(); ++n) {
                    for (int c = 0; c < 3; ++c) {
                        if (float(a.asDouble(n, c)) != mesh.normals[n][c]) return false;
                    }
                }
                return true;
            };
            const auto normals = std::find_if(attributes.begin(), attributes.end(), holdsTheNormals);
            if (normals != attributes.end()) attributes.erase(normals);
        }
    }
    return summarize(attributes);
}

int inspectMesh(const std::string& path, const nonbloppy::SurfaceMesh& mesh, bool json)
{
    const std::optional<std::vector<AttributeSummary>> attributes = meshVertexAttributes(path, mesh);
    const nonbloppy::MeshMeasures m = nonbloppy::measureMesh(mesh);
    const auto bbox = boundingBox(mesh.points);

    if (json) {
        JsonWriter w;
        w.beginObject();
        w.string("file", path);
        w.string("type", "mesh");
        w.integer("vertices", static_cast<long long>(m.vertices));
        w.integer("faces", static_cast<long long>(m.polygons));
        w.integer("triangles", static_cast<long long>(mesh.triangles.size()));
        w.integer("quads", static_cast<long long>(mesh.quads.size()));
        w.boolean("normals", !mesh.normals.empty());
        w.boolean("closed", m.closed);
        w.boolean("manifold", m.manifold);
        w.integer("boundary_edges", static_cast<long long>(m.boundaryEdges));
        w.integer("non_manifold_edges", static_cast<long long>(m.nonManifoldEdges));
        w.integer("inconsistent_edges", static_cast<long long>(m.inconsistentEdges));
        w.integer("unused_vertices", static_cast<long long>(m.unusedVertices));
        w.integer("non_finite_vertices", static_cast<long long>(m.nonFiniteVertices));
        w.integer("zero_area_faces", static_cast<long long>(m.zeroAreaPolygons));
        w.number("area", m.area);
        w.number("volume", m.volume);
        w.boundingBox(bbox);
        if (attributes) writeAttributes(w, *attributes);
        else w.raw("attributes", "null");
        w.endObject();
        std::cout << w.str();
        return 0;
    }

    std::cout << path << ": mesh\n";
    printRow("vertices", std::to_string(m.vertices)
                             + (mesh.normals.empty() ? "" : " (with normals)")
                             + (m.unusedVertices ? ", " + std::to_string(m.unusedVertices) + " unused"
                                                 : "")
                             + (m.nonFiniteVertices ? ", " + std::to_string(m.nonFiniteVertices) + " not finite"
                                                    : ""));
    printRow("faces", std::to_string(m.polygons) + " (" + counted(mesh.triangles.size(), "triangle") + ", "
                          + counted(mesh.quads.size(), "quad")
                          + (m.zeroAreaPolygons ? ", " + std::to_string(m.zeroAreaPolygons) + " of zero area" : "")
                          + ")");
    // Manifold here includes closed (MeshMeasures), so an open or empty mesh says why not.
    if (m.polygons == 0) {
        printRow("closed", "no (no faces)");
        printRow("manifold", "no (no faces)");
    } else {
        printRow("closed", std::string(m.closed ? "yes" : "no") + " (" + counted(m.boundaryEdges, "boundary edge") + ")");
        printRow("manifold", std::string(m.manifold ? "yes" : "no") + " ("
                                 + std::to_string(m.nonManifoldEdges) + " non-manifold, "
                                 + counted(m.inconsistentEdges, "inconsistently oriented edge")
                                 + (m.closed ? "" : "; not closed") + ")");
    }
    printRow("area", formatNumber(m.area));
    printRow("volume", formatNumber(m.volume) + (m.closed ? "" : " (not closed: not meaningful)"));
    if (bbox) {
        printRow("bounding box", formatPoint<float>(bbox->first) + " -> " + formatPoint<float>(bbox->second));
    }
    if (attributes) printAttributes(*attributes);
    else printRow("attributes", "- (the particle readers refuse this file)");
    std::cout.flush();
    return 0;
}

// ---------------------------------------------------------------------------------------
// .vdb files

/// Min and max of the active values of scalar grids; nullopt for other value types and
/// for grids without active values.
std::optional<std::pair<double, double>> activeRange(const openvdb::GridBase& grid)
{
    if (grid.activeVoxelCount() == 0) return std::nullopt;
    auto range = [](const auto& typed) {
        const auto mm = openvdb::tools::minMax(typed.tree());
        return std::make_pair(double(mm.min()), double(mm.max()));
    };
    if (const auto* g = dynamic_cast<const openvdb::FloatGrid*>(&grid)) return range(*g);
    if (const auto* g = dynamic_cast<const openvdb::DoubleGrid*>(&grid)) return range(*g);
    if (const auto* g = dynamic_cast<const openvdb::Int32Grid*>(&grid)) return range(*g);
    if (const auto* g = dynamic_cast<const openvdb::Int64Grid*>(&grid)) return range(*g);
    return std::nullopt;
}

/// A metadata value in JSON syntax: numbers, booleans and vectors as such, the rest as
/// strings.
std::string metadataJson(const openvdb::Metadata& meta)
{
    using namespace openvdb;
    if (auto* m = dynamic_cast<const FloatMetadata*>(&meta)) return jsonNumber(m->value());
    if (auto* m = dynamic_cast<const DoubleMetadata*>(&meta)) return jsonNumber(m->value());
    if (auto* m = dynamic_cast<const Int32Metadata*>(&meta)) return std::to_string(m->value());
    if (auto* m = dynamic_cast<const Int64Metadata*>(&meta)) return std::to_string(m->value());
    if (auto* m = dynamic_cast<const BoolMetadata*>(&meta)) return m->value() ? "true" : "false";
    auto vec = [](const auto& v) {
        return "[" + jsonNumber(double(v[0])) + ", " + jsonNumber(double(v[1])) + ", "
               + jsonNumber(double(v[2])) + "]";
    };
    if (auto* m = dynamic_cast<const Vec3IMetadata*>(&meta)) return vec(m->value());
    if (auto* m = dynamic_cast<const Vec3SMetadata*>(&meta)) return vec(m->value());
    if (auto* m = dynamic_cast<const Vec3DMetadata*>(&meta)) return vec(m->value());
    if (auto* m = dynamic_cast<const StringMetadata*>(&meta)) return jsonString(m->value());
    return jsonString(meta.str());
}

/// The text form: full precision for doubles (Metadata::str() keeps 6 digits); nan and inf
/// as such (JSON has no word for them and says null).
std::string metadataText(const openvdb::Metadata& meta)
{
    const auto number = [](double value) { return std::isfinite(value) ? jsonNumber(value) : formatNumber(value); };
    if (auto* m = dynamic_cast<const openvdb::DoubleMetadata*>(&meta)) return number(m->value());
    if (auto* m = dynamic_cast<const openvdb::FloatMetadata*>(&meta)) return number(m->value());
    return meta.str();
}

void writeMetadataJson(JsonWriter& w, const char* key, const openvdb::MetaMap& metadata)
{
    w.beginObject(key);
    for (auto it = metadata.beginMeta(); it != metadata.endMeta(); ++it) {
        if (it->second) w.raw(it->first.c_str(), metadataJson(*it->second));
    }
    w.endObject();
}

void printMetadata(const openvdb::MetaMap& metadata, const char* indent)
{
    for (auto it = metadata.beginMeta(); it != metadata.endMeta(); ++it) {
        if (it->second) std::cout << indent << it->first << ": " << metadataText(*it->second) << "\n";
    }
}

/// What a PointDataGrid holds: its points and their attributes (name and value type, in
/// the order they are stored), as vdb_print -l shows them.
struct PointsSummary
{
    uint64_t points = 0;
    std::vector<std::pair<std::string, std::string>> attributes;
};

std::optional<PointsSummary> pointsSummary(const openvdb::GridBase& grid)
{
    const auto* points = dynamic_cast<const openvdb::points::PointDataGrid*>(&grid);
    if (!points) return std::nullopt;
    PointsSummary summary;
    summary.points = openvdb::points::pointCount(points->tree());
    // Every leaf shares one descriptor.
    if (const auto leaf = points->tree().cbeginLeaf()) {
        const openvdb::points::AttributeSet::Descriptor& descriptor = leaf->attributeSet().descriptor();
        std::vector<std::pair<size_t, std::string>> byIndex;
        for (const auto& [name, index] : descriptor.map()) byIndex.emplace_back(index, name);
        std::sort(byIndex.begin(), byIndex.end());
        for (const auto& [index, name] : byIndex) summary.attributes.emplace_back(name, descriptor.type(index).first);
    }
    return summary;
}

int inspectVdb(const std::string& path, bool json)
{
    const nonbloppy::VdbFileContents contents = nonbloppy::readVdbFile(path);
    const std::string& fileVersion = contents.formatVersion;
    const openvdb::MetaMap& fileMetadata = contents.metadata;
    const openvdb::GridPtrVec& grids = contents.grids;

    if (json) {
        JsonWriter w;
        w.beginObject();
        w.string("file", path);
        w.string("type", "vdb");
        w.string("format_version", fileVersion);
        writeMetadataJson(w, "metadata", fileMetadata);
        w.beginArray("grids");
        for (const openvdb::GridBase::Ptr& grid : grids) {
            if (!grid) continue;
            w.beginObject();
            w.string("name", grid->getName());
            w.string("value_type", grid->valueType());
            w.string("class", openvdb::GridBase::gridClassToString(grid->getGridClass()));
            const openvdb::Vec3d voxel = grid->voxelSize();
            w.vec3("voxel_size", voxel.x(), voxel.y(), voxel.z());
            const openvdb::CoordBBox bbox = grid->evalActiveVoxelBoundingBox();
            if (bbox.empty()) {
                w.raw("index_bbox", "null");
            } else {
                w.beginObject("index_bbox");
                w.vec3("min", bbox.min().x(), bbox.min().y(), bbox.min().z());
                w.vec3("max", bbox.max().x(), bbox.max().y(), bbox.max().z());
                w.endObject();
            }
            w.integer("active_voxels", static_cast<long long>(grid->activeVoxelCount()));
            w.integer("leaf_nodes", static_cast<long long>(grid->baseTree().leafCount()));
            w.integer("memory_bytes", static_cast<long long>(grid->memUsage()));
            if (const auto range = activeRange(*grid)) {
                w.number("min", range->first);
                w.number("max", range->second);
            } else {
                w.raw("min", "null");
                w.raw("max", "null");
            }
            if (const auto points = pointsSummary(*grid)) {
                w.integer("points", static_cast<long long>(points->points));
                w.beginArray("attributes");
                for (const auto& [name, type] : points->attributes) {
                    w.beginObject();
                    w.string("name", name);
                    w.string("type", type);
                    w.endObject();
                }
                w.endArray();
            }
            writeMetadataJson(w, "metadata", *grid);
            w.endObject();
        }
        w.endArray();
        w.endObject();
        std::cout << w.str();
        return 0;
    }

    std::cout << path << ": OpenVDB file version " << fileVersion << ", " << grids.size()
              << (grids.size() == 1 ? " grid" : " grids") << "\n";
    printMetadata(fileMetadata, "  ");
    for (const openvdb::GridBase::Ptr& grid : grids) {
        if (!grid) continue;
        // One line per grid, as vdb_print: name, type, class, voxel size, index bbox,
        // active voxels, leaves, memory, value range.
        std::ostringstream line;
        line << grid->getName() << "  " << grid->valueType() << "  "
             << openvdb::GridBase::gridClassToString(grid->getGridClass());
        const openvdb::Vec3d voxel = grid->voxelSize();
        if (voxel.x() == voxel.y() && voxel.y() == voxel.z()) {
            line << "  voxel " << formatNumber(voxel.x());
        } else {
            line << "  voxel " << formatVec3(voxel.x(), voxel.y(), voxel.z());
        }
        const openvdb::CoordBBox bbox = grid->evalActiveVoxelBoundingBox();
        if (bbox.empty()) {
            line << "  empty";
        } else {
            const openvdb::Coord dim = bbox.dim();
            line << "  " << formatCoord(bbox.min()) << "->" << formatCoord(bbox.max()) << "  "
                 << dim.x() << "x" << dim.y() << "x" << dim.z();
        }
        const uint64_t voxels = grid->activeVoxelCount();
        const size_t leaves = grid->baseTree().leafCount();
        line << "  " << formatCount(voxels) << (voxels == 1 ? " active voxel  " : " active voxels  ") << leaves
             << (leaves == 1 ? " leaf  " : " leaves  ") << formatBytes(grid->memUsage());
        if (const auto range = activeRange(*grid)) {
            line << "  values [" << formatNumber(range->first) << ", "
                 << formatNumber(range->second) << "]";
        }
        std::cout << line.str() << "\n";
        if (const auto points = pointsSummary(*grid)) {
            std::cout << "    points: " << points->points;
            const char* separator = "; attributes: ";
            for (const auto& [name, type] : points->attributes) {
                std::cout << separator << name << " " << type;
                separator = ", ";
            }
            std::cout << "\n";
        }
        printMetadata(*grid, "    ");
    }
    std::cout.flush();
    return 0;
}

// ---------------------------------------------------------------------------------------

int runInspect(const std::string& path, bool json)
{
    requireFileName(path, "FILE");
    // A format nonbloppy cannot read: exit 2, as for mesh and convert, told from the name
    // alone (before a missing file or a FIFO is). Houdini's own caches: requireParticleFile()
    // refuses them saying which name to export instead.
    const std::string ext = lowerExtension(path);
    if (ext != ".vdb" && ext != ".obj" && !nonbloppy::isParticleFile(path)) {
        if (ext == ".sc" || ext == ".gz" || ext == ".geo" || ext == ".hclassic") {
            requireAsUsage([&] { nonbloppy::requireParticleFile(path); });
        }
        throw UsageError("unknown file extension '" + ext + "' (" + path
                         + "); expected .vdb, .obj, .ply, .vtk, .vtu, .vtp, .xyz, .bgeo, .csv, .txt or .json");
    }
    struct stat info;
    if (::stat(path.c_str(), &info) != 0) {
        throw nonbloppy::FileError("cannot open " + path + ": " + std::strerror(errno));
    }
    if (S_ISDIR(info.st_mode)) {
        throw nonbloppy::FileError("cannot open " + path + ": " + std::strerror(EISDIR));
    }
    // The format is told from the file before it is read, and a mesh's attributes are read
    // again: a FIFO (or a shell's <(...)) would be drained by the first read and block the
    // next open for ever.
    if (!S_ISREG(info.st_mode)) {
        throw nonbloppy::FileError("cannot inspect " + path + ": not a regular file (inspect reads it more than "
                                   "once; save it to a file first)");
    }

    if (ext == ".vdb") return inspectVdb(path, json);
    if (ext == ".obj") return inspectMesh(path, nonbloppy::readMesh(path), json);
    // Both formats hold either particles or polygons: a file that declares polygons is a
    // mesh, whose errors are reported as such (its vertices would read as particles).
    if ((ext == ".ply" || ext == ".vtk") && nonbloppy::declaresPolygons(path)) {
        return inspectMesh(path, nonbloppy::readMesh(path), json);
    }
    return inspectParticles(path, nonbloppy::readParticles(path), json);
}

} // namespace

Command setupInspectCommand(CLI::App& parent)
{
    struct Options { std::string path; bool json = false; };
    auto options = std::make_shared<Options>();

    CLI::App* cmd = parent.add_subcommand(
        "inspect", "Describe a .vdb grid file, a mesh (.obj, .ply, .vtk) or a particle file");
    cmd->footer("A .ply or .vtk file that declares faces is described as a mesh, other .ply and .vtk files\n"
                "as particles; every particle format `nonbloppy mesh` reads is described.");
    cmd->add_option("FILE", options->path, "File to describe")
        ->required()->group(kGroupInputOutput);
    cmd->add_flag("--json", options->json, "Print one JSON object instead of text")
        ->group(kGroupInputOutput);

    return {cmd, [options]() {
        try {
            return runInspect(options->path, options->json);
        } catch (const std::bad_alloc&) {
            // Said with the file's name, not as a bare "out of memory".
            throw nonbloppy::Error("out of memory inspecting " + options->path);
        }
    }};
}

} // namespace nonbloppy_tool
