// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: readParticles() on a .bgeo file, i.e. the streaming BGEO reader
// (readBgeoFile in src/ReadBgeo.cc: plain or gzip, through a bounded buffer); fuzz_bgeo
// covers the in-memory parser.
#include "FuzzFile.h"
#include "FuzzReader.h"

#include <nonbloppy/ReadParticles.h>

NONBLOPPY_FUZZ_READER(nonbloppy::readParticles(nonbloppy_fuzz::writeInput(bytes, size, ".bgeo")))
