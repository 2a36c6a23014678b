// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: readMesh() on a .obj file, i.e. the OBJ reader of src/ReadMesh.cc, which
// `nonbloppy inspect` and the library's mesh stages read meshes with (fuzz_ply and fuzz_vtk
// cover readMesh()'s PLY and VTK parsers).
#include "FuzzFile.h"
#include "FuzzReader.h"

#include <nonbloppy/ReadMesh.h>

NONBLOPPY_FUZZ_READER(nonbloppy::readMesh(nonbloppy_fuzz::writeInput(bytes, size, ".obj")))
