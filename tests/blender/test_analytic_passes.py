"""Pass values of the analytic scene against Blender's own geometry.

Ground truth: rays through the pixel centres (Camera.view_frame, i.e.
Blender's sensor fit/aspect) cast against a BVH of the evaluated meshes.
Compared away from object edges (3x3 neighbourhood of one object), for the
perspective and the orthographic camera:

- Depth   = positive camera-space Z within 1e-4 relative; background 1e10
- Position = hit point (1e-4 x depth); background 0
- Normal  = unit world-space normal (planes: face normal; smooth spheres:
            the interpolated vertex normal at the hit); background 0
- IndexOB / IndexMA = object / material pass index; background 0
- UV      = the floor's UV map (u = (x+8)/16); A = 1 on geometry
- Mist    = Blender's quadratic mist of the ray distance; background 1
- Combined alpha 1 (film not transparent); Env = world colour on background

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_analytic_passes.py
"""

import ast
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

ANALYTIC = None


def stat(values):
    return f"max {np.max(values):.3g}, mean {np.mean(values):.3g}, n={values.size}" if values.size else "n=0"


def check_camera(checks, cam_name, out):
    scene = bpy.context.scene
    scene.camera = bpy.data.objects[cam_name]
    width = scene.render.resolution_x * scene.render.resolution_percentage // 100
    height = scene.render.resolution_y * scene.render.resolution_percentage // 100
    path = U.render_exr(os.path.join(out, cam_name))
    ch = U.read_exr(path)
    L = "ViewLayer"
    depth = ch[f"{L}.Depth.Z"]
    checks.check(depth.shape == (height, width), f"{cam_name}: pass size {width}x{height}")

    depsgraph = bpy.context.evaluated_depsgraph_get()
    cam_ob = scene.camera.evaluated_get(depsgraph)
    origins, dirs, cam_m = U.camera_rays(scene, cam_ob, width, height)
    triangles = U.scene_triangles(depsgraph)
    tri_ob, tri_ma = triangles.object_index, triangles.material_index
    hit, pos, face_n, tri = U.cast_rays(triangles.bvh, origins, dirs)
    label = np.where(hit, tri_ob[np.maximum(tri, 0)], 0)
    interior = U.interior_mask(label, 1)
    geo = interior & hit
    bg = interior & ~hit
    checks.check(geo.sum() > 0.5 * width * height and bg.sum() > 100,
                 f"{cam_name}: enough interior geometry and background pixels", f"{geo.sum()} / {bg.sum()}")

    # Depth: positive camera-space Z.
    forward = -cam_m[:3, 2]
    z_expected = (pos - cam_m[:3, 3]) @ forward
    rel = np.abs(depth - z_expected)[geo] / z_expected[geo]
    checks.check(rel.max() <= 1e-4, f"{cam_name}: Depth = camera-space Z within 1e-4 relative", stat(rel))
    checks.check(np.all(depth[bg] >= 1e9), f"{cam_name}: Depth background 1e10 (Cycles)",
                 f"min {depth[bg].min():.3g}")

    # Position.
    P = U.exr_pass(ch, L, "Position", "XYZ")
    err = np.linalg.norm(P - pos, axis=-1)[geo]
    tol = 1e-4 * z_expected[geo] + 1e-5
    checks.check(np.all(err <= tol), f"{cam_name}: Position = hit point within 1e-4 x depth",
                 stat(err / z_expected[geo]))
    checks.check(np.all(P[bg] == 0), f"{cam_name}: Position background 0")

    # Normal.
    N = U.exr_pass(ch, L, "Normal", "XYZ")
    length = np.linalg.norm(N, axis=-1)
    checks.check(np.abs(length[geo] - 1).max() < 1e-3, f"{cam_name}: Normal unit length away from edges",
                 stat(np.abs(length[geo] - 1)))
    planes = geo & np.isin(label, (1, 2, 6))
    dots = np.einsum("...i,...i->...", N, face_n)[planes]
    checks.check(dots.min() > 0.9999, f"{cam_name}: Normal = world face normal on planes/box", f"min dot {dots.min():.6f}")
    spheres = geo & np.isin(label, [s["pass_index"] for s in ANALYTIC["spheres"]])
    smooth = triangles.shading_normals(tri, pos)
    sphere_dots = np.einsum("...i,...i->...", N, smooth)[spheres]
    checks.check(sphere_dots.size > 0 and sphere_dots.min() > 0.99999,
                 f"{cam_name}: Normal = interpolated vertex normal on smooth spheres",
                 f"min dot {sphere_dots.min():.7f}")
    radial = np.zeros_like(pos)
    for s in ANALYTIC["spheres"]:
        mask = label == s["pass_index"]
        radial[mask] = (pos[mask] - np.array(s["center"])) / s["radius"]
    radial_dots = np.einsum("...i,...i->...", N, radial)[spheres]
    checks.check(radial_dots.min() > 0.995, f"{cam_name}: sphere normals radial within the tessellation error",
                 f"min dot {radial_dots.min():.5f}")
    checks.check(np.all(N[bg] == 0), f"{cam_name}: Normal background 0")

    # Indices.
    ob_index = ch[f"{L}.IndexOB.X"]
    ma_index = ch[f"{L}.IndexMA.X"]
    ma_expected = np.where(hit, tri_ma[np.maximum(tri, 0)], 0)
    checks.check(np.all(ob_index[geo] == label[geo]), f"{cam_name}: IndexOB = object pass index",
                 f"{np.count_nonzero(ob_index[geo] != label[geo])} wrong")
    checks.check(np.all(ma_index[geo] == ma_expected[geo]), f"{cam_name}: IndexMA = material pass index",
                 f"{np.count_nonzero(ma_index[geo] != ma_expected[geo])} wrong; values {np.unique(ma_index)}")
    checks.check(np.all(ob_index[bg] == 0) and np.all(ma_index[bg] == 0), f"{cam_name}: index background 0")

    # UV on the floor (plane UVs map x, y in [-8, 8] to [0, 1]).
    uva = U.exr_pass(ch, L, "UV", "UVA")
    floor = geo & (label == 1)
    du = np.abs(uva[..., 0] - (pos[..., 0] + 8) / 16)[floor]
    dv = np.abs(uva[..., 1] - (pos[..., 1] + 8) / 16)[floor]
    checks.check(max(du.max(), dv.max()) < 1e-3, f"{cam_name}: UV = floor UV map", stat(np.maximum(du, dv)))
    checks.check(np.all(uva[..., 2][geo] == 1) and np.all(uva[bg] == 0), f"{cam_name}: UV alpha 1 on geometry, 0 background")

    # Mist (perspective: distance from the camera; Blender quadratic falloff).
    mist = ch[f"{L}.Mist.Z"]
    if scene.camera.data.type == 'PERSP':
        ms = scene.world.mist_settings
        dist = np.linalg.norm(pos - cam_m[:3, 3], axis=-1)
        expected = np.clip((dist - ms.start) / ms.depth, 0, 1) ** 2
        err = np.abs(mist - expected)[geo]
        checks.check(err.max() < 1e-3, f"{cam_name}: Mist = quadratic falloff of distance", stat(err))
    checks.check(np.allclose(mist[bg], 1.0), f"{cam_name}: Mist background 1")

    # Combined, Env.
    alpha = ch[f"{L}.Combined.A"]
    checks.check(np.allclose(alpha[interior], 1.0), f"{cam_name}: Combined alpha 1 (film not transparent)")
    env = U.exr_pass(ch, L, "Env", "RGB")
    checks.check(np.allclose(env[bg], 0.05, atol=1e-4) and np.allclose(env[geo], 0.0),
                 f"{cam_name}: Env = world colour on background, 0 on geometry")
    rgb = U.exr_pass(ch, L, "Combined", "RGB")
    checks.check(np.allclose(rgb[bg], 0.05, atol=1e-3), f"{cam_name}: background shows the world colour",
                 f"mean {rgb[bg].mean():.4f}")
    checks.check(np.all(np.isfinite(np.stack([ch[k] for k in ch]))), f"{cam_name}: every channel finite")
    diffcol = U.exr_pass(ch, L, "DiffCol", "RGB")
    checks.check(np.allclose(diffcol[floor], 0.6, atol=1e-3), f"{cam_name}: DiffCol = base colour on the floor",
                 f"mean {diffcol[floor].mean():.4f}")


def main():
    global ANALYTIC
    checks = U.Checks("test_analytic_passes")
    scene = bpy.context.scene
    if not U.require_engine(checks):
        checks.finish()
    ANALYTIC = ast.literal_eval(scene["analytic"])  # written by generate_samples.py (repr of a dict)
    scene.deferred_render.samples = 1
    U.set_all_passes(scene.view_layers[0], True)
    out = U.out_dir("analytic_passes")
    for cam in ("Camera", "CameraOrtho"):
        checks.run(cam, check_camera, checks, cam, out)
    checks.finish()


main()
