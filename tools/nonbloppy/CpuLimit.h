// SPDX-License-Identifier: Apache-2.0
/// @file CpuLimit.h
/// @brief The CPU time a container or batch job grants this process, which TBB's default
///        thread count does not see, and the worker count the tool defaults to under it.
///
/// TBB starts one worker per core of the process's affinity mask (so `taskset`, Slurm's and
/// Docker's `--cpuset-cpus` are seen), but not a CPU bandwidth limit: a Kubernetes pod with
/// `limits.cpu: 4`, or `docker run --cpus 4`, on a 64-core node got 64 threads, which the
/// kernel then stops for the rest of every 100 ms period once they have used 4 CPUs' worth
/// (CFS throttling; oneTBB issue #1760 reports 5-10x slowdowns). On this 2-core machine,
/// in a cgroup of one CPU, the 64x benchmark frame took 2.60-2.70 s at the two default
/// threads against 2.40-2.46 s at one (three alternating pairs).

#ifndef NONBLOPPY_TOOL_CPU_LIMIT_H
#define NONBLOPPY_TOOL_CPU_LIMIT_H

#include <tbb/global_control.h>

#include <memory>
#include <optional>
#include <string>

namespace nonbloppy_tool {

/// This process's cgroup for the cpu controller, as @a procSelfCgroup names it under
/// @a mountRoot.
struct CpuCgroup
{
    /// The hierarchy's directory: @a mountRoot for v2, its cpu controller's directory for v1
    /// (`cpu`, or the joined `cpu,cpuacct`).
    std::string hierarchy;
    /// The process's cgroup in it, "/kubepods/pod7/ctr1"; empty where that directory is
    /// missing, as inside a container whose own cgroup is mounted as the root.
    std::string path;
    bool v1 = false;  ///< the limit is spelled cpu.cfs_quota_us over cpu.cfs_period_us, not cpu.max

    std::string directory() const { return hierarchy + path; }
};

/// Where the cgroup of this process lies (see CpuCgroup); nullopt without a cgroup file
/// system under @a mountRoot. Cost: a read of @a procSelfCgroup and a few stat calls.
std::optional<CpuCgroup> cpuCgroup(const std::string& procSelfCgroup = "/proc/self/cgroup",
                                   const std::string& mountRoot = "/sys/fs/cgroup");

/// The CPU bandwidth the cgroup of this process may use, in CPUs (quota over period: 0.5 is
/// half of one CPU's time, 4 four CPUs'), the lowest along its path up to the hierarchy's
/// root, since a parent's limit binds its children (Kubernetes sets the pod's, above the
/// container's). cgroup v2 `cpu.max` ("max" is none), or, where a v1 hierarchy has the cpu
/// controller, `cpu.cfs_quota_us` (-1 is none) over `cpu.cfs_period_us`, from cpuCgroup()
/// up. nullopt without a limit or a readable cgroup file system. Cost: a few small file
/// reads.
std::optional<double> cgroupCpuLimit(const std::string& procSelfCgroup = "/proc/self/cgroup",
                                     const std::string& mountRoot = "/sys/fs/cgroup");

/// The worker threads the tool runs when `--threads` is not given.
struct DefaultThreads
{
    int threads = 1;                 ///< TBB's default, at most the CPU limit rounded up
    std::optional<double> cpuLimit;  ///< cgroupCpuLimit(), where it lowered the count
};

/// TBB's default (the cores of the affinity mask), lowered to the cgroup's CPU limit rounded
/// up (0.5 CPUs: one thread; 2.5: three) where that is smaller.
DefaultThreads defaultThreads();

/// @a cpus for the summary: "1 CPU", "0.5 CPUs", "4 CPUs".
std::string formatCpus(double cpus);

/// The workers of a command: @a given threads where the user gave --threads (> 0), else
/// defaultThreads(). Returns the TBB limit to hold for the command's run (null where TBB's
/// default stands) and, if asked, sets @a origin to how the count came about, for the summary:
/// "(given)", "(default)" or "(the cgroup's CPU limit, 0.5 CPUs)".
std::unique_ptr<tbb::global_control> limitWorkers(int given, std::string* origin = nullptr);

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_CPU_LIMIT_H
