// SPDX-License-Identifier: Apache-2.0
/// @file MeshCommand.cc
/// @brief `nonbloppy mesh IN -o OUT`: read particles, build the surface, write the mesh and,
///        on request, the density grid; print a one-screen summary.

#include "Commands.h"
#include "MeshOutputs.h"

#include "BackgroundRemover.h"
#include "BatchRun.h"
#include "CpuLimit.h"
#include "FrameSequence.h"
#include "Interrupts.h"
#include "Json.h"
#include "NumberOptions.h"
#include "OutputCleanup.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/CropParticles.h>
#include <nonbloppy/DiagnoseSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/Timing.h>
#include <nonbloppy/WriteMesh.h>
#include <nonbloppy/WriteVdb.h>

#include <openvdb/util/NullInterrupter.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <sys/stat.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <unistd.h>

namespace nonbloppy_tool {

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------
// Cancellation and progress

/// The library's interrupter: says "stop" after SIGINT/SIGTERM/SIGHUP and shows progress.
/// - verbose (-v): each stage's name, its progress in quarters and its duration, one line
///   each on stderr, "[progress] frame 12: rasterize density 25%" (@a frame: "frame 12: "
///   in a sequence, whose frames may run side by side);
/// - live: one line on stdout redrawn in place at most every 0.1 s ("rasterize density
///   47%"), for a single frame on a terminal without -v or -q, so long work shows it is
///   going; clearLine() (or the destructor) erases it before anything else is printed.
/// wasInterrupted() is called from worker threads: every line is written whole, under one
/// mutex shared by all interrupters; a live redraw never waits for it.
class ProgressInterrupter : public openvdb::util::NullInterrupter
{
public:
    explicit ProgressInterrupter(bool verbose, bool live = false, std::string frame = "")
        : mVerbose(verbose), mLive(live), mFrame(std::move(frame)) {}
    ~ProgressInterrupter() override { clearLine(); }
    ProgressInterrupter(const ProgressInterrupter&) = delete;
    ProgressInterrupter& operator=(const ProgressInterrupter&) = delete;

    void start(const char* name = nullptr) override
    {
#ifdef __GLIBC__
        // By now the library has freed the density grid (without --vdb) and the extraction's
        // temporaries, but glibc keeps those pages; hand them back before the mesh grows, or
        // they add to the peak of large frames (12.5M particles: 6.6 GiB -> 5.5 GiB).
        if (name && std::strcmp(name, "relax vertices") == 0) malloc_trim(0);
#endif
        std::lock_guard<std::mutex> lock(outputMutex());
        mStages.push_back({name ? name : "working", std::chrono::steady_clock::now()});
        mNextQuarter = 1;
        if (mVerbose) std::cerr << ("[progress] " + mFrame + mStages.back().name + " ...\n") << std::flush;
        if (mLive) draw(-1);
    }

    void end() override
    {
        std::lock_guard<std::mutex> lock(outputMutex());
        if (mStages.empty()) return;
        if (mVerbose) {
            const std::chrono::duration<double> elapsed =
                std::chrono::steady_clock::now() - mStages.back().start;
            char seconds[32];
            std::snprintf(seconds, sizeof(seconds), "%.3f", elapsed.count());
            // A stage a signal cut short, or an error, ends too (its scope unwinds): not
            // "done" just before "truncated POINTS section". The error's own line follows.
            const char* how = interruptRequested() ? " stopped ("
                              : std::uncaught_exceptions() > 0 ? " failed (" : " done (";
            std::cerr << ("[progress] " + mFrame + mStages.back().name + how + seconds + " s)\n") << std::flush;
        }
        // The innermost stage an exception leaves ends first.
        if (std::uncaught_exceptions() > 0 && mFailedStage.empty()) mFailedStage = mStages.back().name;
        mStages.pop_back();
    }

    bool wasInterrupted(int percent = -1) override
    {
        if (mVerbose && percent >= 0 && percent >= 25 * mNextQuarter.load() && percent < 100) {
            std::lock_guard<std::mutex> lock(outputMutex());
            const int quarter = percent / 25;
            if (quarter >= mNextQuarter && !mStages.empty()) {
                mNextQuarter = quarter + 1;
                std::cerr << ("[progress] " + mFrame + mStages.back().name + " " + std::to_string(25 * quarter) +
                              "%\n")
                          << std::flush;
            }
        }
        if (mLive && percent >= 0) {
            const auto now = std::chrono::steady_clock::now();
            std::unique_lock<std::mutex> lock(outputMutex(), std::try_to_lock);
            if (lock.owns_lock() && now - mLastDraw >= std::chrono::milliseconds(100)) draw(percent);
        }
        return interruptRequested();
    }

    /// Erase the live line, if one is shown.
    void clearLine()
    {
        if (!mLive) return;
        std::lock_guard<std::mutex> lock(outputMutex());
        if (mDrawn) std::cout << "\r\033[K" << std::flush;
        mDrawn = false;
    }

    /// The stage an exception ended (its name), or "" if none did.
    const std::string& failedStage() const { return mFailedStage; }

private:
    static std::mutex& outputMutex()
    {
        static std::mutex mutex;
        return mutex;
    }

    /// Redraw the live line (outputMutex() held): the current stage, and @a percent if >= 0.
    void draw(int percent)
    {
        if (mStages.empty()) return;
        std::string line = "\r" + mStages.back().name;
        if (percent >= 0) line += " " + std::to_string(std::min(percent, 100)) + "%";
        std::cout << line << "\033[K" << std::flush;
        mDrawn = true;
        mLastDraw = std::chrono::steady_clock::now();
    }

    struct Stage { std::string name; std::chrono::steady_clock::time_point start; };
    std::string mFailedStage;
    bool mVerbose, mLive;
    std::string mFrame;
    std::vector<Stage> mStages;
    std::atomic<int> mNextQuarter{1};
    bool mDrawn = false;
    std::chrono::steady_clock::time_point mLastDraw{};
};

/// Runs the tool's own stages (reading, writing) under the same names in the interrupter
/// and the timing table.
class StageScope
{
public:
    StageScope(ProgressInterrupter& interrupter, nonbloppy::StageTimings& timings,
               const char* stage)
        : mInterrupter(interrupter), mTimer(timings, stage)
    {
        mInterrupter.start(stage);
    }
    ~StageScope() { mInterrupter.end(); }
    StageScope(const StageScope&) = delete;
    StageScope& operator=(const StageScope&) = delete;

private:
    ProgressInterrupter& mInterrupter;
    nonbloppy::ScopedStageTimer mTimer;
};


// ---------------------------------------------------------------------------------------
// Options and their validation

struct MeshOptions
{
    std::string input, output, vdbPath;
    double spacing = 0, radius = 0, threshold = 0, voxelSize = 0;
    double maxStep = 0;  ///< --max-step, world units (faithful); given or not: maxStepOpt
    double blend = nonbloppy::kDefaultBlend;
    int iterations = nonbloppy::kDefaultIterations;
    double adaptivity = nonbloppy::kDefaultAdaptivity;
    /// Signed, so that -1 is refused; an int, so that CLI11 refuses a value past its range (it
    /// clamped a 64-bit one to 2^63-1 without a word).
    int regionLeaves = int(nonbloppy::kDefaultRegionLeaves);
    std::string method = "faithful";  ///< --method: faithful (default) or paper
    CLI::Option* methodOpt = nullptr;
    bool noSmooth = false;  ///< --no-smooth: skip smoothSurface() after the volume correction
    int threads = 0;
    bool quads = false, quiet = false, verbose = false;
    bool noDirectIo = false;  ///< --no-direct-io: write the mesh through the page cache
    MeshOutputOptions outputs;  ///< --attributes, --vdb-surface, --vdb-points (MeshOutputs.h)
    ParticleBoxOption particleBox;  ///< --particle-box X0 Y0 Z0 X1 Y1 Z1
    // Frame sequences (FrameSequence.h, BatchRun.h).
    std::string frames, logPath;
    int frameJobs = 1;
    bool skipExisting = false, keepGoing = false;
    CLI::Option *framesOpt = nullptr, *frameJobsOpt = nullptr, *skipExistingOpt = nullptr,
                *keepGoingOpt = nullptr, *logOpt = nullptr;

