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
Then partial holdouts, 64 samples, Film > Transparent on and off: the
Wall's material a Mix Shader of its Principled BSDF and a Holdout at Fac
0.3, the Floor's with a Checker (0.2 / 0.7) as Fac. Checks, on the
interior pixels of each (by Cycles' IndexOB):
  * the mean alpha is Cycles' within 0.01 (0.7 on the wall);
  * the mean colour is Cycles' within 2 % (the other closures at their
    weight);
  * per pixel, alpha averaged over 5x5 pixels is Cycles' within 0.05 on
    average (the checker's pattern, not only its mean).

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


def partial_holdouts():
    """Mix(Principled, Holdout): Fac 0.3 on the Wall, a Checker on the Floor."""
    for name, checker in (("MatWall", False), ("MatFloor", True)):
        tree = bpy.data.materials[name].node_tree
        nodes, links = tree.nodes, tree.links
        bsdf, output = nodes["Principled BSDF"], nodes["Material Output"]
        mix = nodes.new("ShaderNodeMixShader")
        holdout = nodes.new("ShaderNodeHoldout")
        links.new(bsdf.outputs[0], mix.inputs[1])
        links.new(holdout.outputs[0], mix.inputs[2])
        links.new(mix.outputs[0], output.inputs["Surface"])
        if checker:
            tex = nodes.new("ShaderNodeTexChecker")
            tex.inputs["Color1"].default_value = (0.2, 0.2, 0.2, 1.0)
            tex.inputs["Color2"].default_value = (0.7, 0.7, 0.7, 1.0)
            tex.inputs["Scale"].default_value = 3.0
            links.new(tex.outputs["Color"], mix.inputs[0])
        else:
            mix.inputs[0].default_value = 0.3


def box_mean(image, radius=2):
    h, w = image.shape
    padded = np.pad(image, radius, mode="edge")
    return sum(padded[radius + dy:radius + dy + h, radius + dx:radius + dx + w]
               for dy in range(-radius, radius + 1) for dx in range(-radius, radius + 1)) / (2 * radius + 1) ** 2


def check_partial(checks, scene):
    partial_holdouts()
    layer = scene.view_layers[0]
    layer.use_pass_object_index = True
    scene.cycles.samples = scene.deferred_render.samples = 64
    for transparent in (False, True):
        scene.render.film_transparent = transparent
        label = "partial, film transparent" if transparent else "partial, film opaque"
        scene.render.engine = "CYCLES"
        cycles = U.read_exr(U.render_exr(os.path.join(OUT, f"partial_cycles_{int(transparent)}"), scene))
        scene.render.engine = "DEFERRED_RENDER"
        ours = U.read_exr(U.render_exr(os.path.join(OUT, f"partial_ours_{int(transparent)}"), scene))
        c_comb = U.exr_pass(cycles, "ViewLayer", "Combined", "RGBA").astype(np.float64)
        o_comb = U.exr_pass(ours, "ViewLayer", "Combined", "RGBA").astype(np.float64)
        index = cycles["ViewLayer.IndexOB.X"].astype(np.int64)
        inner = U.interior_mask(index, radius=2)
        for name, ob_index in (("Wall", 2), ("Floor", 1)):
            mask = inner & (index == ob_index)
            ca, oa = float(c_comb[..., 3][mask].mean()), float(o_comb[..., 3][mask].mean())
            checks.check(mask.sum() > 500 and abs(oa - ca) < 0.01, f"{label}: {name}'s mean alpha is Cycles'",
                         f"{oa:.4f} vs {ca:.4f}")
            cc, oc = c_comb[..., :3][mask].mean(axis=0), o_comb[..., :3][mask].mean(axis=0)
            ratio = oc / np.maximum(cc, 1e-9)
            checks.check(float(np.abs(ratio - 1.0).max()) < 0.02, f"{label}: {name}'s mean colour is Cycles'",
                         f"ours / Cycles {np.round(ratio, 4)}")
            local = np.abs(box_mean(o_comb[..., 3]) - box_mean(c_comb[..., 3]))[mask]
            checks.check(float(local.mean()) < 0.05, f"{label}: {name}'s alpha over 5x5 pixels is Cycles'",
                         f"mean difference {local.mean():.4f}")
        partial = [m for _, m in U.last_messages() if "Holdout" in m]
        checks.check(not partial, f"{label}: no warning about the Holdout", f"{partial}")


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
    check_partial(checks, scene)
    checks.finish()


main()
