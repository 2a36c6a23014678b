# SPDX-License-Identifier: Apache-2.0
"""Tests of the Python module `nonbloppy` (python/nonbloppy_python.cc), run by ctest as
python_module with the built module on PYTHONPATH, NONBLOPPY_TEST_DATA_DIR and
NONBLOPPY_CLI_PATH (the command-line tool, whose output the module must match byte for byte).
"""

import math
import os
import pathlib
import signal
import subprocess
import tempfile
import threading
import unittest
import warnings

import numpy as np

import nonbloppy

DATA = os.environ["NONBLOPPY_TEST_DATA_DIR"]
CLI = os.environ["NONBLOPPY_CLI_PATH"]
DAM_BREAK = os.path.join(DATA, "dam_break_frame_23_24389_particles.vtk")
CUBE = os.path.join(DATA, "cube_2366_particles.vtk")
CENTRE = np.array([12.31, -4.17, 0.05])  # away from the origin on purpose


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def one_particle_mesh(**parameters):
    """The paper's method on one particle, r_e = 1, r_0 = 1, h = 0.05: a sphere of radius
    r_e / (1 + r_0) = 0.5 before relaxation."""
    return nonbloppy.build_surface([CENTRE], radius=1.0, threshold=1.0, voxel_size=0.05,
                                   method="paper", **parameters)


class OneParticle(unittest.TestCase):
    def test_the_unrelaxed_surface_is_a_sphere_of_radius_re_over_1_plus_r0(self):
        mesh = one_particle_mesh(iterations=0)
        self.assertGreater(len(mesh.vertices), 1000)
        distances = np.linalg.norm(mesh.vertices - CENTRE, axis=1)
        # Vertices lie on voxel edges, interpolated linearly in phi: within h/10 of the sphere.
        np.testing.assert_allclose(distances, 0.5, atol=0.005)

    def test_each_relaxation_shrinks_it_by_one_minus_c(self):
        before = one_particle_mesh(iterations=0)
        for blend, iterations in [(0.3, 1), (0.3, 2), (0.5, 4)]:
            after = one_particle_mesh(blend=blend, iterations=iterations)
            self.assertEqual(after.faces.tolist(), before.faces.tolist())
            expected = (1 - blend) ** iterations * np.linalg.norm(before.vertices - CENTRE, axis=1)
            np.testing.assert_allclose(np.linalg.norm(after.vertices - CENTRE, axis=1), expected,
                                       rtol=1e-4, err_msg=f"c = {blend}, t = {iterations}")

    def test_normals_point_out_of_the_sphere(self):
        mesh = one_particle_mesh(iterations=0)
        outward = (mesh.vertices - CENTRE) / np.linalg.norm(mesh.vertices - CENTRE, axis=1)[:, None]
        np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, rtol=1e-5)
        self.assertGreater(np.min(np.sum(mesh.normals * outward, axis=1)), 0.99)

    def test_measure_gives_the_spheres_area_and_volume(self):
        measures = one_particle_mesh(iterations=0).measure()
        self.assertTrue(measures["closed"])
        self.assertTrue(measures["manifold"])
        self.assertEqual((measures["boundary_edges"], measures["inconsistent_edges"]), (0, 0))
        # Polygons inscribed in the sphere of radius 0.5 at h = 0.05 fall short of its area by
        # 0.5% and of its volume by 0.9%.
        self.assertAlmostEqual(measures["area"] / (4 * math.pi * 0.25), 1.0, delta=0.01)
        self.assertAlmostEqual(measures["volume"] / (4 / 3 * math.pi * 0.125), 1.0, delta=0.015)

    def test_parameters_report_what_was_used(self):
        parameters = one_particle_mesh(iterations=3, blend=0.25).parameters
        self.assertEqual(parameters["radius"], 1.0)
        self.assertEqual(parameters["threshold"], 1.0)
        self.assertEqual(parameters["voxel_size"], 0.05)
        self.assertEqual(parameters["blend"], 0.25)
        self.assertEqual(parameters["iterations"], 3)
        self.assertEqual(parameters["method"], "paper")


