// SPDX-License-Identifier: Apache-2.0
/// @file BatchRun.cc
/// @brief The frame loop of a sequence run: parallel frames, skip/resume, keep-going,
///        progress, JSON log, interrupt report; the resident-memory probe.

#include "BatchRun.h"

#include "Commands.h"
#include "Json.h"

#include <nonbloppy/Error.h>

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <memory>
#include <new>

#include <sys/resource.h>
#include <unistd.h>

namespace nonbloppy_tool {

namespace {

namespace fs = std::filesystem;

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start)
{
    return std::chrono::duration<double>(Clock::now() - start).count();
}

/// "3m12s", "1h02m", "45s".
std::string formatDuration(double seconds)
{
    if (!std::isfinite(seconds) || seconds < 0) return "?";
    const long s = std::lround(seconds);
    char buffer[32];
    if (s >= 3600) std::snprintf(buffer, sizeof(buffer), "%ldh%02ldm", s / 3600, (s / 60) % 60);
    else if (s >= 60) std::snprintf(buffer, sizeof(buffer), "%ldm%02lds", s / 60, s % 60);
    else std::snprintf(buffer, sizeof(buffer), "%lds", s);
    return buffer;
}

enum class Status { Pending, Done, Failed, Skipped, Interrupted };

/// Everything the workers share; every member after mMutex is guarded by it.
class BatchState
{
public:
    BatchState(const std::vector<BatchJob>& jobs, const BatchSettings& settings)
        : mJobs(jobs), mSettings(settings), mStatus(jobs.size(), Status::Pending),
          mTerminal(::isatty(STDOUT_FILENO) == 1 && !settings.verbose), mStart(Clock::now())
    {
        if (!settings.logPath.empty()) {
            mLog = std::fopen(settings.logPath.c_str(), "w");
            if (!mLog) {
                throw nonbloppy::FileError("cannot write " + settings.logPath + ": "
                                           + std::strerror(errno));
            }
        }
    }
    ~BatchState()
    {
        if (mLog) std::fclose(mLog);
    }

    std::atomic<size_t> next{0};
    std::atomic<bool> stop{false};

    void skipped(size_t index)
    {
        std::lock_guard<std::mutex> lock(mMutex);
        mStatus[index] = Status::Skipped;
        const BatchJob& job = mJobs[index];
        logLine("{\"frame\": " + std::to_string(job.frame.number) + ", \"status\": \"skipped\", "
                "\"input\": " + jsonString(job.frame.input) + ", \"output\": "
                + jsonString(job.outputs.front()) + ", \"reason\": \"outputs exist\"}");
        progress(index, job.outputs.size() == 1 ? "skipped, " + job.outputs.front() + " exists"
                                                : "skipped, its " + std::to_string(job.outputs.size()) + " outputs exist");
    }

    void done(size_t index, const FrameReport& report, double seconds)
    {
        std::lock_guard<std::mutex> lock(mMutex);
        mStatus[index] = Status::Done;
        mParticles += report.particles;
        mBusySeconds += seconds;
        const BatchJob& job = mJobs[index];

        std::string line = "{\"frame\": " + std::to_string(job.frame.number)
            + ", \"status\": \"done\", \"input\": " + jsonString(job.frame.input)
            + ", \"output\": " + jsonString(job.outputs.front()) + ", \"outputs\": [";
        for (size_t i = 0; i < job.outputs.size(); ++i) {
            line += (i ? ", " : "") + jsonString(job.outputs[i]);
        }
        line += "], \"particles\": " + std::to_string(report.particles)
            + ", \"particles_read\": " + std::to_string(report.particlesRead)
            + ", \"vertices\": " + std::to_string(report.vertices)
            + ", \"faces\": " + std::to_string(report.faces) + ", \"seconds\": {";
        for (size_t i = 0; i < report.timings.entries.size(); ++i) {
            const auto& e = report.timings.entries[i];
            line += (i ? ", " : "") + jsonString(e.stage) + ": " + jsonNumber(e.seconds);
        }
        line += "}, \"total_seconds\": " + jsonNumber(seconds)
            + ", \"cpu_seconds\": " + jsonNumber(report.timings.cpuTotal())
            + ", \"peak_rss_bytes\": " + std::to_string(peakResidentBytes())
            + ", \"parameters\": {";
        for (size_t i = 0; i < report.parameters.size(); ++i) {
            line += (i ? ", " : "") + jsonString(report.parameters[i].first) + ": "
                    + jsonNumber(report.parameters[i].second);
        }
        line += "}}";
        logLine(line);

        char text[160];
        std::snprintf(text, sizeof(text), "%zu particles, %zu vertices, %zu faces, %.2f s",
                      report.particles, report.vertices, report.faces, seconds);
        progress(index, job.frame.input + " -> " + job.outputs.front() + ": " + text);
    }

