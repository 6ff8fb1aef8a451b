"""Light culling on the many-lights sample (1024 point lights + a sun):
the culled render differs from brute force (every light at every pixel) by
no more than the threshold predicts, pixel by pixel. Then Light Samples
(stochastic light selection) on the same scene.

Bound at a pixel with world position P: the sum, over the point lights
farther than their influence radius r = R + sqrt(S / (4 pi^2 T)), of
S / (4 pi^2 (d - R)^2) (what each could add to a white Lambertian surface);
the materials here are not brighter than white Lambert plus a specular
lobe, so the bound gets the specular's share as slack (x 2).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_light_culling.py
"""

import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402


def main():
    checks = U.Checks("light_culling")
    bpy.ops.wm.open_mainfile(filepath=os.path.join(U.SAMPLES, "many_lights.blend"))
    scene = bpy.context.scene
    scene.render.engine = U.ENGINE
    scene.render.resolution_percentage = 25
    scene.deferred_render.samples = 1
    scene.deferred_render.light_samples = 0  # every light: the culling alone is under test
    layer = scene.view_layers[0]
    layer.use_pass_position = True
    out = U.out_dir("light_culling")

    renders = {}
    for culling in (True, False):
        scene.deferred_render.light_culling = culling
        path = U.render_exr(os.path.join(out, "culled" if culling else "brute"))
        ch = U.read_exr(path)
        renders[culling] = (U.exr_pass(ch, layer.name, "Combined", "RGB"),
                            U.exr_pass(ch, layer.name, "Position", "XYZ"))
    culled, pos = renders[True]
    brute, _ = renders[False]

    T = scene.deferred_render.light_threshold / (2.0 ** scene.view_settings.exposure)
    pts = []
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for inst in depsgraph.object_instances:
        ob = inst.object
        if ob.type == 'LIGHT' and ob.data.type == 'POINT':
            S = ob.data.energy * max(ob.data.color)
            pts.append((*inst.matrix_world.translation, S, ob.data.shadow_soft_size))
    pts = np.array(pts)
    checks.check(len(pts) >= 1000, "many_lights has >= 1000 point lights", len(pts))
    P = pos.reshape(-1, 3).astype(np.float64)
    bound = np.zeros(len(P))
    for x, y, z, S, R in pts:
        d = np.linalg.norm(P - np.array([x, y, z]), axis=1)
        r = R + math.sqrt(S / (4 * math.pi ** 2 * T))
        far = d > r
        bound[far] += S / (4 * math.pi ** 2 * np.maximum(d[far] - R, 1e-9) ** 2)
    diff = np.abs(culled - brute).reshape(-1, 3).max(axis=1)
    excess = diff - 2.0 * bound - 1e-5 * np.abs(brute).reshape(-1, 3).max(axis=1) - 1e-6
    print(f"  many_lights: max |culled - brute| {diff.max():.3e}, mean {diff.mean():.3e}, "
          f"largest bound {bound.max():.3e}, worst excess {excess.max():.3e}")
    checks.check(np.isfinite(culled).all() and np.isfinite(brute).all(), "finite pixels")
    checks.check(excess.max() <= 0.0, "culled - brute within the predicted bound", f"{excess.max():.3e}")
    checks.check(diff.max() > 0.0 or bound.max() == 0.0, "culling was active (results differ where allowed)")

    # Light Samples (stochastic selection, default 16) reaches the renderer:
    # the image changes (pixels reached by more than 16 lights shade a
    # selection) and its mean stays that of every light's (one sample here;
    # the convergence is LightSampling.* in the native tests).
    scene.deferred_render.light_culling = True
    scene.deferred_render.light_samples = 16
    ch = U.read_exr(U.render_exr(os.path.join(out, "sampled")))
    sampled = U.exr_pass(ch, layer.name, "Combined", "RGB")
    change = np.abs(sampled - culled).max()
    ratio = float(sampled.mean() / culled.mean())
    checks.check(np.isfinite(sampled).all() and change > 1e-3, "Light Samples 16 selects lights",
                 f"max change {change:.3g}")
    checks.check(abs(ratio - 1.0) < 0.03, "and keeps the image's mean (one sample)", f"{ratio:.4f}")
    checks.finish()


main()
