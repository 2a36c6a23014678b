// SPDX-License-Identifier: Apache-2.0
/// @file WriteParticles.cc
/// @brief Particle writers: PLY, legacy VTK, VTU, XYZ, CSV and VDB points.

#include <nonbloppy/WriteParticles.h>

#include <nonbloppy/Error.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/WriteVdb.h>

#include "AtomicFile.h"
#include "AttributeNames.h"
#include "Cancellation.h"
#include "FileFormats.h"
#include "OpenVdbScale.h"
#include "ParticleIndexImpl.h"

// OpenVDB's point templates must keep default visibility (see src/VisibilityPrelude.h).
#pragma GCC visibility push(default)
#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/tree/LeafManager.h>
#pragma GCC visibility pop

#include <algorithm>
#include <cmath>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <ostream>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>

namespace nonbloppy {

namespace {

using attribute_names_internal::csvWord;
using attribute_names_internal::headerWord;
using attribute_names_internal::NamedAttribute;
using attribute_names_internal::plyColumns;
using attribute_names_internal::vdbWord;
using attribute_names_internal::wholeColumn;
using io_internal::lowerExtension;

/// Whether a reader takes the column @a name for positions: x, y, z or P as they are.
bool
isPositionName(const std::string& name)
{
    return name == "x" || name == "y" || name == "z" || name == "P";
}

/// The same for CSV, whose reader also takes X, Points:0, p_y, ... (tablePositionAxis()): an
/// attribute "X" or a vector "P" written as such made a file nonbloppy then refused ("two
/// columns for coordinate x").
bool
isCsvPositionName(const std::string& name)
{
    return io_internal::tablePositionAxis(name) >= 0;
}

/// CSV columns: name, or name:<c> as ParaView writes them.
std::vector<std::string>
csvColumns(const std::string& base, int components)
{
    if (components == 1) return {base};
    std::vector<std::string> columns;
    for (int c = 0; c < components; ++c) columns.push_back(base + ":" + std::to_string(c));
    return columns;
}

/// PointDataGrid attributes: one for 1 or 3 components, else name_<c> each.
std::vector<std::string>
vdbColumns(const std::string& base, int components)
{
    if (components == 1 || components == 3) return {base};
    std::vector<std::string> columns;
    for (int c = 0; c < components; ++c) columns.push_back(base + "_" + std::to_string(c));
    return columns;
}

/// The lower-case extension of @a path, which must be one writeParticles() writes.
/// @throw FileError as requireParticleOutputFile()
std::string
requireParticleOutput(const std::string& path)
{
    requireParticleOutputFile(path);
    return lowerExtension(path);
}

/// The names the writer of extension @a ext (lower case, with the dot) gives the
/// attributes, one per attribute in order (attribute_names_internal::uniqueNames(); a
/// name nonbloppy's readers take for positions is taken); empty for `.xyz`, which drops them.
std::vector<std::string>
namesForExtension(const ParticleSet& particles, const std::string& ext)
{
    std::vector<NamedAttribute> attributes;
    for (const ParticleAttribute& a : particles.attributes) attributes.emplace_back(a.name, a.components);
    using attribute_names_internal::uniqueNames;
    if (ext == ".ply") return uniqueNames(attributes, headerWord, plyColumns, isPositionName, io_internal::suffixComponentOf);
    if (ext == ".vtk") {
        // A FIELD array line "metadata ..." reads as the METADATA block keyword (any case):
        // the file came back unreadable (bug hunt).
        return uniqueNames(attributes, headerWord, wholeColumn, [](const std::string& column) {
            return isPositionName(column) || io_internal::iequals(column, "METADATA");
        });
    }
    if (ext == ".vtu") return uniqueNames(attributes, headerWord, wholeColumn, isPositionName);
    if (ext == ".csv") return uniqueNames(attributes, csvWord, csvColumns, isCsvPositionName, io_internal::tableComponentOf);
    if (ext == ".vdb") return uniqueNames(attributes, vdbWord, vdbColumns, isPositionName);
    return std::vector<std::string>(particles.attributes.size());
}

/// Bytes of @a count values of @a width in the requested byte order.
void
appendSwapped(std::string& out, const unsigned char* data, size_t count, size_t width, bool bigEndian)
{
    const bool swap = bigEndian != (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__);
    const size_t start = out.size();
    out.append(reinterpret_cast<const char*>(data), count * width);
    if (swap && width > 1) {
        for (size_t i = 0; i < count; ++i) {
            std::reverse(out.begin() + ptrdiff_t(start + i * width),
                         out.begin() + ptrdiff_t(start + (i + 1) * width));
        }
    }
}

std::string
positionBytes(const ParticleSet& particles, bool bigEndian)
{
    std::string out;
    out.reserve(particles.size() * 12);
    appendSwapped(out, reinterpret_cast<const unsigned char*>(particles.positions.data()),
                  particles.size() * 3, 4, bigEndian);
    return out;
}

void
writeXyz(const ParticleSet& particles, std::ostream& os)
{
    const std::string bytes = positionBytes(particles, false);
    os.write(bytes.data(), std::streamsize(bytes.size()));
}

/// The type a 64-bit integer attribute @a a is written as in PLY, which has no 64-bit type
/// (io_internal::plyIntegerType of its range).
ScalarType
plyTypeOf64(const ParticleAttribute& a)
{
    int64_t lowest = std::numeric_limits<int64_t>::max();
    int64_t highest = std::numeric_limits<int64_t>::min();
    for (size_t at = 0; at < a.bytes.size(); at += 8) {
        int64_t value = 0;
        if (!io_internal::integerValue(a.bytes.data() + at, a.type, value)) return ScalarType::Float64;  // a uint64 past int64
        lowest = std::min(lowest, value);
        highest = std::max(highest, value);
    }
    return io_internal::plyIntegerType(lowest, highest);
}

void
writePly(const ParticleSet& particles, std::ostream& os)
{
    std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by nonbloppy\n";
    header += "element vertex " + std::to_string(particles.size()) + "\n";
    header += "property float x\nproperty float y\nproperty float z\n";
    const std::vector<std::string> names = namesForExtension(particles, ".ply");
    std::vector<ScalarType> written(particles.attributes.size());
    for (size_t i = 0; i < particles.attributes.size(); ++i) {
        const ParticleAttribute& a = particles.attributes[i];
        const bool wide = a.type == ScalarType::Int64 || a.type == ScalarType::UInt64;
        written[i] = wide ? plyTypeOf64(a) : a.type;
        for (const std::string& column : plyColumns(names[i], a.components)) {
            header += std::string("property ") + io_internal::plyTypeName(written[i]) + " " + column + "\n";
        }
    }
    header += "end_header\n";
    os.write(header.data(), std::streamsize(header.size()));
    std::string row;
    for (size_t n = 0; n < particles.size(); ++n) {
        row.clear();
        appendSwapped(row, reinterpret_cast<const unsigned char*>(&particles.positions[n]), 3, 4, false);
        for (size_t i = 0; i < particles.attributes.size(); ++i) {
            const ParticleAttribute& a = particles.attributes[i];
            const size_t width = scalarSize(a.type);
            const unsigned char* values = a.bytes.data() + n * size_t(a.components) * width;
            if (written[i] == a.type) {
                appendSwapped(row, values, size_t(a.components), width, false);
                continue;
            }
            for (int c = 0; c < a.components; ++c) {  // a 64-bit integer, narrowed
                const double value = a.asDouble(n, c);
                if (written[i] == ScalarType::Float64) {
                    appendSwapped(row, reinterpret_cast<const unsigned char*>(&value), 1, 8, false);
                } else if (written[i] == ScalarType::Int32) {
                    const int32_t narrow = int32_t(value);  // exact: it fits
                    appendSwapped(row, reinterpret_cast<const unsigned char*>(&narrow), 1, 4, false);
                } else {
                    const uint32_t narrow = uint32_t(value);
                    appendSwapped(row, reinterpret_cast<const unsigned char*>(&narrow), 1, 4, false);
                }
            }
        }
        os.write(row.data(), std::streamsize(row.size()));
    }
}

void
writeVtk(const ParticleSet& particles, std::ostream& os)
{
    const size_t n = particles.size();
    std::string out = "# vtk DataFile Version 4.2\nparticles written by nonbloppy\nBINARY\n"
                      "DATASET UNSTRUCTURED_GRID\nPOINTS " + std::to_string(n) + " float\n";
    out += positionBytes(particles, true);
    out += "\nCELLS " + std::to_string(n) + " " + std::to_string(2 * n) + "\n";
    for (size_t i = 0; i < n; ++i) {
        const int32_t cell[2] = {1, int32_t(i)};
        appendSwapped(out, reinterpret_cast<const unsigned char*>(cell), 2, 4, true);
    }
    out += "\nCELL_TYPES " + std::to_string(n) + "\n";
    const int32_t vertex = 1;  // VTK_VERTEX
    for (size_t i = 0; i < n; ++i) appendSwapped(out, reinterpret_cast<const unsigned char*>(&vertex), 1, 4, true);
    out += "\n";
    if (!particles.attributes.empty()) {
        out += "POINT_DATA " + std::to_string(n) + "\nFIELD FieldData " +
               std::to_string(particles.attributes.size()) + "\n";
        const std::vector<std::string> names = namesForExtension(particles, ".vtk");
        for (size_t i = 0; i < particles.attributes.size(); ++i) {
            const ParticleAttribute& a = particles.attributes[i];
            out += names[i] + " " + std::to_string(a.components) + " " + std::to_string(n) +
                   " " + io_internal::vtkTypeName(a.type) + "\n";
            appendSwapped(out, a.bytes.data(), n * size_t(a.components), scalarSize(a.type), true);
            out += "\n";
        }
    }
    os.write(out.data(), std::streamsize(out.size()));
}

const char*
vtuTypeName(ScalarType type)
{
    switch (type) {
    case ScalarType::Int8: return "Int8";
    case ScalarType::UInt8: return "UInt8";
    case ScalarType::Int16: return "Int16";
    case ScalarType::UInt16: return "UInt16";
    case ScalarType::Int32: return "Int32";
    case ScalarType::UInt32: return "UInt32";
    case ScalarType::Int64: return "Int64";
    case ScalarType::UInt64: return "UInt64";
    case ScalarType::Float32: return "Float32";
    case ScalarType::Float64: return "Float64";
    }
    return "Float64";
}

void
writeVtu(const ParticleSet& particles, std::ostream& os)
{
    const size_t n = particles.size();
    std::string appended, xml;
    auto array = [&](const char* type, const std::string& name, int components, const std::string& bytes) {
        xml += std::string("        <DataArray type=\"") + type + "\" Name=\"" + headerWord(name) +
               "\" NumberOfComponents=\"" + std::to_string(components) +
               "\" format=\"appended\" offset=\"" + std::to_string(appended.size()) + "\"/>\n";
        const uint64_t size = bytes.size();
        appendSwapped(appended, reinterpret_cast<const unsigned char*>(&size), 1, 8, false);
        appended += bytes;
    };
    xml = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
          "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n"
          "    <Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfCells=\"" +
          std::to_string(n) + "\">\n      <Points>\n";
    array("Float32", "Points", 3, positionBytes(particles, false));
    xml += "      </Points>\n      <Cells>\n";
    std::string connectivity, offsets, types(n, char(1));  // VTK_VERTEX
    for (size_t i = 0; i < n; ++i) {
        const int64_t index = int64_t(i), offset = int64_t(i + 1);
        appendSwapped(connectivity, reinterpret_cast<const unsigned char*>(&index), 1, 8, false);
        appendSwapped(offsets, reinterpret_cast<const unsigned char*>(&offset), 1, 8, false);
    }
    array("Int64", "connectivity", 1, connectivity);
    array("Int64", "offsets", 1, offsets);
    array("UInt8", "types", 1, types);
    xml += "      </Cells>\n      <PointData>\n";
    const std::vector<std::string> names = namesForExtension(particles, ".vtu");
    for (size_t i = 0; i < particles.attributes.size(); ++i) {
        const ParticleAttribute& a = particles.attributes[i];
        std::string bytes;
        appendSwapped(bytes, a.bytes.data(), n * size_t(a.components), scalarSize(a.type), false);
        array(vtuTypeName(a.type), names[i], a.components, bytes);
    }
    xml += "      </PointData>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";
    os.write(xml.data(), std::streamsize(xml.size()));
    os.write(appended.data(), std::streamsize(appended.size()));
    const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
    os.write(tail.data(), std::streamsize(tail.size()));
}

/// Shortest text that reads back as the same value of @a type; a whole float keeps ".0", so
/// that it reads back as a float.
void
appendNumber(std::string& out, const ParticleAttribute& a, size_t n, int c)
{
    char buffer[64];
    const size_t width = scalarSize(a.type);
    const unsigned char* p = a.bytes.data() + (n * size_t(a.components) + size_t(c)) * width;
    std::to_chars_result result{};
    switch (a.type) {
    case ScalarType::Float32: { float v; std::memcpy(&v, p, 4); result = std::to_chars(buffer, buffer + 64, v); break; }
    case ScalarType::Float64: { double v; std::memcpy(&v, p, 8); result = std::to_chars(buffer, buffer + 64, v); break; }
    case ScalarType::UInt64: { uint64_t v; std::memcpy(&v, p, 8); result = std::to_chars(buffer, buffer + 64, v); break; }
    case ScalarType::Int64: { int64_t v; std::memcpy(&v, p, 8); result = std::to_chars(buffer, buffer + 64, v); break; }
    default: result = std::to_chars(buffer, buffer + 64, int64_t(a.asDouble(n, c))); break;
    }
    out.append(buffer, result.ptr);
    // A whole float written "300" read back as an integer attribute, which mesh --attributes
    // carries as the nearest particle's value instead of a mean (bug hunt): "300.0".
    const bool isFloat = a.type == ScalarType::Float32 || a.type == ScalarType::Float64;
    if (isFloat && std::all_of(buffer, result.ptr, [](char ch) { return ch == '-' || (ch >= '0' && ch <= '9'); })) {
        out += ".0";
    }
}

/// @a column as a CSV header field: in double quotes, each quote in it doubled (RFC 4180), if
/// it holds ',' or a quote; the reader strips single quotes around an unquoted name.
std::string
csvField(const std::string& column)
{
    if (column.find_first_of(",\"'") == std::string::npos) return column;
    std::string field = "\"";
    for (const char ch : column) field += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    return field + "\"";
}

void
writeCsv(const ParticleSet& particles, std::ostream& os)
{
    std::string out = "x,y,z";
    const std::vector<std::string> names = namesForExtension(particles, ".csv");
    for (size_t i = 0; i < particles.attributes.size(); ++i) {
        for (const std::string& column : csvColumns(names[i], particles.attributes[i].components)) {
            out += "," + csvField(column);
        }
    }
    out += "\n";
    char buffer[64];
    for (size_t n = 0; n < particles.size(); ++n) {
        for (int axis = 0; axis < 3; ++axis) {
            if (axis > 0) out += ',';
            out.append(buffer, std::to_chars(buffer, buffer + 64, particles.positions[n][axis]).ptr);
        }
        for (const ParticleAttribute& a : particles.attributes) {
            for (int c = 0; c < a.components; ++c) {
                out += ',';
                appendNumber(out, a, n, c);
            }
        }
        out += '\n';
        if (out.size() > (size_t(4) << 20)) {
            os.write(out.data(), std::streamsize(out.size()));
            out.clear();
        }
    }
    os.write(out.data(), std::streamsize(out.size()));
}

// --- PointDataGrid ------------------------------------------------------------------------

using PointDataGrid = openvdb::points::PointDataGrid;
using PointIndexGrid = openvdb::tools::PointIndexGrid;

/// Appends the attribute @a name holding @a values (one per particle, in the order
/// @a index's leaves list them) to every leaf of @a grid, as openvdb::points::
/// populateAttribute() does, but a leaf's array is made uniform (one value stored) only
/// when its values are the same bits: populateAttribute() compacts it when they compare
/// equal, as 0.0 and -0.0 do, and the zeros of a leaf came back with the first one's sign
/// (format round-trip hunt).
template<typename ValueT>
void
addVdbAttribute(PointDataGrid& grid, const PointIndexGrid& index, const std::string& name,
                const std::vector<ValueT>& values)
{
    openvdb::points::appendAttribute<ValueT>(grid.tree(), name);
    openvdb::tree::LeafManager<openvdb::points::PointDataTree> leaves(grid.tree());
    leaves.foreach([&](openvdb::points::PointDataTree::LeafNodeType& leaf, size_t) {
        const auto* indexLeaf = index.tree().probeConstLeaf(leaf.origin());
        if (!indexLeaf || indexLeaf->indices().empty()) return;
        const auto& indices = indexLeaf->indices();
        openvdb::points::AttributeWriteHandle<ValueT> handle(leaf.attributeArray(name));
        const ValueT& first = values[openvdb::Index64(indices.front())];
        const bool sameBits = std::all_of(indices.begin(), indices.end(), [&](openvdb::Index64 i) {
            return std::memcmp(&values[i], &first, sizeof(ValueT)) == 0;
        });
        if (sameBits) {
            handle.collapse(first);
            return;
        }
        for (size_t n = 0; n < indices.size(); ++n) handle.set(openvdb::Index(n), values[openvdb::Index64(indices[n])]);
    });
}

template<typename ScalarT>
void
addScalarAttribute(PointDataGrid& grid, const PointIndexGrid& index, const ParticleAttribute& a, int c,
                   const std::string& name)
{
    std::vector<ScalarT> values(a.size());
    for (size_t n = 0; n < values.size(); ++n) {
        if (a.type == ScalarType::Int64 || a.type == ScalarType::UInt64) {
            // 64-bit integers are copied from their own bits: through a double, those above
            // 2^53 lost their low bits (a uint64 past int64 was refused before).
            const unsigned char* p = a.bytes.data() + (n * size_t(a.components) + size_t(c)) * 8;
            uint64_t bits;
            std::memcpy(&bits, p, 8);
            values[n] = static_cast<ScalarT>(static_cast<int64_t>(bits));
        } else {
            values[n] = static_cast<ScalarT>(a.asDouble(n, c));
        }
    }
    addVdbAttribute(grid, index, name, values);
}

template<typename VecT>
void
addVectorAttribute(PointDataGrid& grid, const PointIndexGrid& index, const ParticleAttribute& a,
                   const std::string& name)
{
    using ScalarT = typename VecT::value_type;
    std::vector<VecT> values(a.size());
    for (size_t n = 0; n < values.size(); ++n) {
        values[n] = VecT(static_cast<ScalarT>(a.asDouble(n, 0)), static_cast<ScalarT>(a.asDouble(n, 1)),
                         static_cast<ScalarT>(a.asDouble(n, 2)));
    }
    addVdbAttribute(grid, index, name, values);
}

} // namespace

namespace {

/// @throw ParameterError("non-finite position of particle N, which a .vdb points grid cannot
///        hold" + @a suffix): OpenVDB's point partitioning silently dropped such particles
///        (the other formats write them as they are). Returns the largest |coordinate|.
///        Cost: one parallel pass.
double requirePlaceablePositions(const ParticleSet& particles, const std::string& suffix)
{
    cancellation_internal::CancelPoll never(nullptr, "write particles");
    const particle_index_internal::PositionScan scan = particle_index_internal::scanPositions(particles.positions, never);
    if (scan.firstNonFinite < particles.positions.size()) {
        throw ParameterError(particle_index_internal::nonFinitePositionMessage(scan.firstNonFinite) +
                             ", which a .vdb points grid cannot hold" + suffix);
    }
    return double(scan.maxAbs());
}

/// makePointDataGrid() of positions requirePlaceablePositions() has passed, @a largest
/// their largest |coordinate|.
openvdb::GridBase::Ptr
pointDataGridOfFinitePositions(const ParticleSet& particles, double voxelSize, double largest)
{
    openvdb::initialize();
    std::vector<openvdb::Vec3R> positions(particles.positions.begin(), particles.positions.end());
    const openvdb::points::PointAttributeVector<openvdb::Vec3R> wrapper(positions);
    // OpenVDB's own message for +inf is an ArithmeticError, not a nonbloppy::Error; NaN and
    // -inf picked a size, as 0 does.
    if (!std::isfinite(voxelSize)) {
        std::ostringstream msg;
        msg << "--voxel-size must be finite, got " << voxelSize;
        throw ParameterError(msg.str());
    }
    if (!(voxelSize > 0.0)) {
        // One particle has no spacing to size voxels by: 1, or coarser where it lies too far
        // out for 32-bit voxel coordinates at 1 (one particle 5e9 out was refused).
        const double chosen = positions.size() > 1
                                  ? double(openvdb::points::computeVoxelSize(wrapper, 8))
                                  : std::max(1.0, 2.0 * largest / openvdb_scale_internal::kMaxIndexCoordinate);
        // A power of two: OpenVDB keeps a position as its voxel plus a float offset, and
        // scales their sum by the voxel size. A float position divided by a power of two
        // splits into voxel and offset exactly, and their sum scales back exactly; sizes like
        // computeVoxelSize()'s 1.7457 rounded twice, and some positions came back one float
        // step off (0.45 as 0.44999996; format round-trip hunt). The nearest power, or the one
        // above where the one below would put particles past 32-bit voxel coordinates.
        voxelSize = std::exp2(std::round(std::log2(chosen)));
        if (voxelSize < chosen && largest / voxelSize > openvdb_scale_internal::kMaxIndexCoordinate) voxelSize *= 2.0;
    } else {
        openvdb_scale_internal::requireOpenVdbScale(voxelSize, kMinCellSize, "--voxel-size");
    }
    // Voxel coordinates are 32-bit: past them particles far apart shared voxel -2^31 (bug hunt).
    openvdb_scale_internal::requireIndexRange(largest, voxelSize, "particle", "voxel size");
    const auto transform = openvdb::math::Transform::createLinearTransform(voxelSize);
    const auto index = openvdb::tools::createPointIndexGrid<PointIndexGrid>(wrapper, *transform);
    auto grid = openvdb::points::createPointDataGrid<openvdb::points::NullCodec, PointDataGrid>(
        *index, wrapper, *transform);
    grid->setName("points");
    if (positions.empty() && !particles.attributes.empty()) {
        // Attributes are described by the leaves only, and no particles make no leaf: those
        // of an empty set were gone without a word (format round-trip hunt). One leaf of no
        // points, initialised as createPointDataGrid() does each, carries them.
        const auto descriptor = openvdb::points::AttributeSet::Descriptor::create(
            openvdb::points::TypedAttributeArray<openvdb::Vec3f, openvdb::points::NullCodec>::attributeType());
        grid->tree().touchLeaf(openvdb::Coord(0))->initializeAttributes(descriptor, 0);
    }
    const std::vector<std::string> names = namesForExtension(particles, ".vdb");
    std::string split;  // the attributes written as scalars name_0, name_1, ...
    for (size_t i = 0; i < particles.attributes.size(); ++i) {
        const ParticleAttribute& a = particles.attributes[i];
        if (a.components == 3) {
            if (a.type == ScalarType::Float32) addVectorAttribute<openvdb::Vec3f>(*grid, *index, a, names[i]);
            else if (a.type == ScalarType::Float64) addVectorAttribute<openvdb::Vec3d>(*grid, *index, a, names[i]);
            // int8 to int32, uint8 and uint16 as vec3i; uint32, int64 and uint64 as vec3d,
            // exact to 2^53, where vec3i wrapped 4e9 and 2^40 to -2147483648.
            else if (a.type == ScalarType::Int64 || a.type == ScalarType::UInt32 || a.type == ScalarType::UInt64) {
                addVectorAttribute<openvdb::Vec3d>(*grid, *index, a, names[i]);
            } else {
                addVectorAttribute<openvdb::Vec3i>(*grid, *index, a, names[i]);
            }
            continue;
        }
        io_internal::requireInt64Values(a, "a .vdb stores");  // the widest integer a .vdb attribute holds
        const std::vector<std::string> columns = vdbColumns(names[i], a.components);
        if (columns.size() > 1) split += (split.empty() ? "" : " ") + names[i];
        for (int c = 0; c < a.components; ++c) {
            const std::string& name = columns[size_t(c)];
            switch (a.type) {
            case ScalarType::Int8: addScalarAttribute<int8_t>(*grid, *index, a, c, name); break;
            case ScalarType::UInt8:
            case ScalarType::Int16: addScalarAttribute<int16_t>(*grid, *index, a, c, name); break;
            case ScalarType::UInt16:
            case ScalarType::Int32: addScalarAttribute<int32_t>(*grid, *index, a, c, name); break;
            case ScalarType::UInt32:
            case ScalarType::Int64:
            case ScalarType::UInt64: addScalarAttribute<int64_t>(*grid, *index, a, c, name); break;
            case ScalarType::Float32: addScalarAttribute<float>(*grid, *index, a, c, name); break;
            case ScalarType::Float64: addScalarAttribute<double>(*grid, *index, a, c, name); break;
            }
        }
    }
    // Which runs of scalars readParticles() joins again (io_internal::kSplitAttributesKey):
    // only these, so that another program's scalars w_0, w_1 stay two.
    if (!split.empty()) grid->insertMeta(io_internal::kSplitAttributesKey, openvdb::StringMetadata(split));
    return grid;
}

} // namespace

openvdb::GridBase::Ptr
makePointDataGrid(const ParticleSet& particles, double voxelSize)
{
    io_internal::requireOneValuePerParticle(particles);
    const double largest = requirePlaceablePositions(particles, "");
    return pointDataGridOfFinitePositions(particles, voxelSize, largest);
}

void
writeParticles(const ParticleSet& particles, const std::string& path, const ParticleWriteSettings& settings)
{
    const std::string ext = requireParticleOutput(path);
    io_internal::requireOneValuePerParticle(particles, " (" + path + ")");
    if (ext != ".xyz") {  // .xyz drops the attributes
        for (const ParticleAttribute& a : particles.attributes) io_internal::requireFileComponents(a.name, a.components, " (" + path + ")");
    }
    if (ext == ".vdb") {
        const double largest = requirePlaceablePositions(particles, " (" + path + ")");
        openvdb::GridBase::Ptr grid;
        try {
            for (const ParticleAttribute& a : particles.attributes) io_internal::requireInt64Values(a, "a .vdb stores");
            grid = pointDataGridOfFinitePositions(particles, 0.0, largest);
        } catch (const ParameterError& e) {
            throw ParameterError(e.what() + (" (" + path + ")"));  // named as the other refusals are
        }
        writeVdb({grid}, path);
        return;
    }
    writeFileAtomically(path, [&](std::ostream& os) {
        if (ext == ".ply") writePly(particles, os);
        else if (ext == ".vtk") writeVtk(particles, os);
        else if (ext == ".vtu") writeVtu(particles, os);
        else if (ext == ".xyz") writeXyz(particles, os);
        else writeCsv(particles, os);
    }, /*expectedBytes=*/settings.directIo ? particles.positions.size() * sizeof(openvdb::Vec3f) : 0);
}

std::vector<std::string>
writtenAttributeNames(const ParticleSet& particles, const std::string& path)
{
    const std::string ext = requireParticleOutput(path);
    return namesForExtension(particles, ext);
}

std::vector<std::string>
roundedAttributes(const ParticleSet& particles, const std::string& path)
{
    const std::string ext = requireParticleOutput(path);
    std::vector<std::string> rounded;
    for (const ParticleAttribute& a : particles.attributes) {
        // PLY has no 64-bit integer (plyTypeOf64() falls back to double); a .vdb's 3-vectors
        // of them are vec3d (OpenVDB's integer vectors are 32-bit); its scalars are int64.
        const bool asDoubles = ext == ".ply" || (ext == ".vdb" && a.components == 3);
        if (asDoubles && io_internal::holdsIntegersPastDouble(a)) rounded.push_back(a.name);
    }
    return rounded;
}

bool
isParticleOutputFile(const std::string& path)
{
    const std::string ext = lowerExtension(path);
    return ext == ".ply" || ext == ".vtk" || ext == ".vtu" || ext == ".xyz" || ext == ".csv" ||
           ext == ".vdb";
}

void
requireParticleOutputFile(const std::string& path)
{
    if (!isParticleOutputFile(path)) {
        const std::string ext = lowerExtension(path);
        throw FileError((ext.empty() ? "particle file name has no extension ("
                                     : "unknown particle output extension '" + ext + "' (") +
                        path + "); expected .ply, .vtk, .vtu, .xyz, .csv or .vdb");
    }
}

} // namespace nonbloppy
