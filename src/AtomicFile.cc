// SPDX-License-Identifier: Apache-2.0
/// @file AtomicFile.cc
/// @brief Temporary-file-and-rename writing (see AtomicFile.h).

#include "AtomicFile.h"

#include <nonbloppy/Error.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace nonbloppy {

namespace {

[[noreturn]] void
throwWriteError(const std::string& path, int errorNumber)
{
    throw FileError("cannot write " + path + ": " + std::strerror(errorNumber));
}

/// The mode a file created with open(path, O_CREAT, 0666) would get. mkstemp() creates
/// 0600 files, which would make every output unreadable for other users of a render farm.
/// The umask is read from /proc because umask() can only be queried by changing it, which
/// is not thread-safe.
mode_t
newFileMode(const std::string& path)
{
    struct stat existing;
    if (::stat(path.c_str(), &existing) == 0) return existing.st_mode & 07777;

    mode_t mask = 022;
    if (std::FILE* status = std::fopen("/proc/self/status", "r")) {
        char line[256];
        while (std::fgets(line, sizeof(line), status)) {
            if (std::strncmp(line, "Umask:", 6) == 0) {
                mask = mode_t(std::strtoul(line + 6, nullptr, 8));
                break;
            }
        }
        std::fclose(status);
    }
    return 0666 & ~mask;
}

} // namespace

AtomicFile::AtomicFile(const std::string& path)
    : mPath(path)
{
    std::string pattern = path + ".tmp-XXXXXX";
    std::vector<char> name(pattern.begin(), pattern.end());
    name.push_back('\0');
    const int fd = ::mkstemp(name.data());
    if (fd < 0) throwWriteError(mPath, errno);
    ::close(fd);
    mTempPath = name.data();
}

AtomicFile::~AtomicFile()
{
    if (!mCommitted && !mTempPath.empty()) ::unlink(mTempPath.c_str());
}

void
AtomicFile::commit()
{
    if (mCommitted) return;
    if (::chmod(mTempPath.c_str(), newFileMode(mPath)) != 0 ||
        ::rename(mTempPath.c_str(), mPath.c_str()) != 0)
    {
        const int errorNumber = errno;
        ::unlink(mTempPath.c_str());
        mTempPath.clear();
        throwWriteError(mPath, errorNumber);
    }
    mCommitted = true;
}

void
writeFileAtomically(const std::string& path,
                    const std::function<void(std::ostream&)>& writeContents)
{
    AtomicFile file(path);
    {
        errno = 0; // so a stream failure reports its own cause, not a stale one
        std::ofstream os(file.tempPath(), std::ios::binary | std::ios::trunc);
        if (!os) throwWriteError(path, errno ? errno : EIO);
        try {
            writeContents(os);
        } catch (const Error&) {
            throw; // already one line naming what went wrong (e.g. cancelled)
        } catch (const std::exception& e) {
            throw FileError("cannot write " + path + ": " + e.what());
        }
        os.flush();
        if (!os) throwWriteError(path, errno ? errno : EIO);
        os.close();
        if (!os) throwWriteError(path, errno ? errno : EIO);
    }
    file.commit();
}

} // namespace nonbloppy
