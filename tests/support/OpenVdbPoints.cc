// SPDX-License-Identifier: Apache-2.0
#include "OpenVdbPoints.h"

#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointGroup.h>

namespace nonbloppy_test {

void writeOpenVdbPoints(const std::string& file, const std::vector<openvdb::Vec3R>& positions, double voxelSize,
                        PointExtras extras, std::optional<uint32_t> compression)
{
    openvdb::initialize();
    const openvdb::points::PointAttributeVector<openvdb::Vec3R> wrapper(positions);
    auto transform = openvdb::math::Transform::createLinearTransform(voxelSize);
    auto index = openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(wrapper, *transform);
    auto grid = openvdb::points::createPointDataGrid<openvdb::points::NullCodec, openvdb::points::PointDataGrid>(
        *index, wrapper, *transform);
    grid->setName("points");
    std::vector<float> temperature(positions.size());
    for (size_t i = 0; i < temperature.size(); ++i) temperature[i] = float(i) * 0.5f;
    openvdb::points::appendAttribute<float>(grid->tree(), "temperature");
    openvdb::points::populateAttribute<openvdb::points::PointDataTree, openvdb::tools::PointIndexTree,
        openvdb::points::PointAttributeVector<float>>(grid->tree(), index->tree(), "temperature",
            openvdb::points::PointAttributeVector<float>(temperature));
    if (extras == PointExtras::IdPairAndGroup) {
        openvdb::points::appendAttribute<int32_t>(grid->tree(), "id", 7);
        openvdb::points::appendAttribute<float>(grid->tree(), "pair", 0.0f, /*stride=*/2);
        for (auto leaf = grid->tree().beginLeaf(); leaf; ++leaf) {
            openvdb::points::AttributeWriteHandle<float> pair(leaf->attributeArray("pair"));
            pair.expand();
            for (openvdb::Index i = 0; i < pair.size(); ++i) pair.set(i, 1, float(i));
        }
        openvdb::points::appendGroup(grid->tree(), "tagged");
        openvdb::points::setGroup(grid->tree(), "tagged", true);
    }
    if (extras == PointExtras::QuatMatricesAndSplitVector) {
        openvdb::points::appendAttribute<openvdb::math::Quats>(grid->tree(), "orient",
                                                                openvdb::math::Quats(1.0f, 2.0f, 3.0f, 4.0f));
        openvdb::Mat4s xform;
        for (int k = 0; k < 16; ++k) xform.asPointer()[k] = float(k);
        openvdb::points::appendAttribute<openvdb::Mat4s>(grid->tree(), "xform", xform);
        openvdb::Mat3d stress;
        for (int k = 0; k < 9; ++k) stress.asPointer()[k] = double(k) + 0.5;
        openvdb::points::appendAttribute<openvdb::Mat3d>(grid->tree(), "stress", stress);
        for (int c = 0; c < 4; ++c) {
            openvdb::points::appendAttribute<float>(grid->tree(), "c_" + std::to_string(c), float(10 + c));
        }
    }
    openvdb::io::File out(file);
    if (compression) out.setCompression(*compression);
    out.write({grid});
    out.close();
}

} // namespace nonbloppy_test