    void failed(size_t index, const std::string& message)
    {
        std::lock_guard<std::mutex> lock(mMutex);
        mStatus[index] = Status::Failed;
        const BatchJob& job = mJobs[index];
        logLine("{\"frame\": " + std::to_string(job.frame.number) + ", \"status\": \"failed\", "
                "\"input\": " + jsonString(job.frame.input) + ", \"output\": "
                + jsonString(job.outputs.front()) + ", \"error\": " + jsonString(message) + "}");
        // Named like --keep-going's lines: in a sequence, the message alone may not say which
        // frame (e.g. "cannot estimate the particle spacing from 1 particle").
        if (mFirstError.empty()) mFirstError = "frame " + std::to_string(job.frame.number) + ": " + message;
        if (mSettings.keepGoing) {
            // Reported now, on one line; the run goes on and fails at the end.
            clearBar();
            std::cerr << "nonbloppy: frame " << job.frame.number << ": " << message << std::endl;
        }
        progress(index, "failed");
    }

    /// True if a progress bar is drawn (stdout is a terminal, not --quiet).
    bool showsBar() const { return mTerminal && !mSettings.quiet; }

    /// Print @a line (a whole warning) on stderr, the bar erased first: the next progress or
    /// tick draws it again.
    void printLine(const std::string& line)
    {
        std::lock_guard<std::mutex> lock(mMutex);
        clearBar();
        std::cerr << line << std::flush;
    }

    /// Redraw the bar, so elapsed time and ETA move during long frames.
    void tick()
    {
        std::lock_guard<std::mutex> lock(mMutex);
        if (mBarShown || mFinished == 0) drawBar();
    }

    /// A frame a stop cut short (its partial outputs are removed): logged, and counted apart
    /// from the frames the stop left unstarted.
    void interrupted(size_t index)
    {
        std::lock_guard<std::mutex> lock(mMutex);
        mStatus[index] = Status::Interrupted;
        const BatchJob& job = mJobs[index];
        logLine("{\"frame\": " + std::to_string(job.frame.number) + ", \"status\": \"interrupted\", "
                "\"input\": " + jsonString(job.frame.input) + ", \"output\": " + jsonString(job.outputs.front()) + "}");
    }

