// SPDX-License-Identifier: Apache-2.0
/// @file OpenVdbScale.h
/// @brief Private: the one check, and the one message, for lengths below the smallest voxel
///        or cell OpenVDB's linear transforms accept (kMinCellSize), and for coordinates past
///        the largest index coordinate accepted. Only src/ includes it.

#ifndef NONBLOPPY_OPENVDB_SCALE_H
#define NONBLOPPY_OPENVDB_SCALE_H

#include <nonbloppy/Error.h>

#include "NumberText.h"

#include <sstream>

namespace nonbloppy {
namespace openvdb_scale_internal {

/// The largest index-space coordinate (world coordinate / cell or voxel size) accepted for
/// particles and mesh vertices: OpenVDB's coordinates are 32-bit, and meshToVolume works on
/// float index coordinates that stop resolving voxels far beyond this (a mesh 5e7 out at
/// h = 0.02 hung, unheard by the interrupter).
constexpr double kMaxIndexCoordinate = 1.0e9;

/// Throw ParameterError("<name> <value> is below <least>, the smallest OpenVDB accepts: give
/// the positions in a smaller unit") if @a value < @a least. Called before any grid is made:
/// for the voxel size and the index's cells (least kMinCellSize), and for r_e when it sets
/// the index's cells (least kMinCellSize / kCellOverRadius).
inline void requireOpenVdbScale(double value, double least, const char* name)
{
    if (value < least) {
        std::ostringstream msg;
        msg << name << " " << number_text_internal::numberBeside(value, least) << " is below " << least
            << ", the smallest OpenVDB accepts: give the positions in a smaller unit";
        throw ParameterError(msg.str());
    }
}

/// Throw ParameterError("<what> coordinates up to <largest> are too far from the origin for
/// a <cellName> of <cellSize> (32-bit index space)") if @a largest (the largest |coordinate|)
/// over @a cellSize, plus @a marginCells, passes kMaxIndexCoordinate: for the particle index
/// ("particle", "cell size"), a points grid ("particle", "voxel size") and a mesh's level
/// set ("mesh", "voxel size", its half width as margin).
inline void requireIndexRange(double largest, double cellSize, const char* what, const char* cellName,
                              double marginCells = 0.0)
{
    if (largest / cellSize + marginCells > kMaxIndexCoordinate) {
        std::ostringstream msg;
        msg << what << " coordinates up to " << largest << " are too far from the origin for a " << cellName
            << " of " << cellSize << " (32-bit index space)";
        throw ParameterError(msg.str());
    }
}

} // namespace openvdb_scale_internal
} // namespace nonbloppy

#endif // NONBLOPPY_OPENVDB_SCALE_H
