"""Shader AOVs against Cycles 3.4 (issue: compositing outputs).

The analytic scene at 160x90, 16 samples, with the view layer's AOVs
"pattern" (Color) and "height" (Value): SphereB's and the floor's materials
get AOV Output nodes (a Checker of the Generated coordinates into
"pattern", the Z of the Position into "height"; the floor writes only
"height"), the other objects write nothing. Cycles and this engine render
the AOV passes. SphereC writes "height" through an AOV Output inside a node
group, fed by the group's input (Cycles flattens groups). Checks:
  * both AOVs are passes of the EXR, RGBA and single channel as in Cycles;
  * per pixel they equal Cycles' away from object edges (the interior of
    each object by Cycles' IndexOB), within what two 16-sample estimates of
    a pixel-filtered value can differ by: half the value's range over the
    pixel's 3x3 neighbourhood in Cycles' image (the filter spans 1.5 px),
    plus 1e-3; on 99 % of the pixels;
  * 0 where nothing writes them (background and the other objects);
  * the mean over the image within 1 % of Cycles' (edges included);
  * a material whose only difference is an AOV Output still renders the
    same Combined (the AOV costs no shading change).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_aovs.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("aovs")


def allowed(image):
    """Per pixel: half the range of ``image`` over the 3x3 neighbourhood,
    plus 1e-3 (see the docstring)."""
    padded = np.pad(image, 1, mode="edge")
    h, w = image.shape
    shifts = [padded[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    return 0.5 * (np.max(shifts, axis=0) - np.min(shifts, axis=0)) + 1e-3


def add_aov_outputs(material, pattern):
    nodes, links = material.node_tree.nodes, material.node_tree.links
    geometry = nodes.new("ShaderNodeNewGeometry")
    xyz = nodes.new("ShaderNodeSeparateXYZ")
    links.new(geometry.outputs["Position"], xyz.inputs[0])
    height = nodes.new("ShaderNodeOutputAOV")
    height.name = "height"
    links.new(xyz.outputs["Z"], height.inputs["Value"])
    if pattern:
        coords = nodes.new("ShaderNodeTexCoord")
        checker = nodes.new("ShaderNodeTexChecker")
        checker.inputs["Scale"].default_value = 4.0
        links.new(coords.outputs["Generated"], checker.inputs["Vector"])
        out = nodes.new("ShaderNodeOutputAOV")
        out.name = "pattern"
        links.new(checker.outputs["Color"], out.inputs["Color"])


def add_grouped_aov_output(material):
    """Position.Z -> a group whose AOV Output "height" reads the group's input."""
    group = bpy.data.node_groups.new("AOVGroup", "ShaderNodeTree")
    group.inputs.new("NodeSocketFloat", "Height")
    group_in = group.nodes.new("NodeGroupInput")
    out = group.nodes.new("ShaderNodeOutputAOV")
    out.name = "height"
    group.links.new(group_in.outputs["Height"], out.inputs["Value"])
    nodes, links = material.node_tree.nodes, material.node_tree.links
    geometry = nodes.new("ShaderNodeNewGeometry")
    xyz = nodes.new("ShaderNodeSeparateXYZ")
    links.new(geometry.outputs["Position"], xyz.inputs[0])
    node = nodes.new("ShaderNodeGroup")
    node.node_tree = group
    links.new(xyz.outputs["Z"], node.inputs["Height"])


def setup(scene):
    layer = U.comparison_setup(scene)
    layer.use_pass_object_index = True
    for name, kind in (("pattern", 'COLOR'), ("height", 'VALUE')):
        aov = layer.aovs.add()
        aov.name, aov.type = name, kind
    add_aov_outputs(bpy.data.materials["MatSphereB"], pattern=True)
    add_aov_outputs(bpy.data.materials["MatFloor"], pattern=False)
    add_grouped_aov_output(bpy.data.materials["MatSphereC"])


def render(scene, engine, name):
    scene.render.engine = engine
    return U.read_exr(U.render_exr(os.path.join(OUT, name), scene))