    /// The summary (stdout and log); then the exit code, or the error to throw.
    int finish(bool wasInterrupted)
    {
        std::lock_guard<std::mutex> lock(mMutex);
        clearBar();
        std::vector<int> doneFrames, failedFrames, skippedFrames, cutShort, notRun;
        for (size_t i = 0; i < mJobs.size(); ++i) {
            const int number = mJobs[i].frame.number;
            switch (mStatus[i]) {
            case Status::Done: doneFrames.push_back(number); break;
            case Status::Failed: failedFrames.push_back(number); break;
            case Status::Skipped: skippedFrames.push_back(number); break;
            case Status::Interrupted: cutShort.push_back(number); break;
            default: notRun.push_back(number); break;
            }
        }
        // A signal after the last frame finished interrupted nothing.
        wasInterrupted = wasInterrupted && (!notRun.empty() || !cutShort.empty());
        // Every count is of the frames asked for: those found plus those missing (the stdout
        // summary, the log's "frames" and the failure line once counted differently).
        const size_t requested = mJobs.size() + mSettings.missing.size();
        const double total = secondsSince(mStart);
        const double rate = total > 0 ? double(mParticles) / total : 0.0;

        auto list = [](const std::vector<int>& frames) {
            std::string out = "[";
            for (size_t i = 0; i < frames.size(); ++i) out += (i ? ", " : "") + std::to_string(frames[i]);
            return out + "]";
        };
        logLine("{\"summary\": true, \"input\": " + jsonString(mSettings.inputPattern)
                + ", \"output\": " + jsonString(mSettings.outputPattern)
                + ", \"frames\": " + std::to_string(requested)
                + ", \"frames_done\": " + std::to_string(doneFrames.size())
                + ", \"frames_failed\": " + std::to_string(failedFrames.size())
                + ", \"frames_skipped\": " + std::to_string(skippedFrames.size())
                + ", \"frames_missing\": " + std::to_string(mSettings.missing.size())
                + ", \"frames_interrupted\": " + std::to_string(cutShort.size())
                + ", \"frames_not_run\": " + std::to_string(notRun.size())
                + ", \"failed\": " + list(failedFrames) + ", \"missing\": " + list(mSettings.missing)
                + ", \"interrupted\": " + (wasInterrupted ? "true" : "false")
                + ", \"frame_jobs\": " + std::to_string(mSettings.frameJobs)
                + (mSettings.threads > 0 ? ", \"threads\": " + std::to_string(mSettings.threads) : std::string())
                + ", \"total_seconds\": " + jsonNumber(total)
                + ", \"cpu_seconds\": " + jsonNumber(nonbloppy::processCpuSeconds())
                + ", \"particles\": " + std::to_string(mParticles)
                + ", \"particles_per_second\": " + jsonNumber(rate)
                + ", \"peak_rss_bytes\": " + std::to_string(peakResidentBytes())
                + ", \"rss_bytes\": " + std::to_string(currentResidentBytes()) + "}");
        if (mLog) {
            const bool warned = !mLogError.empty();
            if (!warned && (std::fflush(mLog) != 0 || std::ferror(mLog))) mLogError = std::strerror(errno);
            if (std::fclose(mLog) != 0 && mLogError.empty()) mLogError = std::strerror(errno);
            mLog = nullptr;
            // Said now if the last lines failed; the run fails below, after the summary.
            if (!warned && !mLogError.empty() && (wasInterrupted || !failedFrames.empty())) {
                std::cerr << "nonbloppy: warning: cannot write " << mSettings.logPath << ": " << mLogError
                          << std::endl;
            }
        }

        if (!mSettings.quiet) {
            // Frames a stop left unstarted are counted too, so that the parts add up.
            std::string notRunPart;
            if (!cutShort.empty()) notRunPart += ", " + std::to_string(cutShort.size()) + " interrupted";
            if (!notRun.empty()) notRunPart += ", " + std::to_string(notRun.size()) + " not run";
            char line[256];
            std::snprintf(line, sizeof(line),
                          "%s: %zu done, %zu failed, %zu skipped, %zu missing%s in %.2f s "
                          "(%s particles/s)",
                          counted(requested, "frame").c_str(), doneFrames.size(),
                          failedFrames.size(), skippedFrames.size(), mSettings.missing.size(),
                          notRunPart.c_str(), total, formatCount(uint64_t(rate)).c_str());
            std::cout << line << std::endl;
        }

        if (wasInterrupted) {
            std::cerr << "nonbloppy: interrupted; "
                      << (doneFrames.empty() ? std::string("no frame finished")
                                             : "finished frames: " + formatFrameList(doneFrames))
                      << " (" << doneFrames.size() << " of " << requested << ")" << std::endl;
            return kExitInterrupted;
        }
        if (!failedFrames.empty()) {
            if (!mSettings.keepGoing) throw nonbloppy::Error(mFirstError);
            throw nonbloppy::Error(std::to_string(failedFrames.size()) + " of "
                                   + std::to_string(requested) + " frames failed: "
                                   + formatFrameList(failedFrames));
        }
        if (!mLogError.empty()) throw nonbloppy::FileError("cannot write " + mSettings.logPath + ": " + mLogError);
        return 0;
    }

private:
    void logLine(const std::string& line)
    {
        if (!mLog || !mLogError.empty()) return;
        std::fputs(line.c_str(), mLog);
        std::fputc('\n', mLog);
        // Flushed per line: a farm may kill the job at any moment. A line that cannot be
        // written (a full disk) is said at once, not only at the end of a long run; the
        // frames go on, and the run fails at the end naming the cause.
        if (std::fflush(mLog) != 0 || std::ferror(mLog)) {
            mLogError = std::strerror(errno);
            clearBar();
            std::cerr << "nonbloppy: warning: cannot write " << mSettings.logPath << ": " << mLogError
                      << "; the log stops here, the frames go on" << std::endl;
        }
    }

