// SPDX-License-Identifier: Apache-2.0
/// @file CgroupLimits.h
/// @brief What a container or batch job grants this process: the CPU time and memory its
///        cgroup (and every cgroup above it) allows, which TBB's thread count and the
///        machine's memory figures do not see.
///
/// TBB starts one worker per core of the process's affinity mask (so `taskset`, Slurm's and
/// Docker's `--cpuset-cpus` are seen), but not a CPU bandwidth limit: a Kubernetes pod with
/// `limits.cpu: 4`, or `docker run --cpus 4`, on a 64-core node gets 64 threads, which the
/// kernel then stops for the rest of every 100 ms period once they have used 4 CPUs' worth
/// (CFS throttling; oneTBB issue #1760 reports 5-10x slowdowns). On a 2-core machine, in a
/// cgroup of one CPU, the 64x benchmark frame took 2.60-2.70 s at the two default threads
/// against 2.40-2.46 s at one. A program that links the library and may run in such a
/// container limits TBB itself, once, for as long as it meshes:
///
/// @code
/// tbb::global_control workers(tbb::global_control::max_allowed_parallelism,
///                             nonbloppy::defaultThreads().threads);
/// @endcode
///
/// The library does not do this on its own: TBB's limit is process-wide, the caller's to set.
/// Its memory checks (a stage that cannot fit is refused with a ParameterError before it
/// allocates) do use cgroupMemoryHeadroomBytes().
///
/// Every function takes the files it reads as arguments, defaulting to the kernel's, so that
/// tests can lay out the trees that Docker, Kubernetes and Slurm make. Nothing is cached: each
/// call reads the files again (a few small reads), since a job's limits can change.
/// Thread-safety: reentrant.

#ifndef NONBLOPPY_CGROUP_LIMITS_H
#define NONBLOPPY_CGROUP_LIMITS_H

#include <nonbloppy/Export.h>

#include <optional>
#include <string>

namespace nonbloppy {

/// The cgroup controllers whose limits the library reads.
enum class CgroupController { Cpu, Memory };

/// Where this process's cgroup for one controller lies on the file system.
struct CgroupLocation
{
    /// The hierarchy's mount: the mount root for cgroup v2; for v1, the controller's own
    /// directory under it (`cpu`, `cpu,cpuacct` or `memory`).
    std::string hierarchy;
    /// The process's cgroup in that hierarchy, "/kubepods/pod7/ctr1"; empty where that
    /// directory is missing, as inside a container whose own cgroup is mounted as the root.
    std::string path;
    /// The limits are v1's files (cpu.cfs_quota_us, memory.limit_in_bytes), not v2's.
    bool v1 = false;

    /// The cgroup's directory, whose files hold its limits: hierarchy + path.
    std::string directory() const { return hierarchy + path; }
};

/// Where this process's cgroup for @a controller lies, from @a procSelfCgroup's lines
/// ("0::PATH" for v2, "4:cpu,cpuacct:PATH" for a v1 hierarchy, which governs where the
/// controller has one); nullopt without a cgroup file system under @a mountRoot.
/// Cost: a read of @a procSelfCgroup and a few stat calls.
NONBLOPPY_API std::optional<CgroupLocation>
findCgroup(CgroupController controller, const std::string& procSelfCgroup = "/proc/self/cgroup",
           const std::string& mountRoot = "/sys/fs/cgroup");

/// The CPU bandwidth this process's cgroup may use, in CPUs (quota over period: 0.5 is half
/// of one CPU's time, 4 four CPUs'), the lowest along its path up to the hierarchy's root,
/// since a parent's limit binds its children (Kubernetes sets the pod's, above the
/// container's). cgroup v2 `cpu.max` ("max" is none), or v1 `cpu.cfs_quota_us` (-1 is none)
/// over `cpu.cfs_period_us`. nullopt without a limit or a readable cgroup file system.
/// Cost: two small file reads per level.
NONBLOPPY_API std::optional<double> cgroupCpuLimit(const std::string& procSelfCgroup = "/proc/self/cgroup",
                                                   const std::string& mountRoot = "/sys/fs/cgroup");

/// The bytes this process's cgroups let it still take: at each level from its cgroup up to
/// the root that sets a memory limit, the limit less that cgroup's usage (which counts its
/// children, and so other processes of the same job or pod), not counting the inactive page
/// cache, which the kernel reclaims first; the smallest of these. cgroup v2 `memory.max`
/// ("max" is none), `memory.current` and `memory.stat`'s `inactive_file`, or v1
/// `memory.limit_in_bytes` (2^63 rounded to a page is none), `memory.usage_in_bytes` and
/// `total_inactive_file`. nullopt without a limit. Cost: three small file reads per level.
NONBLOPPY_API std::optional<double>
cgroupMemoryHeadroomBytes(const std::string& procSelfCgroup = "/proc/self/cgroup",
                          const std::string& mountRoot = "/sys/fs/cgroup");

/// The worker threads to run where the user has not said.
struct DefaultThreads
{
    int threads = 1;                 ///< TBB's default, at most the CPU limit rounded up
    std::optional<double> cpuLimit;  ///< cgroupCpuLimit(), where it lowered the count
};

/// TBB's default concurrency (the cores of the affinity mask), lowered to the cgroup's CPU
/// limit rounded up (0.5 CPUs: one thread; 2.5: three) where that is smaller. Cost: as
/// cgroupCpuLimit().
NONBLOPPY_API DefaultThreads defaultThreads();

} // namespace nonbloppy

#endif // NONBLOPPY_CGROUP_LIMITS_H
