// SPDX-License-Identifier: Apache-2.0
/// @file Particles.h
/// @brief Particle inputs: the ParticleList concept every stage accepts, a view over a
///        caller's raw coordinate array, and ParticleSet, the container the readers fill.
///
/// ## The ParticleList concept
/// Stages that take particles are templates over a type modelling OpenVDB's ParticleList /
/// PointArray convention, so callers pass their own arrays and nothing is converted:
/// @code
/// struct MyParticles {
///     using PosType = openvdb::Vec3R;              // optional, for OpenVDB's own tools
///     size_t size() const;                         // number of particles
///     void getPos(size_t n, openvdb::Vec3R& xyz) const; // world-space position of particle n
/// };
/// @endcode
/// Positions are in world units (the simulation's length unit). getPos() is called
/// concurrently from several threads and must therefore be thread-safe for reading.

#ifndef NONBLOPPY_PARTICLES_H
#define NONBLOPPY_PARTICLES_H

#include <nonbloppy/Export.h>

#include <openvdb/openvdb.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace nonbloppy {

/// A non-owning ParticleList over xyz coordinates stored in a caller's array:
/// particle n is at (data[n*stride], data[n*stride+1], data[n*stride+2]).
/// Cost: nothing is copied; the caller keeps the array alive while the view is used.
template<typename ScalarT>
class PositionArrayView
{
public:
    using PosType = openvdb::Vec3R;  ///< position type of the ParticleList concept

    /// @param data    first coordinate of particle 0
    /// @param count   number of particles
    /// @param stride  distance, in ScalarT elements, between two particles (3 for packed xyz)
    PositionArrayView(const ScalarT* data, size_t count, size_t stride = 3)
        : mData(data), mCount(count), mStride(stride) {}

    /// Number of particles.
    size_t size() const { return mCount; }
    /// Position of particle @a n (world units), converted to double.
    void getPos(size_t n, openvdb::Vec3R& xyz) const
    {
        const ScalarT* p = mData + n * mStride;
        xyz = openvdb::Vec3R(double(p[0]), double(p[1]), double(p[2]));
    }

private:
    const ScalarT* mData;
    size_t mCount;
    size_t mStride;
};

/// The type of each component of a particle attribute, as it was stored in the file.
enum class ScalarType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64 };

/// Size in bytes of one component of @a type.
NONBLOPPY_API size_t scalarSize(ScalarType type);
/// Lower-case name of @a type ("float32", "int64", ...), as used by `nonbloppy inspect`.
NONBLOPPY_API const char* scalarTypeName(ScalarType type);
/// True for the eight integer types, false for Float32 and Float64.
NONBLOPPY_API bool isIntegerType(ScalarType type);

/// The ScalarType of the C++ type @a T: scalarTypeOf<float>() is Float32,
/// scalarTypeOf<uint64_t>() UInt64. Only the ten types ScalarType names compile.
template<typename T>
constexpr ScalarType scalarTypeOf()
{
    static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool> && (sizeof(T) <= 8),
                  "a particle attribute holds 8- to 64-bit integers, float or double");
    if constexpr (std::is_floating_point_v<T>) {
        static_assert(sizeof(T) == 4 || sizeof(T) == 8, "float or double");
        return sizeof(T) == 4 ? ScalarType::Float32 : ScalarType::Float64;
    } else if constexpr (std::is_signed_v<T>) {
        return sizeof(T) == 1 ? ScalarType::Int8 : sizeof(T) == 2 ? ScalarType::Int16
             : sizeof(T) == 4 ? ScalarType::Int32 : ScalarType::Int64;
    } else {
        return sizeof(T) == 1 ? ScalarType::UInt8 : sizeof(T) == 2 ? ScalarType::UInt16
             : sizeof(T) == 4 ? ScalarType::UInt32 : ScalarType::UInt64;
    }
}

/// One named per-particle attribute (e.g. "velocity", 3 × Float32), stored in its own
/// type so nothing is lost on the way from reader to writer.
struct NONBLOPPY_API ParticleAttribute
{
    std::string name;                    ///< as in the file, e.g. "velocity"
    ScalarType type = ScalarType::Float32;  ///< stored type of each component
    int components = 1;                  ///< 1 for scalars, 3 for vectors, ...
    std::vector<unsigned char> bytes;    ///< native-endian values, particle-major

    /// The attribute @a name holding @a values, @a components per particle (particle-major:
    /// particle 0's components, then particle 1's), typed after @a T (scalarTypeOf()).
    /// Cost: one copy of the values.
    /// Example: ParticleAttribute::of("velocity", 3, std::vector<float>{vx0, vy0, vz0, ...}).
    template<typename T>
    static ParticleAttribute of(std::string name, int components, const std::vector<T>& values)
    {
        ParticleAttribute attribute;
        attribute.name = std::move(name);
        attribute.type = scalarTypeOf<T>();
        attribute.components = components;
        attribute.bytes.resize(values.size() * sizeof(T));
        if (!values.empty()) std::memcpy(attribute.bytes.data(), values.data(), attribute.bytes.size());
        return attribute;
    }

    /// Number of particles the attribute holds values for.
    size_t size() const;
    /// Component @a c of particle @a n, converted to double.
    double asDouble(size_t n, int c = 0) const;
};

/// Particles read from a file: positions plus every named per-particle attribute.
/// Models the ParticleList concept, so it can be passed to every stage directly.
struct NONBLOPPY_API ParticleSet
{
    using PosType = openvdb::Vec3R;  ///< position type of the ParticleList concept

    std::vector<openvdb::Vec3f> positions;      ///< world units
    std::vector<ParticleAttribute> attributes;  ///< each holds positions.size() values
    /// Per-particle data the file holds that no attribute could take, each said as
    /// "group 'splash'", "string attribute 'name'" (.vdb), "string array 'label'" (VTU,
    /// VTP), "unnamed column 1" (CSV: pandas' and R's row numbers), "list property 'ids'"
    /// or "element 'face'" (PLY: an element other than the vertices, e.g. a mesh's faces),
    /// "POLYGONS section" (legacy VTK: also LINES and TRIANGLE_STRIPS), "Polys section"
    /// (VTP: also Lines and Strips), "point grid 'B'" (.vdb: the point grids after the first,
    /// which alone is read),
    /// so that a caller can tell its user what a conversion leaves behind.
    std::vector<std::string> skipped;

    /// Number of particles.
    size_t size() const { return positions.size(); }
    /// Position of particle @a n, world units.
    void getPos(size_t n, openvdb::Vec3R& xyz) const { xyz = positions[n]; }

    /// The attribute called @a name, or nullptr.
    const ParticleAttribute* findAttribute(const std::string& name) const;
};

} // namespace nonbloppy

#endif // NONBLOPPY_PARTICLES_H
