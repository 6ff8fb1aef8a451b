"""Animation: `-a` over three frames of a moving object writes three frames.

Keys SphereB's x location (frame 1: -2, 2: 0, 3: +2) and the sun's power,
saves a copy of the scene and renders it with

    blender -b anim.blend --addons deferred_render -E DEFERRED_RENDER \
        -o OUT/anim_#### -F OPEN_EXR_MULTILAYER -s 1 -e 3 -a

Checks: three EXRs, pairwise different, SphereB's IndexOB mask moves right
frame by frame by the projected distance.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_animation.py
"""

import glob
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402


def main():
    checks = U.Checks("test_animation")
    scene = bpy.context.scene
    if not U.require_engine(checks):
        checks.finish()
    out = U.out_dir("animation")
    for old in glob.glob(os.path.join(out, "anim_*")):
        os.remove(old)
    sphere = bpy.data.objects["SphereB"]
    for frame, x in ((1, -2.0), (2, 0.0), (3, 2.0)):
        sphere.location.x = x
        sphere.keyframe_insert("location", index=0, frame=frame)
    for fcurve in sphere.animation_data.action.fcurves:
        for key in fcurve.keyframe_points:
            key.interpolation = 'LINEAR'
    scene.frame_start, scene.frame_end = 1, 3
    scene.deferred_render.samples = 1
    U.set_all_passes(scene.view_layers[0], False)
    scene.view_layers[0].use_pass_object_index = True
    blend = os.path.join(out, "anim.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend, copy=True)

    cmd = U.blender_command(blend, "-o", os.path.join(out, "anim_####"), "-F", "OPEN_EXR_MULTILAYER",
                            "-s", "1", "-e", "3", "-a")
    code, output = U.run_blender(cmd)
    checks.check(code == 0, "blender -a exits 0")
    checks.check("Error" not in output, "no error reported",
                 " | ".join(l for l in output.splitlines() if "Error" in l)[:300])
    files = sorted(glob.glob(os.path.join(out, "anim_*.exr")))
    names = [os.path.basename(f) for f in files]
    checks.check(names == ["anim_0001.exr", "anim_0002.exr", "anim_0003.exr"], "three frames written", str(names))
    if len(files) != 3:
        print(output[-3000:])
        checks.finish()
    frames = [U.read_exr(f) for f in files]
    rgb = [np.stack([f[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1) for f in frames]
    different = all(np.abs(rgb[i] - rgb[j]).max() > 0.05 for i, j in ((0, 1), (1, 2), (0, 2)))
    checks.check(different, "the three frames differ")
    centres = []
    for f in frames:
        ys, xs = np.nonzero(f["ViewLayer.IndexOB.X"] == 4)
        centres.append(xs.mean() if len(xs) else float("nan"))
    steps = np.diff(centres)
    checks.check(np.all(steps > 10) and abs(steps[0] - steps[1]) < 3, "SphereB moves right by equal steps",
                 f"centre x {[round(c, 1) for c in centres]}")
    checks.finish()


main()
