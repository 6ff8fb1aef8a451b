"""Holdouts against Cycles 3.4 (issue: compositing outputs).

The analytic scene at 160x90, 16 samples, with three kinds of holdout:
SphereB's Object > Visibility > Holdout, SphereA's material a Holdout
shader, SphereC in a collection marked Holdout in the view layer. Cycles and
this engine render Combined, DiffCol and Depth, with Film > Transparent off
and on. Checks, per setting:
  * the holes (Combined alpha below 0.01) are Cycles' (intersection over
    union at least 0.97, measured 0.979: at 16 samples an edge pixel's
    alpha falls below 0.01 by chance, and at 160x90 the holes' edges are
    about a tenth of their pixels);
  * inside a hole Combined is exactly 0 in ours, and DiffCol too;
  * the mean alpha of the image is Cycles' within 0.005;
  * Depth over the holes is Cycles' background value: a holdout writes no
    data pass (Cycles ends the path there), within 1e-3 relative on 99 % of
    the holes' pixels.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_holdout.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("holdout")


def setup(scene):
    layer = U.comparison_setup(scene)
    layer.use_pass_diffuse_color = True
    layer.use_pass_z = True
    bpy.data.objects["SphereB"].is_holdout = True
    mat = bpy.data.materials.new("HoldoutShader")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    holdout = nodes.new("ShaderNodeHoldout")
    mat.node_tree.links.new(holdout.outputs[0], nodes["Material Output"].inputs["Surface"])
    sphere_a = bpy.data.objects["SphereA"]
    sphere_a.data.materials.clear()
    sphere_a.data.materials.append(mat)
    masked = bpy.data.collections.new("Masked")
    scene.collection.children.link(masked)
    sphere_c = bpy.data.objects["SphereC"]
    for collection in list(sphere_c.users_collection):
        collection.objects.unlink(sphere_c)
    masked.objects.link(sphere_c)
    layer.layer_collection.children["Masked"].holdout = True


def render(scene, engine, name):
    scene.render.engine = engine
    channels = U.read_exr(U.render_exr(os.path.join(OUT, name), scene))
    return (U.exr_pass(channels, "ViewLayer", "Combined", "RGBA").astype(np.float64),
            U.exr_pass(channels, "ViewLayer", "DiffCol", "RGB").astype(np.float64),
            channels["ViewLayer.Depth.Z"].astype(np.float64))


def main():
    checks = U.Checks("holdout")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    setup(scene)
    for transparent in (False, True):
        scene.render.film_transparent = transparent
        label = "film transparent" if transparent else "film opaque"
        c_comb, c_col, c_depth = render(scene, "CYCLES", f"cycles_{int(transparent)}")
        o_comb, o_col, o_depth = render(scene, "DEFERRED_RENDER", f"ours_{int(transparent)}")
        c_hole, o_hole = c_comb[..., 3] < 0.01, o_comb[..., 3] < 0.01
        if transparent:  # the background is a hole too: keep the objects' holes only
            c_hole &= c_opaque_hole_mask
            o_hole &= c_opaque_hole_mask | o_opaque_hole_mask
        iou = float((c_hole & o_hole).sum() / max((c_hole | o_hole).sum(), 1))
        print(f"  {label}: holes {int(c_hole.sum())} px (Cycles), {int(o_hole.sum())} px (ours), IoU {iou:.4f}")
        checks.check(c_hole.sum() > 1000 and iou >= 0.97, f"{label}: the holes are Cycles'", f"IoU {iou:.4f}")
        if not transparent:  # with an opaque film, the holes are the holdouts alone
            c_opaque_hole_mask, o_opaque_hole_mask = c_hole, o_hole
        inner = U.interior_mask(o_hole.astype(np.int64), radius=1) & o_hole
        checks.check(float(np.abs(o_comb[inner]).max()) == 0.0 and float(np.abs(o_col[inner]).max()) == 0.0,
                     f"{label}: Combined and DiffCol are 0 inside the holes")
        da = abs(float(o_comb[..., 3].mean() - c_comb[..., 3].mean()))
        checks.check(da < 0.005, f"{label}: mean alpha is Cycles'", f"{o_comb[..., 3].mean():.4f} vs "
                     f"{c_comb[..., 3].mean():.4f}")
        both = c_hole & o_hole
        rel = np.abs(o_depth[both] - c_depth[both]) / np.maximum(np.abs(c_depth[both]), 1e-6)
        close = float((rel < 1e-3).mean())
        checks.check(close >= 0.99, f"{label}: Depth over the holes is Cycles' (no data pass)", f"{close:.4f}")
    checks.finish()


main()
