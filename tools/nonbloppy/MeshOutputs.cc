// SPDX-License-Identifier: Apache-2.0
/// @file MeshOutputs.cc
/// @brief --attributes, --vdb-surface and --vdb-points of `nonbloppy mesh`.

#include "MeshOutputs.h"

#include "Commands.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/InterpolateAttributes.h>
#include <nonbloppy/MeshToLevelSet.h>
#include <nonbloppy/WriteMesh.h>
#include <nonbloppy/WriteParticles.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <iostream>
#include <vector>

namespace nonbloppy_tool {

namespace {

std::vector<std::string> splitNames(const std::string& list)
{
    std::vector<std::string> names;
    size_t begin = 0;
    while (begin <= list.size()) {
        const size_t comma = std::min(list.find(',', begin), list.size());
        size_t first = begin, last = comma;  // spaces around a name go, those inside stay
        while (first < last && std::isspace(static_cast<unsigned char>(list[first]))) ++first;
        while (last > first && std::isspace(static_cast<unsigned char>(list[last - 1]))) --last;
        if (last > first) names.push_back(list.substr(first, last - first));
        begin = comma + 1;
    }
    return names;
}

} // namespace

void addMeshOutputOptions(CLI::App* cmd, MeshOutputOptions& o, CLI::Option* vdbOption)
{
    o.attributesOpt = cmd->add_option("--attributes", o.attributes,
        "Particle attributes to carry to the mesh vertices, e.g. velocity,id, or all: kernel-weighted "
        "means as float32, integers the nearest particle's value, exact (PLY properties, VTK point data; OBJ "
        "cannot store them)")
        ->group(kGroupInputOutput);
    cmd->add_flag("--vdb-surface", o.vdbSurface,
        "Also store the final surface as a level set grid 'surface' in the --vdb file")
        ->needs(vdbOption)->group(kGroupInputOutput);
    cmd->add_flag("--vdb-points", o.vdbPoints,
        "Also store the input particles as a PointDataGrid 'points' in the --vdb file")
        ->needs(vdbOption)->group(kGroupInputOutput);
}

void checkAttributeList(const MeshOutputOptions& o)
{
    // '--attributes ""' (a variable left unset) used to carry nothing without a word.
    if (o.attributesOpt && o.attributesOpt->count() > 0 && splitNames(o.attributes).empty()) {
        throw UsageError("--attributes names no attribute, got '" + o.attributes + "'");
    }
}

void requireAttributes(const nonbloppy::ParticleSet& particles, const MeshOutputOptions& o)
{
    if (!o.attributes.empty()) nonbloppy::checkAttributes(particles, splitNames(o.attributes));
}

void addSurfaceAttributes(nonbloppy::SurfaceResult& result, const nonbloppy::ParticleSet& particles,
                          const MeshOutputOptions& o, const std::string& meshPath,
                          OutputWarnings& once, openvdb::util::NullInterrupter* interrupter)
{
    if (o.attributes.empty()) return;
    const std::vector<std::string> names = splitNames(o.attributes);
    nonbloppy::interpolateAttributes(result.mesh, particles, names,
                                     result.parameters.effectiveRadius, interrupter);
    const std::string ext = lowerExtension(meshPath);
    if (ext == ".obj" && !result.mesh.attributes.empty() && !once.objDropsAttributes.exchange(true)) {
        once.printer.warn("OBJ cannot store vertex attributes; write .ply or .vtk to keep --attributes");
    }
    if (!once.meshRounds) {  // the scan is for the first frame that needs it
        const std::vector<std::string> rounded = nonbloppy::roundedAttributes(result.mesh, meshPath);
        if (!rounded.empty() && !once.meshRounds.exchange(true)) warnRounded(rounded[0], meshPath, once.printer);
    }
    if (ext != ".obj" && !result.mesh.attributes.empty() && !once.meshRenames.exchange(true)) {
        std::vector<std::string> original;
        for (const auto& a : result.mesh.attributes) original.push_back(a.name);
        warnRenamedAttributes(original, nonbloppy::writtenAttributeNames(result.mesh, meshPath), meshPath, once.printer);
    }
}

void appendVdbGrids(openvdb::GridCPtrVec& grids, const nonbloppy::SurfaceResult& result,
                    const nonbloppy::ParticleSet& particles, const MeshOutputOptions& o, const std::string& vdbPath,
                    OutputWarnings& once, openvdb::util::NullInterrupter* interrupter)
{
    if (o.vdbSurface) {
        grids.push_back(nonbloppy::meshToLevelSet(result.mesh, result.parameters.voxelSize, 3.0f, interrupter));
    }
    if (o.vdbPoints) {
        grids.push_back(nonbloppy::makePointDataGrid(particles));
        if (!particles.attributes.empty() && !once.vdbRenames.exchange(true)) {  // as convert says it
            std::vector<std::string> original;
            for (const auto& a : particles.attributes) original.push_back(a.name);
            warnRenamedAttributes(original, nonbloppy::writtenAttributeNames(particles, vdbPath), vdbPath, once.printer);
        }
        if (!once.vdbRounds) {
            const std::vector<std::string> rounded = nonbloppy::roundedAttributes(particles, vdbPath);
            if (!rounded.empty() && !once.vdbRounds.exchange(true)) warnRounded(rounded[0], vdbPath, once.printer);
        }
    }
}

} // namespace nonbloppy_tool
