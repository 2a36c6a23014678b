// SPDX-License-Identifier: Apache-2.0
/// @file Kernel.h
/// @brief The MPS weight function w(d) = r_e/d − 1 used for both density and relaxation.

#ifndef NONBLOPPY_KERNEL_H
#define NONBLOPPY_KERNEL_H

#include <algorithm>
#include <cmath>

namespace nonbloppy {

/// The kernel is singular at d = 0; distances are clamped to this fraction of the
/// effective radius, so a voxel centred on a particle gets the finite weight
/// 1/kMinDistanceFraction − 1 = 999 instead of infinity.
constexpr float kMinDistanceFraction = 1e-3f;

/// MPS weight w(d) = r_e/d − 1 for d < r_e, 0 beyond (dimensionless).
/// @param distance         |x − r_j| in world units, ≥ 0
/// @param effectiveRadius  r_e in world units, > 0
inline float mpsWeight(float distance, float effectiveRadius)
{
    if (!(distance < effectiveRadius)) return 0.0f;
    const float clamped = std::max(distance, kMinDistanceFraction * effectiveRadius);
    return effectiveRadius / clamped - 1.0f;
}

/// The same weight from a squared distance, as the hot loops have it: saves a sqrt for
/// the particles outside the support.
inline float mpsWeightSquared(float squaredDistance, float effectiveRadius)
{
    const float er2 = effectiveRadius * effectiveRadius;
    if (!(squaredDistance < er2)) return 0.0f;
    const float minDistance = kMinDistanceFraction * effectiveRadius;
    const float clamped = std::max(squaredDistance, minDistance * minDistance);
    return effectiveRadius / std::sqrt(clamped) - 1.0f;
}

} // namespace nonbloppy

#endif // NONBLOPPY_KERNEL_H
