// SPDX-License-Identifier: Apache-2.0
#include "Json.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace nonbloppy_tool {

namespace {

/// Length of the well-formed UTF-8 sequence starting at @a text[at] (1 to 4), or 0 if the
/// bytes there are not one: a stray continuation byte, a truncated sequence, an overlong
/// encoding, a surrogate (U+D800-DFFF) or a code point above U+10FFFF (RFC 3629).
size_t utf8SequenceLength(const std::string& text, size_t at)
{
    const auto byte = [&](size_t n) { return static_cast<unsigned char>(text[n]); };
    const unsigned char lead = byte(at);
    size_t length = 0;
    unsigned char low = 0x80, high = 0xbf;  // allowed range of the second byte
    if (lead < 0x80) return 1;
    if (lead >= 0xc2 && lead <= 0xdf) length = 2;
    else if (lead >= 0xe0 && lead <= 0xef) {
        length = 3;
        if (lead == 0xe0) low = 0xa0;   // overlong
        if (lead == 0xed) high = 0x9f;  // surrogates
    } else if (lead >= 0xf0 && lead <= 0xf4) {
        length = 4;
        if (lead == 0xf0) low = 0x90;   // overlong
        if (lead == 0xf4) high = 0x8f;  // above U+10FFFF
    } else {
        return 0;
    }
    if (at + length > text.size()) return 0;
    if (byte(at + 1) < low || byte(at + 1) > high) return 0;
    for (size_t n = 2; n < length; ++n) {
        if (byte(at + n) < 0x80 || byte(at + n) > 0xbf) return 0;
    }
    return length;
}

} // namespace

std::string jsonString(const std::string& text)
{
    std::string out = "\"";
    for (size_t at = 0; at < text.size();) {
        // JSON text is Unicode: a byte that is not part of well-formed UTF-8 (a Latin-1 file
        // name, say) becomes U+FFFD, as Python's errors="replace" does.
        const size_t length = utf8SequenceLength(text, at);
        if (length == 0) {
            out += "\\ufffd";
            ++at;
            continue;
        }
        if (length > 1) {
            out.append(text, at, length);
            at += length;
            continue;
        }
        const char ch = text[at++];
        const unsigned char c = static_cast<unsigned char>(ch);
        switch (c) {
        case '"': out += "\\\""; break;
        case '\\': out += "\\\\"; break;
        case '\n': out += "\\n"; break;
        case '\r': out += "\\r"; break;
        case '\t': out += "\\t"; break;
        case '\b': out += "\\b"; break;
        case '\f': out += "\\f"; break;
        default:
            if (c < 0x20 || c == 0x7f) {
                char buffer[8];
                std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
                out += buffer;
            } else {
                out += ch;
            }
        }
    }
    return out + "\"";
}

std::string jsonNumber(double value)
{
    if (!std::isfinite(value)) return "null";
    // Six digits read well ("100", not "1e+02"); more only where the value needs them.
    char buffer[40];
    for (int precision = 6; precision <= 17; ++precision) {
        std::snprintf(buffer, sizeof(buffer), "%.*g", precision, value);
        if (std::strtod(buffer, nullptr) == value) break;
    }
    return buffer;
}

} // namespace nonbloppy_tool
