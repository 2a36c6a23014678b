// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: io_internal::readBgeoParticles on arbitrary bytes.
#include "FuzzReader.h"
#include "ParticleReaders.h"

NONBLOPPY_FUZZ_READER(nonbloppy::io_internal::readBgeoParticles(data, size, "fuzz"))
