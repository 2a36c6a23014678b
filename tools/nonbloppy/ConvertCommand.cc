// SPDX-License-Identifier: Apache-2.0
/// @file ConvertCommand.cc
/// @brief `nonbloppy convert IN OUT`: a particle file in any format readParticles() reads,
///        written as PLY, VTK, VTU, XYZ, CSV or VDB points, with every attribute the output
///        format can carry; with --particle-box, only the particles inside a box.

#include "Commands.h"

#include "BackgroundRemover.h"
#include "CpuLimit.h"
#include "Interrupts.h"
#include "NumberOptions.h"
#include "OutputCleanup.h"

#include <nonbloppy/CropParticles.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/WriteParticles.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace nonbloppy_tool {

namespace {

struct ConvertOptions
{
    std::string input, output;
    bool quiet = false;
    bool noDirectIo = false;  ///< --no-direct-io: write through the page cache
    ParticleBoxOption particleBox;  ///< --particle-box: only the particles inside it
};

int runConvert(const ConvertOptions& o)
{
    // Everything that can be checked before reading: a name for each file, the two formats
    // (exit 2, as for mesh), and not overwriting the input.
    requireFileName(o.input, "IN");
    requireFileName(o.output, "OUT");  // not "particle file name has no extension ()"
    requireAsUsage([&] { nonbloppy::requireParticleOutputFile(o.output); });
    requireAsUsage([&] { nonbloppy::requireParticleFile(o.input); });
    std::error_code ec;
    if (o.input == o.output || std::filesystem::equivalent(o.input, o.output, ec)) {
        throw UsageError("cannot write " + o.output + ": it is the input file");
    }
    const std::optional<openvdb::BBoxd> box = o.particleBox.box();

    // A stop signal ends the conversion with exit 130 and OUT as it was: it is acted on once
    // IN is read, before anything is written, or once OUT is written, which is then undone.
    // It used to kill the process, leaving the writer's temporary file beside OUT.
    SignalHandlerScope signals;
    // The readers and writers run in parallel: no more workers than the CPUs a container or
    // job grants (CpuLimit.h).
    const std::unique_ptr<tbb::global_control> threadLimit = limitWorkers(0);
    const WarningPrinter printer;
    nonbloppy::ParticleSet particles = [&] {
        const InputReadScope reading;  // may block (a FIFO): see kStuckReadSeconds
        return nonbloppy::readParticles(o.input);
    }();
    throwIfInterrupted();
    const size_t particlesRead = particles.size();
    if (box) {
        particles = nonbloppy::cropParticles(particles, *box);
        // Written all the same, as a file of no particles is: said, as it is likely a slip.
        if (particles.size() == 0 && particlesRead > 0) {
            WarningLine(printer) << "none of the " << particlesRead << " particles of " << o.input
                                 << " lie inside --particle-box " << formatBox(*box) << ": " << o.output
                                 << " holds no particles";
        }
    }
    if (!particles.skipped.empty()) {
        WarningLine(printer) << "not read from " << o.input << ", so not converted: " << joinedSkipped(particles);
    }
    const bool positionsOnly = lowerExtension(o.output) == ".xyz";
    if (positionsOnly && !particles.attributes.empty()) {
        std::string names;
        for (const auto& a : particles.attributes) names += (names.empty() ? "" : ", ") + a.name;
        WarningLine(printer) << ".xyz holds positions only; attributes dropped: " << names;
    }
    if (!positionsOnly) {
        std::vector<std::string> original;
        for (const auto& a : particles.attributes) original.push_back(a.name);
        warnRenamedAttributes(original, nonbloppy::writtenAttributeNames(particles, o.output), o.output, printer);
    }
    for (const std::string& name : nonbloppy::roundedAttributes(particles, o.output)) warnRounded(name, o.output, printer);
    nonbloppy::ParticleWriteSettings settings;
    settings.directIo = !o.noDirectIo;
    BackgroundRemover remover;
    OutputCleanup cleanup;
    cleanup.willWrite(o.output);
    nonbloppy::writeParticles(particles, o.output, settings);
    cleanup.written();
    throwIfInterrupted();
    cleanup.keep(remover);
    if (!o.quiet) {
        // As written: .xyz keeps none of them (the warning above names those dropped).
        std::cout << "converted " << counted(particles.size(), "particle")
                  << (box ? " (of " + std::to_string(particlesRead) + ", inside --particle-box " + formatBox(*box) + ")"
                          : std::string())
                  << " with " << counted(positionsOnly ? 0 : particles.attributes.size(), "attribute") << ": "
                  << o.input << " -> " << o.output << std::endl;
    }
    return 0;
}

} // namespace

Command setupConvertCommand(CLI::App& parent)
{
    auto options = std::make_shared<ConvertOptions>();
    CLI::App* cmd = parent.add_subcommand(
        "convert", "Convert a particle file to another format, keeping its attributes");
    cmd->footer("Reads .vtk, .vtu, .vtp, .ply, .xyz, .bgeo (also .bhclassic), .vdb (points), .csv, .txt, .json;\n"
                "writes .ply, .vtk, .vtu, .xyz (positions only), .csv, .vdb (PointDataGrid).\n"
                ".xyz is raw binary: little-endian float32 x y z triples (write text tables as .csv).");
    cmd->add_option("IN", options->input, "Particle file to read")->required()->group(kGroupInputOutput);
    cmd->add_option("OUT", options->output, "Particle file to write")->required()->group(kGroupInputOutput);
    cmd->add_flag("--no-direct-io", options->noDirectIo,
        "Write through the page cache (by default files of 1 MiB or more bypass it on local ext4, "
        "XFS and Btrfs disks; the bytes are the same)")
        ->group(kGroupInputOutput);
    options->particleBox.add(cmd, "written with their attributes");
    cmd->add_flag("-q,--quiet", options->quiet, "Print only warnings and errors (stderr)")->group(kGroupDebug);
    return {cmd, [options]() { return runConvert(*options); }};
}

} // namespace nonbloppy_tool
