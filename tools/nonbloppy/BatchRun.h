// SPDX-License-Identifier: Apache-2.0
/// @file BatchRun.h
/// @brief The frame loop of `nonbloppy mesh` on a sequence: --frame-jobs, --skip-existing,
///        --keep-going, the progress bar (or one line per frame), the --log JSON lines, and
///        the resident-memory probe behind `-v`'s bytes per particle.
///
/// @code
/// BatchSettings settings;                 // frameJobs, skipExisting, keepGoing, logPath, ...
/// std::vector<BatchJob> jobs = ...;       // one per frame: input and every output it writes
/// int exitCode = runBatch(jobs, settings, [&](const BatchJob& job) {
///     auto meshed = meshOneFrame(job);    // read and mesh
///     return [=] { return writeOutputs(meshed); };  // FrameReport: counts, stage seconds, ...
/// }, [] { return interruptRequested(); });
/// @endcode

#ifndef NONBLOPPY_TOOL_BATCH_RUN_H
#define NONBLOPPY_TOOL_BATCH_RUN_H

#include "FrameSequence.h"

#include <nonbloppy/Timing.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace nonbloppy_tool {

/// One frame to do: the frame and every file meshing it writes (mesh first).
struct BatchJob
{
    Frame frame;
    std::vector<std::string> outputs;
};

/// What one frame produced, for the progress line and the log.
struct FrameReport
{
    size_t particles = 0, vertices = 0, faces = 0;  ///< particles meshed (after --particle-box)
    size_t particlesRead = 0;                         ///< particles in the file
    nonbloppy::StageTimings timings;                         ///< seconds per stage, in order
    std::vector<std::pair<std::string, double>> parameters;  ///< resolved values, by name
};

class WarningPrinter;

struct BatchSettings
{
    int frameJobs = 1;          ///< frames meshed at once (each uses the shared TBB arena)
    int threads = 0;            ///< the workers they share, for the log's summary (0: not said)
    bool skipExisting = false;  ///< skip a frame whose outputs all exist
    bool keepGoing = false;     ///< go on after a failed frame
    bool quiet = false;         ///< print nothing but errors
    /// A line per frame instead of the bar on a terminal: -v's progress lines (stderr) ran on
    /// after the bar's (stdout).
    bool verbose = false;
    std::string logPath;        ///< --log: JSON lines, "" for none
    std::string inputPattern, outputPattern;
    std::vector<int> missing;   ///< requested frames not on disk (listed once, skipped)
    /// The frames' warnings: while the bar shows, runBatch() routes them past it.
    WarningPrinter* warnings = nullptr;
};

/// Meshes one frame and returns the step that writes its outputs and reports it: run at once
/// when frames are meshed side by side (--frame-jobs 2 or more), otherwise on a thread of
/// its own while the next frame is meshed. Either step may throw (the frame failed).
using MeshFrameFunction = std::function<std::function<FrameReport()>(const BatchJob&)>;

/// Mesh every job with @a meshFrame, at most settings.frameJobs at a time, and report.
/// With one frame at a time, each frame is written while the next one is meshed (see
/// MeshFrameFunction); frames are reported in order either way.
/// @a interrupted is polled between frames; a frame that is interrupted throws
/// nonbloppy::CancelledError from either step (having removed its partial outputs).
/// @return 0 when every frame was done or skipped, kExitInterrupted after an interrupt
///         (stderr names the finished frames).
/// @throw the first frame's error when !keepGoing (after the summary and log are written),
///        nonbloppy::Error "N of M frames failed: 3, 7" when keepGoing and frames failed,
///        nonbloppy::FileError if the log cannot be written.
int runBatch(const std::vector<BatchJob>& jobs, const BatchSettings& settings,
             const MeshFrameFunction& meshFrame, const std::function<bool()>& interrupted);

// ---------------------------------------------------------------------------------------
// Memory

/// The process's peak resident set so far (getrusage ru_maxrss), in bytes.
uint64_t peakResidentBytes();
/// The process's resident set now (/proc/self/statm), in bytes; 0 if unknown.
uint64_t currentResidentBytes();

/// Samples the resident set every 2 ms on a background thread, from construction until
/// stop(), to attribute peaks to the stages of one frame afterwards (the stages run one
/// after another, so their durations in a StageTimings place each sample in a stage).
class ResidentSampler
{
public:
    ResidentSampler();
    ~ResidentSampler();
    ResidentSampler(const ResidentSampler&) = delete;
    ResidentSampler& operator=(const ResidentSampler&) = delete;

    void stop();

    /// One line per stage on @a out: the highest resident set sampled while the stage ran,
    /// minus the resident set at construction, in bytes per particle; then the process peak.
    std::string report(const nonbloppy::StageTimings& timings, size_t particles) const;

private:
    struct Sample { double seconds; uint64_t bytes; };
    std::chrono::steady_clock::time_point mStart;
    uint64_t mBaseline = 0;
    std::vector<Sample> mSamples;
    mutable std::mutex mMutex;
    std::atomic<bool> mStop{false};
    std::thread mThread;
};

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_BATCH_RUN_H
