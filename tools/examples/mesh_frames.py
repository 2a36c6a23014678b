#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Example: mesh the frames of a simulation cache from Python, every frame with the first
frame's lengths (no flicker from a spacing estimate that follows the fluid), carrying the
particles' velocity to the vertices for motion blur where the files have one.

  usage: PYTHONPATH=build/python python3 tools/examples/mesh_frames.py OUT_DIR FRAME_FILE...

Writes OUT_DIR/<frame name>.ply per frame and prints a line per frame: vertices, polygons,
seconds, and the stage that took longest. Ctrl-C stops the frame being meshed.
"""

import os
import sys
import time

import nonbloppy


def main(out_dir, frame_files):
    os.makedirs(out_dir, exist_ok=True)
    pinned = {}  # empty until the first frame is meshed
    for path in frame_files:
        start = time.perf_counter()
        particles = nonbloppy.read_particles(path)
        carried = ["velocity"] if "velocity" in particles.attributes else None
        mesh = nonbloppy.build_surface(particles, attributes=carried, **pinned)
        pinned = pinned or mesh.pinned_parameters
        name = os.path.basename(path).split(".")[0]
        mesh.write(os.path.join(out_dir, name + ".ply"))
        slowest = max(mesh.timings, key=mesh.timings.get)
        print(f"{name}: {len(particles)} particles -> {len(mesh.vertices)} vertices, "
              f"{len(mesh.faces)} triangles, {time.perf_counter() - start:.2f} s (longest: {slowest}), "
              f"radius {mesh.parameters['radius']:.6g}")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: mesh_frames.py OUT_DIR FRAME_FILE...")
    try:
        main(sys.argv[1], sys.argv[2:])
    except nonbloppy.Error as error:  # a bad file or parameter: its one-line message
        sys.exit(f"mesh_frames.py: {error}")
