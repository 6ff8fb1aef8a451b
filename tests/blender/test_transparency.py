"""Stochastic transparency against Cycles 3.4 (max_bounces 0).

One scene, built here: a floor (Diffuse), a red cube behind everything, and
in front of it, under a sun light (so their shadows fall on the floor):
  * a pane of constant Principled Alpha 0.4 (the constant-material path),
  * a pane whose Alpha comes from a Checker texture (0.1 / 0.9; node path),
  * a sphere mixing Diffuse with a white Transparent BSDF at factor 0.35,
  * two overlapping panes of alpha 0.5 (transmittance multiplies: 0.25),
  * a fully transparent plane (Principled Alpha 0): invisible, no shadow,
  * a "shadowless" sphere: Diffuse mixed with a Transparent BSDF by Light
    Path > Is Shadow Ray (opaque to the camera, casts no shadow; its caster
    program evaluates the graph as a shadow ray).
Both engines render Combined at the same resolution; Cycles at 1024
samples (the reference), ours at 256. Per object (object-index pass of
Cycles, eroded) and on the floor's shadow regions the mean of ours must be
within MEAN_LIMIT of Cycles', relative; a region with an opaque-drawn pane
or an opaque shadow is off by 40-60 %.
(A Diffuse Color pass keeps that comparison stochastic.) Exact layers
(native layer_order.h), with Combined and the data passes only: the planes
and the spheres composited by the forward pass at every sample, less noisy
than stochastic at 4 samples and within MEAN_LIMIT at 16.
Blend Mode (EEVEE's setting): Blend on the panes renders them with the
forward pass, within MEAN_LIMIT of the same Cycles reference at 16
samples; Alpha Clip at 0.5 equals a 0/1 alpha exactly.
Also: Alpha NaN, negative or above 1 from a node renders finite (1: the
default, 0 and 1),
and 1000 overlapping panes of alpha 0.1 render (bounded cost) and hide
what is behind them as 0.9^1000 says, stochastic and in Blend mode.

    blender -b --factory-startup --addons deferred_render -E DEFERRED_RENDER \\
        --python-exit-code 1 --python tests/blender/test_transparency.py
"""

import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("transparency")
MEAN_LIMIT = 0.01      # relative, per region; measured worst 0.4 % (opaque-drawn: 3-60 % off)
OURS_SAMPLES = 256
CYCLES_SAMPLES = 1024


def material(name, build):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    build(mat.node_tree.nodes, mat.node_tree.links, mat.node_tree.nodes["Principled BSDF"])
    return mat


def principled(color, alpha=1.0):
    def build(nodes, links, bsdf):
        bsdf.inputs["Base Color"].default_value = (*color, 1.0)
        bsdf.inputs["Alpha"].default_value = alpha
        bsdf.inputs["Specular"].default_value = 0.0
        bsdf.inputs["Roughness"].default_value = 1.0
    return build


def checker_alpha(nodes, links, bsdf):
    bsdf.inputs["Base Color"].default_value = (0.2, 0.3, 0.9, 1.0)
    bsdf.inputs["Specular"].default_value = 0.0
    checker = nodes.new("ShaderNodeTexChecker")
    checker.inputs["Scale"].default_value = 3.0
    checker.inputs["Color1"].default_value = (0.9, 0.9, 0.9, 1.0)
    checker.inputs["Color2"].default_value = (0.1, 0.1, 0.1, 1.0)
    links.new(checker.outputs["Fac"], bsdf.inputs["Alpha"])
    math_node = nodes.new("ShaderNodeMapRange")  # Fac 0/1 -> alpha 0.1/0.9
    math_node.inputs["To Min"].default_value = 0.1
    math_node.inputs["To Max"].default_value = 0.9
    links.new(checker.outputs["Fac"], math_node.inputs["Value"])
    links.new(math_node.outputs["Result"], bsdf.inputs["Alpha"])


