// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: readParticles() on a .csv file, i.e. the streaming table reader
// (readTableFile in src/ReadTable.cc, which reads .txt files too); fuzz_table covers the
// in-memory parser.
#include "FuzzFile.h"
#include "FuzzReader.h"

#include <nonbloppy/ReadParticles.h>

NONBLOPPY_FUZZ_READER(nonbloppy::readParticles(nonbloppy_fuzz::writeInput(bytes, size, ".csv")))
