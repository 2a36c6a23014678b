// SPDX-License-Identifier: Apache-2.0
/// @file NumberOptions.h
/// @brief Numbers on the command line, read as decimal text only and checked for double's
///        range, and the --particle-box option that `mesh` and `convert` share.

#ifndef NONBLOPPY_TOOL_NUMBER_OPTIONS_H
#define NONBLOPPY_TOOL_NUMBER_OPTIONS_H

#include <CLI/CLI.hpp>
#include <openvdb/Types.h>

#include <optional>
#include <string>
#include <vector>

namespace nonbloppy_tool {

/// Read @a option's values as decimal numbers only (integers if @a integer), before CLI11
/// converts them: CLI11 reads integers with strtoll in base 0, so "-t 010" ran 8 iterations
/// (octal), "-t 08" was "out of range" and "-t 0x10" 16, and reals with strtold, which takes
/// hexadecimal ("--spacing 0x1p-4") and leading blanks too (hostile-input audit). An integer
/// loses its leading zeros ("010" is 10); a real may also be inf or nan (refused or taken by
/// the range checks, with their own messages); an empty value is left to requireNumberText().
/// @throw UsageError("-t needs an integer, got '0x10'"), "--spacing needs a number, got ' 1'".
void readDecimalOnly(CLI::Option* option, bool integer);

/// Throw UsageError("--blend needs a number, got ''") for an empty or blank value of
/// @a option (CLI11 reads '--blend ""' as 0 without a word), and, if @a real,
/// UsageError("--spacing 1e400 lies outside double's range (it reads as infinity)") for a
/// value past double's range (1e-400 reads as 0, 1e400 as inf), unless @a infinityAllowed
/// and the value is +inf.
void requireNumberText(const CLI::Option* option, bool real, bool infinityAllowed = false);

/// --particle-box X0 Y0 Z0 X1 Y1 Z1 (nonbloppy/CropParticles.h): its six values, the option
/// once added.
struct ParticleBoxOption
{
    std::vector<double> values;
    CLI::Option* option = nullptr;

    /// Add the option to @a command (under the Input/output heading), @a what saying what
    /// the kept particles go to.
    void add(CLI::App* command, const std::string& what);
    /// The box, or nullopt where the option was not given. @throw UsageError for a bad value
    /// ("--particle-box: its minimum y -1 exceeds its maximum -2").
    std::optional<openvdb::BBoxd> box() const;
};

/// @a box as the summary and errors give it: "(x0, y0, z0) -> (x1, y1, z1)", each number in
/// the shortest text that reads back as it (the values as given, not rounded to six digits).
std::string formatBox(const openvdb::BBoxd& box);

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_NUMBER_OPTIONS_H
