// SPDX-License-Identifier: Apache-2.0
// The CPU and memory limits of a container or batch job (nonbloppy/CgroupLimits.h), read
// from cgroup file systems laid out in a scratch directory as the kernel, Docker, Kubernetes
// and Slurm lay them out; and the tool's summary of them (tools/nonbloppy/CpuLimit.h).
#include "CpuLimit.h"
#include "TestUtil.h"

#include <nonbloppy/CgroupLimits.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>

namespace {

using nonbloppy::cgroupCpuLimit;
using nonbloppy::cgroupMemoryHeadroomBytes;
using nonbloppy_tool::formatCpus;
using nonbloppy_test::ScratchDirTest;
using nonbloppy_test::writeBytes;

class CgroupLimitsTest : public ScratchDirTest
{
protected:
    /// The file @a name under the fake mount root, with its directories.
    void file(const std::string& name, const std::string& text) const
    {
        std::filesystem::create_directories(std::filesystem::path(path("sys/" + name)).parent_path());
        writeBytes(path("sys/" + name), text);
    }
    std::optional<double> limit(const std::string& procSelfCgroup) const
    {
        writeBytes(path("cgroup"), procSelfCgroup);
        return cgroupCpuLimit(path("cgroup"), path("sys"));
    }
    std::optional<double> memory(const std::string& procSelfCgroup) const
    {
        writeBytes(path("cgroup"), procSelfCgroup);
        return cgroupMemoryHeadroomBytes(path("cgroup"), path("sys"));
    }
};

TEST_F(CgroupLimitsTest, CgroupV2QuotaOverPeriod)
{
    // docker run --cpus 1.5: the container's cpu.max.
    file("system.slice/docker-1.scope/cpu.max", "150000 100000\n");
    EXPECT_EQ(limit("0::/system.slice/docker-1.scope\n"), 1.5);
    file("system.slice/docker-1.scope/cpu.max", "max 100000\n");
    EXPECT_EQ(limit("0::/system.slice/docker-1.scope\n"), std::nullopt);
}

TEST_F(CgroupLimitsTest, TheLowestLimitOnThePathToTheRootBinds)
{
    // Kubernetes: limits.cpu on the pod, nothing on the container below it.
    file("kubepods/burstable/pod7/cpu.max", "400000 100000\n");
    file("kubepods/burstable/pod7/ctr1/cpu.max", "max 100000\n");
    file("kubepods/burstable/cpu.max", "max 100000\n");
    EXPECT_EQ(limit("0::/kubepods/burstable/pod7/ctr1\n"), 4.0);
    // A tighter child wins over its parent; a looser one does not.
    file("kubepods/burstable/pod7/ctr1/cpu.max", "50000 100000\n");
    EXPECT_EQ(limit("0::/kubepods/burstable/pod7/ctr1\n"), 0.5);
    file("kubepods/burstable/pod7/ctr1/cpu.max", "800000 100000\n");
    EXPECT_EQ(limit("0::/kubepods/burstable/pod7/ctr1/\n"), 4.0);
}

TEST_F(CgroupLimitsTest, AContainersOwnCgroupMountedAsTheRoot)
{
    // Inside a container with its own cgroup namespace the path is "/", and without one the
    // host's path, which the container's mount does not hold: the root's files then count.
    file("cpu.max", "200000 100000\n");
    EXPECT_EQ(limit("0::/\n"), 2.0);
    EXPECT_EQ(limit("0::/system.slice/docker-2.scope\n"), 2.0);
}

TEST_F(CgroupLimitsTest, CgroupV1CpuController)
{
    // Slurm with cgroup v1 (ConstrainCores sets a cpuset, which TBB sees; a CPU quota is
    // what TBB misses), the controller mounted under its joined name.
    file("cpu,cpuacct/slurm/uid_0/job_12/cpu.cfs_quota_us", "300000\n");
    file("cpu,cpuacct/slurm/uid_0/job_12/cpu.cfs_period_us", "100000\n");
    file("memory/slurm/uid_0/job_12/memory.limit_in_bytes", "1073741824\n");
    const std::string cgroups = "12:memory:/slurm/uid_0/job_12\n4:cpu,cpuacct:/slurm/uid_0/job_12\n0::/\n";
    EXPECT_EQ(limit(cgroups), 3.0);
    file("cpu,cpuacct/slurm/uid_0/job_12/cpu.cfs_quota_us", "-1\n");
    EXPECT_EQ(limit(cgroups), std::nullopt);
    // A parent's quota, and the controller mounted as plain "cpu" (this machine's layout).
    std::filesystem::remove_all(path("sys/cpu,cpuacct"));
    file("cpu/nb/cpu.cfs_quota_us", "50000\n");
    file("cpu/nb/cpu.cfs_period_us", "100000\n");
    file("cpu/nb/inner/cpu.cfs_quota_us", "-1\n");
    file("cpu/nb/inner/cpu.cfs_period_us", "100000\n");
    file("cpu/cpu.cfs_quota_us", "-1\n");
    file("cpu/cpu.cfs_period_us", "100000\n");
    EXPECT_EQ(limit("3:cpuset:/\n2:cpu:/nb/inner\n1:cpuacct:/nb/inner\n0::/\n"), 0.5);
    // Where that cgroup lies, as the tests that make a real one use it.
    const std::optional<nonbloppy::CgroupLocation> where =
        nonbloppy::findCgroup(nonbloppy::CgroupController::Cpu, path("cgroup"), path("sys"));
    ASSERT_TRUE(where);
    EXPECT_TRUE(where->v1);
    EXPECT_EQ(where->directory(), path("sys/cpu/nb/inner"));
}

TEST_F(CgroupLimitsTest, NoLimitWhereNothingIsReadable)
{
    // No cgroup file system, an unreadable /proc/self/cgroup, text that is no limit.
    EXPECT_EQ(cgroupCpuLimit(path("missing"), path("sys-missing")), std::nullopt);
    file("cpu.max", "200000 100000\n");
    EXPECT_EQ(cgroupCpuLimit(path("missing"), path("sys")), 2.0);  // the root's, as in a container
    // A path without its leading slash, which no kernel writes, names no directory: the
    // root's limit, and no exception.
    EXPECT_EQ(limit("0::kube\n"), 2.0);
    for (const char* text : {"", "max", "100000", "0 100000", "-5 100000", "abc 100000", "100000 0", "1e999 1"}) {
        SCOPED_TRACE(text);
        file("cpu.max", text);
        EXPECT_EQ(limit("0::/\n"), std::nullopt);
    }
}

TEST_F(CgroupLimitsTest, MemoryHeadroomIsTheLimitLessTheUsageNotCountingInactivePageCache)
{
    // docker run --memory 1g, v2: 300 MB used, of which 100 MB are page cache the kernel
    // reclaims first.
    file("system.slice/docker-1.scope/memory.max", "1000000000\n");
    file("system.slice/docker-1.scope/memory.current", "300000000\n");
    file("system.slice/docker-1.scope/memory.stat", "anon 200000000\nfile 100000000\ninactive_file 100000000\n");
    EXPECT_EQ(memory("0::/system.slice/docker-1.scope\n"), 800e6);
    // More in use than the limit (page cache above it) leaves nothing, not a negative count.
    file("system.slice/docker-1.scope/memory.current", "1200000000\n");
    file("system.slice/docker-1.scope/memory.stat", "inactive_file 10\n");
    EXPECT_EQ(memory("0::/system.slice/docker-1.scope\n"), 0.0);
    file("system.slice/docker-1.scope/memory.max", "max\n");
    EXPECT_EQ(memory("0::/system.slice/docker-1.scope\n"), std::nullopt);
}

TEST_F(CgroupLimitsTest, AParentsMemoryLimitBindsItsChildren)
{
    // Slurm, cgroup v2: the job's limit, its step with none of its own, and another step of
    // the same job holding memory too (the job's usage counts both).
    file("system.slice/slurmstepd.scope/job_7/memory.max", "4000000000\n");
    file("system.slice/slurmstepd.scope/job_7/memory.current", "3000000000\n");
    file("system.slice/slurmstepd.scope/job_7/step_0/memory.max", "max\n");
    file("system.slice/slurmstepd.scope/job_7/step_0/memory.current", "1000000000\n");
    file("system.slice/slurmstepd.scope/memory.max", "max\n");
    const std::string step = "0::/system.slice/slurmstepd.scope/job_7/step_0\n";
    EXPECT_EQ(memory(step), 1e9);
    // A step's own tighter limit wins; a looser one does not.
    file("system.slice/slurmstepd.scope/job_7/step_0/memory.max", "1500000000\n");
    EXPECT_EQ(memory(step), 0.5e9);
    file("system.slice/slurmstepd.scope/job_7/step_0/memory.max", "8000000000\n");
    EXPECT_EQ(memory(step), 1e9);
}

TEST_F(CgroupLimitsTest, CgroupV1MemoryController)
{
    // This machine's layout: v1 controllers, each in its own hierarchy. The unlimited root
    // says 2^63 rounded down to a page; the inactive page cache is the hierarchy's total.
    const std::string cgroups = "12:memory:/nb/inner\n4:cpu,cpuacct:/\n0::/\n";
    file("memory/memory.limit_in_bytes", "9223372036854771712\n");
    file("memory/memory.usage_in_bytes", "20000000000\n");
    file("memory/nb/inner/memory.limit_in_bytes", "9223372036854771712\n");
    file("memory/nb/inner/memory.usage_in_bytes", "100000000\n");
    EXPECT_EQ(memory(cgroups), std::nullopt);
    file("memory/nb/memory.limit_in_bytes", "1572864000\n");
    file("memory/nb/memory.usage_in_bytes", "300000000\n");
    file("memory/nb/memory.stat", "inactive_file 5\ntotal_inactive_file 100000000\n");
    EXPECT_EQ(memory(cgroups), 1572864000.0 - 200e6);
    const std::optional<nonbloppy::CgroupLocation> where =
        nonbloppy::findCgroup(nonbloppy::CgroupController::Memory, path("cgroup"), path("sys"));
    ASSERT_TRUE(where);
    EXPECT_TRUE(where->v1);
    EXPECT_EQ(where->directory(), path("sys/memory/nb/inner"));
    // The memory limit is not the CPU's, nor the other way round.
    EXPECT_EQ(limit(cgroups), std::nullopt);
}

TEST_F(CgroupLimitsTest, NoMemoryLimitWhereNothingIsReadable)
{
    EXPECT_EQ(cgroupMemoryHeadroomBytes(path("missing"), path("sys-missing")), std::nullopt);
    // A container's own cgroup as the root, and text that is no limit or no usage.
    file("memory.max", "2000000000\n");
    file("memory.current", "500000000\n");
    EXPECT_EQ(memory("0::/\n"), 1.5e9);
    EXPECT_EQ(memory("0::/system.slice/docker-2.scope\n"), 1.5e9);
    for (const char* text : {"", "max", "-5", "abc", "1e999"}) {
        SCOPED_TRACE(text);
        file("memory.max", text);
        EXPECT_EQ(memory("0::/\n"), std::nullopt);
        file("memory.max", "2000000000\n");
        file("memory.current", text);
        EXPECT_EQ(memory("0::/\n"), std::nullopt);
        file("memory.current", "500000000\n");
    }
}

TEST(CpuLimit, FormatCpus)
{
    EXPECT_EQ(formatCpus(1.0), "1 CPU");
    EXPECT_EQ(formatCpus(0.5), "0.5 CPUs");
    EXPECT_EQ(formatCpus(4.0), "4 CPUs");
    EXPECT_EQ(formatCpus(2.345), "2.35 CPUs");
}

} // namespace