def main():
    checks = U.Checks("aovs")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    setup(scene)
    cycles = render(scene, "CYCLES", "cycles")
    ours = render(scene, "DEFERRED_RENDER", "ours")
    names = sorted(k for k in cycles if k.startswith("ViewLayer.pattern") or k.startswith("ViewLayer.height"))
    mine = sorted(k for k in ours if k.startswith("ViewLayer.pattern") or k.startswith("ViewLayer.height"))
    checks.check(names == mine and len(names) == 5, "the AOV passes and channels are Cycles'", f"{mine}")
    index = cycles["ViewLayer.IndexOB.X"].astype(np.int64)
    inner = U.interior_mask(index, radius=1)
    sphere_b, floor, sphere_c = inner & (index == 4), inner & (index == 1), inner & (index == 5)
    others = inner & ~np.isin(index, (1, 4, 5))

    c_h, o_h = cycles["ViewLayer.height.X"].astype(np.float64), ours["ViewLayer.height.X"].astype(np.float64)
    writes = sphere_b | floor | sphere_c
    close = float((np.abs(o_h - c_h) <= allowed(c_h))[writes].mean())
    grouped = float((np.abs(o_h - c_h) <= allowed(c_h))[sphere_c].mean())
    checks.check(sphere_c.sum() > 300 and grouped >= 0.99 and float(np.abs(c_h[sphere_c]).min()) > 0.1,
                 "height written inside a node group is Cycles'", f"{grouped:.4f}")
    print(f"  height: {int(writes.sum())} interior px, {close:.4f} within the filter's spread")
    checks.check(writes.sum() > 3000 and close >= 0.99, "height (Value AOV) is Cycles' on the writing objects",
                 f"{close:.4f}")
    c_p = np.stack([cycles[f"ViewLayer.pattern.{c}"] for c in "RGBA"], -1).astype(np.float64)
    o_p = np.stack([ours[f"ViewLayer.pattern.{c}"] for c in "RGBA"], -1).astype(np.float64)
    bound = np.max([allowed(c_p[..., c]) for c in range(3)], axis=0)
    same = float((np.abs(o_p[..., :3] - c_p[..., :3]).max(axis=-1) <= bound)[sphere_b].mean())
    print(f"  pattern on SphereB: {int(sphere_b.sum())} interior px, {same:.4f} equal; alpha ours "
          f"{o_p[sphere_b, 3].mean():.4f}, Cycles {c_p[sphere_b, 3].mean():.4f}")
    checks.check(sphere_b.sum() > 500 and same >= 0.99, "pattern (Color AOV) is Cycles' on SphereB", f"{same:.4f}")
    checks.check(float(np.abs(o_p[sphere_b, 3] - c_p[sphere_b, 3]).max()) < 1e-3,
                 "the Color AOV's alpha is Cycles'", f"{o_p[sphere_b, 3].mean():.4f} vs {c_p[sphere_b, 3].mean():.4f}")
    background = cycles["ViewLayer.IndexOB.X"] == 0
    zero = float(np.abs(o_p[others | floor | sphere_c]).max()) + float(np.abs(o_h[others]).max()) + \
        float(np.abs(o_h[background & inner]).max())
    checks.check(zero == 0.0, "0 where nothing writes the AOV", f"{zero:g}")
    for label, c, o in (("height", c_h, o_h), ("pattern", c_p[..., :3], o_p[..., :3])):
        ratio = float(o.mean() / c.mean())
        checks.check(abs(ratio - 1.0) < 0.01, f"{label}: image mean within 1 % of Cycles'", f"{ratio:.4f}")

    # The AOV Output changes nothing else: Combined as without the AOVs asked.
    layer = scene.view_layers[0]
    with_aovs = U.exr_pass(ours, "ViewLayer", "Combined", "RGB")
    for aov in layer.aovs:
        aov.name = ""  # an AOV without a name is not asked for (is_valid false)
    without = U.exr_pass(render(scene, "DEFERRED_RENDER", "no_aovs"), "ViewLayer", "Combined", "RGB")
    diff = float(np.abs(with_aovs - without).max())
    checks.check(diff < 1e-5, "Combined is the same with and without the AOVs asked", f"{diff:.2e}")
    checks.finish()


main()
