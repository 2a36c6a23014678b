// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: readParticles() on a .ply file, i.e. the streaming PLY reader of
// src/ReadParticles.cc (fuzz_ply covers the in-memory parser readMesh() uses).
#include "FuzzFile.h"
#include "FuzzReader.h"

#include <nonbloppy/ReadParticles.h>

NONBLOPPY_FUZZ_READER(nonbloppy::readParticles(nonbloppy_fuzz::writeInput(bytes, size, ".ply")))
