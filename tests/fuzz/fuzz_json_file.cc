// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: readParticles() on a .json file, i.e. the streaming JSON particle-list
// reader (readJsonFile in src/ReadTable.cc); fuzz_json covers the in-memory parser.
#include "FuzzFile.h"
#include "FuzzReader.h"

#include <nonbloppy/ReadParticles.h>

NONBLOPPY_FUZZ_READER(nonbloppy::readParticles(nonbloppy_fuzz::writeInput(bytes, size, ".json")))
