// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: io_internal::readTableParticles on arbitrary bytes.
#include "FuzzReader.h"
#include "ParticleReaders.h"

NONBLOPPY_FUZZ_READER(nonbloppy::io_internal::readTableParticles(data, size, "fuzz"))
