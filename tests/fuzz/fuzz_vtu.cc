// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: io_internal::readVtuParticles on arbitrary bytes, fed to the streaming
// XML parser in 1 MiB chunks and again 1 to 13 bytes at a time. Only nonbloppy::Error is an
// accepted outcome, and both runs must agree — the same particles or the same message —
// since what the decoders make of inline data must not depend on where expat splits it.
// (XML errors only need to be XML errors on both: expat places some of them differently
// when a bad token is split between two calls.)
#include "ParticleReaders.h"
#include "ReadVtu.h"

#include <nonbloppy/Error.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

/// The message of the nonbloppy::Error @a read throws, or "" with its particles in @a out.
template<typename ReadT>
std::string
outcomeOf(ReadT&& read, nonbloppy::ParticleSet& out)
{
    try {
        out = read();
        return std::string();
    } catch (const nonbloppy::Error& error) {
        return std::string("error: ") + error.what();
    }
}

/// True if @a a and @a b hold the same positions and attributes, byte for byte (NaN
/// coordinates included, which compare unequal as values).
bool
sameParticles(const nonbloppy::ParticleSet& a, const nonbloppy::ParticleSet& b)
{
    if (a.positions.size() != b.positions.size() || a.attributes.size() != b.attributes.size()
        || (!a.positions.empty() && std::memcmp(a.positions.data(), b.positions.data(),
                                                a.positions.size() * sizeof(a.positions[0])) != 0)) {
        return false;
    }
    for (size_t k = 0; k < a.attributes.size(); ++k) {
        const nonbloppy::ParticleAttribute& x = a.attributes[k];
        const nonbloppy::ParticleAttribute& y = b.attributes[k];
        if (x.name != y.name || x.type != y.type || x.components != y.components || x.bytes != y.bytes) {
            return false;
        }
    }
    return true;
}

/// True if @a a and @a b are the same outcome (any two XML errors count as the same).
bool
sameOutcome(const std::string& a, const std::string& b)
{
    const std::string xml = "error: XML error at byte ";
    return a == b || (a.compare(0, xml.size(), xml) == 0 && b.compare(0, xml.size(), xml) == 0);
}

} // namespace

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size)
{
    namespace io = nonbloppy::io_internal;
    const char* data = reinterpret_cast<const char*>(bytes);
    nonbloppy::ParticleSet whole, split;
    const std::string wholeOutcome = outcomeOf([&] { return io::readVtuParticles(data, size, "fuzz"); }, whole);
    const size_t feed = 1 + (size > 0 ? bytes[size / 2] % 13 : 0);
    const std::string splitOutcome = outcomeOf([&] { return io::readVtuBuffer(data, size, "fuzz", feed); }, split);
    if (!sameOutcome(wholeOutcome, splitOutcome) || !sameParticles(whole, split)) {
        std::fprintf(stderr, "fuzz_vtu: fed %zu bytes at a time the reader gave\n  %s\ninstead of\n  %s\n", feed,
                     splitOutcome.empty() ? "particles" : splitOutcome.c_str(),
                     wholeOutcome.empty() ? "particles" : wholeOutcome.c_str());
        std::abort();
    }
    return 0;
}
