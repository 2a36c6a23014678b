// SPDX-License-Identifier: Apache-2.0
/// @file VectorArea.h
/// @brief Private: twice the vector area of a mesh polygon, the one formula the stages that
///        weigh faces by area and orientation share (ComputeNormals, CorrectSurface,
///        SmoothSurface, MeasureMesh), and the signed volume a triangle adds to a closed
///        mesh's. In float or double, as the caller's vectors are.

#ifndef NONBLOPPY_VECTOR_AREA_H
#define NONBLOPPY_VECTOR_AREA_H

namespace nonbloppy {

/// Twice the vector area of triangle abc: the cross product of its edges from a. Its length
/// is twice the area; it points along the normal of the counter-clockwise corners.
template<typename VecT>
inline VecT twiceVectorArea(const VecT& a, const VecT& b, const VecT& c)
{
    return (b - a).cross(c - a);
}

/// Twice the vector area of quad abcd, planar or not: the cross product of its diagonals
/// (the sum of the vector areas of its two triangles, however it is split).
template<typename VecT>
inline VecT twiceVectorArea(const VecT& a, const VecT& b, const VecT& c, const VecT& d)
{
    return (c - a).cross(d - b);
}

/// Six times the signed volume of the tetrahedron (origin, a, b, c): summed over the
/// triangles of a closed mesh, six times its volume (divergence theorem), positive when
/// they run counter-clockwise seen from outside.
template<typename VecT>
inline auto sixTimesSignedVolume(const VecT& a, const VecT& b, const VecT& c)
{
    return a.dot(b.cross(c));
}

} // namespace nonbloppy

#endif // NONBLOPPY_VECTOR_AREA_H
