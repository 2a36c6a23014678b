// SPDX-License-Identifier: Apache-2.0
/// @file MeshOutputs.h
/// @brief The extra outputs of `nonbloppy mesh`: particle attributes on the surface
///        (--attributes), the surface as a level set and the particles as points in the
///        --vdb file (--vdb-surface, --vdb-points). MeshCommand.cc declares them through
///        addMeshOutputOptions() and calls the two functions below per frame.

#ifndef NONBLOPPY_TOOL_MESH_OUTPUTS_H
#define NONBLOPPY_TOOL_MESH_OUTPUTS_H

#include "Commands.h"

#include <CLI/CLI.hpp>

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Particles.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

#include <atomic>
#include <string>

namespace nonbloppy_tool {

struct MeshOutputOptions
{
    std::string attributes;  ///< --attributes: comma-separated names, or "all"
    CLI::Option* attributesOpt = nullptr;  ///< set by addMeshOutputOptions()
    bool vdbSurface = false, vdbPoints = false;

    /// True if the particles (positions and attributes) are needed after meshing.
    bool needParticles() const { return !attributes.empty() || vdbPoints; }
};

/// The warnings the extra outputs give once per run, however many frames it writes (the
/// frames of a sequence carry the same attributes). One per run of the mesh command.
struct OutputWarnings
{
    WarningPrinter printer;  ///< where every warning of the run goes (see runBatch())
    std::atomic<bool> objDropsAttributes{false};
    std::atomic<bool> meshRounds{false};
    std::atomic<bool> meshRenames{false};
    std::atomic<bool> vdbRounds{false};
    std::atomic<bool> vdbRenames{false};
};

/// Declare --attributes, --vdb-surface and --vdb-points on @a cmd (the last two need
/// @a vdbOption, the --vdb FILE option).
void addMeshOutputOptions(CLI::App* cmd, MeshOutputOptions& options, CLI::Option* vdbOption);

/// @throw UsageError("--attributes names no attribute, got ','") if --attributes was given
///        a list without a name ('' or only commas and spaces). Checked before any input is read.
void checkAttributeList(const MeshOutputOptions& options);

/// @throw nonbloppy::ParameterError("unknown attribute 'x'; the particles have: ...") if
///        --attributes names an attribute @a particles lack, or one interpolateAttributes()
///        refuses (nonbloppy::checkAttributes()): checked once the frame is read, before it
///        is meshed.
void requireAttributes(const nonbloppy::ParticleSet& particles, const MeshOutputOptions& options);

/// With --attributes, interpolate the named attributes of @a particles to the final
/// vertices of result.mesh (see nonbloppy::interpolateAttributes). Warns once per run (@a once)
/// on stderr when @a meshPath is an OBJ file, which cannot store them, or stores one rounded
/// or renamed.
void addSurfaceAttributes(nonbloppy::SurfaceResult& result, const nonbloppy::ParticleSet& particles,
                          const MeshOutputOptions& options, const std::string& meshPath,
                          OutputWarnings& once, openvdb::util::NullInterrupter* interrupter);

/// Append to @a grids what --vdb-surface ("surface" level set at the density's voxel
/// size) and --vdb-points ("points" PointDataGrid, warned once per run (@a once) if
/// @a vdbPath stores an attribute rounded or renamed) ask for. The level set, seconds on
/// large frames, asks @a interrupter as it goes (nonbloppy::CancelledError on a stop).
void appendVdbGrids(openvdb::GridCPtrVec& grids, const nonbloppy::SurfaceResult& result,
                    const nonbloppy::ParticleSet& particles, const MeshOutputOptions& options,
                    const std::string& vdbPath, OutputWarnings& once,
                    openvdb::util::NullInterrupter* interrupter);

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_MESH_OUTPUTS_H
