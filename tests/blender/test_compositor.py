"""The compositor sees the passes and computes the expected pixels.

Builds, in the analytic scene:

    Render Layers.Image  -> Composite
    Render Layers.Depth  -> Math(x 0.01)                         -> File Output "depth"
    Render Layers.Normal -> Separate XYZ.Z -> Math(+1) -> Math(x 0.5) -> File Output "normal_z"
    Render Layers.IndexOB -> ID Mask(index 4)                    -> File Output "mask"

renders (F12 with write_still) and compares the File Output EXRs with the
same passes of the multilayer EXR written by the render. A second File
Output node (multilayer EXR) writes every output of the Render Layers node
(every pass, Vector, Shadow Catcher and Cryptomatte included): each of its
layers equals the render's pass (a vector socket carries three channels).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_compositor.py
"""

import glob
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402


def build_tree(scene, out):
    scene.use_nodes = True
    scene.render.use_compositing = True
    tree = scene.node_tree
    tree.nodes.clear()
    rl = tree.nodes.new("CompositorNodeRLayers")
    rl.layer = "ViewLayer"
    comp = tree.nodes.new("CompositorNodeComposite")
    tree.links.new(rl.outputs["Image"], comp.inputs["Image"])

    scale = tree.nodes.new("CompositorNodeMath")
    scale.operation = 'MULTIPLY'
    scale.inputs[1].default_value = 0.01
    tree.links.new(rl.outputs["Depth"], scale.inputs[0])

    sep = tree.nodes.new("CompositorNodeSeparateXYZ")
    tree.links.new(rl.outputs["Normal"], sep.inputs[0])
    add = tree.nodes.new("CompositorNodeMath")
    add.operation = 'ADD'
    add.inputs[1].default_value = 1.0
    tree.links.new(sep.outputs["Z"], add.inputs[0])
    half = tree.nodes.new("CompositorNodeMath")
    half.operation = 'MULTIPLY'
    half.inputs[1].default_value = 0.5
    tree.links.new(add.outputs[0], half.inputs[0])

    mask = tree.nodes.new("CompositorNodeIDMask")
    mask.index = 4          # SphereB's object pass index
    mask.use_antialiasing = False
    tree.links.new(rl.outputs["IndexOB"], mask.inputs[0])

    fo = tree.nodes.new("CompositorNodeOutputFile")
    fo.base_path = os.path.join(out, "fileout") + os.sep
    fo.format.file_format = 'OPEN_EXR'
    fo.format.color_depth = '32'
    fo.format.color_mode = 'RGB'
    # (file_slots.clear() leaks a block in Blender 3.4: rename the default slot instead)
    fo.file_slots[0].path = "depth"
    fo.file_slots.new("normal_z")
    fo.file_slots.new("mask")
    for index, socket in enumerate((scale.outputs[0], half.outputs[0], mask.outputs[0])):
        tree.links.new(socket, fo.inputs[index])

    every = tree.nodes.new("CompositorNodeOutputFile")
    every.base_path = os.path.join(out, "everypass") + os.sep
    every.format.file_format = 'OPEN_EXR_MULTILAYER'
    every.format.color_depth = '32'
    outputs = [s for s in rl.outputs if s.enabled]
    every.layer_slots[0].name = outputs[0].name
    for socket in outputs[1:]:
        every.layer_slots.new(socket.name)
    for index, socket in enumerate(outputs):
        tree.links.new(socket, every.inputs[index])
    return rl


# A channel's place in its pass: RGBA, XYZW, UVA (the UV pass), rgba (Cryptomatte), V (a value).
CHANNEL_ORDER = {"R": 0, "G": 1, "B": 2, "A": 3, "X": 0, "Y": 1, "Z": 2, "W": 3, "U": 0, "V": 1,
                 "r": 0, "g": 1, "b": 2, "a": 3}


