"""Shadow catchers against Cycles 3.4 (issue: compositing outputs).

The analytic scene at 160x90, 64 samples, its Floor a shadow catcher
(Object > Visibility > Mask > Shadow Catcher): the spheres and the box
shadow it under the sun, the point light and the world. Three settings, as
Cycles 3.4 renders them (kernel/film/read.h):
  * film transparent with the Shadow Catcher pass (the compositing
    workflow): Combined has the floor as a hole (alpha < 0.01 on the same
    pixels as Cycles', IoU >= 0.97); the Shadow Catcher pass on the floor's
    interior pixels is Cycles' within 1 % on average and per pixel within
    0.05 on 95 % of them (its shadows are the maps' soft shadows, Cycles'
    the lights' exact ones), 1 off the floor; the pass darkens where the
    objects shadow the floor (below 0.6 somewhere); "footage" (a colour
    ramp) x Shadow Catcher with Combined over it is Cycles' composite within
    relMSE 5e-3; and ours differs from Cycles' no more than Cycles' own
    renders with two seeds differ (RMSE over the floor, 15 % of margin);
  * film transparent without the pass (Cycles' approximate catcher): the
    floor's Combined alpha is the shadow, its mean within 0.01 of Cycles';
  * film opaque without the pass: the floor shows the world darkened by
    the shadow, its mean within 2 % of Cycles'.
The other objects' Combined stays Cycles' (mean within 2 %).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_shadow_catcher.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("shadow_catcher")
SAMPLES = 64


def render(scene, engine, name):
    scene.render.engine = engine
    channels = U.read_exr(U.render_exr(os.path.join(OUT, name), scene))
    combined = U.exr_pass(channels, "ViewLayer", "Combined", "RGBA").astype(np.float64)
    catcher = (U.exr_pass(channels, "ViewLayer", "Shadow Catcher", "RGB").astype(np.float64)
               if "ViewLayer.Shadow Catcher.R" in channels else None)
    return combined, catcher, channels


def main():
    checks = U.Checks("shadow_catcher")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    layer = U.comparison_setup(scene, samples=SAMPLES)
    layer.use_pass_object_index = True
    bpy.data.objects["Floor"].is_shadow_catcher = True

    # 1. Film transparent, Shadow Catcher pass.
    scene.render.film_transparent = True
    layer.cycles.use_pass_shadow_catcher = True
    c_comb, c_sc, c_ch = render(scene, "CYCLES", "pass_cycles")
    o_comb, o_sc, _ = render(scene, "DEFERRED_RENDER", "pass_ours")
    index = c_ch["ViewLayer.IndexOB.X"].astype(np.int64)
    inner = U.interior_mask(index, radius=2)
    floor = inner & (index == 1)
    others = inner & np.isin(index, (2, 3, 4, 5, 6))
    c_hole, o_hole = c_comb[..., 3] < 0.01, o_comb[..., 3] < 0.01
    iou = float((c_hole & o_hole).sum() / max((c_hole | o_hole).sum(), 1))
    checks.check(floor.sum() > 3000 and iou >= 0.97 and bool(o_hole[floor].all()),
                 "pass: Combined has the catcher as a hole, as Cycles'", f"IoU {iou:.4f}")
    if checks.check(o_sc is not None, "pass: the Shadow Catcher pass is there (RGB)"):
        ratio = float(o_sc[floor].mean() / c_sc[floor].mean())
        close = float((np.abs(o_sc - c_sc).max(axis=-1) <= 0.05)[floor].mean())
        print(f"  Shadow Catcher on the floor: mean ours {o_sc[floor].mean():.4f}, Cycles {c_sc[floor].mean():.4f}; "
              f"{close:.4f} of pixels within 0.05; darkest ours {o_sc[floor].min():.3f} Cycles {c_sc[floor].min():.3f}")
        checks.check(abs(ratio - 1.0) < 0.01, "pass: the floor's Shadow Catcher mean is Cycles'", f"{ratio:.4f}")
        checks.check(close >= 0.95, "pass: per pixel within 0.05 of Cycles' on 95 % of the floor", f"{close:.4f}")
        checks.check(float(o_sc[floor].min()) < 0.6, "pass: the objects' shadows darken it",
                     f"{o_sc[floor].min():.3f}")
        off = inner & (index != 1)
        checks.check(float(np.abs(o_sc[off] - 1.0).max()) < 1e-6, "pass: 1 off the catcher, as Cycles",
                     f"{np.abs(c_sc[off] - 1.0).max():.2e} in Cycles")
        # Compositing over footage: footage x Shadow Catcher, Combined over it.
        h, w = index.shape
        footage = np.stack(np.meshgrid(np.linspace(0.2, 0.9, w), np.linspace(0.3, 0.7, h)) + [np.full((h, w), 0.5)],
                           axis=-1)

        def composite(comb, sc):
            return comb[..., :3] + (1.0 - comb[..., 3:4]) * footage * sc
        a, b = composite(o_comb, o_sc), composite(c_comb, c_sc)
        rel = float((((a - b) ** 2) / (b ** 2 + 1e-2)).mean())
        checks.check(rel < 5e-3, "pass: composited over footage as Cycles' render composites", f"relMSE {rel:.2e}")
        # Within Cycles' own noise: ours against Cycles differs no more than
        # Cycles against itself with another seed (RMSE over the floor, 15 %
        # of margin).
        scene.cycles.seed = 1
        _, c_sc_b, _ = render(scene, "CYCLES", "pass_cycles_seed1")
        scene.cycles.seed = 0
        noise = float(np.sqrt(((c_sc - c_sc_b)[floor] ** 2).mean()))
        error = float(np.sqrt(((o_sc - c_sc)[floor] ** 2).mean()))
        checks.check(error <= 1.15 * noise, "pass: within Cycles' own noise on the floor",
                     f"RMSE {error:.4f} vs Cycles seed to seed {noise:.4f}")
    means = o_comb[others][:, :3].mean(axis=0) / c_comb[others][:, :3].mean(axis=0)
    checks.check(float(np.abs(means - 1.0).max()) < 0.02, "the other objects' Combined is Cycles'",
                 f"{np.round(means, 4)}")

    # 2. Film transparent, no pass: the shadow in Combined's alpha.
    layer.cycles.use_pass_shadow_catcher = False
    c_comb, _, _ = render(scene, "CYCLES", "approx_cycles")
    o_comb, o_sc, _ = render(scene, "DEFERRED_RENDER", "approx_ours")
    checks.check(o_sc is None, "approximate: no Shadow Catcher pass when not asked for")
    ca, oa = float(c_comb[..., 3][floor].mean()), float(o_comb[..., 3][floor].mean())
    checks.check(abs(oa - ca) < 0.01 and oa > 0.02, "approximate: the floor's alpha is Cycles' shadow",
                 f"{oa:.4f} vs {ca:.4f}")
    checks.check(float(np.abs(o_comb[floor][:, :3]).max()) < 1e-6, "approximate: the floor's colour is black")

    # 3. Film opaque, no pass: the world darkened by the shadow.
    scene.render.film_transparent = False
    c_comb, _, _ = render(scene, "CYCLES", "opaque_cycles")
    o_comb, _, _ = render(scene, "DEFERRED_RENDER", "opaque_ours")
    ratio = o_comb[floor][:, :3].mean(axis=0) / c_comb[floor][:, :3].mean(axis=0)
    checks.check(float(np.abs(ratio - 1.0).max()) < 0.02 and float(o_comb[..., 3][floor].min()) > 0.999,
                 "opaque: the floor shows the world darkened by the shadow, as Cycles", f"{np.round(ratio, 4)}")
    checks.finish()


main()
