"""Render region (border) and crop behave as in Cycles; percentage honoured.

The add-on renders the full frame and crops the border rectangle out of
every pass (engine/frame.py). Checks, on the analytic scene at 50 %:
- with crop: the image has the border's size (same as Cycles), and every
  pass equals the same rectangle of a full render (IndexOB exactly, the
  rest up to GPU noise);
- without crop: the full size (same as Cycles), the rectangle equals the
  full render, the outside is empty (alpha 0).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_border.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

BORDER = (0.13, 0.71, 0.2, 0.9)  # min x, max x, min y, max y


def border_rect(render):
    """Blender's disprect: float32 product truncated (render_init_from_main)."""
    w = render.resolution_x * render.resolution_percentage // 100
    h = render.resolution_y * render.resolution_percentage // 100
    f = np.float32
    x0, x1 = int(f(render.border_min_x) * f(w)), int(f(render.border_max_x) * f(w))
    y0, y1 = int(f(render.border_min_y) * f(h)), int(f(render.border_max_y) * f(h))
    return w, h, x0, x1, y0, y1


def main():
    checks = U.Checks("test_border")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    render = scene.render
    render.resolution_percentage = 50
    scene.deferred_render.samples = 1
    scene.cycles.samples = 1
    U.set_all_passes(scene.view_layers[0], True)
    out = U.out_dir("border")

    render.use_border = False
    full_path = U.render_exr(os.path.join(out, "full"))
    full = U.read_exr(full_path)
    checks.check(U.exr_size(full_path) == (160, 90), "resolution percentage 50 % -> 160x90",
                 str(U.exr_size(full_path)))

    render.use_border = True
    render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y = BORDER
    w, h, x0, x1, y0, y1 = border_rect(render)
    for crop in (True, False):
        render.use_crop_to_border = crop
        label = "crop" if crop else "no crop"
        sizes = {}
        for engine in ("DEFERRED_RENDER", "CYCLES"):
            render.engine = engine
            path = U.render_exr(os.path.join(out, f"{engine.lower()}_{'crop' if crop else 'nocrop'}"))
            sizes[engine] = U.exr_size(path)
            if engine == "DEFERRED_RENDER":
                img = U.read_exr(path)
        render.engine = "DEFERRED_RENDER"
        expected = (x1 - x0, y1 - y0) if crop else (w, h)
        checks.check(sizes["DEFERRED_RENDER"] == expected == sizes["CYCLES"],
                     f"{label}: image size {expected} (Cycles: {sizes['CYCLES']})", str(sizes))
        # Same pixels as the full render's rectangle: IndexOB exactly; other
        # passes up to GPU noise (llvmpipe may differ in the last bits on a
        # pixel or two between two renders of the same frame).
        same, worst = True, 0.0
        for name, full_values in full.items():
            region = full_values[y0:y1, x0:x1]
            got = img[name] if crop else img[name][y0:y1, x0:x1]
            if got.shape != region.shape:
                same = False
                continue
            if ".IndexOB." in name:
                same &= np.array_equal(got, region)
                continue
            close = np.abs(got - region) <= 1e-4 + 1e-4 * np.abs(region)
            worst = max(worst, 1.0 - close.mean())
        same &= worst <= 1e-3
        checks.check(same, f"{label}: every pass in the border equals the full render's rectangle",
                     f"worst pass: {100 * worst:.3f} % of pixels differ by > 1e-4")
        if not crop:
            alpha = img["ViewLayer.Combined.A"].copy()
            alpha[y0:y1, x0:x1] = 0
            checks.check(np.all(alpha == 0), f"{label}: outside the border is empty (alpha 0)")
    render.use_border = False
    checks.finish()


main()
