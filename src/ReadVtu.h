// SPDX-License-Identifier: Apache-2.0
/// @file ReadVtu.h
/// @brief Private: the streaming VTK XML particle reader (`.vtu`, `.vtp`) by path, and a
///        buffer entry point with an adjustable parser feed size for the tests.
///
/// readVtuParticles() (ParticleReaders.h) runs the same code over a memory block; all three
/// give the same particles and, word for word, the same errors.

#ifndef NONBLOPPY_READ_VTU_H
#define NONBLOPPY_READ_VTU_H

#include <nonbloppy/Particles.h>

#include <cstddef>
#include <string>

namespace nonbloppy {
namespace io_internal {

/// The particles of the VTK XML file @a path, read without holding the file: the XML goes
/// through expat in chunks of kChunkBytes, inline arrays are decoded from the parser's
/// character data straight into the ParticleSet, and appended arrays are read from their
/// offsets afterwards (raw ones with pread() directly into the final arrays). A pipe or
/// other non-regular file, which cannot be seeked, is read whole first.
/// @throw FileError naming @a path.
ParticleSet readVtuFile(const std::string& path);

/// readVtuParticles() feeding the XML parser @a feedBytes bytes at a time (at least 1), so
/// tests can split inline data over many character-data callbacks.
ParticleSet readVtuBuffer(const char* data, size_t size, const std::string& path,
                          size_t feedBytes);

} // namespace io_internal
} // namespace nonbloppy

#endif // NONBLOPPY_READ_VTU_H
