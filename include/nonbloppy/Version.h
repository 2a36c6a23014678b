// SPDX-License-Identifier: Apache-2.0
/// @file Version.h
/// @brief Compile-time and run-time version of nonbloppy.

#ifndef NONBLOPPY_VERSION_H
#define NONBLOPPY_VERSION_H

#include <nonbloppy/Export.h>

#include <string>

/// Major version of the headers (incompatible API changes).
#define NONBLOPPY_VERSION_MAJOR 0
/// Minor version of the headers (additions; ABI may change while MAJOR is 0).
#define NONBLOPPY_VERSION_MINOR 1
/// Patch version of the headers (fixes).
#define NONBLOPPY_VERSION_PATCH 0
/// "MAJOR.MINOR.PATCH"; equals the CMake project version (checked by the test suite).
#define NONBLOPPY_VERSION_STRING "0.1.0"

namespace nonbloppy {

/// The version of the library actually linked, "MAJOR.MINOR.PATCH"; compare with
/// NONBLOPPY_VERSION_STRING to detect a header/library mismatch.
NONBLOPPY_API const char* version();

/// "nonbloppy MAJOR.MINOR.PATCH (OpenVDB X.Y.Z)": this library and the OpenVDB it runs
/// with, as `nonbloppy --version` prints them and writeVdb() records them ("creator").
NONBLOPPY_API std::string versionLine();

} // namespace nonbloppy

#endif // NONBLOPPY_VERSION_H