class SameAsTheCommandLine(unittest.TestCase):
    """build_surface() is buildSurface() with the tool's defaults: the same bytes."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def path(self, name):
        return os.path.join(self.tmp.name, name)

    def cli_mesh(self, name, *options):
        subprocess.run([CLI, "mesh", DAM_BREAK, "-o", self.path(name), "-q", *options], check=True)
        return read_bytes(self.path(name))

    def test_defaults_give_the_tools_bytes(self):
        mesh = nonbloppy.build_surface(nonbloppy.read_particles(DAM_BREAK))
        mesh.write(pathlib.Path(self.path("python.ply")))
        self.assertEqual(read_bytes(self.path("python.ply")), self.cli_mesh("cli.ply"))
        self.assertEqual(mesh.particle_count, 24389)

    def test_parameters_and_attributes_give_the_tools_bytes(self):
        mesh = nonbloppy.build_surface(nonbloppy.read_particles(DAM_BREAK), spacing=0.05, blend=0.25,
                                       iterations=3, attributes="all")
        mesh.write(self.path("python.ply"), quads=True)
        self.assertEqual(read_bytes(self.path("python.ply")),
                         self.cli_mesh("cli.ply", "--spacing", "0.05", "--blend", "0.25", "--iterations", "3",
                                       "--attributes", "all", "--quads"))

    def test_too_strong_a_relaxation_warns_as_the_tool_does(self):
        particles = nonbloppy.read_particles(DAM_BREAK)
        with self.assertWarns(nonbloppy.SurfaceWarning) as caught:
            nonbloppy.build_surface(particles, blend=0.4, iterations=3)
        self.assertEqual(str(caught.warning), "blend=0.4, iterations=3 relax too strongly for the threshold to be "
                         "calibrated: flat faces end inside the particles; lower blend or iterations, or give "
                         "spacing to correct the volume")
        result = subprocess.run([CLI, "mesh", DAM_BREAK, "-o", self.path("cli.ply"), "--blend", "0.4",
                                 "--iterations", "3"], check=True, capture_output=True, text=True)
        self.assertIn("relax too strongly", result.stderr)

    def test_a_bare_array_and_one_thread_give_the_same_mesh(self):
        particles = nonbloppy.read_particles(CUBE)
        reference = nonbloppy.build_surface(particles)
        as_float64 = nonbloppy.build_surface(particles.positions.astype(np.float64), threads=1)
        # A transposed copy: numpy's layout does not matter.
        strided = nonbloppy.build_surface(np.asfortranarray(particles.positions))
        for mesh in (as_float64, strided):
            np.testing.assert_array_equal(mesh.vertices, reference.vertices)
            np.testing.assert_array_equal(mesh.triangles, reference.triangles)
            np.testing.assert_array_equal(mesh.normals, reference.normals)


class Sequences(unittest.TestCase):
    def test_pinned_parameters_mesh_other_frames_with_the_first_frames_lengths(self):
        first = nonbloppy.build_surface(nonbloppy.read_particles(DAM_BREAK))
        pinned = first.pinned_parameters
        self.assertEqual(set(pinned), {"radius", "voxel_size", "threshold", "max_step"})
        again = nonbloppy.build_surface(nonbloppy.read_particles(DAM_BREAK), **pinned)
        np.testing.assert_array_equal(again.vertices, first.vertices)
        other = nonbloppy.read_particles(os.path.join(DATA, "dam_break_frame_9_6859_particles.bgeo"))
        alone = nonbloppy.build_surface(other).parameters
        alike = nonbloppy.build_surface(other, **pinned).parameters
        self.assertNotAlmostEqual(alone["radius"], pinned["radius"], places=4)  # the estimate moved
        for name, value in pinned.items():
            self.assertEqual(alike[name], value, name)

    def test_a_given_spacing_is_pinned_too(self):
        mesh = nonbloppy.build_surface(nonbloppy.read_particles(CUBE), spacing=0.1, iterations=1)
        self.assertEqual(mesh.pinned_parameters["spacing"], 0.1)
        self.assertTrue(mesh.parameters["preserve_volume"])


class Arrays(unittest.TestCase):
    def test_read_particles_keeps_every_attribute_in_its_type(self):
        particles = nonbloppy.read_particles(DAM_BREAK)
        self.assertEqual(len(particles), 24389)
        self.assertEqual(particles.positions.shape, (24389, 3))
        self.assertEqual(particles.positions.dtype, np.float32)
        self.assertIn("id", particles.attributes)
        ids = particles.attributes["id"]
        self.assertEqual(ids.shape, (24389,))
        self.assertEqual(np.sort(ids.astype(np.int64)).tolist(), list(range(ids.min(), ids.min() + 24389)))
        self.assertIn("24389 particles", repr(particles))
        from_path = nonbloppy.read_particles(pathlib.Path(DAM_BREAK))  # any os.PathLike
        np.testing.assert_array_equal(from_path.positions, particles.positions)
        with self.assertRaises(TypeError):
            nonbloppy.read_particles(DAM_BREAK.encode())

    def test_mesh_arrays_are_views_that_keep_the_mesh_alive(self):
        mesh = nonbloppy.build_surface(nonbloppy.read_particles(CUBE))
        vertices, triangles, quads, faces = mesh.vertices, mesh.triangles, mesh.quads, mesh.faces
        count = len(vertices)
        self.assertEqual(vertices.dtype, np.float32)
        self.assertEqual((triangles.dtype, quads.dtype, faces.dtype), (np.uint32,) * 3)
        self.assertGreater(len(quads), 0)  # volumeToMesh's quads, kept until written
        self.assertEqual(faces.shape, (len(triangles) + 2 * len(quads), 3))
        np.testing.assert_array_equal(faces[len(triangles)::2], quads[:, [0, 1, 2]])
        np.testing.assert_array_equal(faces[len(triangles) + 1::2], quads[:, [0, 2, 3]])
        del mesh
        self.assertEqual(len(vertices), count)
        self.assertLess(int(faces.max()), count)
        triangles = faces
        # Every edge of the closed surface is shared by exactly two triangles.
        edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
        _, counts = np.unique(edges, axis=0, return_counts=True)
        self.assertEqual(set(counts.tolist()), {2})

    def test_a_constant_attribute_comes_back_exactly_and_ids_stay_integers(self):
        cube = nonbloppy.read_particles(CUBE)
        count = len(cube)
        velocity = np.tile(np.array([0.25, -1.5, 3.0], dtype=np.float32), (count, 1))
        ids = np.arange(count, dtype=np.uint32) + 4_000_000_000
        particles = nonbloppy.Particles(cube.positions, attributes={"velocity": velocity, "id": ids})
        mesh = nonbloppy.build_surface(particles, attributes=["velocity", "id"])
        self.assertEqual(mesh.attributes["velocity"].shape, (len(mesh.vertices), 3))
        np.testing.assert_array_equal(mesh.attributes["velocity"],
                                      np.broadcast_to(velocity[0], (len(mesh.vertices), 3)))
        self.assertEqual(mesh.attributes["id"].dtype, np.int64)
        self.assertTrue(set(mesh.attributes["id"].tolist()) <= set(ids.tolist()))
        self.assertIn("interpolate attributes", mesh.timings)


class Warnings(unittest.TestCase):
    """What diagnoseSurface() finds comes out as nonbloppy.SurfaceWarning, in the tool's words."""

    def warnings_of(self, *args, **parameters):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            nonbloppy.build_surface(*args, **parameters)
        self.assertTrue(all(w.category is nonbloppy.SurfaceWarning for w in caught))
        self.assertTrue(all(w.filename == __file__ for w in caught))  # the caller's line
        return [str(w.message) for w in caught]

    def test_a_mesh_as_asked_warns_of_nothing(self):
        self.assertEqual(self.warnings_of(nonbloppy.read_particles(CUBE)), [])

    def test_an_empty_mesh(self):
        self.assertEqual(self.warnings_of([CENTRE], radius=1.0, threshold=1e30, voxel_size=0.05, method="paper"),
                         ["the mesh is empty: the density of the 1 particle, sampled at voxel_size 0.05, nowhere "
                          "reaches threshold 1e+30"])

    def test_particles_far_from_the_origin(self):
        messages = self.warnings_of([[2.0 ** 20, 0, 0]], radius=1.0, threshold=1.0, voxel_size=0.05,
                                    method="paper", iterations=0)
        self.assertEqual(messages[0], "the particles reach 1048576.0 from the origin, where float positions step by "
                         "0.125, more than 1/8 of the voxel size 0.05: the surface is quantized there, and droplets "
                         "may vanish; move the particles nearer the origin")
        # Vertices snapped to a step of 2.5 voxels: faces with no area.
        self.assertEqual(len(messages), 2)
        self.assertRegex(messages[1], r"^\d+ of the \d+ vertices have no normal \(the faces around them have no "
                                      r"area\)$")

    def test_vertices_without_normals(self):
        messages = self.warnings_of([CENTRE], radius=1.0, threshold=1.0, voxel_size=0.05, method="paper",
                                    blend=1.0, iterations=1)
        self.assertEqual(len(messages), 1)
        self.assertRegex(messages[0], r"^\d+ of the \d+ vertices have no normal \(the faces around them have no "
                                      r"area\): blend=1 collapses droplets onto their particles; lower blend$")

    def test_a_nan_attribute(self):
        cube = nonbloppy.read_particles(CUBE)
        temperature = np.full(len(cube), 300.0, dtype=np.float32)
        temperature[7] = math.nan
        particles = nonbloppy.Particles(cube.positions, attributes={"temperature": temperature})
        messages = self.warnings_of(particles, attributes="all")
        self.assertEqual(len(messages), 1)
        self.assertRegex(messages[0], r"^\d+ of the \d+ vertices have a NaN or infinite 'temperature': particles "
                                      r"near them hold such values$")

    def test_warnings_made_errors_raise(self):
        with warnings.catch_warnings():
            warnings.simplefilter("error", nonbloppy.SurfaceWarning)
            with self.assertRaises(nonbloppy.SurfaceWarning):
                nonbloppy.build_surface([CENTRE], radius=1.0, threshold=1e30, voxel_size=0.05, method="paper")