def check_every_pass(checks, out, render_channels, socket_names):
    """Each layer the multilayer File Output wrote equals the render's pass."""
    files = sorted(glob.glob(os.path.join(out, "everypass", "*.exr")))
    if not checks.check(len(files) == 1, "a File Output node writes every pass", str(files)):
        return
    written = U.read_exr(files[0])
    compared, worst = [], 0.0
    for name in socket_names:
        pass_name = "Combined" if name in ("Image", "Alpha") else name
        theirs = sorted((k for k in render_channels if k.startswith(f"ViewLayer.{pass_name}.")),
                        key=lambda k: CHANNEL_ORDER[k.rsplit(".", 1)[1]])
        mine = sorted((k for k in written if k.startswith(f"{name}.")), key=lambda k: CHANNEL_ORDER[k.rsplit(".", 1)[1]])
        if name == "Alpha":
            theirs = [f"ViewLayer.Combined.A"]
        n = min(len(theirs), len(mine))
        if not checks.check(n > 0, f"File Output layer {name} has the pass's channels", f"{mine} / {theirs}"):
            continue
        for a, b in zip(mine[:n], theirs[:n]):
            worst = max(worst, float(np.abs(written[a].astype(np.float64) - render_channels[b]).max()))
        compared.append(name)
    print(f"  File Output layers compared: {compared}")
    checks.check(len(compared) == len(socket_names) and worst < 1e-5,
                 f"every pass written through the compositor equals the render's ({len(compared)} layers)",
                 f"largest difference {worst:.2e}")


def main():
    checks = U.Checks("test_compositor")
    scene = bpy.context.scene
    if not U.require_engine(checks):
        checks.finish()
    scene.deferred_render.samples = 1
    U.set_all_passes(scene.view_layers[0], True)
    scene.view_layers[0].use_pass_cryptomatte_object = True
    out = U.out_dir("compositor")
    for old in glob.glob(os.path.join(out, "fileout", "*")) + glob.glob(os.path.join(out, "everypass", "*")):
        os.remove(old)
    rl = build_tree(scene, out)
    enabled = [s.name for s in rl.outputs if s.enabled]
    checks.check({"Image", "Alpha", "Depth", "Normal", "IndexOB", "Position", "UV"} <= set(enabled),
                 "Render Layers node shows the registered passes", str(enabled))

    path = U.render_exr(os.path.join(out, "render"))
    ch = U.read_exr(path)
    depth = ch["ViewLayer.Depth.Z"]
    nz = ch["ViewLayer.Normal.Z"]
    index = ch["ViewLayer.IndexOB.X"]

    def file_output(name):
        files = sorted(glob.glob(os.path.join(out, "fileout", name + "*.exr")))
        if not checks.check(len(files) == 1, f"File Output wrote {name}", str(files)):
            return None
        return U.read_exr(files[0])["R"]

    got = file_output("depth")
    if got is not None:
        expected = depth * np.float32(0.01)
        rel = np.abs(got - expected) / np.maximum(np.abs(expected), 1e-6)
        checks.check(rel.max() < 1e-5, "Depth x 0.01 through a Math node", f"max rel {rel.max():.2e}")
    got = file_output("normal_z")
    if got is not None:
        expected = (nz + 1) * 0.5
        err = np.abs(got - expected)
        checks.check(err.max() < 1e-6, "(Normal.Z + 1) / 2 through Separate XYZ and Math nodes", f"max {err.max():.2e}")
        checks.check(np.abs(got[index == 1] - 1.0).max() < 1e-5, "floor pixels: normal_z = 1")
    got = file_output("mask")
    if got is not None:
        expected = (index == 4).astype(np.float32)
        checks.check(np.array_equal(got, expected), "ID Mask of IndexOB selects SphereB exactly",
                     f"{int(expected.sum())} px")
    check_every_pass(checks, out, ch, [s.name for s in rl.outputs if s.enabled])
    layers = sorted({name.rsplit(".", 2)[0] for name in ch})
    print("  EXR layers:", layers)
    if "Composite" in layers:
        comp = np.stack([ch[f"Composite.Combined.{c}"] for c in "RGB"], -1)
        rgb = np.stack([ch[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1)
        checks.check(np.abs(comp - rgb).max() < 1e-5, "Composite = Render Layers Image")
    checks.finish()


main()
