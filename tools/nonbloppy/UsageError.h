// SPDX-License-Identifier: Apache-2.0
/// @file UsageError.h
/// @brief The tool's "bad command line" error (exit 2).

#ifndef NONBLOPPY_TOOL_USAGE_ERROR_H
#define NONBLOPPY_TOOL_USAGE_ERROR_H

#include <nonbloppy/Error.h>

namespace nonbloppy_tool {

/// A command line that cannot run whatever the files hold: an option value out of its range
/// or unreadable, a frame list or pattern that does not parse, an option without the one it
/// needs, an output name of no known format or naming the input. main() exits with 2 for
/// it, as for CLI11's own parse errors, so that a farm script can tell "fix the command" (2)
/// from "a frame failed" (1). What depends on the files (a missing input, a radius too small
/// for the particles' spacing, a directory that cannot be written) stays exit 1.
class UsageError : public nonbloppy::Error
{
public:
    using nonbloppy::Error::Error;
};

/// Runs @a check, one of the library's checks of an output file name (requireMeshFile(),
/// requireParticleOutputFile()), before any work: the name it refuses is a mistake in the
/// command line, so its FileError becomes a UsageError with the same message.
template<typename CheckT>
void requireAsUsage(const CheckT& check)
{
    try {
        check();
    } catch (const nonbloppy::FileError& e) {
        throw UsageError(e.what());
    }
}

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_USAGE_ERROR_H