class ParticleFiles(unittest.TestCase):
    def test_written_particles_read_back_with_their_attributes(self):
        particles = nonbloppy.read_particles(DAM_BREAK)
        with tempfile.TemporaryDirectory() as tmp:
            for name in ("p.ply", "p.vtu", "p.csv", "p.vdb"):
                with self.subTest(name):
                    particles.write(pathlib.Path(tmp, name))
                    back = nonbloppy.read_particles(os.path.join(tmp, name))
                    if name == "p.vdb":  # a points grid holds them leaf by leaf, not in file order
                        order = np.lexsort(particles.positions.T)
                        back_order = np.lexsort(back.positions.T)
                    else:
                        order = back_order = slice(None)
                    np.testing.assert_array_equal(back.positions[back_order], particles.positions[order])
                    for attribute, values in particles.attributes.items():
                        # CSV declares no types: its numbers read back as float64 and int64,
                        # which hold the written values exactly.
                        np.testing.assert_array_equal(back.attributes[attribute][back_order].astype(values.dtype),
                                                      values[order])
            with self.assertRaises(nonbloppy.FileError) as caught:
                particles.write(os.path.join(tmp, "p.obj"))
            self.assertEqual(str(caught.exception), "unknown particle output extension '.obj' (" +
                             os.path.join(tmp, "p.obj") + "); expected .ply, .vtk, .vtu, .xyz, .csv or .vdb")

    def test_crop_keeps_what_a_numpy_mask_keeps(self):
        particles = nonbloppy.read_particles(DAM_BREAK)
        lower, upper = (-10.0, -10.0, -10.0), (0.0, 10.0, 10.0)
        kept = particles.crop(lower, upper)
        inside = np.all((particles.positions >= lower) & (particles.positions <= upper), axis=1)
        self.assertGreater(len(kept), 0)
        self.assertLess(len(kept), len(particles))
        np.testing.assert_array_equal(kept.positions, particles.positions[inside])
        np.testing.assert_array_equal(kept.attributes["id"], particles.attributes["id"][inside])
        with self.assertRaises(nonbloppy.ParameterError) as caught:
            particles.crop((0, 0, 0), (1, -1, 1))
        self.assertEqual(str(caught.exception), "particle box: its minimum y 0 exceeds its maximum -1")


