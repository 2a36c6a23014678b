// SPDX-License-Identifier: Apache-2.0
/// @file ReadParticles.cc
/// @brief Stage "read particles": legacy VTK, PLY and raw XYZ particle files.

#include <nonbloppy/ReadParticles.h>

#include <nonbloppy/Error.h>

#include "FileFormats.h"
#include "ParticleReaders.h"

#include <cmath>
#include <cstring>

namespace nonbloppy {

namespace {

using namespace io_internal;

const char* const kParticleExtensions =
    ".vtk, .vtu, .vtp, .ply, .xyz, .bgeo, .vdb, .csv, .txt or .json";

ParticleAttribute
toAttribute(NumericArray&& array)
{
    ParticleAttribute attribute;
    attribute.name = std::move(array.name);
    attribute.type = array.type;
    attribute.components = array.components;
    attribute.bytes = std::move(array.bytes);
    return attribute;
}

ParticleSet
readVtkParticles(const std::vector<char>& file, const std::string& path)
{
    VtkData vtk = parseVtk(file.data(), file.size(), path, /*wantPolygons=*/false);
    ParticleSet particles;
    particles.positions = std::move(vtk.points);
    for (NumericArray& array : vtk.pointArrays) {
        particles.attributes.push_back(toAttribute(std::move(array)));
    }
    return particles;
}

ParticleSet
readPlyParticles(const std::vector<char>& file, const std::string& path)
{
    PlyData ply = parsePly(file.data(), file.size(), path, /*wantFaces=*/false);
    ParticleSet particles;
    particles.positions.resize(ply.vertexCount);
    for (NumericArray& property : ply.vertexProperties) {
        const int axis = property.name == "x" ? 0 : property.name == "y" ? 1
            : property.name == "z" ? 2 : -1;
        if (axis < 0) {
            particles.attributes.push_back(toAttribute(std::move(property)));
            continue;
        }
        if (property.type != ScalarType::Float32 && property.type != ScalarType::Float64) {
            fail(path, std::string("PLY property '") + property.name +
                "' must be float or double");
        }
        const std::vector<float> values = toFloats(property);
        for (size_t i = 0; i < values.size(); ++i) particles.positions[i][axis] = values[i];
    }
    return particles;
}

ParticleSet
readXyzParticles(const std::vector<char>& file, const std::string& path)
{
    if (file.size() % 12 != 0) {
        fail(path, "XYZ file size " + std::to_string(file.size()) +
            " is not a multiple of 12 bytes (three float32 per particle)");
    }
    ParticleSet particles;
    particles.positions.resize(file.size() / 12);
    static_assert(sizeof(openvdb::Vec3f) == 12, "Vec3f must be three packed floats");
    if (!file.empty()) std::memcpy(particles.positions.data(), file.data(), file.size());
    if (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__) {
        for (openvdb::Vec3f& p : particles.positions) {
            for (int axis = 0; axis < 3; ++axis) {
                uint32_t bits;
                std::memcpy(&bits, &p[axis], 4);
                bits = __builtin_bswap32(bits);
                std::memcpy(&p[axis], &bits, 4);
            }
        }
    }
    return particles;
}

} // namespace

ParticleSet
readParticles(const std::string& path)
{
    const std::string ext = lowerExtension(path);
    if (ext.empty()) {
        throw FileError("particle file name has no extension (" + path +
            "); expected " + kParticleExtensions);
    }
    if (!isParticleFile(path)) {
        throw FileError("unknown particle file extension '" + ext + "' (" + path +
            "); expected " + kParticleExtensions);
    }
    const std::vector<char> file = loadFile(path);

    ParticleSet particles;
    if (ext == ".vtk") particles = readVtkParticles(file, path);
    else if (ext == ".ply") particles = readPlyParticles(file, path);
    else if (ext == ".xyz") particles = readXyzParticles(file, path);
    else if (ext == ".bgeo") particles = readBgeoParticles(file.data(), file.size(), path);
    else if (ext == ".vtu" || ext == ".vtp") particles = readVtuParticles(file.data(), file.size(), path);
    else if (ext == ".csv" || ext == ".txt") particles = readTableParticles(file.data(), file.size(), path);
    else if (ext == ".json") particles = readJsonParticles(file.data(), file.size(), path);
    else particles = readVdbPointsParticles(file.data(), file.size(), path);

    // Later stages hash positions into voxels; one NaN would poison the whole grid.
    for (size_t i = 0; i < particles.positions.size(); ++i) {
        const openvdb::Vec3f& p = particles.positions[i];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
            throw ParameterError("non-finite position of particle " + std::to_string(i) +
                " (" + path + ")");
        }
    }
    return particles;
}

bool
isParticleFile(const std::string& path)
{
    const std::string ext = io_internal::lowerExtension(path);
    return ext == ".vtk" || ext == ".ply" || ext == ".xyz" || ext == ".bgeo" || ext == ".vtu"
        || ext == ".vtp" || ext == ".csv" || ext == ".txt" || ext == ".json" || ext == ".vdb";
}

} // namespace nonbloppy
