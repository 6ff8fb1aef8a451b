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

    def test_allocator_note_names_jemallocs_setting(self):
        """On a CPU rasteriser, a process whose allocator is jemalloc with
        its defaults (Blender links it) gets a note naming MALLOC_CONF; with
        the setting, or with glibc's malloc (which the module tunes itself),
        none. In subprocesses: jemalloc reads MALLOC_CONF at start-up."""
        import os
        import subprocess
        import sys
        if "llvmpipe" not in self.r.gl_info["renderer"] and "softpipe" not in self.r.gl_info["renderer"]:
            self.skipTest("not a CPU rasteriser")
        self.assertEqual(self.r.gl_info["allocator_note"], "")  # this process: glibc
        jemalloc = "/lib/x86_64-linux-gnu/libjemalloc.so.2"
        if not os.path.exists(jemalloc):
            self.skipTest("no libjemalloc (the blender package brings it)")
        code = "import deferred_native as dn; print(repr(dn.Renderer().gl_info['allocator_note']))"
        conf = "muzzy_decay_ms:-1,lg_extent_max_active_fit:20"
        for malloc_conf, expect_note in ((None, True), ("dirty_decay_ms:5000", True), (conf, False)):
            env = dict(os.environ, LD_PRELOAD=jemalloc)
            env.pop("MALLOC_CONF", None)
            if malloc_conf:
                env["MALLOC_CONF"] = malloc_conf
            out = subprocess.run([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, text=True,
                                 timeout=120, check=True).stdout.strip()
            if expect_note:
                self.assertIn(f"MALLOC_CONF={conf}", out, malloc_conf)
            else:
                self.assertEqual(out, "''", malloc_conf)

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


def _lookup3_uint(kx):
    """Cycles' hash_uint (util/hash.h), for the test's expected values."""
    def rot(x, k):
        return ((x << k) | (x >> (32 - k))) & 0xFFFFFFFF
    a = b = c = (0xdeadbeef + (1 << 2) + 13) & 0xFFFFFFFF
    a = (a + kx) & 0xFFFFFFFF
    for x, y, z, k in (("c", "b", None, 14), ("a", "c", None, 11), ("b", "a", None, 25), ("c", "b", None, 16),
                       ("a", "c", None, 4), ("b", "a", None, 14), ("c", "b", None, 24)):
        v = {"a": a, "b": b, "c": c}
        v[x] = ((v[x] ^ v[y]) - rot(v[y], k)) & 0xFFFFFFFF
        a, b, c = v["a"], v["b"], v["c"]
    return c


class MeshAttributes(unittest.TestCase):
    """compute_pointiness / compute_random_per_island (native/src/mesh_attributes.cpp)."""

    def grid(self, n=4):
        s = np.arange(n + 1, dtype=np.float32)
        x, y = np.meshgrid(s, s)
        positions = np.stack([x.ravel(), y.ravel(), np.zeros(x.size, np.float32)], -1).astype(np.float32)
        idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
        edges = np.concatenate([np.stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()], -1),
                                np.stack([idx[:-1, :].ravel(), idx[1:, :].ravel()], -1)]).astype(np.uint32)
        normals = np.tile(np.float32([0, 0, 1]), (len(positions), 1))
        return positions, normals, edges

    def test_a_flat_grid_is_one_half_everywhere(self):
        # Every edge lies in the plane: acos(N . mean edge) = pi / 2.
        p, n, e = self.grid()
        values = dn.compute_pointiness(p, n, e)
        self.assertEqual(values.shape, (len(p),))
        np.testing.assert_allclose(values, 0.5, atol=1e-6)

    def test_a_cube_corner_is_convex(self):
        # A cube's corner: its three edges point away from the outward normal,
        # so N . mean edge < 0 and the value is above 0.5 (Cycles: convex > 0.5).
        p = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], np.float32)
        n = (p - 0.5) / np.linalg.norm(p - 0.5, axis=1, keepdims=True)
        e = np.array([[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6],
                      [3, 7]], np.uint32)
        values = dn.compute_pointiness(p, n.astype(np.float32), e)
        raw = np.arccos(-1 / np.sqrt(3)) / np.pi   # N = (1,1,1)/sqrt 3 against the mean edge -(1,1,1)/3
        np.testing.assert_allclose(values, raw, rtol=1e-5)   # every vertex alike: the blur keeps it

    def test_duplicate_vertices_weld(self):
        # A bumpy grid's last column duplicated (as a seam or a split edge
        # leaves it): the copies weld to the originals and read their value.
        p, n, e = self.grid(2)
        p[:, 2] = np.float32([0.0, 0.3, -0.2, 0.1, 0.5, 0.0, -0.4, 0.2, 0.1])
        seam = [2, 5, 8]
        alone = dn.compute_pointiness(p, n, e)
        values = dn.compute_pointiness(np.concatenate([p, p[seam]]), np.concatenate([n, n[seam]]), e)
        np.testing.assert_allclose(values[len(p):], values[seam], atol=0)
        np.testing.assert_allclose(values[:len(p)], alone, atol=1e-7)

    def test_islands_hash_their_disjoint_set_root(self):
        # Two triangles sharing an edge (one island) and a third apart.
        edges = np.array([[0, 1], [1, 2], [2, 0], [1, 3], [3, 2], [4, 5], [5, 6], [6, 4]], np.uint32)
        first = np.array([0, 1, 4], np.uint32)
        values = dn.compute_random_per_island(7, edges, first)
        # Union by rank in edge order: 0 takes 1, then 2 (and 3); 4 takes 5 and 6.
        # float(hash) / float(0xFFFFFFFF) in float32, as util/hash.h.
        expect = [np.float32(_lookup3_uint(r)) / np.float32(4294967295.0) for r in (0, 0, 4)]
        np.testing.assert_array_equal(values, np.array(expect, np.float32))
        self.assertNotEqual(values[0], values[2])

    def test_an_edge_whose_ends_weld_reads_one(self):
        # A vertex duplicated onto another and joined to it by an edge: the
        # edge has no direction (Cycles normalises a zero vector, NaN, and
        # its clamp turns NaN into -1: acos(-1) / pi = 1) before the blur.
        p, n, e = self.grid(2)
        p2 = np.concatenate([p, p[4:5]])
        n2 = np.concatenate([n, n[4:5]])
        e2 = np.concatenate([e, np.array([[4, 9]], np.uint32)])
        values = dn.compute_pointiness(p2, n2, e2)
        self.assertTrue(np.isfinite(values).all())
        # Vertex 4 (the centre) has 4 real edges and the self edge: raw 1,
        # blurred with its 4 neighbours (0.5 each) and itself twice more.
        self.assertAlmostEqual(float(values[4]), (1.0 + 4 * 0.5 + 2 * 1.0) / 7.0, places=6)
        self.assertEqual(values[9], values[4])

    def test_bad_arrays(self):
        p, n, e = self.grid(1)
        with self.assertRaises(ValueError):
            dn.compute_pointiness(p, n[:2], e)
        with self.assertRaises(ValueError):
            dn.compute_pointiness(p, n, np.array([[0, 99]], np.uint32))
        with self.assertRaises(ValueError):
            dn.compute_random_per_island(2, np.array([[0, 5]], np.uint32), np.array([0], np.uint32))


if __name__ == "__main__":
    unittest.main()