class Errors(unittest.TestCase):
    def test_a_missing_file_is_a_file_error_naming_it(self):
        with self.assertRaises(nonbloppy.FileError) as caught:
            nonbloppy.read_particles("/nonexistent/fluid.vtk")
        self.assertEqual(str(caught.exception), "cannot open /nonexistent/fluid.vtk: No such file or directory")
        self.assertIsInstance(caught.exception, OSError)
        self.assertIsInstance(caught.exception, nonbloppy.Error)

    def test_bad_parameters_are_parameter_errors(self):
        cases = [
            (dict(blend=1.5), "blend must lie in [0,1], got 1.5"),
            (dict(voxel_size=-1.0), "voxel_size must be > 0, got -1"),
            (dict(method="blobby"), "method must be 'faithful' or 'paper', not 'blobby'"),
            (dict(threads=0), "threads must be at least 1, not 0"),
        ]
        for parameters, message in cases:
            with self.subTest(**parameters), self.assertRaises(nonbloppy.ParameterError) as caught:
                nonbloppy.build_surface(np.zeros((10, 3)) + CENTRE, radius=1.0, **parameters)
            self.assertEqual(str(caught.exception), message)
            self.assertIsInstance(caught.exception, ValueError)

    def test_bad_positions_are_refused(self):
        with self.assertRaises(nonbloppy.ParameterError) as caught:
            nonbloppy.build_surface(np.zeros((5, 2)))
        self.assertEqual(str(caught.exception), "positions must have shape (N, 3), not (5, 2)")
        with self.assertRaises(nonbloppy.ParameterError) as caught:
            nonbloppy.build_surface(np.zeros((0, 3)))
        self.assertEqual(str(caught.exception), "no particles to mesh")
        positions = np.zeros((3, 3))
        positions[1, 2] = math.nan
        with self.assertRaises(nonbloppy.ParameterError) as caught:
            nonbloppy.build_surface(positions, radius=1.0)
        self.assertIn("particle 1", str(caught.exception))
        with self.assertRaises(TypeError):
            nonbloppy.build_surface("fluid.vtk")

    def test_bad_attributes_are_refused_before_the_work(self):
        positions = np.zeros((4, 3))
        with self.assertRaises(nonbloppy.ParameterError) as caught:
            nonbloppy.Particles(positions, attributes={"velocity": np.zeros((3, 3))})
        self.assertEqual(str(caught.exception), "attribute 'velocity' has 3 rows for 4 particles")
        with self.assertRaises(nonbloppy.ParameterError) as caught:
            nonbloppy.Particles(positions, attributes={"flag": np.zeros(4, dtype=bool)})
        self.assertEqual(str(caught.exception),
                         "attribute 'flag' has dtype bool; a particle attribute holds int8 to int64, uint8 to "
                         "uint64, float32 or float64 in native byte order")
        particles = nonbloppy.Particles(positions + CENTRE, attributes={"mass": np.ones(4)})
        with self.assertRaises(nonbloppy.ParameterError) as caught:
            nonbloppy.build_surface(particles, radius=1.0, attributes=["velocity"])
        self.assertEqual(str(caught.exception), "unknown attribute 'velocity'; the particles have: mass")
        with self.assertRaises(nonbloppy.ParameterError) as caught:
            nonbloppy.build_surface(positions, attributes="all")
        self.assertEqual(str(caught.exception), "attributes need a nonbloppy.Particles (positions and their "
                                                "attributes), not a bare array of positions")

    def test_a_bad_mesh_name_is_refused_and_nothing_is_written(self):
        mesh = one_particle_mesh(iterations=0)
        with tempfile.TemporaryDirectory() as tmp:
            with self.assertRaises(nonbloppy.FileError) as caught:
                mesh.write(os.path.join(tmp, "mesh.stl"))
            self.assertEqual(str(caught.exception), "unknown mesh file extension '.stl' (" +
                             os.path.join(tmp, "mesh.stl") + "); expected .obj, .ply or .vtk")
            with self.assertRaises(nonbloppy.FileError):
                mesh.write(os.path.join(tmp, "missing", "mesh.ply"))
            self.assertEqual(os.listdir(tmp), [])