    /// A frame has finished (one way or another): a line or a new bar.
    void progress(size_t index, const std::string& what)
    {
        ++mFinished;
        if (mSettings.quiet) return;
        if (mTerminal) {
            drawBar();
            return;
        }
        std::cout << "frame " << mJobs[index].frame.number << " (" << mFinished << "/"
                  << mJobs.size() << "): " << what << std::endl;
    }

    void clearBar()
    {
        if (mTerminal && mBarShown && !mSettings.quiet) {
            std::cout << "\r\033[K" << std::flush;
            mBarShown = false;
        }
    }

    void drawBar()
    {
        if (!mTerminal || mSettings.quiet) return;
        constexpr int kWidth = 30;
        const size_t total = mJobs.size();
        const int filled = total ? int(kWidth * mFinished / total) : kWidth;
        std::string bar(size_t(filled), '#');
        bar.resize(kWidth, '-');
        const double elapsed = secondsSince(mStart);
        size_t worked = 0;
        for (Status s : mStatus) worked += (s == Status::Done || s == Status::Failed);
        const size_t remaining = total - mFinished;
        const double eta = worked ? elapsed / double(worked) * double(remaining) : NAN;
        const double rate = elapsed > 0 ? double(mParticles) / elapsed : 0.0;
        char line[256];
        std::snprintf(line, sizeof(line), "\r[%s] %zu/%zu frames  %s particles/s  elapsed %s  ETA %s",
                      bar.c_str(), mFinished, total, formatCount(uint64_t(rate)).c_str(),
                      formatDuration(elapsed).c_str(),
                      remaining == 0 ? "0s" : formatDuration(eta).c_str());
        std::cout << line << "\033[K" << std::flush;
        mBarShown = true;
    }

    const std::vector<BatchJob>& mJobs;
    const BatchSettings& mSettings;
    std::mutex mMutex;
    std::vector<Status> mStatus;
    const bool mTerminal;
    const Clock::time_point mStart;
    std::FILE* mLog = nullptr;
    std::string mLogError;    ///< why the log could not be written (strerror), or empty
    std::string mFirstError;  ///< "frame N: message" of the first frame that failed
    size_t mFinished = 0;
    uint64_t mParticles = 0;
    double mBusySeconds = 0.0;
    bool mBarShown = false;
};

bool allExist(const std::vector<std::string>& paths)
{
    for (const std::string& path : paths) {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) return false;
    }
    return true;
}

/// Runs @a body for frame @a index; an exception it throws is reported as the frame's
/// failure (or interruption), after @a beforeReport (which must not throw), and stops the
/// run unless settings.keepGoing. Returns whether @a body succeeded.
template<typename BodyT, typename BeforeReportT>
bool reportingFailures(BatchState& state, size_t index, const BatchSettings& settings, const BodyT& body,
                       const BeforeReportT& beforeReport)
{
    try {
        body();
        return true;
    } catch (const nonbloppy::CancelledError&) {
        beforeReport();
        state.interrupted(index);
        state.stop = true;
    } catch (const std::bad_alloc&) {
        beforeReport();
        // Each frame's memory checks see what the others hold as they start, not what they
        // will take: frames that fit alone may not fit side by side.
        state.failed(index, settings.frameJobs > 1 ? "out of memory with " + std::to_string(settings.frameJobs)
                                                         + " frames at once; give a lower --frame-jobs"
                                                   : std::string("out of memory"));
        if (!settings.keepGoing) state.stop = true;
    } catch (const std::exception& e) {
        beforeReport();
        state.failed(index, e.what());
        if (!settings.keepGoing) state.stop = true;
    } catch (...) {
        beforeReport();
        state.failed(index, "unknown error");
        if (!settings.keepGoing) state.stop = true;
    }
    return false;
}

