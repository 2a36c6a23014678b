// SPDX-License-Identifier: Apache-2.0
/// @file Version.h
/// @brief Compile-time and run-time version of nonbloppy.

#ifndef NONBLOPPY_VERSION_H
#define NONBLOPPY_VERSION_H

#define NONBLOPPY_VERSION_MAJOR 0
#define NONBLOPPY_VERSION_MINOR 1
#define NONBLOPPY_VERSION_PATCH 0
#define NONBLOPPY_VERSION_STRING "0.1.0"

namespace nonbloppy {

/// The version of the library actually linked, "MAJOR.MINOR.PATCH"; compare with
/// NONBLOPPY_VERSION_STRING to detect a header/library mismatch.
const char* version();

} // namespace nonbloppy

#endif // NONBLOPPY_VERSION_H
