"""The Vector pass against Cycles 3.4 (issue: compositing outputs).

The analytic scene at 160x90, 32 samples, frame 2 of an animation:
  * objects: the Box slides and turns (keyframes at frames 1, 2, 3, Bezier
    as Blender makes them, so the neighbouring frames are evaluated, not
    extrapolated), SphereA grows through an animated shape key (deformation
    motion), SphereC stands still; the camera stands still;
  * camera: the objects stand still and the camera moves and turns.
Checks, per case, on the interior pixels of each object (by Cycles' IndexOB,
away from edges, where both engines average the same surface):
  * the pass is Cycles' Vector (XYZW) and its motion per pixel is within
    0.05 px of Cycles' on 99 % of the pixels where the motion is smooth
    (it varies by less than 1 px over the 3x3 neighbourhood in Cycles'
    pass); both are 32-sample averages over the pixel filter, so where the
    motion varies steeply (a face seen edge-on at a crease of the turning
    Box: up to 3 px from one pixel to the next) they differ by that
    variation's sampling noise: there the bound is 0.05 px plus a tenth of
    the neighbourhood's range, on 99 % of all the interior pixels;
  * the still sphere is 0 in the objects case (a Decimate modifier changes
    its vertex count every frame: warned, its deformation left out, as
    Cycles), the background 0 in both;
  * the motion is real: the Box moves by pixels, SphereA's deformation
    makes its rim move outwards.
(With Motion Blur on the pass is 0, as in Cycles: test_motion_blur.py.)
Then through the compositor, in Blender: a Vector Blur node fed with our
Vector and Depth passes blurs the moving Box as Cycles' passes make it
blur (the blurred images differ from each other no more than the two
engines' unblurred images do, plus 2e-3 per pixel on average), and it does
change our image around the Box (so the pass reached the node); a File
Output node writes our Vector pass as the render has it.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_vector_pass.py
"""

import glob
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("vector_pass")
SAMPLES = 32


def keyframe(ob, path, values):
    for frame, value in zip((1, 2, 3), values):
        setattr(ob, path, value)
        ob.keyframe_insert(path, frame=frame)


def animate_objects(scene):
    box = bpy.data.objects["Box"]
    keyframe(box, "location", [(-1.9, -4.0, 0.5), (-1.5, -4.0, 0.5), (-0.8, -3.7, 0.5)])
    keyframe(box, "rotation_euler", [(0.0, 0.0, -0.25), (0.0, 0.0, 0.0), (0.0, 0.0, 0.4)])
    sphere = bpy.data.objects["SphereA"]
    sphere.shape_key_add(name="Basis")
    grow = sphere.shape_key_add(name="Grow")
    for v in grow.data:
        v.co = v.co * 1.25
    for frame, value in zip((1, 2, 3), (0.0, 0.4, 1.0)):
        grow.value = value
        grow.keyframe_insert("value", frame=frame)
    # SphereC stands still but a Decimate modifier changes its vertex count
    # every frame: its deformation cannot be matched (warned, no motion).
    decimate = bpy.data.objects["SphereC"].modifiers.new("Decimate", 'DECIMATE')
    for frame, ratio in zip((1, 2, 3), (0.5, 0.7, 0.9)):
        decimate.ratio = ratio
        decimate.keyframe_insert("ratio", frame=frame)


def animate_camera(scene):
    for name in ("Box", "SphereA"):
        ob = bpy.data.objects[name]
        ob.animation_data_clear()
        if ob.data.shape_keys is not None:
            ob.data.shape_keys.animation_data_clear()
            ob.shape_key_clear()
    cam = scene.camera
    loc, rot = tuple(cam.location), tuple(cam.rotation_euler)
    keyframe(cam, "location", [(loc[0] - 0.6, loc[1] + 0.3, loc[2] + 0.2), loc,
                               (loc[0] + 0.5, loc[1] - 0.4, loc[2] - 0.1)])
    keyframe(cam, "rotation_euler", [(rot[0] + 0.03, rot[1], rot[2] - 0.04), rot,
                                     (rot[0] - 0.02, rot[1], rot[2] + 0.05)])


def render(scene, engine, name):
    scene.render.engine = engine
    return U.read_exr(U.render_exr(os.path.join(OUT, name), scene))


def vector(channels):
    return U.exr_pass(channels, "ViewLayer", "Vector", "XYZW").astype(np.float64)


