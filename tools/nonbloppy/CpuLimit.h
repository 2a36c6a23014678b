// SPDX-License-Identifier: Apache-2.0
/// @file CpuLimit.h
/// @brief The worker threads a command runs: `--threads` where given, else the library's
///        defaultThreads(), which lowers TBB's count to a container's or batch job's CPU
///        limit (nonbloppy/CgroupLimits.h says why that matters).

#ifndef NONBLOPPY_TOOL_CPU_LIMIT_H
#define NONBLOPPY_TOOL_CPU_LIMIT_H

#include <tbb/global_control.h>

#include <memory>
#include <string>

namespace nonbloppy_tool {

/// @a cpus for the summary: "1 CPU", "0.5 CPUs", "4 CPUs".
std::string formatCpus(double cpus);

/// The workers of a command: @a given threads where the user gave --threads (> 0), else
/// nonbloppy::defaultThreads(). Returns the TBB limit to hold for the command's run (null
/// where TBB's default stands) and, if asked, sets @a origin to how the count came about, for
/// the summary: "(given)", "(default)" or "(the cgroup's CPU limit, 0.5 CPUs)".
std::unique_ptr<tbb::global_control> limitWorkers(int given, std::string* origin = nullptr);

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_CPU_LIMIT_H
