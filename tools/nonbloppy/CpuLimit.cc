// SPDX-License-Identifier: Apache-2.0
#include "CpuLimit.h"

#include <tbb/info.h>

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

namespace nonbloppy_tool {
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

/// A positive number spelled by the whole of @a word, or nullopt ("max", "-1", "").
std::optional<double> positiveNumber(const std::string& word)
{
    if (word.empty()) return std::nullopt;
    char* end = nullptr;
    const double value = std::strtod(word.c_str(), &end);
    if (end != word.c_str() + word.size() || !(value > 0.0) || !std::isfinite(value)) return std::nullopt;
    return value;
}

/// The limit one cgroup directory sets, in CPUs; nullopt for none.
std::optional<double> limitIn(const std::string& dir, bool v1)
{
    std::optional<double> quota, period;
    if (v1) {
        const std::vector<std::string> q = wordsOfFirstLine(dir + "/cpu.cfs_quota_us");
        const std::vector<std::string> p = wordsOfFirstLine(dir + "/cpu.cfs_period_us");
        if (!q.empty()) quota = positiveNumber(q[0]);
        if (!p.empty()) period = positiveNumber(p[0]);
    } else {
        const std::vector<std::string> max = wordsOfFirstLine(dir + "/cpu.max");  // "QUOTA PERIOD"
        if (max.size() >= 2) {
            quota = positiveNumber(max[0]);
            period = positiveNumber(max[1]);
        }
    }
    if (!quota || !period) return std::nullopt;
    return *quota / *period;
}

} // namespace

std::optional<CpuCgroup> cpuCgroup(const std::string& procSelfCgroup, const std::string& mountRoot)
{
    // Lines "ID:CONTROLLERS:PATH": v2's is "0::PATH"; a v1 hierarchy with the cpu controller
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
        for (std::string controller; std::getline(list, controller, ',');) {
            if (controller == "cpu") {
                hasV1 = true;
                v1Path = path;
            }
        }
    }
    CpuCgroup cgroup;
    cgroup.v1 = hasV1;
    cgroup.path = hasV1 ? v1Path : unifiedPath;
    if (hasV1) {
        // Mounted as cpu (often a link to cpu,cpuacct) or under the joined name.
        for (const char* name : {"/cpu", "/cpu,cpuacct", "/cpuacct,cpu"}) {
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
    std::optional<CpuCgroup> cgroup = cpuCgroup(procSelfCgroup, mountRoot);
    if (!cgroup) return std::nullopt;
    // The lowest limit from the process's cgroup up to the root.
    std::optional<double> lowest;
    for (;;) {
        const std::optional<double> limit = limitIn(cgroup->directory(), cgroup->v1);
        if (limit && (!lowest || *limit < *lowest)) lowest = limit;
        if (cgroup->path.empty()) break;
        const size_t parent = cgroup->path.rfind('/');
        cgroup->path.erase(parent == std::string::npos ? 0 : parent);
    }
    return lowest;
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

std::string formatCpus(double cpus)
{
    char text[48];
    std::snprintf(text, sizeof(text), "%.3g CPU%s", cpus, cpus == 1.0 ? "" : "s");
    return text;
}

std::unique_ptr<tbb::global_control> limitWorkers(int given, std::string* origin)
{
    const auto tell = [origin](std::string text) {
        if (origin) *origin = std::move(text);
    };
    if (given > 0) {
        tell("(given)");
        return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(given));
    }
    const DefaultThreads fallback = defaultThreads();
    if (!fallback.cpuLimit) {
        tell("(default)");
        return nullptr;
    }
    tell("(the cgroup's CPU limit, " + formatCpus(*fallback.cpuLimit) + ")");
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                 size_t(fallback.threads));
}

} // namespace nonbloppy_tool
