// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the legacy VTK parser (particles and polygons) on arbitrary bytes.
#include "FileFormats.h"
#include "FuzzReader.h"

NONBLOPPY_FUZZ_READER(nonbloppy::io_internal::parseVtk(data, size, "fuzz", /*wantPolygons=*/size % 2 == 0))
