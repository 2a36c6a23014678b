// SPDX-License-Identifier: Apache-2.0
/// @file ReadVdbPoints.cc
/// @brief Particles from a `.vdb` file holding an openvdb::points::PointDataGrid (as Houdini
///        and OpenVDB's own tools write them): world position from `P`, and every other
///        attribute of a numeric or vector type, by name. Group and string attributes have
///        no ParticleAttribute counterpart and are skipped.
///
/// The bytes are read through openvdb::io::Stream from memory, so the reader never opens
/// the file twice and the fuzz target can feed it bytes. Points are visited leaf by leaf in
/// tree order, so the particle order is the same on every run.

#include "FileFormats.h"
#include "ParticleReaders.h"

#include <nonbloppy/Error.h>

// OpenVDB's point templates must keep default visibility, as src/VisibilityPrelude.h
// explains for the grid types it covers (else openvdb::initialize() crashes).
#pragma GCC visibility push(default)
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/points/PointDataGrid.h>
#pragma GCC visibility pop

#include <algorithm>
#include <cstring>
#include <sstream>

namespace nonbloppy {
namespace io_internal {

namespace {

using openvdb::points::AttributeHandle;
using openvdb::points::PointDataGrid;

template<typename ValueT, typename StoredT, int ComponentsT>
void
copyAttribute(const PointDataGrid& grid, size_t arrayIndex, size_t count, ParticleAttribute& out)
{
    out.components = ComponentsT;
    out.bytes.resize(count * ComponentsT * sizeof(StoredT));
    unsigned char* dst = out.bytes.data();
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
        AttributeHandle<ValueT> handle(leaf->constAttributeArray(arrayIndex));
        for (auto index = leaf->beginIndexAll(); index; ++index) {
            const ValueT value = handle.get(*index);
            StoredT stored[ComponentsT];
            if constexpr (ComponentsT == 1) {
                stored[0] = static_cast<StoredT>(value);
            } else {
                for (int c = 0; c < ComponentsT; ++c) stored[c] = static_cast<StoredT>(value[c]);
            }
            std::memcpy(dst, stored, sizeof(stored));
            dst += sizeof(stored);
        }
    }
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
    uint64_t count = 0;
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
        if (!(leaf->attributeSet().descriptor() == descriptor)) {
            fail(path, "leaves of PointDataGrid '" + printable(grid.getName()) +
                 "' have different attributes");
        }
        for (size_t a = 0; a < descriptor.size(); ++a) {
            const openvdb::points::AttributeArray* array = leaf->attributeSet().getConst(a);
            if (!array || (array->size() != leaf->pointCount() && !array->isUniform())) {
                fail(path, "corrupt attribute array in PointDataGrid '" + printable(grid.getName()) + "'");
            }
        }
        count += leaf->pointCount();
    }

    particles.positions.resize(size_t(count));
    size_t n = 0;
    const openvdb::math::Transform& transform = grid.transform();
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
        AttributeHandle<openvdb::Vec3f> handle(leaf->constAttributeArray(positionIndex));
        for (auto index = leaf->beginIndexAll(); index; ++index) {
            const openvdb::Vec3d voxel = index.getCoord().asVec3d();
            const openvdb::Vec3d world = transform.indexToWorld(voxel + openvdb::Vec3d(handle.get(*index)));
            particles.positions[n++] = openvdb::Vec3f(world);
        }
    }

    // Attributes in the order the descriptor numbers them.
    std::vector<std::pair<size_t, std::string>> arrays;
    for (const auto& entry : descriptor.map()) arrays.emplace_back(entry.second, entry.first);
    std::sort(arrays.begin(), arrays.end());
    for (const auto& [arrayIndex, name] : arrays) {
        if (arrayIndex == positionIndex) continue;
        const openvdb::points::AttributeArray& array = firstLeaf->constAttributeArray(arrayIndex);
        if (openvdb::points::isGroup(array) || openvdb::points::isString(array)) continue;
        const std::string valueType = descriptor.valueType(arrayIndex);
        ParticleAttribute attribute;
        attribute.name = name;
        const size_t c = size_t(count);
        if (valueType == "float") { attribute.type = ScalarType::Float32; copyAttribute<float, float, 1>(grid, arrayIndex, c, attribute); }
        else if (valueType == "double") { attribute.type = ScalarType::Float64; copyAttribute<double, double, 1>(grid, arrayIndex, c, attribute); }
        else if (valueType == "int8") { attribute.type = ScalarType::Int8; copyAttribute<int8_t, int8_t, 1>(grid, arrayIndex, c, attribute); }
        else if (valueType == "int16") { attribute.type = ScalarType::Int16; copyAttribute<int16_t, int16_t, 1>(grid, arrayIndex, c, attribute); }
        else if (valueType == "int32") { attribute.type = ScalarType::Int32; copyAttribute<int32_t, int32_t, 1>(grid, arrayIndex, c, attribute); }
        else if (valueType == "int64") { attribute.type = ScalarType::Int64; copyAttribute<int64_t, int64_t, 1>(grid, arrayIndex, c, attribute); }
        else if (valueType == "bool") { attribute.type = ScalarType::UInt8; copyAttribute<bool, uint8_t, 1>(grid, arrayIndex, c, attribute); }
        else if (valueType == "vec3s") { attribute.type = ScalarType::Float32; copyAttribute<openvdb::Vec3f, float, 3>(grid, arrayIndex, c, attribute); }
        else if (valueType == "vec3d") { attribute.type = ScalarType::Float64; copyAttribute<openvdb::Vec3d, double, 3>(grid, arrayIndex, c, attribute); }
        else if (valueType == "vec3i") { attribute.type = ScalarType::Int32; copyAttribute<openvdb::Vec3i, int32_t, 3>(grid, arrayIndex, c, attribute); }
        else continue;  // matrices, quaternions: nothing the pipeline can use
        particles.attributes.push_back(std::move(attribute));
    }
    return particles;
}

} // namespace

ParticleSet
readVdbPointsParticles(const char* data, size_t size, const std::string& path)
{
    openvdb::initialize();
    openvdb::GridPtrVecPtr grids;
    try {
        std::istringstream stream(std::string(data, size), std::ios::in | std::ios::binary);
        openvdb::io::Stream vdbStream(stream, /*delayLoad=*/false);
        grids = vdbStream.getGrids();
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        fail(path, "corrupt .vdb file: it asks for more memory than there is");
    } catch (const std::exception& e) {
        std::string message = e.what();
        for (char& ch : message) {
            if (static_cast<unsigned char>(ch) < 0x20 || static_cast<unsigned char>(ch) >= 0x7f) ch = '?';
        }
        fail(path, "cannot read .vdb file: " + message);
    }
    if (grids) {
        for (const openvdb::GridBase::Ptr& grid : *grids) {
            if (const auto points = openvdb::gridConstPtrCast<PointDataGrid>(grid)) {
                return convertGrid(*points, path);
            }
        }
    }
    fail(path, "no PointDataGrid in this .vdb file (grids: " +
         [&] {
             std::string names;
             if (grids) {
                 for (const auto& grid : *grids) {
                     if (!names.empty()) names += ", ";
                     names += printable(grid->getName()) + " " + grid->valueType();
                 }
             }
             return names.empty() ? std::string("none") : names;
         }() + "); a density cache cannot be meshed as particles");
}

} // namespace io_internal
} // namespace nonbloppy
