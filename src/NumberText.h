// SPDX-License-Identifier: Apache-2.0
/// @file NumberText.h
/// @brief Private: how parameter errors spell a number next to the limit it broke.
#ifndef NONBLOPPY_NUMBER_TEXT_H
#define NONBLOPPY_NUMBER_TEXT_H

#include <charconv>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>

namespace nonbloppy {
namespace number_text_internal {

/// %g with 6 significant digits, as errors and summaries print numbers ("0.05", "1.5e-05").
inline std::string sixDigits(double value)
{
    if (std::isnan(value)) return "nan";  // whatever its sign bit ("-nan")
    std::ostringstream out;
    out << value;
    return out.str();
}

/// @a value, which broke @a limit, as its error prints it: sixDigits(), unless that reads as
/// the limit itself; then the shortest text that reads back as exactly @a value. Six digits
/// alone answered a blend of 1.0000001 with "--blend must lie in [0,1], got 1", and a
/// derived voxel size of 1.499995e-05 with "1.5e-05 is below 1.5e-05" (bug hunt).
inline std::string numberBeside(double value, double limit)
{
    const std::string text = sixDigits(value);
    if (value == limit || text != sixDigits(limit)) return text;
    char digits[32];
    const auto result = std::to_chars(digits, digits + sizeof(digits), value);
    return std::string(digits, result.ptr);
}

/// Two numbers an error compares, both printed: numberBeside() each against the other, so
/// that 0.09999997 and 0.09999996 do not read "0.09999997 is too large for 0.1" (review).
inline std::pair<std::string, std::string> numbersApart(double a, double b)
{
    return {numberBeside(a, b), numberBeside(b, a)};
}

} // namespace number_text_internal
} // namespace nonbloppy

#endif // NONBLOPPY_NUMBER_TEXT_H