def neighbourhood_range(image):
    """Per pixel, the largest range of any channel over the 3x3 neighbourhood."""
    h, w = image.shape[:2]
    padded = np.pad(image, ((1, 1), (1, 1), (0, 0)), mode="edge")
    shifts = [padded[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    return (np.max(shifts, axis=0) - np.min(shifts, axis=0)).max(axis=-1)


def compare(checks, case, cycles, ours, moving):
    names = sorted(k for k in ours if ".Vector." in k)
    checks.check(names == sorted(k for k in cycles if ".Vector." in k) and len(names) == 4,
                 f"{case}: the Vector pass has Cycles' channels", f"{names}")
    c, o = vector(cycles), vector(ours)
    index = cycles["ViewLayer.IndexOB.X"].astype(np.int64)
    inner = U.interior_mask(index, radius=1)
    spread = neighbourhood_range(c)
    error = np.abs(o - c).max(axis=-1)
    for label, ids in moving.items():
        mask = inner & np.isin(index, ids)
        smooth = mask & (spread < 1.0)
        err = error[smooth]
        share = float((err <= 0.05).mean())
        share_all = float((error[mask] <= 0.05 + 0.1 * spread[mask]).mean())
        size = float(np.abs(c[mask]).max())
        print(f"  {case} {label}: {int(mask.sum())} px ({int(smooth.sum())} smooth), Cycles' largest |motion| "
              f"{size:.2f} px, ours - Cycles where smooth: median {np.median(err):.4f}, 99th percentile "
              f"{np.percentile(err, 99):.4f} px; everywhere: largest {error[mask].max():.3f} px")
        checks.check(smooth.sum() > 40 and share >= 0.99, f"{case}: {label} within 0.05 px of Cycles' motion",
                     f"{share:.4f} of the smooth pixels, 99th percentile {np.percentile(err, 99):.4f} px")
        checks.check(share_all >= 0.99, f"{case}: {label} within 0.05 px + a tenth of the local variation",
                     f"{share_all:.4f} of its interior pixels")
    background = inner & (index == 0)
    checks.check(background.sum() > 100 and float(np.abs(o[background]).max()) == 0.0,
                 f"{case}: the background has no motion", f"{np.abs(o[background]).max():g}")
    return c, o, index, inner


def vector_blur_composite(scene, name):
    """Composite through Render Layers -> Vector Blur (Image, Depth, Vector) into a single-layer EXR."""
    scene.use_nodes = True
    tree = scene.node_tree
    tree.nodes.clear()
    layers = tree.nodes.new("CompositorNodeRLayers")
    blur = tree.nodes.new("CompositorNodeVecBlur")
    blur.samples = 32
    blur.factor = 1.0
    composite = tree.nodes.new("CompositorNodeComposite")
    tree.links.new(layers.outputs["Image"], blur.inputs["Image"])
    tree.links.new(layers.outputs["Depth"], blur.inputs["Z"])
    tree.links.new(layers.outputs["Vector"], blur.inputs["Speed"])
    tree.links.new(blur.outputs["Image"], composite.inputs["Image"])
    # And the Vector pass itself through a File Output node.
    for old in glob.glob(os.path.join(OUT, "fileout", name + "*")):
        os.remove(old)
    file_output = tree.nodes.new("CompositorNodeOutputFile")
    file_output.base_path = os.path.join(OUT, "fileout") + os.sep
    file_output.format.file_format = 'OPEN_EXR'
    file_output.format.color_depth = '32'
    file_output.format.color_mode = 'RGB'
    file_output.file_slots[0].path = name + "_vector"
    tree.links.new(layers.outputs["Vector"], file_output.inputs[0])
    scene.render.use_compositing = True
    img = scene.render.image_settings
    img.file_format = 'OPEN_EXR'
    img.color_depth = '32'
    scene.render.filepath = os.path.join(OUT, name)
    bpy.ops.render.render(write_still=True)
    scene.use_nodes = False
    channels = U.read_exr(os.path.join(OUT, name) + ".exr")
    written = sorted(glob.glob(os.path.join(OUT, "fileout", name + "_vector*.exr")))
    vector_file = U.read_exr(written[0]) if len(written) == 1 else None
    return np.stack([channels[k] for k in ("R", "G", "B")], axis=-1).astype(np.float64), vector_file


def main():
    checks = U.Checks("vector_pass")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    layer = U.comparison_setup(scene, samples=SAMPLES)
    layer.use_pass_object_index = True
    layer.use_pass_vector = True
    layer.use_pass_z = True
    scene.render.use_motion_blur = False
    scene.frame_set(2)

    animate_objects(scene)
    scene.frame_set(2)
    cycles = render(scene, "CYCLES", "objects_cycles")
    ours = render(scene, "DEFERRED_RENDER", "objects_ours")
    checks.check(scene.frame_current == 2, "the render leaves the scene at its frame", f"{scene.frame_current}")
    c, o, index, inner = compare(checks, "objects", cycles, ours, {"Box": [6], "SphereA (shape key)": [3],
                                                                    "SphereC (still)": [5]})
    still = inner & (index == 5)
    checks.check(float(np.abs(o[still]).max()) == 0.0, "objects: the still sphere has no motion",
                 f"{np.abs(o[still]).max():g}")
    box = inner & (index == 6)
    checks.check(float(np.abs(o[box][:, :2]).max()) > 1.0, "objects: the Box moves by pixels",
                 f"{np.abs(o[box][:, :2]).max():.2f} px")
    # SphereA grows from frame 1 to 3: its rim moves outwards, so the motion
    # to the next frame (zw = now - next) points inwards on its left side.
    sphere = inner & (index == 3)
    xs = np.nonzero(sphere)[1]
    left = sphere & (np.arange(sphere.shape[1])[None, :] < np.percentile(xs, 10))
    checks.check(float(o[left][:, 2].mean()) > 0.2, "objects: the shape key's growth is in the pass",
                 f"zw.x on the left rim {o[left][:, 2].mean():.3f} px (Cycles {c[left][:, 2].mean():.3f})")
    warned = [m for _, m in U.last_messages() if "'SphereC'" in m and "vertex count changes" in m]
    checks.check(len(warned) >= 1, "objects: a vertex count that changes between frames is warned about",
                 f"{warned[:1]}")

    # Vector Blur on the objects case: ours blurs as Cycles' passes do.
    sharp_ours = U.exr_pass(ours, "ViewLayer", "Combined", "RGB").astype(np.float64)
    sharp_cycles = U.exr_pass(cycles, "ViewLayer", "Combined", "RGB").astype(np.float64)
    scene.render.engine = 'DEFERRED_RENDER'
    blurred_ours, vector_file = vector_blur_composite(scene, "blurred_ours")
    scene.render.engine = 'CYCLES'
    blurred_cycles, _ = vector_blur_composite(scene, "blurred_cycles")
    if checks.check(vector_file is not None, "a File Output node writes our Vector pass"):
        # (Its image file gets the socket's first three channels.)
        written = np.stack([vector_file[k] for k in "RGB"], axis=-1).astype(np.float64)
        diff = float(np.abs(written - o[..., :3]).max())
        checks.check(diff < 1e-5, "... equal to the render's Vector pass", f"{diff:.2e}")
    # Around the Box (its pixels grown by 12 px, the length of its motion).
    near_box = cycles["ViewLayer.IndexOB.X"] == 6
    for _ in range(12):
        near_box = near_box | np.roll(near_box, 1, 0) | np.roll(near_box, -1, 0) | np.roll(near_box, 1, 1) | \
            np.roll(near_box, -1, 1)
    changed = float(np.abs(blurred_ours - sharp_ours)[near_box].mean())
    engines_sharp = float(np.abs(sharp_ours - sharp_cycles).mean())
    engines_blurred = float(np.abs(blurred_ours - blurred_cycles).mean())
    print(f"  Vector Blur: ours changed by {changed:.4f} on average around the Box; ours - Cycles {engines_sharp:.4f} "
          f"unblurred, {engines_blurred:.4f} blurred")
    checks.check(changed > 0.01, "Vector Blur blurs our render around the Box (the pass reaches the node)",
                 f"{changed:.4f}")
    checks.check(engines_blurred <= engines_sharp + 2e-3, "Vector Blur of ours is Cycles' Vector Blur",
                 f"{engines_blurred:.4f} vs unblurred {engines_sharp:.4f}")

    animate_camera(scene)
    scene.frame_set(2)
    cycles = render(scene, "CYCLES", "camera_cycles")
    ours = render(scene, "DEFERRED_RENDER", "camera_ours")
    compare(checks, "camera", cycles, ours, {"floor": [1], "wall": [2], "spheres": [3, 4, 5], "Box": [6]})
    checks.finish()


if __name__ == "__main__":  # (test_motion_blur imports the animations)
    main()