    // Set after declaration, to tell "given" from "default".
    CLI::Option *spacingOpt = nullptr, *radiusOpt = nullptr, *thresholdOpt = nullptr,
                *voxelSizeOpt = nullptr, *blendOpt = nullptr, *iterationsOpt = nullptr,
                *adaptivityOpt = nullptr, *threadsOpt = nullptr, *vdbOpt = nullptr,
                *regionLeavesOpt = nullptr, *maxStepOpt = nullptr, *noSmoothOpt = nullptr;
};

std::optional<double> ifGiven(const CLI::Option* option, double value)
{
    if (option->count() > 0) return value;
    return std::nullopt;
}

/// The library's parameters from the command line's options.
nonbloppy::SurfaceParameters surfaceParameters(const MeshOptions& o)
{
    nonbloppy::SurfaceParameters params;
    params.spacing = ifGiven(o.spacingOpt, o.spacing);
    params.effectiveRadius = ifGiven(o.radiusOpt, o.radius);
    params.threshold = ifGiven(o.thresholdOpt, o.threshold);
    params.voxelSize = ifGiven(o.voxelSizeOpt, o.voxelSize);
    params.blend = o.blend;
    params.iterations = o.iterations;
    params.adaptivity = o.adaptivity;
    params.method = o.method == "paper" ? nonbloppy::Method::Paper : nonbloppy::Method::Faithful;
    params.maxStep = ifGiven(o.maxStepOpt, o.maxStep);
    if (o.noSmooth) params.smoothSurface = false;
    // Without --vdb nothing needs the grid: the library frees it before relaxing, which
    // lowers the peak memory of large frames.
    params.keepDensity = !o.vdbPath.empty();
    params.trimFreedMemory = true;  // the process is ours: no host's threads to stall
    params.regionLeaves = size_t(o.regionLeaves);
    return params;
}

/// True if @a a and @a b name one file: the same name (which need not exist yet), or
/// existing paths to one file (hard links, symbolic links, "./").
bool sameFile(const std::string& a, const std::string& b)
{
    std::error_code ec;
    return a == b || fs::equivalent(a, b, ec);
}

/// Fail now, before any work, if @a path's directory does not exist or cannot be written, or
/// @a path is something other than a regular file (a directory, a device such as /dev/null, a
/// FIFO; symbolic links followed), which the writers refuse only once the mesh is made.
void requireWritableDirectory(const std::string& path)
{
    std::error_code statusError;
    const fs::file_status existing = fs::status(path, statusError);
    if (fs::is_directory(existing)) {
        throw nonbloppy::FileError("cannot write " + path + ": " + std::strerror(EISDIR));
    }
    if (fs::exists(existing) && !fs::is_regular_file(existing)) {
        throw nonbloppy::FileError("cannot write " + path + ": not a regular file");
    }
    // The directory of the file written: a link into a missing directory passed, and the
    // run failed only after the work (bug hunt).
    fs::path dir = fs::path(writtenFile(path)).parent_path();
    if (dir.empty()) dir = ".";
    std::error_code ec;
    const fs::file_status status = fs::status(dir, ec);
    int error = 0;
    if (!fs::exists(status)) error = ENOENT;
    else if (!fs::is_directory(status)) error = ENOTDIR;
    else if (::access(dir.c_str(), W_OK | X_OK) != 0) error = errno;
    if (error != 0) {
        throw nonbloppy::FileError("cannot write " + path + ": " + std::strerror(error));
    }
}

/// Check everything that can be checked without reading the input, so a mistake costs
/// nothing and leaves no file behind. The library checks the same ranges again.
/// validateParameters() checks the numbers, validatePaths() the files of one frame.
void validateParameters(const MeshOptions& o)
{
    if (o.vdbOpt->count() > 0) requireFileName(o.vdbPath, "--vdb");
    checkAttributeList(o.outputs);
    // CLI11 reads an empty value ('--blend ""') as 0 without a word, and a real one past
    // double's range, 1e-400 or 1e400, as 0 or inf, which the range checks then answered
    // with "--spacing must be > 0, got 0": say what the text was.
    const std::vector<const CLI::Option*> integerOptions = {o.iterationsOpt, o.regionLeavesOpt, o.threadsOpt,
                                                            o.frameJobsOpt};
    for (const CLI::Option* option : {o.spacingOpt, o.radiusOpt, o.thresholdOpt, o.voxelSizeOpt, o.blendOpt,
                                      o.iterationsOpt, o.adaptivityOpt, o.regionLeavesOpt, o.threadsOpt,
                                      o.frameJobsOpt, o.maxStepOpt}) {
        if (!option) continue;
        const bool real = std::find(integerOptions.begin(), integerOptions.end(), option) == integerOptions.end();
        // --max-step 1e400 is +inf, which means no cap, as "inf" does.
        requireNumberText(option, real, /*infinityAllowed=*/option == o.maxStepOpt);
    }
    // Every range, and the limits between given lengths (--voxel-size 0.001 with --radius 1),
    // in the library's words: exit 2 before the input is read, not 1 after.
    try {
        nonbloppy::checkParameters(surfaceParameters(o));
    } catch (const nonbloppy::ParameterError& e) {
        throw UsageError(e.what());
    }
    if (o.regionLeaves < 0) {
        throw UsageError("--region-leaves must be >= 0, got " + std::to_string(o.regionLeaves));
    }
    o.particleBox.box();  // throws for a bad box
    // The paper's method has no step cap and no smoothing: these would be ignored.
    if (o.method == "paper") {
        for (const CLI::Option* option : {o.maxStepOpt, o.noSmoothOpt}) {
            if (option->count() > 0) {
                throw UsageError(option->get_name() + " applies to --method faithful only, not paper");
            }
        }
    }
    // TBB takes any count; at 10^8 the run took 13 GB and 18 s, at 10^9 it ran out of memory.
    constexpr int kMaxThreads = 4096;
    if (o.threadsOpt->count() > 0 && (o.threads < 1 || o.threads > kMaxThreads)) {
        throw UsageError("--threads must lie in [1, " + std::to_string(kMaxThreads) + "], got " +
                         std::to_string(o.threads));
    }
}

void validatePaths(const MeshOptions& o)
{
    requireFileName(o.input, "IN");
    requireFileName(o.output, "--output");  // not "mesh file name has no extension ()"
    // writeMesh()'s own check, which would say the same after all the work.
    requireAsUsage([&] { nonbloppy::requireMeshFile(o.output); });
    // An input format nonbloppy cannot read, like an unknown output format, is a command line
    // that cannot run whatever the file holds (exit 2), told with what to export instead
    // for Houdini's other caches.
    requireAsUsage([&] { nonbloppy::requireParticleFile(o.input); });
    if (!o.vdbPath.empty() && lowerExtension(o.vdbPath) != ".vdb") {
        throw UsageError("--vdb file name must end in .vdb (" + o.vdbPath + ")");
    }

    struct stat info;
    if (::stat(o.input.c_str(), &info) != 0) {
        throw nonbloppy::FileError("cannot open " + o.input + ": " + std::strerror(errno));
    }

    std::vector<std::string> outputs{o.output};
    if (!o.vdbPath.empty()) outputs.push_back(o.vdbPath);
    for (const std::string& out : outputs) {
        requireWritableDirectory(out);
        if (sameFile(o.input, out)) {
            throw UsageError("cannot write " + out + ": it is the input file");
        }
    }
    if (!o.vdbPath.empty() && sameFile(o.vdbPath, o.output)) {
        throw UsageError("cannot write " + o.vdbPath + ": --vdb and --output name the same file");
    }
}

void validate(const MeshOptions& o)
{
    validateParameters(o);
    validatePaths(o);
}

// ---------------------------------------------------------------------------------------
// Summary

std::string origin(bool given, const char* otherwise) { return given ? "(given)" : otherwise; }

void printSummary(const MeshOptions& o, const nonbloppy::SurfaceResult& result,
                  const nonbloppy::StageTimings& timings, int threads, const std::string& threadsOrigin,
                  size_t particlesRead)
{
    const nonbloppy::ResolvedParameters& p = result.parameters;
    const nonbloppy::SurfaceMesh& mesh = result.mesh;
    char line[512];
    std::ostream& out = std::cout;

    auto row = [&](const char* label, const std::string& value, const std::string& note) {
        std::snprintf(line, sizeof(line), "  %-20s %-14s %s", label, value.c_str(), note.c_str());
        std::string text = line;
        while (!text.empty() && text.back() == ' ') text.pop_back();
        out << text << "\n";
    };

    out << "input\n";
    row("file", o.input, "");
    const std::optional<openvdb::BBoxd> box = o.particleBox.box();
    row("particles", std::to_string(result.particleCount),
        box ? "(of " + std::to_string(particlesRead) + ", inside --particle-box " + formatBox(*box) + ")" : "");
    out << "parameters\n";
    // The spacing is only estimated when something was derived from it.
    const bool spacingUsed = p.spacingGiven || !p.effectiveRadiusGiven || !p.thresholdGiven
                             || !p.voxelSizeGiven;
    row("spacing s", spacingUsed ? formatNumber(p.spacing) : "-",
        spacingUsed ? origin(p.spacingGiven, "(derived)") : "(not needed)");
    row("radius r_e", formatNumber(p.effectiveRadius), origin(p.effectiveRadiusGiven, "(derived)"));
    row("threshold r_0", formatNumber(p.threshold), origin(p.thresholdGiven, "(derived)"));
    row("voxel size h", formatNumber(p.voxelSize), origin(p.voxelSizeGiven, "(derived)"));
    row("blend c", formatNumber(p.blend), origin(o.blendOpt->count() > 0, "(default)"));
    row("iterations t", std::to_string(p.iterations),
        origin(o.iterationsOpt->count() > 0, "(default)"));
    row("adaptivity", formatNumber(p.adaptivity), origin(o.adaptivityOpt->count() > 0, "(default)"));
    row("method", o.method, origin(o.methodOpt->count() > 0, "(default)"));
    if (p.method == nonbloppy::Method::Faithful) {
        row("max step", p.maxStep > 0.0 ? formatNumber(p.maxStep) : "none",
            o.maxStepOpt->count() > 0 ? "(given)" : p.maxStep > 0.0 ? "(s/2)" : "(no spacing to derive it from)");
        row("volume offset",
            !p.preserveVolume ? "off" : p.volumeOffset == nonbloppy::VolumeOffset::Convex ? "convex" : "uniform",
            p.preserveVolume ? "(N*s^3, --spacing given)" : "(needs --spacing)");
        row("smoothing", p.smoothSurface ? "on" : "off",
            o.noSmooth ? "(--no-smooth)" : p.smoothSurface ? "(with the volume offset)" : "(needs --spacing)");
    }
    row("region leaves", std::to_string(p.regionLeaves), origin(o.regionLeavesOpt->count() > 0, "(default)"));
    row("threads", std::to_string(threads), threadsOrigin);

    out << "result\n";
    if (result.density) {
        const uint64_t activeVoxels = result.density->activeVoxelCount();
        row("active voxels", std::to_string(activeVoxels),
            "(" + formatCount(activeVoxels) + ", density grid)");
    } else {
        row("active voxels", "-", "(density grid not kept without --vdb)");
    }
    row("vertices", std::to_string(mesh.points.size()), "");
    if (o.quads) {
        row("polygons", std::to_string(mesh.polygonCount()),
            "(" + counted(mesh.triangles.size(), "triangle") + ", " + counted(mesh.quads.size(), "quad") + ")");  // as inspect
    } else {
        row("triangles", std::to_string(mesh.triangleCount()), "");
    }
    row("mesh", o.output, "");
    if (!o.vdbPath.empty()) row("density grid", o.vdbPath, "");

    // Wall-clock time, its share, and the cores the stage kept busy (process CPU time over
    // wall-clock time): a stage far below the thread count waits on something serial.
    // 22 wide: "interpolate attributes", the longest stage name, stays in line.
    out << "timings" << std::string(22, ' ') << "wall" << std::string(13, ' ') << "cores\n";
    const double total = timings.total();
    const auto cores = [](double cpuSeconds, double seconds) { return seconds > 0 ? cpuSeconds / seconds : 0.0; };
    for (const auto& entry : timings.entries) {
        std::snprintf(line, sizeof(line), "  %-22s %8.3f s  (%4.1f%%)  %5.2f", entry.stage.c_str(),
                      entry.seconds, total > 0 ? 100.0 * entry.seconds / total : 0.0,
                      cores(entry.cpuSeconds, entry.seconds));
        out << line << "\n";
    }
    std::snprintf(line, sizeof(line), "  %-22s %8.3f s           %5.2f", "total", total,
                  cores(timings.cpuTotal(), total));
    out << line << "\n";
    out.flush();
}

// ---------------------------------------------------------------------------------------
// The command

/// The warnings a run of the mesh command gives once, however many of its frames (meshed
/// one after another or by concurrent frame jobs) would give them.
struct OnceWarnings
{
    std::atomic<bool> facesEndInside{false};
    std::atomic<bool> coarseFloats{false};
    std::atomic<bool> meshInput{false};
    std::atomic<bool> attributesNotRead{false};
    std::atomic<bool> normalsMissing{false};
    std::atomic<bool> attributesNotFinite{false};
    OutputWarnings outputs;  ///< those of --attributes, --vdb-surface and --vdb-points
    /// Each frame meshed and its parameters, for warnIfLengthsMoved() at the end of the run.
    std::mutex frameLengthsMutex;
    std::vector<std::pair<int, nonbloppy::ResolvedParameters>> frameLengths;
};

/// A warning line of this run, printed when the statement ends (see WarningPrinter).
WarningLine warning(const OnceWarnings& once)
{
    return WarningLine(once.outputs.printer);
}

/// What meshing one frame produced: the library's result and every stage's seconds
/// (the tool's own "read particles", "write mesh", "write vdb" included).
struct FrameOutcome
{
    nonbloppy::SurfaceResult result;
    nonbloppy::StageTimings timings;
    std::string faces;  ///< a mesh input's faces not read ("element 'face'"), or ""
    size_t particlesRead = 0;  ///< in the file, before --particle-box kept result.particleCount
};

/// A frame read and meshed, its outputs not yet written (see writeFrame()).
struct MeshedFrame
{
    nonbloppy::ParticleSet particles;  ///< kept only for --attributes and --vdb-points
    nonbloppy::SurfaceResult result;
    nonbloppy::StageTimings before;    ///< "read particles", and "crop particles" with --particle-box
    nonbloppy::StageTimings after;     ///< "interpolate attributes", then the writes
    std::string faces;                 ///< what made the input a mesh, or "" (FrameOutcome)
    size_t particlesRead = 0;          ///< in the file (FrameOutcome)
};

/// Read o.input and build the surface (with its attributes); writes nothing.
MeshedFrame meshFrameSurface(const MeshOptions& o, ProgressInterrupter& interrupter, OnceWarnings& once)
{
    MeshedFrame frame;
    {
        StageScope stage(interrupter, frame.before, "read particles");
        const InputReadScope reading;  // may block (a FIFO): see kStuckReadSeconds
        frame.particles = nonbloppy::readParticles(o.input);
    }
    if (frame.particles.size() == 0) {
        throw nonbloppy::FileError("no particles in " + o.input);
    }
    frame.particlesRead = frame.particles.size();
    if (const std::optional<openvdb::BBoxd> box = o.particleBox.box()) {
        {
            StageScope stage(interrupter, frame.before, "crop particles");
            frame.particles = nonbloppy::cropParticles(frame.particles, *box);
        }
        if (frame.particles.size() == 0) {
            throw nonbloppy::ParameterError("none of the " + std::to_string(frame.particlesRead) + " particles of " +
                                            o.input + " lie inside --particle-box " + formatBox(*box));
        }
    }
    for (const std::string& skipped : frame.particles.skipped) {
        // A mesh's faces, not read: its vertices are meshed (said by warnIfMeshInput()).
        if (isSurfaceSkipped(skipped)) frame.faces = skipped;
    }
    // Once per run, and only where the particles' attributes are used; particles left out
    // (a .vdb's other point grids) whatever the outputs.
    const std::string notRead = joinedSkipped(frame.particles, /*withSurfaces=*/false);
    const bool particlesLeft = std::any_of(frame.particles.skipped.begin(), frame.particles.skipped.end(), isPointGridSkipped);
    if ((o.outputs.needParticles() || particlesLeft) && !notRead.empty() && !once.attributesNotRead.exchange(true)) {
        warning(once) << "not read from " << o.input << ": " << notRead;
    }
    // Before meshing: a misspelt name used to cost the whole frame's work first.
    try {
        requireAttributes(frame.particles, o.outputs);
    } catch (const nonbloppy::ParameterError& e) {
        throw nonbloppy::ParameterError(o.input + ": " + e.what());
    }
    throwIfInterrupted();

    const nonbloppy::SurfaceParameters params = surfaceParameters(o);

    // The particles are handed over, unless --attributes or --vdb-points still need them.
    const bool keepParticles = o.outputs.needParticles();
    try {
        frame.result = nonbloppy::buildSurface(
            keepParticles ? std::vector<openvdb::Vec3f>(frame.particles.positions) : std::move(frame.particles.positions),
            params, &interrupter);
    } catch (const nonbloppy::ParameterError& e) {
        // validate() has checked every parameter that needs no particles: what is left comes
        // of this input (a spacing that cannot be estimated, lengths derived from it out of
        // range), and the message names it.
        throw nonbloppy::ParameterError(o.input + ": " + e.what());
    }
    if (!keepParticles) frame.particles = nonbloppy::ParticleSet();
    throwIfInterrupted();
    if (!o.outputs.attributes.empty()) {
        nonbloppy::ScopedStageTimer timer(frame.after, "interpolate attributes");
        addSurfaceAttributes(frame.result, frame.particles, o.outputs, o.output, once.outputs, &interrupter);
    }
    return frame;
}

/// What an interrupt does to writeFrame().
enum class OnInterrupt
{
    Stop,    ///< stop between outputs and remove what was written (a single file's run)
    Finish,  ///< write the outputs: a sequence's frame meshed before an interrupt is still
             ///< written (a write is short, and stopping it would throw a finished frame
             ///< away); only --vdb-surface's conversion, which takes seconds, still stops
};

/// Write @a frame's o.output (and o.vdbPath). On any exception the files written so far are
/// removed again. The files the outputs replaced are handed to @a remover once the frame
/// has succeeded. Returns the surface and every stage's seconds.
FrameOutcome writeFrame(const MeshOptions& o, MeshedFrame& frame, ProgressInterrupter& interrupter,
                        BackgroundRemover& remover, OnceWarnings& once, OnInterrupt onInterrupt)
{
    const bool stoppable = onInterrupt == OnInterrupt::Stop;
    OutputCleanup cleanup;
    nonbloppy::SurfaceResult& result = frame.result;
    {
        StageScope stage(interrupter, frame.after, "write mesh");
        nonbloppy::MeshWriteSettings settings;
        settings.keepQuads = o.quads;
        settings.directIo = !o.noDirectIo;
        cleanup.willWrite(o.output);
        nonbloppy::writeMesh(result.mesh, o.output, settings);
        cleanup.written();
    }
    if (stoppable) throwIfInterrupted();

    if (!o.vdbPath.empty()) {
        if (!result.density) throw nonbloppy::Error("no density grid to write");
        result.density->insertMeta("source_file", openvdb::StringMetadata(o.input));
        openvdb::GridCPtrVec grids{result.density};
        if (o.outputs.vdbSurface || o.outputs.vdbPoints) {
            // A stage of its own: the surface's level set takes seconds, which "write vdb"
            // showed as if it were disk time (bug hunt).
            StageScope stage(interrupter, frame.after, "build vdb grids");
            appendVdbGrids(grids, result, frame.particles, o.outputs, o.vdbPath, once.outputs, &interrupter);
        }
        StageScope stage(interrupter, frame.after, "write vdb");
        cleanup.willWrite(o.vdbPath);
        nonbloppy::writeVdb(grids, o.vdbPath);  // its "creator" is versionLine(), as convert's
        cleanup.written();
    }
    if (stoppable) throwIfInterrupted();
    cleanup.keep(remover);

    FrameOutcome outcome;
    outcome.faces = frame.faces;
    outcome.particlesRead = frame.particlesRead;
    outcome.timings = frame.before;
    outcome.timings.add(result.timings);
    outcome.timings.add(frame.after);
    outcome.result = std::move(result);
    return outcome;
}

/// Read o.input, build the surface, write o.output (and o.vdbPath): meshFrameSurface(), then
/// writeFrame(), which an interrupt stops. Used for a single file; a sequence writes each
/// frame while the next one is meshed.
FrameOutcome meshFrame(const MeshOptions& o, ProgressInterrupter& interrupter, BackgroundRemover& remover,
                       OnceWarnings& once)
{
    MeshedFrame frame = meshFrameSurface(o, interrupter, once);
    return writeFrame(o, frame, interrupter, remover, once, OnInterrupt::Stop);
}

/// How far a sequence's spacing estimate may move from the first frame's, as a fraction of
/// it, before warnIfLengthsMoved() says so: each derived length moves by as much, and 1% of h
/// is a whole voxel 100 voxels from the origin. (Two dam-break frames simulated with the
/// same particle radius, 0.025, estimate 0.0467 and 0.0486: 4% apart.)
constexpr double kSpacingMoveTolerance = 0.01;

/// Keeps frame @a frame's parameters for warnIfLengthsMoved(), unless its lengths are all
/// given (then none moves). Any thread.
void recordFrameLengths(int frame, const nonbloppy::ResolvedParameters& p, OnceWarnings& once)
{
    if (p.spacingGiven || (p.effectiveRadiusGiven && p.voxelSizeGiven && p.thresholdGiven)) return;
    std::lock_guard<std::mutex> lock(once.frameLengthsMutex);
    once.frameLengths.emplace_back(frame, p);
}

/// Once per run of a sequence, at its end: the lengths not given are derived from each
/// frame's own spacing estimate, so when that moves, the voxel grid (h), the kernel (r_e) and
/// the iso-value (r_0) move with it and the surface changes from frame to frame for that
/// alone (a flicker in a rendered sequence). Names the lowest-numbered frame meshed and the
/// first one after it whose estimate moved, and the values that pin the lengths: the
/// former's. At the end, in frame order, so the warning is the same whatever --frame-jobs
/// (as frames finished, it named whichever finished first; hostile-input audit).
void warnIfLengthsMoved(bool maxStepGiven, OnceWarnings& once)
{
    std::vector<std::pair<int, nonbloppy::ResolvedParameters>> frames;
    {
        std::lock_guard<std::mutex> lock(once.frameLengthsMutex);
        frames = once.frameLengths;
    }
    if (frames.size() < 2) return;
    std::sort(frames.begin(), frames.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const auto& [firstFrame, first] = frames.front();
    const double reference = first.spacing;
    const auto moved = std::find_if(frames.begin() + 1, frames.end(), [&](const auto& frame) {
        return std::abs(frame.second.spacing - reference) > kSpacingMoveTolerance * reference;
    });
    if (moved == frames.end()) return;
    const nonbloppy::ResolvedParameters& p = moved->second;
    std::string pin;
    if (!p.effectiveRadiusGiven) pin += " --radius " + formatNumber(first.effectiveRadius);
    if (!p.voxelSizeGiven) pin += " --voxel-size " + formatNumber(first.voxelSize);
    if (!p.thresholdGiven) pin += " --threshold " + formatNumber(first.threshold);
    // The faithful step cap s/2 follows the estimate too, and with the three lengths given
    // and no spacing there is none: pinned as well, so the pinned run meshes frame 1 alike.
    if (p.method == nonbloppy::Method::Faithful && !maxStepGiven) {
        pin += " --max-step " + formatNumber(first.maxStep);
    }
    warning(once) << "the spacing estimate moves between frames (" << formatNumber(reference) << " in frame "
                  << firstFrame << ", " << formatNumber(p.spacing) << " in frame " << moved->first
                  << ") and the lengths derived from it move too; to mesh every frame alike, give frame "
                  << firstFrame << "'s:" << pin;
}

/// Once per run: relaxation too strong for the calibrated r_0 shrinks every flat face.
void warnIfFacesEndInside(const MeshOptions& o, const nonbloppy::SurfaceDiagnostics& d, bool spacingGiven,
                          OnceWarnings& once)
{
    if (!d.facesEndInside || once.facesEndInside.exchange(true)) return;
    warning(once) << "--blend " << formatNumber(o.blend) << " --iterations " << o.iterations
                  << " relax too strongly for --threshold to be calibrated: flat faces end inside the "
                     "particles; lower --blend or --iterations"
                  << (spacingGiven ? "" : ", or give --spacing to correct the volume");
}

/// Once per run: positions are floats, whose step grows with the distance from the origin;
/// a scene placed far out (georeferenced, say) meshes to a surface quantized to that step,
/// and nothing else tells why it looks rough; where the step nears the spacing, droplets
/// collapse to points and vanish from the mesh. Warned when the step at the particles'
/// farthest coordinate exceeds 1/16 of the spacing (from 8192 units out for s = 0.01;
/// SurfaceDiagnostics::floatStepLimit). The particles, not the mesh: a part of the fluid
/// that is lost leaves no vertex to tell.
void warnIfCoarseFloats(const nonbloppy::SurfaceDiagnostics& d, const nonbloppy::ResolvedParameters& p,
                        OnceWarnings& once)
{
    if (!d.coarseFloats() || once.coarseFloats.exchange(true)) return;
    warning(once) << "the particles reach " << formatNumber(d.farthestCoordinate)
                  << " from the origin, where float positions step by " << formatNumber(d.floatStep) << ", more than "
                  << (p.spacing > 0.0 ? "1/16 of the spacing " + formatNumber(p.spacing)
                                      : "1/8 of the voxel size " + formatNumber(p.voxelSize))
                  << ": the surface is quantized there" << (d.dropletsMayVanish() ? ", and droplets may vanish" : "")
                  << "; move the particles nearer the origin";
}

/// An empty mesh from particles is written (a frame of spray may have none), but said: an
/// out-of-scale --threshold (1e308) gave 0 vertices and exit 0 without a word. The density
/// is named as sampled: it reaches any threshold at a particle's centre, but a lone particle
/// between voxel centres can leave every sample below it (bug hunt).
void warnIfEmpty(const nonbloppy::SurfaceDiagnostics& d, const nonbloppy::SurfaceResult& result,
                 const std::string& output, const OnceWarnings& once)
{
    if (!d.empty) return;
    warning(once) << output << " is empty: the density of the " << result.particleCount
                  << (result.particleCount == 1 ? " particle" : " particles") << ", sampled at --voxel-size "
                  << formatNumber(result.parameters.voxelSize) << ", nowhere reaches --threshold "
                  << formatNumber(result.parameters.threshold);
}

/// Once per run: an input with faces (PLY) or polygons (legacy VTK) is a mesh, not
/// particles; its vertices were meshed as particles (the readers read the vertices of any
/// PLY or VTK file and list what they leave out: @a faces).
void warnIfMeshInput(const std::string& input, const std::string& faces, OnceWarnings& once)
{
    if (faces.empty() || once.meshInput.exchange(true)) return;
    warning(once) << input << " is a mesh (its " << faces << " was not read): its "
                  << "vertices were meshed as particles";
}

/// Once per run: vertices without a normal ((0,0,0), computeNormals()) shade black or not at
/// all, and nothing said why: -c 1 moves every vertex onto its particles' weighted mean,
/// which collapses a droplet to a point (bug hunt: 32 of the 1,032 vertices of the bundled
/// free-particle frame with --method paper).
void warnIfNormalsMissing(const nonbloppy::SurfaceDiagnostics& d, const nonbloppy::SurfaceResult& result,
                          const std::string& output, OnceWarnings& once)
{
    if (d.verticesWithoutNormal == 0 || once.normalsMissing.exchange(true)) return;
    warning(once) << d.verticesWithoutNormal << " of the " << result.mesh.normals.size() << " vertices of " << output
                  << " have no normal (the faces around them have no area)"
                  << (result.parameters.blend == 1.0 ? ": -c 1 collapses droplets onto their particles; lower --blend"
                                                     : "");
}

/// Once per run: vertices whose carried attribute (--attributes) is NaN or infinite. The
/// particles' values are averaged as they are, so one NaN velocity in a cache from a
/// simulation that blew up makes every vertex within r_e of it NaN, which a renderer's motion
/// blur does not survive; `nonbloppy inspect IN` counts such values per attribute. The first
/// such attribute is named.
void warnIfAttributesNotFinite(const nonbloppy::SurfaceDiagnostics& d, const nonbloppy::SurfaceResult& result,
                               const std::string& input, const std::string& output, OnceWarnings& once)
{
    if (d.nonFiniteAttributes.empty() || once.attributesNotFinite.exchange(true)) return;
    const auto& [name, vertices] = d.nonFiniteAttributes.front();
    warning(once) << vertices << " of the " << result.mesh.points.size() << " vertices of " << output
                  << " have a NaN or infinite '" << name << "': particles of " << input
                  << " near them hold such values (nonbloppy inspect counts them)";
}

/// The warnings about one meshed frame (@a f: its options, paths included), each printed
/// once per run.
void warnAboutFrame(const MeshOptions& f, const FrameOutcome& outcome, OnceWarnings& once)
{
    const nonbloppy::SurfaceResult& result = outcome.result;
    const nonbloppy::SurfaceDiagnostics d = nonbloppy::diagnoseSurface(result);
    warnIfFacesEndInside(f, d, result.parameters.spacingGiven, once);
    warnIfCoarseFloats(d, result.parameters, once);
    warnIfEmpty(d, result, f.output, once);
    warnIfNormalsMissing(d, result, f.output, once);
    warnIfMeshInput(f.input, outcome.faces, once);
    warnIfAttributesNotFinite(d, result, f.input, f.output, once);
}

// ---------------------------------------------------------------------------------------
// Frame sequences

/// The refusal of a placeholder that only a directory of @a path spells.
std::string placeholderInDirectoryError(const std::string& option, const std::string& path)
{
    return option + ": the frame placeholder must be in the file name, not in a directory ('" + path + "')";
}

/// True if IN names a sequence: it has a frame placeholder and is not itself a file
/// (so a single file whose name happens to contain '#' still meshes as before).
bool isSequenceInput(const std::string& input)
{
    struct stat info;
    if (::stat(input.c_str(), &info) == 0) return false;
    if (parseFramePattern(input, "IN").hasPlaceholder()) return true;
    // A placeholder only in a directory that does not exist: frames in directories, which
    // nonbloppy does not take. In one that exists, a file is missing ("cannot open").
    const std::string directory = std::filesystem::path(input).parent_path().string();
    if (placeholderInDirectory(input) && ::stat(directory.c_str(), &info) != 0) {
        throw UsageError(placeholderInDirectoryError("IN", input));
    }
    return false;
}

/// @a o with the paths of @a frame filled in. Every option that names a file per frame
/// must be substituted here.
MeshOptions optionsForFrame(const MeshOptions& o, const Frame& frame)
{
    MeshOptions f = o;
    f.input = frame.input;
    f.output = parseFramePattern(o.output, "--output").path(frame);
    if (!o.vdbPath.empty()) f.vdbPath = parseFramePattern(o.vdbPath, "--vdb").path(frame);
    return f;
}

/// An output option for a sequence must hold a placeholder, or every frame would overwrite
/// the same file.
void requirePlaceholder(const std::string& path, const std::string& option, const MeshOptions& o)
{
    if (!parseFramePattern(path, option).hasPlaceholder()) {
        if (placeholderInDirectory(path)) throw UsageError(placeholderInDirectoryError(option, path));
        throw UsageError(option + ": no frame placeholder ({}, #### or %04d) in '"
                                        + path + "', but IN is the sequence '" + o.input + "'");
    }
}

/// A single IN with a frame placeholder in @a path (-o or --vdb) wrote a file literally
/// named 'm_{}.obj'.
void requireNoPlaceholder(const std::string& path, const std::string& option, const MeshOptions& o)
{
    bool placeholder = false;
    try {
        placeholder = parseFramePattern(path, option).hasPlaceholder();
    } catch (const UsageError&) {
        placeholder = true;  // more than one
    }
    if (placeholder) {
        throw UsageError(option + ": a frame placeholder ({}, #### or %04d) in '" + path + "', but IN is the single file '"
                         + o.input + "'");
    }
}

/// What names one file: its device and inode when it exists (hard links, symbolic links and
/// "./" all agree), else its path made absolute and normal ("./m_0002.obj" and m_0002.obj).
std::string fileIdentity(const std::string& path)
{
    struct stat info;
    if (::stat(path.c_str(), &info) == 0) {
        return std::to_string(info.st_dev) + ":" + std::to_string(info.st_ino);
    }
    std::error_code ec;
    const fs::path normal = fs::weakly_canonical(fs::absolute(path, ec), ec);
    return "path:" + (ec ? path : normal.string());
}

/// fileIdentity() of the directory @a input's frames lie in.
std::string directoryIdentity(const FramePattern& input)
{
    return fileIdentity(input.directory().empty() ? "." : input.directory());
}

/// The frame number the input pattern @a input would read @a path as, if any: its file name
/// matches the pattern and it lies in the pattern's directory (whose fileIdentity() is
/// @a inputDirectory, directoryIdentity()).
std::optional<int> frameReadAs(const FramePattern& input, const std::string& inputDirectory, const std::string& path)
{
    const fs::path asPath(path);
    const std::string directory = asPath.parent_path().empty() ? "." : asPath.parent_path().string();
    const std::optional<std::string> digits = input.matchFileName(asPath.filename().string());
    if (!digits || fileIdentity(directory) != inputDirectory) return std::nullopt;
    return std::stoi(*digits);
}

/// Refuse, before any frame is meshed, an output of one frame that is an input of the
/// sequence (@a sequence: every frame on disk, requested or not; 'x{}.vtk' -o 'x1{}.vtk':
/// frame 1's mesh x11.vtk would replace frame 11's particles, then be read as them), and a
/// --log that names an input (overwritten with JSON) or an output (whose rename would
/// replace the log), and an output the input pattern would read as a frame ('f_{}.vtk' -o
/// 'f_####.vtk': frame 7's mesh f_0007.vtk beside the particles f_007.vtk made every later
/// run stop at "f_0007.vtk and f_007.vtk are both frame 7"). Each frame's own input is
/// checked again by validatePaths(). Cost: one stat() (and, for files not yet there, one
/// weakly_canonical()) per path and per output directory, O(F log F) for F frames.
void requireOutputsApart(const FramePattern& input, const std::vector<Frame>& sequence,
                         const std::vector<BatchJob>& jobs, const std::string& logPath)
{
    const std::string inputDirectory = directoryIdentity(input);
    std::map<std::string, int> inputs;
    for (const Frame& frame : sequence) {
        inputs.emplace(fileIdentity(frame.input), frame.number);
        if (!frame.otherInput.empty()) inputs.emplace(fileIdentity(frame.otherInput), frame.number);
    }
    const std::string log = logPath.empty() ? std::string() : fileIdentity(logPath);
    if (!log.empty()) {
        if (const auto found = inputs.find(log); found != inputs.end()) {
            throw UsageError("cannot write " + logPath + ": --log names the input of frame " +
                             std::to_string(found->second));
        }
        // Not there yet, but read as a frame by the next run (review).
        if (const std::optional<int> frame = frameReadAs(input, inputDirectory, logPath)) {
            throw UsageError("cannot write " + logPath + ": " + input.text() + " would read it as frame " +
                             std::to_string(*frame));
        }
    }
    for (const BatchJob& job : jobs) {
        for (const std::string& output : job.outputs) {
            const std::string identity = fileIdentity(output);
            if (const auto found = inputs.find(identity); found != inputs.end()) {
                throw UsageError("cannot write " + output + ": it is the input of frame " +
                                 std::to_string(found->second));
            }
            if (const std::optional<int> frame = frameReadAs(input, inputDirectory, output)) {
                throw UsageError("cannot write " + output + ": " + input.text() + " would read it as frame " +
                                 std::to_string(*frame));
            }
            if (identity == log) {
                throw UsageError("cannot write " + logPath + ": --log names an output of frame " +
                                 std::to_string(job.frame.number));
            }
        }
    }
}

/// For a run that ends before its first frame (no frames on disk, two files for one frame,
/// an output that cannot be written or would clash with an input): replace the --log with
/// one summary line naming the error, so that a log an earlier run left there is not read as
/// this run's. Left alone when the log names an input of the sequence or one of @a jobs'
/// outputs (or the directory cannot be read to tell); a log that cannot be written is not
/// reported over @a error.
void logEarlyFailure(const MeshOptions& o, const FramePattern& input, const std::string& error,
                     const std::vector<BatchJob>& jobs = {})
{
    if (o.logPath.empty()) return;
    try {
        const std::string log = fileIdentity(o.logPath);
        for (const Frame& frame : findFrames(input)) {
            if (fileIdentity(frame.input) == log) return;
            if (!frame.otherInput.empty() && fileIdentity(frame.otherInput) == log) return;
        }
        for (const BatchJob& job : jobs) {
            for (const std::string& output : job.outputs) {
                if (fileIdentity(output) == log) return;
            }
        }
        if (frameReadAs(input, directoryIdentity(input), o.logPath)) return;
    } catch (const std::exception&) {
        return;
    }
    if (std::FILE* file = std::fopen(o.logPath.c_str(), "w")) {
        const std::string line = "{\"summary\": true, \"input\": " + jsonString(o.input) + ", \"output\": " +
                                 jsonString(o.output) + ", \"frames_done\": 0, \"error\": " + jsonString(error) +
                                 "}\n";
        std::fputs(line.c_str(), file);
        std::fclose(file);
    }
}

int runSequence(const MeshOptions& o)
{
    validateParameters(o);
    if (o.frameJobs < 1) {
        throw UsageError("--frame-jobs must be >= 1, got "
                                        + std::to_string(o.frameJobs));
    }
    if (o.logOpt->count() > 0) requireFileName(o.logPath, "--log");
    const FramePattern input = parseFramePattern(o.input, "IN");
    requirePlaceholder(o.output, "--output", o);
    if (!o.vdbPath.empty()) requirePlaceholder(o.vdbPath, "--vdb", o);
    std::optional<std::vector<int>> requested;
    if (o.framesOpt->count() > 0) requested = parseFrameList(o.frames, "--frames");

    FramePlan plan;
    try {
        // An input format nonbloppy cannot read (exit 2) whether or not a frame exists.
        requireAsUsage([&] { nonbloppy::requireParticleFile(o.input); });
        plan = planFrames(input, requested);
        if (plan.frames.empty()) {
            throw nonbloppy::FileError(requested ? "none of the frames " + formatFrameList(*requested) + " of " +
                                                       o.input + " exist"
                                                 : "no file matches " + o.input);
        }
    } catch (const nonbloppy::Error& e) {  // FileError, or UsageError for the format
        logEarlyFailure(o, input, e.what());
        throw;
    }
    std::vector<BatchJob> jobs;
    for (const Frame& frame : plan.frames) {
        const MeshOptions f = optionsForFrame(o, frame);
        BatchJob job{frame, {f.output}};
        if (!f.vdbPath.empty()) job.outputs.push_back(f.vdbPath);
        jobs.push_back(std::move(job));
    }
    // Output extensions and directories, before any work. Refused here, the run replaces its
    // log too (bug hunt: an earlier run's summary was left, reading as this one's).
    try {
        validatePaths(optionsForFrame(o, plan.frames.front()));
        requireOutputsApart(input, plan.onDisk, jobs, o.logPath);
    } catch (const nonbloppy::Error& e) {
        logEarlyFailure(o, input, e.what(), jobs);
        throw;
    }

    const std::unique_ptr<tbb::global_control> threadLimit = limitWorkers(o.threadsOpt->count() > 0 ? o.threads : 0);
    SignalHandlerScope signals;

    BatchSettings settings;
    settings.frameJobs = o.frameJobs;
    settings.threads = static_cast<int>(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    settings.skipExisting = o.skipExisting;
    settings.keepGoing = o.keepGoing;
    settings.quiet = o.quiet;
    settings.verbose = o.verbose;
    settings.logPath = o.logPath;
    settings.inputPattern = o.input;
    settings.outputPattern = o.output;
    settings.missing = plan.missing;

    std::mutex verboseMutex;
    OnceWarnings once;
    settings.warnings = &once.outputs.printer;
    BackgroundRemover remover;  // replaced outputs are freed while the next frames run
    // Writes a meshed frame, warns, and reports it; the frame's memory goes on return.
    const auto writeAndReport = [&](const MeshOptions& f, const BatchJob& job, MeshedFrame& frame,
                                    ProgressInterrupter& interrupter, ResidentSampler* sampler) {
        const FrameOutcome outcome = writeFrame(f, frame, interrupter, remover, once, OnInterrupt::Finish);
        warnAboutFrame(f, outcome, once);
        recordFrameLengths(job.frame.number, outcome.result.parameters, once);

        FrameReport report;
        const nonbloppy::SurfaceResult& result = outcome.result;
        const nonbloppy::ResolvedParameters& p = result.parameters;
        report.particles = result.particleCount;
        report.particlesRead = outcome.particlesRead;
        report.vertices = result.mesh.points.size();
        // As written: quads are split into two triangles unless --quads keeps them.
        report.faces = f.quads ? result.mesh.polygonCount() : result.mesh.triangleCount();
        report.timings = outcome.timings;
        // No spacing (every length given, none derived) is null, as in inspect --json; 0 read
        // as a length. A max_step of 0 is the uncapped step that --max-step 0 gives back.
        const double spacing = p.spacing > 0.0 ? p.spacing : std::numeric_limits<double>::quiet_NaN();
        report.parameters = {{"spacing", spacing}, {"effective_radius", p.effectiveRadius},
                             {"threshold", p.threshold}, {"voxel_size", p.voxelSize},
                             {"blend", p.blend}, {"iterations", double(p.iterations)},
                             {"adaptivity", p.adaptivity}, {"region_leaves", double(p.regionLeaves)},
                             {"max_step", p.maxStep}};
        if (sampler) {
            sampler->stop();
            std::lock_guard<std::mutex> lock(verboseMutex);
            std::cerr << "[memory] frame " << job.frame.number << "\n"
                      << sampler->report(outcome.timings, result.particleCount) << std::flush;
        }
        return report;
    };
    // Meshes a frame here; its write step may run on another thread while the next frame is
    // meshed (see runBatch()), so what it needs is shared with it.
    auto meshOne = [&](const BatchJob& job) {
        const MeshOptions f = optionsForFrame(o, job.frame);
        validatePaths(f);
        auto interrupter = std::make_shared<ProgressInterrupter>(
            o.verbose, false, "frame " + std::to_string(job.frame.number) + ": ");
        std::shared_ptr<ResidentSampler> sampler;
        if (o.verbose) sampler = std::make_shared<ResidentSampler>();
        auto frame = std::make_shared<MeshedFrame>(meshFrameSurface(f, *interrupter, once));
        return std::function<FrameReport()>([&writeAndReport, f, job, interrupter, sampler, frame]() mutable {
            const FrameReport report = writeAndReport(f, job, *frame, *interrupter, sampler.get());
            frame.reset();
#ifdef __GLIBC__
            // Hand back the pages this frame freed. glibc keeps them (main() lets up to
            // 256 MB stay at the heap's top, and freed blocks amid the heap are never
            // returned unless trimmed), and the next frame's allocations reuse them only in
            // part: on the 64x benchmark input a sequence's peak RSS rose 328 -> 440 MB by
            // the third frame, so a farm job sized by meshing one frame could be killed
            // mid-sequence. With this, 328 -> 345-353 MB; cost about 3% of the wall time per
            // frame (8 frames, median of 4 alternating pairs), nothing measurable at 512x
            // (1.71 GB peak either way). Once the frame is written, not as the next one
            // starts: that one starts while this one is written.
            malloc_trim(0);
#endif
            return report;
        });
    };
    const int status = runBatch(jobs, settings, meshOne, [] { return interruptRequested(); });
    warnIfLengthsMoved(o.maxStepOpt->count() > 0, once);
    return status;
}

int runMesh(const MeshOptions& o)
{
    if (isSequenceInput(o.input)) return runSequence(o);
    for (const CLI::Option* option : {o.framesOpt, o.frameJobsOpt, o.skipExistingOpt,
                                      o.keepGoingOpt, o.logOpt}) {
        if (option->count() > 0) {
            throw UsageError(option->get_name() + " needs a frame sequence as IN "
                                            "(a name with {}, #### or %04d), got '" + o.input + "'");
        }
    }
    requireNoPlaceholder(o.output, "--output", o);
    if (!o.vdbPath.empty()) requireNoPlaceholder(o.vdbPath, "--vdb", o);
    validate(o);

    std::string threadsOrigin;
    const std::unique_ptr<tbb::global_control> threadLimit =
        limitWorkers(o.threadsOpt->count() > 0 ? o.threads : 0, &threadsOrigin);
    const int threads = static_cast<int>(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

    SignalHandlerScope signals;
    const bool live = !o.quiet && !o.verbose && ::isatty(STDOUT_FILENO) == 1;
    ProgressInterrupter interrupter(o.verbose, live);
    std::unique_ptr<ResidentSampler> sampler;
    if (o.verbose) sampler = std::make_unique<ResidentSampler>();

    // Declared before the outcome, so that the replaced mesh is freed while the outcome's
    // memory is given back and the summary printed.
    BackgroundRemover remover;
    OnceWarnings once;
    try {
        const FrameOutcome outcome = meshFrame(o, interrupter, remover, once);
        interrupter.clearLine();
        warnAboutFrame(o, outcome, once);
        if (sampler) {
            sampler->stop();
            std::cerr << sampler->report(outcome.timings, outcome.result.particleCount);
        }
        if (!o.quiet) printSummary(o, outcome.result, outcome.timings, threads, threadsOrigin, outcome.particlesRead);
        return 0;
    } catch (const nonbloppy::CancelledError&) {
        // meshFrame() has removed what was written; the library leaves nothing behind.
        std::cerr << "nonbloppy: interrupted" << std::endl;
        return kExitInterrupted;
    } catch (const std::bad_alloc&) {
        // The stages whose memory grows with their input refuse what will not fit before
        // they allocate; what remains (a tight ulimit -v, memory taken by others meanwhile)
        // says at least where and what, not a bare "out of memory".
        const std::string& stage = interrupter.failedStage();
        throw nonbloppy::Error("out of memory" + (stage.empty() ? std::string() : " in stage '" + stage + "'")
                               + " meshing " + o.input);
    }
}

} // namespace

Command setupMeshCommand(CLI::App& parent)
{
    auto options = std::make_shared<MeshOptions>();
    MeshOptions& o = *options;

    CLI::App* cmd = parent.add_subcommand(
        "mesh", "Build a surface mesh from a particle file");
    cmd->footer(
        "Lengths are absolute, in the particle file's units (not multiples of the spacing).\n"
        "Unset parameters are derived from the particle spacing s: r_e = 2 s, h = s/2, and r_0\n"
        "so that a flat block of fluid gets its surface s/2 outside the outer particles.");

    cmd->add_option("IN", o.input,
        "Particle file (.vtk, .vtu, .ply, classic .bgeo or .bhclassic, .vdb, .csv, .xyz: binary float32 triples, ...), or a sequence: fluid_{}.vtk, fluid_####.vtk, "
        "fluid_%04d.vtk")
        ->required()->group(kGroupInputOutput);
    cmd->add_option("-o,--output", o.output,
        "Mesh to write (.obj, .ply or .vtk); for a sequence, with a placeholder: mesh_{}.obj")
        ->required()->group(kGroupInputOutput);
    cmd->add_flag("--quads", o.quads, "Keep quads instead of splitting them into triangles")
        ->group(kGroupInputOutput);
    o.particleBox.add(cmd, "meshed, and taken by --attributes and --vdb-points");
    cmd->add_flag("--no-direct-io", o.noDirectIo,
        "Write the mesh through the page cache (by default meshes of 1 MiB or more bypass it on "
        "local ext4, XFS and Btrfs disks; the bytes are the same)")
        ->group(kGroupInputOutput);

    o.spacingOpt = cmd->add_option("--spacing", o.spacing,
        "Particle spacing s (default: estimated, the volume per particle inside the fluid)")
        ->group(kGroupNumerical);
    o.radiusOpt = cmd->add_option("--radius", o.radius,
        "Effective (kernel) radius r_e (default: 2 s)")->group(kGroupNumerical);
    o.thresholdOpt = cmd->add_option("--threshold", o.threshold,
        "Density iso-value r_0 (default: calibrated from r_e/s, c, t and --max-step; paper: from r_e/s)")->group(kGroupNumerical);
    o.voxelSizeOpt = cmd->add_option("--voxel-size", o.voxelSize,
        "Voxel size h of the density grid (default: s/2)")->group(kGroupNumerical);
    o.blendOpt = cmd->add_option("-c,--blend", o.blend,
        "Relaxation blend c in [0,1] (default: 0.3)")->group(kGroupNumerical);
    o.iterationsOpt = cmd->add_option("-t,--iterations", o.iterations,
        "Relaxation iterations t >= 0 (default: 2)")->group(kGroupNumerical);
    o.methodOpt = cmd->add_option("--method", o.method,
        "faithful (default): r_0 calibrated for the relaxed surface, steps capped at s/2, folds "
        "repaired, volume N*s^3 kept and faces smoothed when --spacing is given; paper: the paper's plain method")
        ->check(CLI::IsMember({"faithful", "paper"}))->group(kGroupNumerical);
    o.maxStepOpt = cmd->add_option("--max-step", o.maxStep,
        "faithful: the farthest one relaxation step moves a vertex; 0 or inf: no cap (default: s/2; no "
        "cap when --radius, --threshold and --voxel-size are all given without --spacing)")
        ->group(kGroupNumerical);
    o.noSmoothOpt = cmd->add_flag("--no-smooth", o.noSmooth,
        "faithful: skip the edge-preserving smoothing that follows the volume correction "
        "(on when --spacing is given)")->group(kGroupNumerical);

    o.adaptivityOpt = cmd->add_option("--adaptivity", o.adaptivity,
        "Polygon merging in flat regions, in [0,1] (default: 0)")->group(kGroupAdvanced);
    o.regionLeavesOpt = cmd->add_option("--region-leaves", o.regionLeaves,
        "Density leaves per extraction region: smaller takes less memory and answers Ctrl-C "
        "sooner; 0: the whole grid at once, about 10% faster to extract and uninterruptible; the same surface either way, "
        "its vertices in another order (with --spacing, whose smoothing sums in that order, to the last bits) "
        "(default: " + std::to_string(nonbloppy::kDefaultRegionLeaves) + ")")->group(kGroupAdvanced);
    o.threadsOpt = cmd->add_option("--threads", o.threads,
        "Worker threads (default: all cores, or as many as a container's or job's CPU limit rounds up to); results do not depend on it")
        ->group(kGroupAdvanced);

    o.vdbPath.clear();
    o.vdbOpt = cmd->add_option("--vdb", o.vdbPath,
        "Also write the density grid to this .vdb file (vdb_print reads it)")
        ->group(kGroupDebug);
    addMeshOutputOptions(cmd, o.outputs, o.vdbOpt);
    // Frame sequences: IN and the outputs are patterns such as fluid_{}.vtk.
    constexpr const char* kGroupSequence = "Frame sequences";
    o.framesOpt = cmd->add_option("--frames", o.frames,
        "Frames to mesh: 1-240, 1-240:2, 12,15,90-99 (default: every frame found)")
        ->group(kGroupSequence);
    o.skipExistingOpt = cmd->add_flag("--skip-existing", o.skipExisting,
        "Skip frames whose outputs all exist (resume an interrupted run)")->group(kGroupSequence);
    o.keepGoingOpt = cmd->add_flag("--keep-going", o.keepGoing,
        "Go on after a failed frame; list the failed frames and exit 1 at the end")
        ->group(kGroupSequence);
    o.frameJobsOpt = cmd->add_option("--frame-jobs", o.frameJobs,
        "Frames meshed at once (default 1); they share the --threads workers")
        ->group(kGroupSequence);
    o.logOpt = cmd->add_option("--log", o.logPath,
        "Write one JSON object per frame and a summary line to this file")
        ->group(kGroupSequence);

    CLI::Option* quiet = cmd->add_flag("-q,--quiet", o.quiet, "Print only warnings and errors (stderr)")
        ->group(kGroupDebug);
    CLI::Option* verbose = cmd->add_flag("-v,--verbose", o.verbose,
        "Print each stage, its progress and its memory (bytes per particle) on stderr")->group(kGroupDebug);
    quiet->excludes(verbose);

    for (CLI::Option* option : {o.iterationsOpt, o.regionLeavesOpt, o.threadsOpt, o.frameJobsOpt}) {
        readDecimalOnly(option, /*integer=*/true);
    }
    for (CLI::Option* option : {o.spacingOpt, o.radiusOpt, o.thresholdOpt, o.voxelSizeOpt, o.blendOpt,
                                o.adaptivityOpt, o.maxStepOpt}) {
        readDecimalOnly(option, /*integer=*/false);
    }

    return {cmd, [options]() { return runMesh(*options); }};
}

} // namespace nonbloppy_tool
