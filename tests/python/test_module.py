"""The pybind11 module on its own (no Blender): numpy in without copies,
clear ValueErrors for bad arrays, native errors as exceptions, passes out as
float32 arrays. Run with /usr/bin/python3.11 (Blender's Python)."""
import threading
import time
import unittest

import numpy as np

import deferred_native as dn


def plane(half=2.0):
    positions = np.array([[-half, -half, 0], [half, -half, 0], [half, half, 0], [-half, half, 0]], np.float32)
    indices = np.array([[0, 1, 2], [0, 2, 3]], np.uint32)
    normals = np.tile(np.array([0, 0, 1], np.float32), (6, 1))
    return positions, indices, normals


def camera(height=5.0):
    m = np.eye(4)
    m[2, 3] = height
    return dn.Camera(type="ORTHO", matrix=m, ortho_scale=4.0, clip_start=0.01, clip_end=100.0)


class ModuleTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.r = dn.Renderer()

    def setUp(self):
        self.r.clear_scene()

    def test_gl_info(self):
        info = self.r.gl_info
        self.assertTrue(info["version"].startswith("4."), info)
        self.assertTrue(info["renderer"])

    def test_render_returns_float32_passes(self):
        p, i, n = plane()
        mesh = self.r.add_mesh(p, i, corner_normals=n)
        mat = self.r.add_material(base_color=(0.5, 0.5, 0.5), pass_index=3)
        self.r.add_instances(mesh, np.eye(4)[None], object_indices=np.array([9], np.uint32), material_slots=[mat])
        self.r.add_light(type="SUN", energy=2.0)
        out = self.r.render(camera(), 8, 6, passes=["Combined", "Depth", "IndexOB", "IndexMA"])
        self.assertEqual(set(out), {"Combined", "Depth", "IndexOB", "IndexMA"})
        self.assertEqual(out["Combined"].shape, (6, 8, 4))
        self.assertEqual(out["Combined"].dtype, np.float32)
        self.assertEqual(out["Depth"].shape, (6, 8, 1))
        np.testing.assert_allclose(out["Depth"], 5.0, rtol=1e-6)
        np.testing.assert_array_equal(out["IndexOB"], 9.0)
        np.testing.assert_array_equal(out["IndexMA"], 3.0)
        self.assertGreater(out["Combined"][..., 0].min(), 0.0)
        self.assertIn("lighting_ms", self.r.last_timings)

    def test_world_graph(self):
        """A world graph is baked (a constant Background seen by the camera)
        and one that cannot compile renders the fallback colour, warned."""
        background = {"nodes": [{"func": "node_emission", "args": [("const", "color", 0), ("const", "float", 3)],
                                 "outputs": ["closure"]}],
                      "surface": (0, 0), "constants": [0.25, 0.5, 1.0, 2.0], "images": [], "attributes": []}
        self.r.set_world(color=(0.0, 0.0, 0.0), graph=background)
        out = self.r.render(camera(), 8, 6, passes=["Combined", "Env"])
        np.testing.assert_allclose(out["Combined"][..., :3], np.broadcast_to([0.5, 1.0, 2.0], (6, 8, 3)), rtol=1e-6)
        np.testing.assert_allclose(out["Env"][..., :3], out["Combined"][..., :3], rtol=1e-6)
        self.assertGreater(self.r.last_timings["world_map_width"], 0)
        broken = dict(background, nodes=[{"func": "node_not_in_the_library", "args": [], "outputs": ["closure"]}])
        self.r.clear_scene()
        self.r.set_world(color=(0.1, 0.2, 0.3), graph=broken)
        out = self.r.render(camera(), 8, 6, passes=["Combined"])
        np.testing.assert_allclose(out["Combined"][..., :3], np.broadcast_to([0.1, 0.2, 0.3], (6, 8, 3)), rtol=1e-6)
        self.assertTrue(any("World" in w for w in self.r.last_warnings), self.r.last_warnings)
        self.assertEqual(self.r.last_timings["world_map_width"], 0)

    def test_bad_arrays_raise_value_error_naming_the_array(self):
        p, i, n = plane()
        cases = [
            (dict(positions=p.astype(np.float64), indices=i), "positions"),
            (dict(positions=p[:, :2].copy(), indices=i), "positions"),
            (dict(positions=p, indices=i.astype(np.int64)), "indices"),
            (dict(positions=p, indices=np.array([[0, 1, 7]], np.uint32)), "indices"),
            (dict(positions=p, indices=i, corner_normals=n[:5].copy()), "corner_normals"),
            (dict(positions=p, indices=i, material_indices=np.array([0], np.int32)), "material_indices"),
            (dict(positions=np.array([[np.nan, 0, 0]] * 4, np.float32), indices=i), "positions"),
            (dict(positions=p[:, ::-1], indices=i), "positions"),  # not C-contiguous
        ]
        for kwargs, name in cases:
            with self.assertRaises(ValueError) as ctx:
                self.r.add_mesh(**kwargs)
            self.assertIn(name, str(ctx.exception))

    def test_material_slot_out_of_range(self):
        p, i, n = plane()
        mesh = self.r.add_mesh(p, i, material_indices=np.array([0, 2], np.int32))
        mat = self.r.add_material()
        with self.assertRaises(ValueError) as ctx:
            self.r.add_instances(mesh, np.eye(4)[None], material_slots=[mat])
        self.assertIn("slot", str(ctx.exception))

    def test_unknown_pass_and_bad_resolution(self):
        with self.assertRaises(ValueError):
            self.r.render(camera(), 4, 4, passes=["Combined", "Nope"])
        with self.assertRaises(ValueError) as ctx:
            self.r.render(camera(), 100000, 100000)
        self.assertIn("100000x100000", str(ctx.exception))

    def test_fov_equals_lens(self):
        p, i, n = plane(20.0)
        mesh = self.r.add_mesh(p, i, corner_normals=n)
        self.r.add_instances(mesh, np.eye(4)[None], material_slots=[self.r.add_material()])
        m = np.eye(4)
        m[2, 3] = 5.0
        pos_lens = self.r.render(dn.Camera(matrix=m, lens=35.0), 16, 9, passes=["Position"])["Position"]
        fov = 2.0 * np.arctan(36.0 / (2.0 * 35.0))
        pos_fov = self.r.render(dn.Camera(matrix=m, fov=fov, lens=99.0), 16, 9, passes=["Position"])["Position"]
        np.testing.assert_allclose(pos_fov, pos_lens, atol=1e-5)

    def test_cancel_stops_a_running_render(self):
        p, i, n = plane()
        mesh = self.r.add_mesh(p, i, corner_normals=n)
        self.r.add_instances(mesh, np.eye(4)[None], material_slots=[self.r.add_material()])
        self.r.add_light(type="AREA", size=1.0, energy=50.0, matrix=np.array(
            [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]], float))
        outcome = {}

        def work():
            try:
                self.r.render(camera(), 256, 256, samples=4096)
                outcome["done"] = True
            except dn.Cancelled:
                outcome["cancelled"] = True

        t = threading.Thread(target=work)
        t.start()
        # Keep asking until the render (4096 samples: minutes here) stops; a
        # cancel that arrives before render() starts is cleared by it.
        deadline = time.monotonic() + 60
        while t.is_alive() and time.monotonic() < deadline:
            self.r.cancel()
            t.join(0.05)
        self.assertFalse(t.is_alive())
        self.assertEqual(outcome, {"cancelled": True})
        # The renderer stays usable.
        out = self.r.render(camera(), 8, 8)
        self.assertEqual(out["Combined"].shape, (8, 8, 4))

    def test_bad_device_index_is_native_error(self):
        with self.assertRaises(dn.Error) as ctx:
            dn.Renderer(device_index=999)
        self.assertIn("EGL device 999", str(ctx.exception))

    def test_gil_released_while_rendering(self):
        p, i, n = plane()
        mesh = self.r.add_mesh(p, i, corner_normals=n)
        self.r.add_instances(mesh, np.eye(4)[None], material_slots=[self.r.add_material()])
        self.r.add_light(type="AREA", size=1.0, energy=50.0, matrix=np.array(
            [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]], float))
        ticks = []
        done = threading.Event()

        def count():
            while not done.is_set():
                ticks.append(1)
                done.wait(0.001)

        t = threading.Thread(target=count)
        t.start()
        self.r.render(camera(), 256, 256, samples=64)
        done.set()
        t.join()
        # A Python thread ran while the native render was going on.
        self.assertGreater(len(ticks), 5)


if __name__ == "__main__":
    unittest.main()
