// SPDX-License-Identifier: Apache-2.0
/// @file OutputCleanup.h
/// @brief A command's output files, put back as they were unless the command succeeds.

#ifndef NONBLOPPY_TOOL_OUTPUT_CLEANUP_H
#define NONBLOPPY_TOOL_OUTPUT_CLEANUP_H

#include "Interrupts.h"

#include <string>
#include <vector>

namespace nonbloppy_tool {

class BackgroundRemover;

/// The file a writer writes for @a path: symbolic links followed, also to a target that does
/// not exist yet, as the library's writers (and a shell's '>') follow them. A loop of links
/// stops at the 40th, where the writer fails anyway.
std::string writtenFile(const std::string& path);

/// The outputs of one frame (or one conversion), put back as they were unless it succeeds.
/// Each output is written atomically, but the mesh is in place before the .vdb is written:
/// when that failed, removing the new mesh used to leave neither it nor the mesh an earlier
/// run had written there; and an interrupt that arrives during a write is seen only once the
/// file is in place. So before an output is written, the file it will replace (symbolic
/// links followed, as the writers do) gets a hard link beside it; on failure that link is
/// renamed back over the new file, or, where nothing was replaced, the new file is removed.
/// Cost: a link() and an unlink() per existing output, the unlink() off the caller's path
/// (BackgroundRemover). Where the file system has no hard links, a failure still removes
/// the new file (the old one is then lost).
class OutputCleanup
{
public:
    OutputCleanup() = default;
    OutputCleanup(const OutputCleanup&) = delete;
    OutputCleanup& operator=(const OutputCleanup&) = delete;
    /// Puts every output announced since the last keep() back as it was.
    ~OutputCleanup();

    /// Call before writing @a path.
    void willWrite(const std::string& path);
    /// Call once the output last announced by willWrite() is written.
    void written() { mOutputs.back().written = true; }
    /// Success: keep the new files, drop the links to the old ones. The old files' blocks
    /// are freed on @a remover's thread (see BackgroundRemover.h for the wait).
    void keep(BackgroundRemover& remover);

private:
    struct Output
    {
        std::string target;  ///< the file it names (links followed, also to a file yet to be)
        std::string backup;  ///< hard link to the replaced file, or empty
        bool written;
    };
    std::vector<Output> mOutputs;
    OutputsPendingScope mPending;  ///< a stuck read's default action waits for this
};

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_OUTPUT_CLEANUP_H
