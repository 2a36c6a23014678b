// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/Version.h>

namespace nonbloppy {

const char* version() { return NONBLOPPY_VERSION_STRING; }

} // namespace nonbloppy
