// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/Version.h>

#include <openvdb/version.h>

namespace nonbloppy {

const char* version() { return NONBLOPPY_VERSION_STRING; }

std::string versionLine()
{
    return std::string("nonbloppy ") + version() + " (OpenVDB " + openvdb::getLibraryVersionString() + ")";
}

} // namespace nonbloppy
