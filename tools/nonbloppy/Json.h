// SPDX-License-Identifier: Apache-2.0
/// @file Json.h
/// @brief The two JSON value encoders the tool's outputs share (`inspect --json`, the
///        `--log` lines of a frame sequence): strings and numbers.

#ifndef NONBLOPPY_TOOL_JSON_H
#define NONBLOPPY_TOOL_JSON_H

#include <string>

namespace nonbloppy_tool {

/// @a text as a JSON string literal, quotes included: `"` `\` and control characters
/// escaped, well-formed UTF-8 passed through, and each byte that is not part of it (a
/// Latin-1 file name) written as U+FFFD, so that the result is valid JSON.
std::string jsonString(const std::string& text);

/// @a value as a JSON number in the fewest significant digits (at least 6) that read back
/// to the same double; `null` when not finite (JSON has no NaN or infinity).
std::string jsonNumber(double value);

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_JSON_H
