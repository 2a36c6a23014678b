// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the PLY parser (vertices and faces) on arbitrary bytes.
#include "FileFormats.h"
#include "FuzzReader.h"

NONBLOPPY_FUZZ_READER(nonbloppy::io_internal::parsePly(data, size, "fuzz", /*wantFaces=*/size % 2 == 0))