class Progress(unittest.TestCase):
    def test_progress_sees_every_stage_in_order(self):
        stages = []
        nonbloppy.build_surface(nonbloppy.read_particles(CUBE),
                                progress=lambda stage, percent: stages.append(stage) if stage not in stages else None)
        self.assertEqual(stages[:5], ["estimate parameters", "index particles", "rasterize density",
                                      "extract surface", "relax vertices"])
        self.assertEqual(stages[-1], "compute normals")

    def test_an_exception_in_the_callback_stops_the_work_and_comes_out(self):
        class Stop(Exception):
            pass
        stages = []

        def progress(stage, percent):
            stages.append(stage)
            if stage == "rasterize density":
                raise Stop("enough")

        with self.assertRaises(Stop):
            nonbloppy.build_surface(nonbloppy.read_particles(DAM_BREAK), progress=progress)
        self.assertEqual(stages[-1], "rasterize density")  # not called again once it raised

    def test_ctrl_c_stops_the_work_with_keyboard_interrupt(self):
        # Eight copies of the dam-break frame (195,112 particles, a few tenths of a second);
        # SIGINT, as a terminal's Ctrl-C sends it, comes 20 ms into the work.
        frame = nonbloppy.read_particles(DAM_BREAK).positions
        size = frame.max(axis=0) - frame.min(axis=0) + 1.0
        copies = np.concatenate([frame + size * np.array(offset) for offset in np.ndindex(2, 2, 2)])
        stages = []
        timers = []

        def progress(stage, percent):
            if not timers:
                timers.append(threading.Timer(0.02, os.kill, (os.getpid(), signal.SIGINT)))
                timers[0].start()
            stages.append(stage)

        with self.assertRaises(KeyboardInterrupt):
            nonbloppy.build_surface(copies, progress=progress)
        timers[0].join()
        self.assertNotIn("compute normals", stages)

if __name__ == "__main__":
    unittest.main(verbosity=2)
