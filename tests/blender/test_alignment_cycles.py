"""Geometry alignment: our Position pass against Cycles' Position pass.

Both engines render the analytic scene (Cycles: 1 sample, pixel filter
width 0.01 px, so its one sample sits at the pixel centre) for three camera
set-ups: the perspective camera; the same with lens 35, sensor fit
VERTICAL, shift (0.15, -0.1) and pixel aspect 1.5 x 1; the orthographic
camera. Away from edges, the world-space difference of the Position passes
is converted to a sub-pixel offset with the local Jacobian of our Position
pass (least squares of dP = J (dx, dy)), and reported in pixels (ALIGN
line). The median and 99th percentile must stay below 0.01 and 0.05 px.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_alignment_cycles.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

MEDIAN_LIMIT_PX = 0.01
P99_LIMIT_PX = 0.05


def configure(name):
    scene = bpy.context.scene
    render = scene.render
    render.pixel_aspect_x = render.pixel_aspect_y = 1.0
    if name == "ortho":
        scene.camera = bpy.data.objects["CameraOrtho"]
        return
    scene.camera = bpy.data.objects["Camera"]
    cam = scene.camera.data
    if name == "perspective":
        cam.lens, cam.sensor_fit, cam.shift_x, cam.shift_y = 50.0, 'AUTO', 0.0, 0.0
    else:
        cam.lens, cam.sensor_fit, cam.shift_x, cam.shift_y = 35.0, 'VERTICAL', 0.15, -0.1
        render.pixel_aspect_x = 1.5


def render(engine, out, name):
    scene = bpy.context.scene
    scene.render.engine = engine
    path = U.render_exr(os.path.join(out, f"{name}_{engine.lower()}"))
    return U.read_exr(path)


def subpixel_offsets(ours, theirs, labels):
    """Per-pixel (dx, dy) with ours(x + dx, y + dy) ~= theirs, on interior pixels."""
    jx = np.zeros_like(ours)
    jy = np.zeros_like(ours)
    jx[:, 1:-1] = (ours[:, 2:] - ours[:, :-2]) / 2
    jy[1:-1, :] = (ours[2:, :] - ours[:-2, :]) / 2
    mask = U.interior_mask(labels, 2) & (labels > 0)
    J = np.stack([jx[mask], jy[mask]], axis=-1)          # (n, 3, 2)
    d = (theirs - ours)[mask][..., None]                 # (n, 3, 1)
    JtJ = np.einsum("nki,nkj->nij", J, J)
    Jtd = np.einsum("nki,nkj->nij", J, d)
    ok = np.abs(np.linalg.det(JtJ)) > 1e-20
    offsets = np.linalg.solve(JtJ[ok], Jtd[ok])[..., 0]
    return np.linalg.norm(offsets, axis=-1), int(mask.sum())


def main():
    checks = U.Checks("test_alignment_cycles")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    scene.render.resolution_percentage = 50
    scene.deferred_render.samples = 1
    cy = scene.cycles
    cy.samples = 1
    cy.filter_width = 0.01
    cy.seed = 0
    layer = scene.view_layers[0]
    U.set_all_passes(layer, False)
    layer.use_pass_position = True
    layer.use_pass_object_index = True
    out = U.out_dir("alignment_cycles")
    for name in ("perspective", "shift_vertical_aspect", "ortho"):
        configure(name)
        ours = render("DEFERRED_RENDER", out, name)
        theirs = render("CYCLES", out, name)
        scene.render.engine = "DEFERRED_RENDER"
        p_ours = U.exr_pass(ours, "ViewLayer", "Position", "XYZ").astype(np.float64)
        p_cyc = U.exr_pass(theirs, "ViewLayer", "Position", "XYZ").astype(np.float64)
        idx_ours = ours["ViewLayer.IndexOB.X"]
        idx_cyc = theirs["ViewLayer.IndexOB.X"]
        labels = np.where(idx_ours == idx_cyc, idx_ours, -1).astype(np.int64)
        same = np.mean(idx_ours == idx_cyc)
        checks.check(same > 0.98, f"{name}: IndexOB agrees with Cycles on {100 * same:.2f} % of pixels")
        offsets, n = subpixel_offsets(p_ours, p_cyc, labels)
        if not checks.check(offsets.size > 1000, f"{name}: enough interior pixels", f"{offsets.size}"):
            continue
        median, p99, worst = np.median(offsets), np.percentile(offsets, 99), offsets.max()
        print(f"  ALIGN {name}: Position vs Cycles, {offsets.size} px: median {median:.4f} px, "
              f"99th percentile {p99:.4f} px, max {worst:.4f} px")
        checks.check(median < MEDIAN_LIMIT_PX and p99 < P99_LIMIT_PX,
                     f"{name}: aligned with Cycles (median < {MEDIAN_LIMIT_PX}, p99 < {P99_LIMIT_PX} px)",
                     f"median {median:.4f}, p99 {p99:.4f}, max {worst:.4f} px")
    checks.finish()


main()
