// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: io_internal::readJsonParticles on arbitrary bytes, and a differential
// check of its two ways of reading: the usual `[[x, y, z], ...]` is read without nlohmann,
// anything else by nlohmann, which a UTF-8 byte order mark in front forces (it skips it).
// Both must accept the same texts with the same position bits; an error either way must be
// an error the other way too.
#include "FuzzReader.h"
#include "ParticleReaders.h"

#include <cstdlib>
#include <string>

namespace {

/// The positions read from @a text, or false with an error.
bool readPositions(const std::string& text, std::string& bits)
{
    try {
        const nonbloppy::ParticleSet particles = nonbloppy::io_internal::readJsonParticles(text.data(), text.size(), "fuzz");
        bits.assign(reinterpret_cast<const char*>(particles.positions.data()), particles.positions.size() * 12);
        return true;
    } catch (const nonbloppy::Error&) {
        return false;
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size)
{
    const std::string text(reinterpret_cast<const char*>(bytes), size);
    std::string direct, throughNlohmann;
    const bool directOk = readPositions(text, direct);
    if (size > 0 && bytes[0] == 0xef) return 0;  // a byte order mark already, or its start
    const bool nlohmannOk = readPositions("\xef\xbb\xbf" + text, throughNlohmann);
    if (directOk != nlohmannOk || direct != throughNlohmann) std::abort();
    return 0;
}
