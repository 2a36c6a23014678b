# SPDX-License-Identifier: Apache-2.0
"""The benchmark's mesh made from Python (run_benchmark.sh): read IN, mesh it with the
benchmark's parameters, write OUT, as `nonbloppy mesh IN -o OUT --voxel-size 0.025
--radius 0.1 --blend 0.3 --iterations 2` does (the same bytes).

  usage: PYTHONPATH=build/python python3 tests/bench/mesh_from_python.py IN OUT
"""

import sys

import nonbloppy

particles = nonbloppy.read_particles(sys.argv[1])
mesh = nonbloppy.build_surface(particles, voxel_size=0.025, radius=0.1, blend=0.3, iterations=2)
mesh.write(sys.argv[2])
