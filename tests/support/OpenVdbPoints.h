// SPDX-License-Identifier: Apache-2.0
/// @file OpenVdbPoints.h
/// @brief Points .vdb files made by OpenVDB's own point conversion, for the reader's tests.
///
/// One translation unit (OpenVdbPoints.cc) includes openvdb/points/PointConversion.h, which
/// costs half a minute of compile time wherever it is included.
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace nonbloppy_test {

/// What writeOpenVdbPoints() puts in a grid besides the positions and "temperature".
enum class PointExtras
{
    None,
    /// A uniform int "id" (7), a non-uniform float pair "pair" (stride 2: 0 and the point's
    /// index in its leaf) and a group "tagged" that holds every point.
    IdPairAndGroup,
    /// Uniform values of the types nonbloppy reads as several components: a quats
    /// "orient" (1, 2, 3, 4), a mat4s "xform" (0 to 15 row by row), a mat3d "stress" (0.5
    /// to 8.5), and float scalars "c_0" to "c_3" (10 to 13) as writeParticles() splits a
    /// 4-component attribute.
    QuatMatricesAndSplitVector,
};

/// Writes @a file with one PointDataGrid "points" of @a positions (linear transform of
/// @a voxelSize), made by openvdb::points::createPointDataGrid, with a float attribute
/// "temperature" holding each point's number / 2, so a reader's output can be matched
/// point for point. @a compression, if given, is the file's (io::COMPRESS_* flags);
/// otherwise io::File's default.
void writeOpenVdbPoints(const std::string& file, const std::vector<openvdb::Vec3R>& positions, double voxelSize,
                        PointExtras extras = PointExtras::None, std::optional<uint32_t> compression = std::nullopt);

} // namespace nonbloppy_test