/// Takes frames one after another until there are none left or the run stops; at most one
/// frame in memory per worker. Each frame is meshed and written in turn.
void work(BatchState& state, const std::vector<BatchJob>& jobs, const BatchSettings& settings,
          const MeshFrameFunction& meshFrame, const std::function<bool()>& interrupted)
{
    while (!state.stop && !interrupted()) {
        const size_t index = state.next++;
        if (index >= jobs.size()) return;
        const BatchJob& job = jobs[index];
        if (settings.skipExisting && allExist(job.outputs)) {
            state.skipped(index);
            continue;
        }
        const Clock::time_point start = Clock::now();
        reportingFailures(state, index, settings, [&] {
            FrameReport report;
            // While this frame waits for its own parallel loops, the thread must not pick up
            // another worker's frame: that would put more than frameJobs frames in memory.
            tbb::this_task_arena::isolate([&] { report = meshFrame(job)(); });
            state.done(index, report, secondsSince(start));
        }, [] {});
    }
}

/// work() for one frame at a time, each frame's outputs written on a thread of their own
/// while the next frame is meshed: a write mostly waits on the disk (the 64x benchmark
/// mesh: 119 MB, 0.07 s at 1.8 GB/s, direct I/O) and reading the next frame mostly waits
/// on one core, both while the other cores idle. Frames are reported in order: a frame's
/// report waits for the write before it. Memory: one frame's, plus the surface of the frame
/// before while it is written (gone when the write ends, well before the next frame peaks
/// as it extracts). A failed write stops the run (without --keep-going) once the frame
/// meshed meanwhile is done; that frame is then not written.
/// Measured, eight 64x benchmark frames, two threads, 4 rounds alternating with each frame
/// written in turn and with --frame-jobs 2: 10.29-11.72 s (median 10.82) at 329-335 MB,
/// against 10.72-13.04 s (11.49) at 342-355 MB and 10.17-10.91 s (10.38) at 567-575 MB;
/// faster than in turn in each round.
void workWritingBehind(BatchState& state, const std::vector<BatchJob>& jobs, const BatchSettings& settings,
                       const MeshFrameFunction& meshFrame, const std::function<bool()>& interrupted)
{
    std::thread writer;  // writes the frame before
    const auto waitForWriter = [&writer] {
        if (writer.joinable()) writer.join();
    };
    // On every way out, a throw included: a joinable std::thread's destructor terminates.
    struct JoinWriter
    {
        const decltype(waitForWriter)& wait;
        ~JoinWriter() { wait(); }
    } joinWriter{waitForWriter};
    while (!state.stop && !interrupted()) {
        const size_t index = state.next++;
        if (index >= jobs.size()) break;
        const BatchJob& job = jobs[index];
        if (settings.skipExisting && allExist(job.outputs)) {
            waitForWriter();
            state.skipped(index);
            continue;
        }
        const Clock::time_point start = Clock::now();
        std::function<FrameReport()> write;
        if (!reportingFailures(state, index, settings, [&] { write = meshFrame(job); }, waitForWriter)) continue;
        waitForWriter();
        if (state.stop) break;  // the write before failed or was interrupted
        writer = std::thread([&state, &settings, index, start, write = std::move(write)] {
            reportingFailures(state, index, settings, [&] {
                const FrameReport report = write();
                state.done(index, report, secondsSince(start));
            }, [] {});
        });
    }
}

} // namespace

