// SPDX-License-Identifier: Apache-2.0
/// @file Particles.cc
/// @brief The non-inline parts of Particles.h: scalar type sizes and names, attribute access.

#include <nonbloppy/Particles.h>

#include <cassert>
#include <cstring>

namespace nonbloppy {

size_t
scalarSize(ScalarType type)
{
    switch (type) {
        case ScalarType::Int8:
        case ScalarType::UInt8: return 1;
        case ScalarType::Int16:
        case ScalarType::UInt16: return 2;
        case ScalarType::Int32:
        case ScalarType::UInt32:
        case ScalarType::Float32: return 4;
        case ScalarType::Int64:
        case ScalarType::UInt64:
        case ScalarType::Float64: return 8;
    }
    return 0;
}

const char*
scalarTypeName(ScalarType type)
{
    switch (type) {
        case ScalarType::Int8: return "int8";
        case ScalarType::UInt8: return "uint8";
        case ScalarType::Int16: return "int16";
        case ScalarType::UInt16: return "uint16";
        case ScalarType::Int32: return "int32";
        case ScalarType::UInt32: return "uint32";
        case ScalarType::Int64: return "int64";
        case ScalarType::UInt64: return "uint64";
        case ScalarType::Float32: return "float32";
        case ScalarType::Float64: return "float64";
    }
    return "unknown";
}

bool
isIntegerType(ScalarType type)
{
    return type != ScalarType::Float32 && type != ScalarType::Float64;
}

size_t
ParticleAttribute::size() const
{
    const size_t valueBytes = scalarSize(type) * size_t(components > 0 ? components : 0);
    return valueBytes == 0 ? 0 : bytes.size() / valueBytes;
}

namespace {

template<typename T>
double
loadAs(const unsigned char* p)
{
    T value;
    std::memcpy(&value, p, sizeof(T));
    return double(value);
}

} // namespace

double
ParticleAttribute::asDouble(size_t n, int c) const
{
    assert(c >= 0 && c < components && n < size());
    const size_t width = scalarSize(type);
    const unsigned char* p = bytes.data() + (n * size_t(components) + size_t(c)) * width;
    switch (type) {
        case ScalarType::Int8: return loadAs<int8_t>(p);
        case ScalarType::UInt8: return loadAs<uint8_t>(p);
        case ScalarType::Int16: return loadAs<int16_t>(p);
        case ScalarType::UInt16: return loadAs<uint16_t>(p);
        case ScalarType::Int32: return loadAs<int32_t>(p);
        case ScalarType::UInt32: return loadAs<uint32_t>(p);
        case ScalarType::Int64: return loadAs<int64_t>(p);
        case ScalarType::UInt64: return loadAs<uint64_t>(p);
        case ScalarType::Float32: return loadAs<float>(p);
        case ScalarType::Float64: return loadAs<double>(p);
    }
    return 0.0;
}

const ParticleAttribute*
ParticleSet::findAttribute(const std::string& name) const
{
    for (const ParticleAttribute& attribute : attributes) {
        if (attribute.name == name) return &attribute;
    }
    return nullptr;
}

} // namespace nonbloppy