def diffuse_transparent_mix(nodes, links, bsdf):
    out = nodes["Material Output"]
    nodes.remove(bsdf)
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.9, 0.8, 0.2, 1.0)
    transparent = nodes.new("ShaderNodeBsdfTransparent")
    mix = nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = 0.35
    links.new(diffuse.outputs[0], mix.inputs[1])
    links.new(transparent.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], out.inputs["Surface"])


def shadowless(nodes, links, bsdf):
    out = nodes["Material Output"]
    nodes.remove(bsdf)
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.8, 0.3, 0.8, 1.0)
    transparent = nodes.new("ShaderNodeBsdfTransparent")
    path = nodes.new("ShaderNodeLightPath")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(path.outputs["Is Shadow Ray"], mix.inputs["Fac"])
    links.new(diffuse.outputs[0], mix.inputs[1])
    links.new(transparent.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], out.inputs["Surface"])


def add(scene, name, mesh_op, location, mat, index, rotation=(0.0, 0.0, 0.0), **kwargs):
    mesh_op(location=location, rotation=rotation, **kwargs)
    ob = bpy.context.object
    ob.name = name
    ob.pass_index = index
    ob.data.materials.append(mat)
    return ob


def build_scene():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 240, 160
    scene.render.resolution_percentage = 100
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.05, 0.05, 1.0)
    upright = (math.pi / 2, 0.0, 0.0)
    ops = bpy.ops.mesh
    add(scene, "Floor", ops.primitive_plane_add, (0, 0, 0), material("floor", principled((0.8, 0.8, 0.8))), 1,
        size=20)
    add(scene, "Back", ops.primitive_cube_add, (0, 3.0, 1.0), material("back", principled((0.8, 0.1, 0.1))), 2,
        size=2.0, scale=(4.0, 0.2, 1.0))
    add(scene, "Pane04", ops.primitive_plane_add, (-2.4, 0.0, 1.0), material("pane 0.4", principled((0.1, 0.8, 0.2), 0.4)),
        3, rotation=upright, size=1.4)
    add(scene, "Checker", ops.primitive_plane_add, (-0.8, 0.0, 1.0), material("checker alpha", checker_alpha), 4,
        rotation=upright, size=1.4)
    add(scene, "Sphere", ops.primitive_uv_sphere_add, (0.8, 0.0, 1.0), material("diffuse transparent",
                                                                                 diffuse_transparent_mix), 5,
        radius=0.7, segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    half = material("pane 0.5", principled((0.2, 0.4, 0.9), 0.5))
    add(scene, "PaneA", ops.primitive_plane_add, (2.4, -0.2, 1.0), half, 6, rotation=upright, size=1.4)
    add(scene, "PaneB", ops.primitive_plane_add, (2.4, 0.2, 1.0), half, 6, rotation=upright, size=1.4)
    add(scene, "Invisible", ops.primitive_plane_add, (0.0, -1.2, 1.0), material("alpha 0", principled((1, 1, 1), 0.0)),
        7, rotation=upright, size=1.4)
    add(scene, "Shadowless", ops.primitive_uv_sphere_add, (-1.6, 1.6, 0.5), material("shadowless", shadowless), 8,
        radius=0.45)
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    cam.location = (0.0, -9.0, 3.0)
    cam.rotation_euler = (math.radians(78), 0.0, 0.0)
    cam.data.lens = 32
    scene.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 3.0
    sun.data.angle = math.radians(2.0)
    sun.rotation_euler = (math.radians(35), 0.0, math.radians(-20))
    scene.collection.objects.link(sun)
    layer = scene.view_layers[0]
    U.set_all_passes(layer, False)
    layer.use_pass_object_index = True
    # A colour pass keeps every partly transparent surface stochastic (the
    # forward layer of exact layers reaches no colour pass): the main
    # comparison is the stochastic path's; exact_layers() turns it off.
    layer.use_pass_diffuse_color = True
    scene.cycles.samples = CYCLES_SAMPLES
    scene.cycles.max_bounces = 0
    # Blender's default (the test file has 0, which makes Cycles' transparent
    # surfaces opaque); this engine does not limit transparent layers.
    scene.cycles.transparent_max_bounces = 8
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.seed = 3
    scene.deferred_render.samples = OURS_SAMPLES
    return scene


def render(scene, engine):
    scene.render.engine = engine
    channels = U.read_exr(U.render_exr(os.path.join(OUT, engine.lower()), scene))
    return (U.exr_pass(channels, "ViewLayer", "Combined", "RGB").astype(np.float64),
            channels["ViewLayer.IndexOB.X"].astype(np.int64))


def main():
    checks = U.Checks("transparency")
    if not U.require_engine(checks):
        checks.finish()
    scene = build_scene()
    cycles, index = render(scene, "CYCLES")
    ours, our_index = render(scene, "DEFERRED_RENDER")
    # Object Index follows the view layer's Alpha Threshold (0.5), as in
    # Cycles: the alpha 0.4 pane and the 0.1 checker squares are not in it,
    # the two 0.5 panes and 0.9 squares are. Edges may differ (filter).
    inner = U.interior_mask(index, radius=1)
    same = float((our_index[inner] == index[inner]).mean())
    print(f"  Object Index equal to Cycles' on {same:.4f} of the pixels")
    checks.check(same > 0.98, "Object Index follows the Alpha Threshold as in Cycles", f"{same:.4f}")
    h, w = index.shape
    block = (slice(int(h * 0.3), int(h * 0.6)), slice(int(w * 0.12), int(w * 0.26)))  # behind the 0.4 pane
    behind = float((our_index[block] == index[block]).mean())
    # Measured 0.948: Cycles itself keeps the pane's index on ~5 % of these
    # pixels (scattered, at sample 0); without the rule ours would on ~40 %.
    print(f"  ... behind the alpha 0.4 pane: {behind:.4f} (the pane's own index on 40 % without the rule)")
    checks.check(behind > 0.9, "behind the alpha 0.4 pane the index is mostly what is behind it", f"{behind:.4f}")
    checks.check(np.isfinite(ours).all(), "the image is finite")
    # Regions by what Cycles' first opaque-enough hit is (its Index pass
    # follows the alpha threshold), eroded so filtered edges do not count.
    names = {1: "floor (incl. partial shadows)", 2: "red back wall (seen through panes)"}
    for k, name in names.items():
        mask = (index == k) & U.interior_mask(index, radius=2)
        c, o = cycles[mask].mean(), ours[mask].mean()
        print(f"  {name}: {mask.sum()} px, Cycles {c:.4f}, ours {o:.4f}, ratio {o / c:.4f}")
        checks.check(mask.sum() > 200 and abs(o / c - 1.0) < MEAN_LIMIT, f"{name}: mean within {MEAN_LIMIT:.0%}",
                     f"ratio {o / c:.4f}")
    # Each transparent object's screen box (from its projected bounds) and
    # its shadow's region are compared as blocks of the image.
    h, w = index.shape
    rows = slice(int(h * 0.2), int(h * 0.8))
    for label, cols in (("alpha 0.4 pane", (0.08, 0.30)), ("checker alpha pane", (0.30, 0.48)),
                        ("diffuse/transparent sphere", (0.52, 0.70)), ("two 0.5 panes", (0.72, 0.92))):
        block = (rows, slice(int(w * cols[0]), int(w * cols[1])))
        c, o = cycles[block].mean(), ours[block].mean()
        print(f"  {label}: Cycles {c:.4f}, ours {o:.4f}, ratio {o / c:.4f}")
        checks.check(abs(o / c - 1.0) < MEAN_LIMIT, f"{label}: mean within {MEAN_LIMIT:.0%}", f"ratio {o / c:.4f}")
    diff = np.abs(ours - cycles).mean(axis=2)
    print(f"  whole image: mean |ours - Cycles| {diff.mean():.4f}, relMSE "
          f"{float(np.mean((ours - cycles) ** 2 / (cycles ** 2 + 0.01))):.2e}")
    checks.run("Blend mode (forward pass)", blend_mode, checks, scene, cycles)
    checks.run("exact layers (Combined only)", exact_layers, checks, scene, cycles)
    checks.run("Clip mode", clip_mode, checks, scene)
    checks.run("sharp sun", sharp_sun, checks, scene, index)
    checks.run("film transparent", film_transparent, checks, scene)
    checks.run("bad alpha values", bad_alpha, checks, scene)
    checks.run("1000 overlapping panes", many_panes, checks, scene)
    checks.finish()


BLEND_SAMPLES = 16


def blend_mode(checks, scene, cycles):
    """Material > Blend Mode: Blend on the panes (the forward pass): each
    single-layer pane, and the two 0.5 panes (two objects, sorted back to
    front), within MEAN_LIMIT of Cycles' 1024 samples at 16 samples (their
    partial shadows are still stochastic), and the forward pass ran."""
    from deferred_render.engine import final
    names = ("pane 0.4", "checker alpha", "pane 0.5")
    for name in names:
        bpy.data.materials[name].blend_method = 'BLEND'
    scene.deferred_render.samples = BLEND_SAMPLES
    try:
        ours, _ = render(scene, "DEFERRED_RENDER")
        forward_ms = float(final.last_timings.get("forward_ms", 0.0))
    finally:
        for name in names:
            bpy.data.materials[name].blend_method = 'OPAQUE'
        scene.deferred_render.samples = OURS_SAMPLES
    checks.check(forward_ms > 0.0, "the forward pass ran", f"{forward_ms:.1f} ms")
    fallbacks = [m for _, m in final.last_messages if "Blend-mode (forward) program did not compile" in m]
    checks.check(not fallbacks, "every Blend material's forward program compiled (no stochastic fallback)",
                 f"{fallbacks[:1]}")
    warned = [m for _, m in final.last_messages if "Blend-mode materials reach Combined only" in m]
    checks.check(bool(warned) and "IndexOB" in warned[0],
                 "the passes Blend surfaces do not write are named in a warning", f"{warned[:1]}")
    h, w = cycles.shape[:2]
    rows = slice(int(h * 0.2), int(h * 0.8))
    for label, cols in (("alpha 0.4 pane", (0.08, 0.30)), ("checker alpha pane", (0.30, 0.48)),
                        ("two 0.5 panes", (0.72, 0.92))):
        block = (rows, slice(int(w * cols[0]), int(w * cols[1])))
        c, o = cycles[block].mean(), ours[block].mean()
        print(f"  Blend mode, {label}: Cycles {c:.4f}, ours at {BLEND_SAMPLES} samples {o:.4f}, ratio {o / c:.4f}")
        checks.check(abs(o / c - 1.0) < MEAN_LIMIT, f"Blend mode, {label}: mean within {MEAN_LIMIT:.0%} of Cycles",
                     f"ratio {o / c:.4f}")


EXACT_SAMPLES = 4
PANE_BLOCKS = (("alpha 0.4 pane", (0.08, 0.30)), ("checker alpha pane", (0.30, 0.48)),
               ("diffuse/transparent sphere", (0.52, 0.70)), ("two 0.5 panes", (0.72, 0.92)))


def exact_layers(checks, scene, cycles):
    """With Combined and data passes only, the panes (planar, partly
    transparent, ordered by the plane test: native layer_order.h) and the
    sphere (convex: its near side, then its far side) are composited by the
    forward pass at every sample instead of stochastically, though their
    Blend Mode is Opaque: all seven are taken (the alpha 0 plane and the
    shadowless sphere, opaque to the camera, too), with
    Object Index on as well (the data G-buffer keeps them at the Alpha
    Threshold). A colour pass (Diffuse Color) keeps them stochastic. At
    EXACT_SAMPLES samples each block is nearer Cycles' 1024 samples, per
    pixel, than the stochastic render, and its mean is within MEAN_LIMIT at
    BLEND_SAMPLES."""
    from deferred_render.engine import final
    layer = scene.view_layers[0]
    runs = {}
    try:
        for name, index_pass, colour_pass, samples in (("exact", False, False, EXACT_SAMPLES),
                                                       ("exact_index", True, False, EXACT_SAMPLES),
                                                       ("stochastic", True, True, EXACT_SAMPLES),
                                                       ("exact16", False, False, BLEND_SAMPLES)):
            layer.use_pass_object_index = index_pass
            layer.use_pass_diffuse_color = colour_pass
            scene.deferred_render.samples = samples
            ours = render(scene, "DEFERRED_RENDER")[0] if index_pass else render_combined(scene)
            runs[name] = (ours, int(final.last_timings.get("exact_layers", 0)))
    finally:
        layer.use_pass_object_index = True
        layer.use_pass_diffuse_color = True
        scene.deferred_render.samples = OURS_SAMPLES
    checks.check(runs["exact"][1] == 7, "Combined only: the five planes and both spheres are exact layers",
                 f"{runs['exact'][1]}")
    checks.check(runs["exact_index"][1] == 7, "with Object Index on too", f"{runs['exact_index'][1]}")
    checks.check(runs["stochastic"][1] == 0, "with Diffuse Color on: none (stochastic)", f"{runs['stochastic'][1]}")
    same = float(np.abs(runs["exact"][0] - runs["exact_index"][0]).max())
    checks.check(same < 1e-4, "Object Index on leaves Combined as it is", f"max difference {same:.2e}")
    h, w = cycles.shape[:2]
    rows = slice(int(h * 0.2), int(h * 0.8))
    for label, cols in PANE_BLOCKS:
        block = (rows, slice(int(w * cols[0]), int(w * cols[1])))
        rmse = {k: float(np.sqrt(np.mean((runs[k][0][block] - cycles[block]) ** 2))) for k in ("exact", "stochastic")}
        c, o = cycles[block].mean(), runs["exact16"][0][block].mean()
        print(f"  exact layers, {label}: per-pixel RMSE against Cycles at {EXACT_SAMPLES} samples {rmse['exact']:.4f} "
              f"(stochastic {rmse['stochastic']:.4f}); mean at {BLEND_SAMPLES} samples {o:.4f} (Cycles {c:.4f}, "
              f"ratio {o / c:.4f})")
        checks.check(rmse["exact"] < 0.85 * rmse["stochastic"], f"exact layers, {label}: less noise than stochastic",
                     f"{rmse['exact']:.4f} vs {rmse['stochastic']:.4f}")
        checks.check(abs(o / c - 1.0) < MEAN_LIMIT, f"exact layers, {label}: mean within {MEAN_LIMIT:.0%} of Cycles",
                     f"ratio {o / c:.4f}")


def render_combined(scene):
    """Ours with Combined alone (a single-layer EXR)."""
    scene.render.engine = "DEFERRED_RENDER"
    channels = U.read_exr(U.render_exr(os.path.join(OUT, "combined_only"), scene))
    return U.exr_pass(channels, "ViewLayer", "Combined", "RGB").astype(np.float64)


def clip_mode(checks, scene):
    """Blend Mode: Alpha Clip at 0.5 on the checker pane (alpha 0.1 / 0.9):
    the same image as a checker of alpha 0 / 1 with stochastic alpha (which
    is then deterministic), to float precision."""
    mat = bpy.data.materials["checker alpha"]
    remap = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeMapRange")
    scene.deferred_render.samples = 4
    try:
        mat.blend_method = 'CLIP'
        mat.alpha_threshold = 0.5
        clipped, _ = render(scene, "DEFERRED_RENDER")
        mat.blend_method = 'OPAQUE'
        remap.inputs["To Min"].default_value, remap.inputs["To Max"].default_value = 0.0, 1.0
        binary, _ = render(scene, "DEFERRED_RENDER")
    finally:
        mat.blend_method = 'OPAQUE'
        remap.inputs["To Min"].default_value, remap.inputs["To Max"].default_value = 0.1, 0.9
        scene.deferred_render.samples = OURS_SAMPLES
    worst = float(np.abs(clipped - binary).max())
    print(f"  Alpha Clip 0.5 vs a 0/1 checker: max |difference| {worst:.2e}")
    checks.check(worst < 1e-5, "Alpha Clip cuts at the threshold (as a 0/1 alpha)", f"{worst:.2e}")


def sharp_sun(checks, scene, index):
    """A sun without angle: its shadow maps would be drawn once, but the
    transparent casters must be drawn anew every sample or the partial
    shadows freeze into a dither (floor relMSE 1.6e-2 instead of 3.1e-3)."""
    sun = scene.objects["Sun"].data
    angle = sun.angle
    sun.angle = 0.0
    try:
        cycles, _ = render(scene, "CYCLES")
        ours, _ = render(scene, "DEFERRED_RENDER")
    finally:
        sun.angle = angle
    floor = (index == 1) & U.interior_mask(index, radius=2)
    rel = float(np.mean((ours[floor] - cycles[floor]) ** 2 / (cycles[floor] ** 2 + 0.01)))
    ratio = ours[floor].mean() / cycles[floor].mean()
    print(f"  sun without angle: floor relMSE {rel:.2e}, mean ratio {ratio:.4f}")
    # Measured 3.1e-3 (shadow-map edges of a sharp sun); 1.6e-2 with the maps frozen.
    checks.check(rel < 7e-3 and abs(ratio - 1.0) < MEAN_LIMIT, "partial shadows of a sharp sun converge",
                 f"relMSE {rel:.2e}, ratio {ratio:.4f}")


def film_transparent(checks, scene):
    """Film > Transparent: the alpha over the panes (no wall or floor behind
    them: both hidden) is Cycles' 1 - transmittance, per pane."""
    for name in ("Floor", "Back"):
        scene.objects[name].hide_render = True
    scene.render.film_transparent = True
    alphas = {}
    for engine in ("CYCLES", "DEFERRED_RENDER"):
        scene.render.engine = engine
        channels = U.read_exr(U.render_exr(os.path.join(OUT, "film_" + engine.lower()), scene))
        alphas[engine] = channels["ViewLayer.Combined.A"].astype(np.float64)
    scene.render.film_transparent = False
    for name in ("Floor", "Back"):
        scene.objects[name].hide_render = False
    c, o = alphas["CYCLES"], alphas["DEFERRED_RENDER"]
    h, w = c.shape
    rows = slice(int(h * 0.3), int(h * 0.7))
    for label, cols in (("alpha 0.4 pane", (0.12, 0.26)), ("checker alpha pane", (0.33, 0.45)),
                        ("two 0.5 panes", (0.76, 0.88))):
        block = (rows, slice(int(w * cols[0]), int(w * cols[1])))
        print(f"  film alpha, {label}: Cycles {c[block].mean():.4f}, ours {o[block].mean():.4f}")
        checks.check(abs(o[block].mean() - c[block].mean()) < 0.01, f"film alpha over the {label} as Cycles'",
                     f"{o[block].mean():.4f} vs {c[block].mean():.4f}")


def bad_alpha(checks, scene):
    """Alpha from a Value node: NaN (a non-finite constant takes the input's
    default, 1: export/material.py _sanitize), -1 (clamped to 0) and 3
    (clamped to 1): a finite image where the pane is opaque, absent and
    opaque."""
    for ob in [o for o in scene.objects if o.name not in {"Floor", "Back", "Camera", "Sun"}]:
        bpy.data.objects.remove(ob)
    upright = (math.pi / 2, 0.0, 0.0)
    for x, value in ((-2.0, float("nan")), (0.0, -1.0), (2.0, 3.0)):
        def build(nodes, links, bsdf, value=value):
            bsdf.inputs["Base Color"].default_value = (0.0, 0.0, 1.0, 1.0)
            v = nodes.new("ShaderNodeValue")
            v.outputs[0].default_value = value
            links.new(v.outputs[0], bsdf.inputs["Alpha"])
        add(scene, f"Bad{x}", bpy.ops.mesh.primitive_plane_add, (x, 0.0, 1.0), material(f"alpha {value}", build), 9,
            rotation=upright, size=1.4)
    scene.deferred_render.samples = 16
    ours, _ = render(scene, "DEFERRED_RENDER")
    checks.check(np.isfinite(ours).all(), "finite image", "")
    h, w = ours.shape[:2]
    blue = ours[..., 2] - ours[..., 0]  # the panes are pure blue, the back wall red
    cols = {"NaN": (0.22, 0.34), "-1": (0.45, 0.55), "3": (0.66, 0.78)}
    rows = slice(int(h * 0.35), int(h * 0.55))
    seen = {k: float(blue[rows, int(w * a):int(w * b)].mean()) for k, (a, b) in cols.items()}
    print(f"  blue minus red over each pane: {seen}")
    checks.check(seen["3"] > 0.1 and seen["NaN"] > 0.1 and seen["-1"] < 0.0,
                 "alpha 3 and NaN (the default) are opaque, -1 is transparent", str(seen))


def many_panes(checks, scene):
    for ob in [o for o in scene.objects if o.name not in {"Floor", "Back", "Camera", "Sun"}]:
        bpy.data.objects.remove(ob)
    n = 1000
    verts, faces = [], []
    for i in range(n):
        y = -1.0 + 1.5 * i / n
        base = len(verts)
        verts += [(-1.5, y, 0.3), (1.5, y, 0.3), (1.5, y, 2.0), (-1.5, y, 2.0)]
        faces.append((base, base + 1, base + 2, base + 3))
    mesh = bpy.data.meshes.new("panes")
    mesh.from_pydata(verts, [], faces)
    mesh.materials.append(material("pane 0.1", principled((0.1, 0.9, 0.1), 0.1)))
    ob = bpy.data.objects.new("Panes", mesh)
    scene.collection.objects.link(ob)
    scene.deferred_render.samples = 4
    import time
    t0 = time.perf_counter()
    ours, _ = render(scene, "DEFERRED_RENDER")
    seconds = time.perf_counter() - t0
    h, w = ours.shape[:2]
    centre = ours[int(h * 0.4):int(h * 0.55), int(w * 0.4):int(w * 0.6)]
    red_over_green = float(centre[..., 0].mean() / max(centre[..., 1].mean(), 1e-9))
    print(f"  1000 panes: {seconds:.2f} s at 4 samples; red/green behind them {red_over_green:.4f}")
    checks.check(np.isfinite(ours).all() and red_over_green < 0.2,
                 "the panes hide the red wall (transmittance 0.9^1000)", f"{red_over_green:.4f}")
    # The same in Blend mode: one object of 1000 layers in the forward pass
    # (composited in triangle order; equal layers make the order moot).
    mesh.materials[0].blend_method = 'BLEND'
    t0 = time.perf_counter()
    blended, _ = render(scene, "DEFERRED_RENDER")
    seconds = time.perf_counter() - t0
    centre = blended[int(h * 0.4):int(h * 0.55), int(w * 0.4):int(w * 0.6)]
    red_over_green = float(centre[..., 0].mean() / max(centre[..., 1].mean(), 1e-9))
    print(f"  1000 panes in Blend mode: {seconds:.2f} s at 4 samples; red/green behind them {red_over_green:.4f}")
    checks.check(np.isfinite(blended).all() and red_over_green < 0.2,
                 "Blend mode: the panes hide the red wall too", f"{red_over_green:.4f}")


main()
