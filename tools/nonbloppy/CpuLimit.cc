// SPDX-License-Identifier: Apache-2.0
#include "CpuLimit.h"

#include <nonbloppy/CgroupLimits.h>

#include <cstdio>
#include <utility>

namespace nonbloppy_tool {

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
    const nonbloppy::DefaultThreads fallback = nonbloppy::defaultThreads();
    if (!fallback.cpuLimit) {
        tell("(default)");
        return nullptr;
    }
    tell("(the cgroup's CPU limit, " + formatCpus(*fallback.cpuLimit) + ")");
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                 size_t(fallback.threads));
}

} // namespace nonbloppy_tool