int runBatch(const std::vector<BatchJob>& jobs, const BatchSettings& settings,
             const MeshFrameFunction& meshFrame, const std::function<bool()>& interrupted)
{
    BatchState state(jobs, settings);
    // A notice, not an error: -q leaves it to the summary's count and the log's "missing".
    if (!settings.missing.empty() && !settings.quiet) {
        std::cerr << "nonbloppy: " << settings.missing.size() << " missing frame"
                  << (settings.missing.size() == 1 ? "" : "s") << " skipped: "
                  << formatFrameList(settings.missing) << " (" << settings.inputPattern << ")"
                  << std::endl;
    }

    // The frames' warnings go past the bar while it shows (a warning ran on after its line).
    struct RouteWarnings {
        WarningPrinter* printer;
        ~RouteWarnings() { if (printer) printer->route(nullptr); }
    } routeWarnings{state.showsBar() ? settings.warnings : nullptr};
    if (routeWarnings.printer) {
        routeWarnings.printer->route([&state](const std::string& line) { state.printLine(line); });
    }

    std::atomic<bool> finished{false};
    std::thread ticker;
    if (state.showsBar()) {
        ticker = std::thread([&] {
            for (int step = 1; !finished; ++step) {
                std::this_thread::sleep_for(std::chrono::milliseconds(100));
                if (step % 10 == 0 && !finished) state.tick();
            }
        });
    }
    struct JoinTicker {
        std::atomic<bool>& finished;
        std::thread& ticker;
        ~JoinTicker() { finished = true; if (ticker.joinable()) ticker.join(); }
    } joinTicker{finished, ticker};

    const int workers = std::max(1, std::min<int>(settings.frameJobs, int(jobs.size())));
    if (workers == 1) {
        workWritingBehind(state, jobs, settings, meshFrame, interrupted);
    } else {
        // Frames are tasks in the same arena as the parallel loops inside each frame, so
        // frames and loops share the --threads workers and never oversubscribe the machine.
        tbb::task_group group;
        for (int w = 0; w < workers; ++w) {
            group.run([&] { work(state, jobs, settings, meshFrame, interrupted); });
        }
        group.wait();
    }
    finished = true;
    if (ticker.joinable()) ticker.join();
    return state.finish(interrupted());
}

// ---------------------------------------------------------------------------------------
// Memory

uint64_t peakResidentBytes()
{
    struct rusage usage;
    if (::getrusage(RUSAGE_SELF, &usage) != 0) return 0;
    return uint64_t(usage.ru_maxrss) * 1024u; // kilobytes on Linux
}

uint64_t currentResidentBytes()
{
    std::FILE* file = std::fopen("/proc/self/statm", "r");
    if (!file) return 0;
    unsigned long long size = 0, resident = 0;
    const int read = std::fscanf(file, "%llu %llu", &size, &resident);
    std::fclose(file);
    if (read != 2) return 0;
    return uint64_t(resident) * uint64_t(::sysconf(_SC_PAGESIZE));
}

ResidentSampler::ResidentSampler()
    : mStart(Clock::now()), mBaseline(currentResidentBytes())
{
    mSamples.push_back({0.0, mBaseline});
    mThread = std::thread([this] {
        while (!mStop) {
            const uint64_t bytes = currentResidentBytes();
            {
                std::lock_guard<std::mutex> lock(mMutex);
                mSamples.push_back({secondsSince(mStart), bytes});
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
    });
}

ResidentSampler::~ResidentSampler() { stop(); }

void ResidentSampler::stop()
{
    mStop = true;
    if (mThread.joinable()) mThread.join();
}

std::string ResidentSampler::report(const nonbloppy::StageTimings& timings, size_t particles) const
{
    std::lock_guard<std::mutex> lock(mMutex);
    std::string out = "[memory] resident set per stage, sampled every 2 ms, above the "
                      + formatBytes(mBaseline) + " before the frame:\n";
    double stageStart = 0.0;
    size_t s = 0;
    for (const auto& entry : timings.entries) {
        const double stageEnd = stageStart + entry.seconds;
        uint64_t peak = 0;
        // The sample just before the stage starts belongs to it too (short stages).
        while (s < mSamples.size() && mSamples[s].seconds <= stageEnd) {
            peak = std::max(peak, mSamples[s].bytes);
            ++s;
        }
        if (s < mSamples.size()) peak = std::max(peak, mSamples[s].bytes);
        const uint64_t above = peak > mBaseline ? peak - mBaseline : 0;
        char line[200];
        std::snprintf(line, sizeof(line), "[memory]   %-22s peak %10s  %8.1f bytes/particle\n",
                      entry.stage.c_str(), formatBytes(above).c_str(),
                      particles ? double(above) / double(particles) : 0.0);
        out += line;
        stageStart = stageEnd;
    }
    const uint64_t peak = peakResidentBytes();
    char line[200];
    std::snprintf(line, sizeof(line),
                  "[memory]   %-22s peak %10s  %8.1f bytes/particle (getrusage ru_maxrss, whole "
                  "process)\n", "process", formatBytes(peak).c_str(),
                  particles ? double(peak) / double(particles) : 0.0);
    out += line;
    return out;
}

} // namespace nonbloppy_tool
