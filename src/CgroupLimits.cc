// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/CgroupLimits.h>

#include <tbb/info.h>

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

namespace nonbloppy {
namespace {

bool isDirectory(const std::string& path)
{
    struct stat info;
    return ::stat(path.c_str(), &info) == 0 && S_ISDIR(info.st_mode);
}

/// The whitespace-separated words of the file @a path's first line; none if unreadable.
std::vector<std::string> wordsOfFirstLine(const std::string& path)
{
    std::ifstream file(path);
    std::string line;
    std::vector<std::string> words;
    if (!std::getline(file, line)) return words;
    std::istringstream in(line);
    for (std::string word; in >> word;) words.push_back(word);
    return words;
}

/// A finite number >= 0 spelled by the whole of @a word; else nullopt ("max", "-1", "").
std::optional<double> numberFrom(const std::string& word)
{
    if (word.empty()) return std::nullopt;
    char* end = nullptr;
    const double value = std::strtod(word.c_str(), &end);
    if (end != word.c_str() + word.size() || !(value >= 0.0) || !std::isfinite(value)) return std::nullopt;
    return value;
}

/// numberFrom() the first word of the file @a path.
std::optional<double> firstNumberIn(const std::string& path)
{
    const std::vector<std::string> words = wordsOfFirstLine(path);
    return words.empty() ? std::nullopt : numberFrom(words[0]);
}

/// The value of @a key in a memory.stat file ("inactive_file 123" lines), or 0.
double statValue(const std::string& path, const std::string& key)
{
    std::ifstream file(path);
    std::string name;
    double value = 0.0;
    while (file >> name >> value) {
        if (name == key) return value;
    }
    return 0.0;
}

/// The limit one cgroup directory sets, in CPUs; nullopt for none.
std::optional<double> cpuLimitIn(const std::string& dir, bool v1)
{
    std::optional<double> quota, period;
    if (v1) {
        quota = firstNumberIn(dir + "/cpu.cfs_quota_us");
        period = firstNumberIn(dir + "/cpu.cfs_period_us");
    } else {
        const std::vector<std::string> max = wordsOfFirstLine(dir + "/cpu.max");  // "QUOTA PERIOD"
        if (max.size() >= 2) {
            quota = numberFrom(max[0]);
            period = numberFrom(max[1]);
        }
    }
    if (!quota || !period || !(*quota > 0.0) || !(*period > 0.0)) return std::nullopt;
    return *quota / *period;
}

/// What one cgroup directory's memory limit leaves, in bytes; nullopt without a limit.
std::optional<double> memoryHeadroomIn(const std::string& dir, bool v1)
{
    const std::optional<double> limit = firstNumberIn(dir + (v1 ? "/memory.limit_in_bytes" : "/memory.max"));
    const std::optional<double> usage = firstNumberIn(dir + (v1 ? "/memory.usage_in_bytes" : "/memory.current"));
    // v2 writes no limit as "max", v1 as 2^63 rounded down to a page.
    if (!limit || *limit > 1e18 || !usage) return std::nullopt;
    const double inactive = statValue(dir + "/memory.stat", v1 ? "total_inactive_file" : "inactive_file");
    return std::max(0.0, *limit - std::max(0.0, *usage - inactive));
}

/// The smallest of @a valueIn(directory) from @a cgroup up to its hierarchy's root.
template<typename ValueInT>
std::optional<double> lowestOnThePathUp(CgroupLocation cgroup, ValueInT valueIn)
{
    std::optional<double> lowest;
    for (;;) {
        const std::optional<double> value = valueIn(cgroup.directory(), cgroup.v1);
        if (value && (!lowest || *value < *lowest)) lowest = value;
        if (cgroup.path.empty()) return lowest;
        const size_t parent = cgroup.path.rfind('/');
        cgroup.path.erase(parent == std::string::npos ? 0 : parent);
    }
}

} // namespace

std::optional<CgroupLocation> findCgroup(CgroupController controller, const std::string& procSelfCgroup,
                                         const std::string& mountRoot)
{
    const std::string wanted = controller == CgroupController::Cpu ? "cpu" : "memory";
    // Lines "ID:CONTROLLERS:PATH": v2's is "0::PATH"; a v1 hierarchy with the controller
    // lists it among others ("4:cpu,cpuacct:/PATH").
    std::ifstream cgroups(procSelfCgroup);
    std::string unifiedPath, v1Path;
    bool hasV1 = false;
    for (std::string line; std::getline(cgroups, line);) {
        const size_t first = line.find(':');
        const size_t second = first == std::string::npos ? first : line.find(':', first + 1);
        if (second == std::string::npos) continue;
        const std::string controllers = line.substr(first + 1, second - first - 1);
        const std::string path = line.substr(second + 1);
        if (line.compare(0, first, "0") == 0 && controllers.empty()) unifiedPath = path;
        std::istringstream list(controllers);
        for (std::string name; std::getline(list, name, ',');) {
            if (name == wanted) {
                hasV1 = true;
                v1Path = path;
            }
        }
    }
    CgroupLocation cgroup;
    cgroup.v1 = hasV1;
    cgroup.path = hasV1 ? v1Path : unifiedPath;
    if (hasV1) {
        // cpu is mounted as cpu (often a link to cpu,cpuacct) or under the joined name.
        const std::vector<std::string> names = controller == CgroupController::Cpu
                                                   ? std::vector<std::string>{"/cpu", "/cpu,cpuacct", "/cpuacct,cpu"}
                                                   : std::vector<std::string>{"/memory"};
        for (const std::string& name : names) {
            if (isDirectory(mountRoot + name)) {
                cgroup.hierarchy = mountRoot + name;
                break;
            }
        }
        if (cgroup.hierarchy.empty()) return std::nullopt;
    } else if (isDirectory(mountRoot)) {
        cgroup.hierarchy = mountRoot;
    } else {
        return std::nullopt;
    }
    while (!cgroup.path.empty() && cgroup.path.back() == '/') cgroup.path.pop_back();
    if (!isDirectory(cgroup.directory())) cgroup.path.clear();  // a container's own cgroup mounted as the root
    return cgroup;
}

std::optional<double> cgroupCpuLimit(const std::string& procSelfCgroup, const std::string& mountRoot)
{
    const std::optional<CgroupLocation> cgroup = findCgroup(CgroupController::Cpu, procSelfCgroup, mountRoot);
    return cgroup ? lowestOnThePathUp(*cgroup, cpuLimitIn) : std::nullopt;
}

std::optional<double> cgroupMemoryHeadroomBytes(const std::string& procSelfCgroup, const std::string& mountRoot)
{
    const std::optional<CgroupLocation> cgroup = findCgroup(CgroupController::Memory, procSelfCgroup, mountRoot);
    return cgroup ? lowestOnThePathUp(*cgroup, memoryHeadroomIn) : std::nullopt;
}

DefaultThreads defaultThreads()
{
    DefaultThreads result;
    result.threads = std::max(1, tbb::info::default_concurrency());
    const std::optional<double> limit = cgroupCpuLimit();
    if (limit && std::ceil(*limit) < double(result.threads)) {
        result.threads = std::max(1, int(std::ceil(*limit)));
        result.cpuLimit = limit;
    }
    return result;
}

} // namespace nonbloppy
