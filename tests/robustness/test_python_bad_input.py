"""Bad input through the Python module (issue 7): every wrong shape, dtype,
range or type is a ValueError naming the argument and the problem; device
errors are deferred_native.Error; a refused call leaves the scene as it was;
random garbage never crashes and never gets past validation.

Run with Blender's Python (CTest: robustness_python):

    PYTHONPATH=build/blender_scripts/addons/deferred_render \
        /usr/bin/python3.11 -m unittest -v tests/robustness/test_python_bad_input.py

DEFERRED_FUZZ_SEED sets the seed of the random part (printed).
"""
import os
import random
import subprocess
import sys
import unittest

import numpy as np

import deferred_native as dn

NAN, INF = float("nan"), float("inf")


def plane():
    positions = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    indices = np.array([[0, 1, 2], [0, 2, 3]], np.uint32)
    normals = np.tile(np.array([0, 0, 1], np.float32), (6, 1))
    uvs = np.zeros((6, 2), np.float32)
    mats = np.zeros(2, np.int32)
    return positions, indices, normals, uvs, mats


def top_camera():
    m = np.eye(4)
    m[2, 3] = 3.0
    return dn.Camera(type="ORTHO", matrix=m, ortho_scale=3.0, clip_start=0.01, clip_end=10.0)


class BadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.r = dn.Renderer()

    def setUp(self):
        self.r.clear_scene()

    def assertRefused(self, call, *needles):
        with self.assertRaises(ValueError) as ctx:
            call()
        message = str(ctx.exception)
        for needle in needles:
            self.assertIn(needle, message, f"message was: {message}")
        return message

    def test_arrays_through_pickle(self):
        """An array that came through pickle (another process, a capture)
        has a dtype equal to float32 but not the same object: accepted."""
        import pickle
        p, i, n, uv, m = plane()
        p2, i2 = pickle.loads(pickle.dumps((p, i)))
        self.assertIsNot(p2.dtype, np.dtype(np.float32))
        self.assertEqual(self.r.add_mesh(p2, i2), 0)

    def test_mesh_arrays(self):
        p, i, n, uv, m = plane()
        r = self.r
        cases = [
            (lambda: r.add_mesh(p.astype(np.float64), i), "positions", "dtype float32"),
            (lambda: r.add_mesh(p.astype(">f4"), i), "positions", "dtype float32"),  # big-endian
            (lambda: r.add_mesh(p.tolist(), i), "positions", "numpy array"),
            (lambda: r.add_mesh(None, i), "positions", "numpy array"),
            (lambda: r.add_mesh(p[:, :2].copy(), i), "positions", "dimension 1 must be 3"),
            (lambda: r.add_mesh(p.reshape(-1), i), "positions", "shape (N,3)"),
            (lambda: r.add_mesh(np.asfortranarray(p), i), "positions", "C-contiguous"),
            (lambda: r.add_mesh(p, i.astype(np.int32)), "indices", "dtype uint32"),
            (lambda: r.add_mesh(p, i.astype(np.int64)), "indices", "dtype uint32"),
            (lambda: r.add_mesh(p, i.reshape(3, 2).copy()), "indices", "dimension 1 must be 3"),
            (lambda: r.add_mesh(p, np.array([[0, 1, 4]], np.uint32)), "indices", "out of range for 4 vertices"),
            (lambda: r.add_mesh(p, np.array([[0, 1, 2**32 - 1]], np.uint32)), "indices", "out of range"),
            (lambda: r.add_mesh(p, i, corner_normals=n[:4].copy()), "corner_normals", "expected 6 rows"),
            (lambda: r.add_mesh(p, i, corner_normals=n.astype(np.float16)), "corner_normals", "dtype"),
            (lambda: r.add_mesh(p, i, corner_uvs=uv[:, :1].copy()), "corner_uvs", "dimension 1 must be 2"),
            (lambda: r.add_mesh(p, i, corner_uvs=np.zeros((5, 2), np.float32)), "corner_uvs", "expected 6 rows"),
            (lambda: r.add_mesh(p, i, material_indices=m.astype(np.uint32)), "material_indices", "dtype int32"),
            (lambda: r.add_mesh(p, i, material_indices=np.zeros(3, np.int32)), "material_indices", "expected 2 values"),
            (lambda: r.add_mesh(p, i, material_indices=np.array([0, -1], np.int32)), "material_indices", "negative"),
        ]
        for poison in (NAN, INF, -INF):
            bad = p.copy()
            bad[2, 1] = poison
            cases.append((lambda bad=bad: r.add_mesh(bad, i), "positions", "element 7"))
            bad_n = n.copy()
            bad_n[5, 2] = poison
            cases.append((lambda bad_n=bad_n: r.add_mesh(p, i, corner_normals=bad_n), "corner_normals", "NaN or infinite"))
            bad_uv = uv.copy()
            bad_uv[0, 0] = poison
            cases.append((lambda bad_uv=bad_uv: r.add_mesh(p, i, corner_uvs=bad_uv), "corner_uvs", "NaN or infinite"))
        far = p.copy()
        far[0, 0] = 1e16
        cases.append((lambda: r.add_mesh(far, i), "positions", "exceeds the limit"))
        for call, *needles in cases:
            with self.subTest(needles=needles):
                self.assertRefused(call, *needles)
        # Nothing half-added: the next mesh gets id 0.
        self.assertEqual(r.add_mesh(p, i), 0)
        # Empty meshes are fine.
        self.assertEqual(r.add_mesh(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32)), 1)

    def test_instances(self):
        p, i, n, uv, _ = plane()
        r = self.r
        mesh = r.add_mesh(p, i, material_indices=np.array([0, 2], np.int32))
        mat = r.add_material()
        eye = np.eye(4)[None]
        self.assertRefused(lambda: r.add_instances(mesh, eye, material_slots=[mat]), "material_indices", "uses slot 2",
                           "1 material slot")
        self.assertRefused(lambda: r.add_instances(mesh, eye, material_slots=[mat, mat, 5]), "material_slots",
                           "material id 5 does not exist")
        self.assertRefused(lambda: r.add_instances(mesh, eye, material_slots=[mat, -1, mat]), "material_slots",
                           "element 1", "out of range")
        self.assertRefused(lambda: r.add_instances(mesh, eye, material_slots=["a", 0, 0]), "material_slots",
                           "expected an integer")
        self.assertRefused(lambda: r.add_instances(mesh, eye, material_slots=3), "material_slots")
        self.assertRefused(lambda: r.add_instances(-1, eye), "mesh_id", "out of range")
        self.assertRefused(lambda: r.add_instances(7, eye), "mesh id 7 does not exist")
        self.assertRefused(lambda: r.add_instances(1.5, eye), "mesh_id", "expected an integer")
        self.assertRefused(lambda: r.add_instances(mesh, np.eye(4)), "matrices", "shape (N,4,4)")
        self.assertRefused(lambda: r.add_instances(mesh, eye.astype(np.float32)), "matrices", "dtype float64")
        self.assertRefused(lambda: r.add_instances(mesh, np.zeros((1, 3, 4))), "matrices", "dimension 1 must be 4")
        nan = eye.copy()
        nan[0, 1, 3] = NAN
        self.assertRefused(lambda: r.add_instances(mesh, nan, material_slots=[mat] * 3), "matrices", "NaN")
        far = eye.copy()
        far[0, 0, 3] = 1e16
        self.assertRefused(lambda: r.add_instances(mesh, far, material_slots=[mat] * 3), "matrices", "exceeds the limit")
        self.assertRefused(lambda: r.add_instances(mesh, eye, object_indices=np.array([1, 2], np.uint32),
                                                   material_slots=[mat] * 3), "object_indices", "expected 1 values")
        self.assertRefused(lambda: r.add_instances(mesh, eye, object_indices=np.array([-1], np.int32),
                                                   material_slots=[mat] * 3), "object_indices", "dtype uint32")
        # A refused add_instances added nothing: the frame is background only.
        out = r.render(top_camera(), 4, 4, passes=["IndexOB"])
        self.assertTrue((out["Combined"][..., 3] == 1).all())
        self.assertTrue((out["IndexOB"] == 0).all())

    def test_materials_lights_world(self):
        r = self.r
        for kwargs, needles in [
            (dict(base_color=(-1, 0, 0)), ("base_color component 0",)),
            (dict(base_color=(1e6, 0, 0)), ("65504",)),
            (dict(base_color="red"), ("base_color", "expected 3 numbers")),
            (dict(base_color=(1, 2)), ("base_color", "expected 3 numbers")),
            (dict(base_color=(1, "x", 0)), ("base_color", "element 1 is not a number")),
            (dict(roughness=NAN), ("roughness is NaN",)),
            (dict(roughness=1.5), ("roughness = 1.5 is outside [0, 1]",)),
            (dict(metallic=-0.1), ("metallic",)),
            (dict(specular=13.0), ("specular", "[0, 12]")),
            (dict(emission=(INF, 0, 0)), ("emission must be finite",)),
            (dict(emission_strength=-2.0), ("emission_strength",)),
            (dict(alpha=2.0), ("alpha",)),
            (dict(pass_index=-1), ("pass_index", "out of range")),
            (dict(pass_index=2**24), ("pass_index", "2^24")),
        ]:
            with self.subTest(kwargs=kwargs):
                self.assertRefused(lambda: r.add_material(**kwargs), *needles)
        for kwargs, needles in [
            (dict(type="LASER"), ("type 'LASER'",)),
            (dict(type="AREA", shape="STAR"), ("shape 'STAR'",)),
            (dict(color=5), ("color", "expected 3 numbers")),
            (dict(color="abc"), ("color", "expected 3 numbers")),
            (dict(color=(NAN, 0, 0)), ("color must be finite",)),
            (dict(energy=INF), ("energy",)),
            (dict(energy=1e13), ("energy x colour", "exceeds")),
            (dict(radius=-1.0), ("radius",)),
            (dict(spot_size=4.0), ("spot_size",)),
            (dict(spot_blend=-0.5), ("spot_blend",)),
            (dict(angle=7.0), ("angle",)),
            (dict(size=-1.0), ("size",)),
            (dict(matrix=np.full((4, 4), NAN)), ("matrix", "NaN")),
            (dict(matrix=np.eye(3)), ("matrix", "(4, 4)")),
        ]:
            with self.subTest(kwargs=kwargs):
                self.assertRefused(lambda: r.add_light(**kwargs), *needles)
        # Blender allows negative, zero and huge power: accepted.
        for energy in (-100.0, 0.0, 1e9):
            r.add_light(energy=energy)
        self.assertRefused(lambda: r.set_world(color=(NAN, 0, 0)), "world", "finite")
        self.assertRefused(lambda: r.set_world(color=(-1, 0, 0)), "world", "component 0")
        self.assertRefused(lambda: r.set_world(color=(1, 1)), "set_world: color", "expected 3 numbers")

    def test_camera_and_render_settings(self):
        r = self.r
        p, i, *_ = plane()
        r.add_instances(r.add_mesh(p, i), np.eye(4)[None], material_slots=[r.add_material()])
        self.assertRefused(lambda: dn.Camera(type="PANO"), "Camera.type")
        self.assertRefused(lambda: dn.Camera(sensor_fit="DIAGONAL"), "Camera.sensor_fit")
        self.assertRefused(lambda: dn.Camera(matrix=np.full((4, 4), INF)), "Camera.matrix", "NaN/Inf")
        self.assertRefused(lambda: dn.Camera(matrix=np.eye(3)), "Camera.matrix", "(4, 4)")
        self.assertRefused(lambda: dn.Camera(fov=4.0), "Camera.fov")
        for kwargs, needle in [(dict(lens=NAN), "lens"), (dict(lens=0.0), "lens"), (dict(clip_start=1.0, clip_end=0.5), "clip"),
                               (dict(clip_start=1e-9), "clip_start"), (dict(pixel_aspect_x=INF), "pixel aspect"),
                               (dict(shift_x=NAN), "shift"), (dict(lens=1e-40), "float32")]:
            with self.subTest(kwargs=kwargs):
                self.assertRefused(lambda: r.render(dn.Camera(**kwargs), 4, 4), "camera", needle)
        cam = top_camera()
        self.assertRefused(lambda: r.render(cam, 0, 4), "resolution 0x4")
        self.assertRefused(lambda: r.render(cam, 4, -3), "resolution 4x-3")
        self.assertRefused(lambda: r.render(cam, 16000, 16000), "16000x16000", "budget")
        self.assertRefused(lambda: r.render(cam, 4, 4, passes=["Depth", "Bogus"]), "unknown pass 'Bogus'")
        self.assertRefused(lambda: r.render(cam, 4, 4, samples=0), "samples")
        self.assertRefused(lambda: r.render(cam, 4, 4, filter_width=NAN), "filter_width")
        self.assertRefused(lambda: r.render(cam, 4, 4, mist_falloff="CUBIC"), "mist_falloff")
        # The renderer still renders after all of that.
        out = r.render(cam, 1, 1, passes=["Depth"])
        self.assertAlmostEqual(float(out["Depth"][0, 0, 0]), 3.0, places=5)

    def test_device_errors_are_native_errors_and_recoverable(self):
        with self.assertRaises(dn.Error) as ctx:
            dn.Renderer(device_index=999)
        self.assertIn("EGL device 999", str(ctx.exception))
        self.assertNotIsInstance(ctx.exception, ValueError)
        # The process (and other renderers) keep working.
        out = self.r.render(top_camera(), 2, 2)
        self.assertEqual(out["Combined"].shape, (2, 2, 4))
        other = dn.Renderer()
        other.close()

    def test_egl_unavailable_in_a_subprocess(self):
        # No EGL vendor library at all (libglvnd finds none), and a bad
        # DEFERRED_EGL_DEVICE: a clear Python exception, a normal exit.
        script = ("import deferred_native as dn\n"
                  "try:\n    dn.Renderer()\nexcept dn.Error as e:\n    print('ERROR:', e)\n"
                  "else:\n    print('NO ERROR')\n")
        for env_extra, expect in [({"__EGL_VENDOR_LIBRARY_FILENAMES": "/nonexistent.json"}, "ERROR: "),
                                  ({"DEFERRED_EGL_DEVICE": "gpu0"}, "DEFERRED_EGL_DEVICE='gpu0'"),
                                  ({"DEFERRED_EGL_DEVICE": "77"}, "EGL device 77")]:
            env = dict(os.environ, **env_extra)
            proc = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=120)
            with self.subTest(env=env_extra):
                print(f"  {env_extra}: exit {proc.returncode}: {proc.stdout.strip()[:160]}")
                self.assertEqual(proc.returncode, 0, proc.stderr[-2000:])
                self.assertIn(expect, proc.stdout)

    def test_random_garbage(self):
        """Thousands of calls with random arrays (dtype, shape, order, values):
        only ValueError (or TypeError for a wrong Python type) may come out,
        and a valid render afterwards still works."""
        seed = int(os.environ.get("DEFERRED_FUZZ_SEED", random.SystemRandom().randrange(2**32)))
        print(f"  python garbage fuzz: seed {seed} (DEFERRED_FUZZ_SEED to override)")
        rng = np.random.default_rng(seed)
        r = self.r
        dtypes = [np.float32, np.float64, np.int32, np.uint32, np.int64, np.float16, np.uint8, bool]

        def garbage_array(rows, cols):
            kind = rng.integers(8)
            shape = (rows,) if cols is None else (rows, cols)
            if kind == 0:
                shape = (int(rng.integers(0, 5)), int(rng.integers(0, 5)))
            elif kind == 1:
                shape = shape + (1,)
            dtype = dtypes[int(rng.integers(len(dtypes)))] if rng.random() < 0.3 else None
            a = rng.normal(0, 10, size=shape)
            if rng.random() < 0.1 and a.size:
                a.flat[int(rng.integers(a.size))] = rng.choice([NAN, INF, -INF, 1e30])
            if dtype is not None:
                with np.errstate(all="ignore"):
                    a = a.astype(dtype)
            if rng.random() < 0.1 and a.ndim == 2:
                a = np.asfortranarray(a)
            return a

        outcomes = {"ok": 0, "ValueError": 0, "TypeError": 0}
        calls = int(os.environ.get("DEFERRED_PY_FUZZ_CALLS", "3000"))
        for k in range(calls):
            nv, nt = int(rng.integers(0, 6)), int(rng.integers(0, 4))
            if k % 3 == 0:
                args = (garbage_array(nv, 3).astype(np.float32) if rng.random() < 0.7 else garbage_array(nv, 3),
                        (rng.integers(0, nv + 2, size=(nt, 3)).astype(np.uint32) if rng.random() < 0.7
                         else garbage_array(nt, 3)))
                kwargs = {}
                if rng.random() < 0.5:
                    kwargs["corner_normals"] = garbage_array(nt * 3, 3).astype(np.float32)
                if rng.random() < 0.3:
                    kwargs["corner_uvs"] = garbage_array(nt * 3, 2)
                if rng.random() < 0.3:
                    kwargs["material_indices"] = rng.integers(-1, 3, size=nt).astype(np.int32)
                call = lambda: r.add_mesh(*args, **kwargs)
            elif k % 3 == 1:
                values = {key: float(rng.choice([0, 0.5, 1, -1, 2, 13, NAN, INF, 1e30]))
                          for key in rng.choice(["metallic", "roughness", "specular", "sheen", "clearcoat", "alpha",
                                                 "emission_strength"], size=2)}
                call = lambda: r.add_material(base_color=tuple(rng.choice([0, 1, -1, 1e5, NAN], size=3)), **values)
            else:
                m = rng.normal(0, 1, size=(int(rng.integers(0, 3)), 4, 4))
                if rng.random() < 0.2 and m.size:
                    m.flat[int(rng.integers(m.size))] = rng.choice([NAN, INF, 1e20])
                call = lambda: r.add_instances(int(rng.integers(-1, 3)), m,
                                               material_slots=list(rng.integers(-1, 3, size=int(rng.integers(0, 4)))))
            try:
                call()
                outcomes["ok"] += 1
            except ValueError:
                outcomes["ValueError"] += 1
            except TypeError:
                outcomes["TypeError"] += 1
            if k % 500 == 499:
                r.clear_scene()
        print(f"  python garbage fuzz: {calls} calls: {outcomes}")
        self.assertGreater(outcomes["ok"], 0)
        self.assertGreater(outcomes["ValueError"], 0)
        # Still renders, all finite.
        r.clear_scene()
        p, i, *_ = plane()
        r.add_instances(r.add_mesh(p, i), np.eye(4)[None], material_slots=[r.add_material()])
        r.add_light(energy=50.0)
        out = r.render(top_camera(), 8, 8, passes=[name for name, *_ in dn.PASSES])
        for name, image in out.items():
            self.assertTrue(np.isfinite(image).all(), name)


if __name__ == "__main__":
    unittest.main()
