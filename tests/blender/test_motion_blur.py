"""Motion blur against Cycles 3.4 (issue: compositing outputs).

The analytic scene at 160x90, frame 2 of an animation with Render
Properties > Motion Blur on (Shutter 0.5 frames, Position Center): the Box
slides and turns, SphereA grows through an animated shape key; then the
camera pans instead; then Position Start with a 1-frame shutter. Cycles
renders each twice (seeds 0 and 1), ours once, all at 64 samples. Checks,
on the pixels the motion touches (where the blurred and the unblurred
Cycles images differ by more than 0.02, grown by 2 px):
  * ours against Cycles' first render differs no more than Cycles' two
    renders differ from each other (RMSE, with 15 % of margin): the blur
    is within Cycles' own noise at equal samples;
  * the blur is there, as much as in Cycles: ours differs from our
    unblurred render there by more than twice that noise, and by as much as
    Cycles' blurred render differs from its unblurred one (within 15 %);
  * the frame is left where it was, and the Vector pass, asked for, is 0
    with a warning (Cycles leaves it empty with motion blur);
  * a lens animated over the shutter (not blurred here) is warned about.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \\
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_motion_blur.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402
import test_vector_pass as V  # noqa: E402  (the animations; its main() runs only as a script)

OUT = U.out_dir("motion_blur")
SAMPLES = 64


def render(scene, engine, name, seed=0):
    scene.render.engine = engine
    scene.cycles.seed = seed
    channels = U.read_exr(U.render_exr(os.path.join(OUT, name), scene))
    return U.exr_pass(channels, "ViewLayer", "Combined", "RGB").astype(np.float64), channels


def grow(mask, pixels):
    for _ in range(pixels):
        mask = mask | np.roll(mask, 1, 0) | np.roll(mask, -1, 0) | np.roll(mask, 1, 1) | np.roll(mask, -1, 1)
    return mask


def rmse(a, b, mask):
    return float(np.sqrt(((a - b)[mask] ** 2).mean()))


def compare(checks, scene, case):
    scene.render.use_motion_blur = False
    sharp_cycles, _ = render(scene, "CYCLES", f"{case}_sharp_cycles")
    sharp_ours, _ = render(scene, "DEFERRED_RENDER", f"{case}_sharp_ours")
    scene.render.use_motion_blur = True
    cycles_a, _ = render(scene, "CYCLES", f"{case}_cycles_a", seed=0)
    cycles_b, _ = render(scene, "CYCLES", f"{case}_cycles_b", seed=1)
    ours, channels = render(scene, "DEFERRED_RENDER", f"{case}_ours")
    moving = grow(np.abs(cycles_a - sharp_cycles).max(axis=-1) > 0.02, 2)
    noise = rmse(cycles_a, cycles_b, moving)
    error = rmse(ours, cycles_a, moving)
    blur = rmse(ours, sharp_ours, moving)
    cycles_blur = rmse(cycles_a, sharp_cycles, moving)
    print(f"  {case}: {int(moving.sum())} px touched by motion; RMSE ours - Cycles {error:.4f}, Cycles - Cycles "
          f"{noise:.4f}, blurred - unblurred ours {blur:.4f} Cycles {cycles_blur:.4f}; means ours "
          f"{ours[moving].mean():.4f} Cycles {cycles_a[moving].mean():.4f}")
    checks.check(moving.sum() > 200 and error <= 1.15 * noise, f"{case}: the blur is Cycles' within its own noise",
                 f"RMSE {error:.4f} vs Cycles' own {noise:.4f}")
    checks.check(blur > 2.0 * noise and abs(blur / cycles_blur - 1.0) < 0.15,
                 f"{case}: the render is blurred as much as Cycles'", f"{blur:.4f} vs Cycles {cycles_blur:.4f}")
    return channels


def main():
    checks = U.Checks("motion_blur")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    layer = U.comparison_setup(scene, samples=SAMPLES)
    scene.render.motion_blur_shutter = 0.5
    scene.cycles.motion_blur_position = 'CENTER'
    V.animate_objects(scene)
    scene.frame_set(2)
    layer.use_pass_vector = True
    channels = compare(checks, scene, "objects")
    checks.check(scene.frame_current == 2 and scene.frame_subframe == 0.0, "the frame is left where it was")
    vector = V.vector(channels)
    warned = [m for _, m in U.last_messages() if "Vector pass is empty" in m]
    checks.check(float(np.abs(vector).max()) == 0.0 and len(warned) >= 1,
                 "the Vector pass is 0 with motion blur, warned (as Cycles leaves it)", f"{warned[:1]}")
    layer.use_pass_vector = False

    scene.cycles.motion_blur_position = 'START'
    scene.render.motion_blur_shutter = 1.0
    compare(checks, scene, "objects, Position Start, shutter 1")
    checks.check(scene.frame_current == 2 and scene.frame_subframe == 0.0,
                 "the frame is left where it was (the shutter's middle was frame 2.5)",
                 f"{scene.frame_current} + {scene.frame_subframe}")
    scene.cycles.motion_blur_position = 'CENTER'
    scene.render.motion_blur_shutter = 0.5

    V.animate_camera(scene)
    scene.frame_set(2)
    compare(checks, scene, "camera")
    lens_warnings = [m for _, m in U.last_messages() if "lens, ortho scale or shift" in m]
    checks.check(not lens_warnings, "no lens warning while only the camera's transform moves", f"{lens_warnings}")

    # A zoom over the shutter is not blurred: said.
    lens = scene.camera.data
    for frame, value in zip((1, 2, 3), (45.0, 50.0, 55.0)):
        lens.lens = value
        lens.keyframe_insert("lens", frame=frame)
    scene.frame_set(2)
    render(scene, "DEFERRED_RENDER", "zoom_ours")
    lens_warnings = [m for _, m in U.last_messages() if "lens, ortho scale or shift" in m]
    checks.check(len(lens_warnings) == 1, "a zoom over the shutter is warned about", f"{lens_warnings}")
    checks.finish()


main()
