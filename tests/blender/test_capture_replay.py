"""Scene capture and replay (issue: the GPU as the first-class target, item 7).

A render with DEFERRED_RENDER_CAPTURE=/path/scene_####.npz writes the calls
it made on the native renderer; build/tools/deferred_render_replay renders
them again without Blender. Checked here, on the materials sample (node
materials with images, every pass, a world, four lights):

- the capture is written (with # replaced by the frame) and reported;
- the replay at the captured settings equals Blender's render in every
  channel of every pass (bit for bit: same calls, same GPU);
- --size / --samples / --passes / --repeat / --json change what they say;
- a motion-blurred render (instance and camera motion) replays equal too;
- a file that is not a capture fails with a message, not a traceback;
- without the variable nothing is written.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_capture_replay.py
"""

import glob
import json
import os
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

from deferred_render.engine import capture  # noqa: E402


def replay_tool():
    scripts = os.environ.get("BLENDER_USER_SCRIPTS", "")
    return os.path.join(os.path.dirname(os.path.abspath(scripts)), "tools", "deferred_render_replay")


def replay(*args):
    proc = subprocess.run([replay_tool(), *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=600)
    return proc.returncode, proc.stdout.decode("utf-8", "replace"), proc.stderr.decode("utf-8", "replace")


def main():
    checks = U.Checks("capture_replay")
    out = U.out_dir("capture_replay")
    for old in glob.glob(os.path.join(out, "*")):
        os.remove(old)
    bpy.ops.wm.open_mainfile(filepath=os.path.join(U.SAMPLES, "materials.blend"))
    scene = bpy.context.scene
    scene.render.engine = U.ENGINE
    scene.render.resolution_x, scene.render.resolution_y = 160, 90
    scene.render.resolution_percentage = 100
    scene.deferred_render.samples = 4
    scene.frame_current = 7

    os.environ[capture.ENV] = os.path.join(out, "scene_####.npz")
    try:
        blender_exr = U.render_exr(os.path.join(out, "blender"), scene)
    finally:
        del os.environ[capture.ENV]
    path = os.path.join(out, "scene_0007.npz")
    checks.check(os.path.exists(path), "the capture is written, # replaced by the frame", path)
    reported = [m for level, m in U.last_messages() if "scene captured to" in m]
    checks.check(len(reported) == 1, "the capture is reported", reported[0] if reported else "")
    if not os.path.exists(path):
        return checks.finish()
    data = np.load(path)
    calls = json.loads(bytes(data["__calls__"]).decode())
    methods = [c["method"] for c in calls]
    checks.check(methods.count("render") == 1 and methods[-1] == "render" and "add_image" in methods
                 and "add_graph_material" in methods and "set_world" in methods,
                 "the calls: scene, images, node materials, world, one render", f"{len(calls)} calls")

    # Replay at the captured settings: every channel equal to Blender's.
    code, stdout, stderr = replay(path, "--out", os.path.join(out, "replay.exr"), "--json")
    checks.check(code == 0, "replay exits 0", stderr.strip()[-300:])
    if code == 0:
        result = json.loads(stdout)
        checks.check(result["size"] == [160, 90] and result["samples"] == 4 and len(result["runs"]) == 1,
                     "replay renders the captured size and samples", f"{result['size']} {result['samples']}")
        ours = U.read_exr(blender_exr)
        theirs = U.read_exr(os.path.join(out, "replay.exr"))
        checks.check(set(ours) == set(theirs), "the replay writes every pass Blender wrote",
                     f"{len(ours)} channels; only Blender: {sorted(set(ours) - set(theirs))[:4]}; "
                     f"only replay: {sorted(set(theirs) - set(ours))[:4]}")
        worst = max((float(np.abs(ours[c].astype(np.float64) - theirs[c]).max()), c)
                    for c in set(ours) & set(theirs))
        checks.check(worst[0] == 0.0, "the replay equals Blender's render in every channel",
                     f"largest difference {worst[0]:.3g} in {worst[1]}")
        combined = theirs["ViewLayer.Combined.R"]
        checks.check(float(combined.mean()) > 0.01, "and it is lit", f"mean R {combined.mean():.4f}")
        # Twice the shadow quality: finer maps, more texels drawn.
        texels = result["runs"][-1]["shadow_texels"]
        code, stdout, stderr = replay(path, "--shadow-quality", "2", "--json")
        checks.check(code == 0, "replay --shadow-quality 2 exits 0", stderr.strip()[-300:])
        if code == 0:
            finer = json.loads(stdout)
            checks.check(finer["shadow_quality"] == 2.0 and finer["runs"][-1]["shadow_texels"] > 2 * texels,
                         "--shadow-quality 2 draws finer maps",
                         f"{finer['shadow_quality']}: {finer['runs'][-1]['shadow_texels']} against {texels} texels")

    # The same capture with the G-buffer from the visibility buffer (the
    # benchmark's switch on a GPU server): taken, and the same image to
    # rounding (materials.blend's node materials; tests/blender/
    # test_visibility_buffer.py holds the two paths to their bounds).
    code, stdout, stderr = replay(path, "--visibility-buffer", "on", "--json",
                                  "--out", os.path.join(out, "replay_visibility.exr"))
    checks.check(code == 0, "replay --visibility-buffer on exits 0", stderr.strip()[-300:])
    if code == 0:
        result = json.loads(stdout)
        checks.check(result["visibility_buffer"] is True and result["runs"][-1]["visibility_buffer"] is True,
                     "--visibility-buffer on takes the visibility buffer", str(result.get("visibility_buffer")))
        raster = U.read_exr(os.path.join(out, "replay.exr"))["ViewLayer.Combined.R"].astype(np.float64)
        vis = U.read_exr(os.path.join(out, "replay_visibility.exr"))["ViewLayer.Combined.R"].astype(np.float64)
        diff = float(np.abs(raster - vis).mean())
        checks.check(diff <= 2e-3 * max(float(raster.mean()), 1e-6), "the visibility buffer's replay is the same image",
                     f"mean |difference| {diff:.3g} against a mean of {raster.mean():.3g}")

    # Overrides.
    code, stdout, stderr = replay(path, "--size", "80x44", "--samples", "2", "--passes", "Combined,Normal",
                                  "--repeat", "2", "--threads", "--json", "--out", os.path.join(out, "small.npz"))
    checks.check(code == 0, "replay with overrides exits 0", stderr.strip()[-300:])
    if code == 0:
        result = json.loads(stdout)
        checks.check(result["size"] == [80, 44] and result["samples"] == 2 and len(result["runs"]) == 2,
                     "--size, --samples, --repeat", f"{result['size']} {result['samples']} {len(result['runs'])}")
        checks.check(set(result["passes"]) == {"Combined", "Normal"}, "--passes", str(result["passes"]))
        run = result["runs"][-1]
        checks.check(all(isinstance(run[k], (int, float)) for k in ("wall_ms", "geometry_ms", "lighting_ms",
                                                                     "readback_ms", "total_ms")),
                     "each run has its wall time and stage timings", str({k: run[k] for k in list(run)[:4]}))
        # --threads: each run's CPU time per thread, the render thread
        # named (native/src/render_thread.cpp) and busy in every render.
        threads = run.get("threads") or []
        render = [t for t in threads if t["role"] == "render"]
        checks.check(len(render) == 1 and render[0]["name"] == "deferred-gl",
                     "--threads finds the render thread by its name", str([(t["name"], t["role"]) for t in threads]))
        checks.check(all(t["cpu_ms"] >= 0 for t in threads) and sum(t["cpu_ms"] for t in threads) > 0,
                     "--threads reports each thread's CPU time in the run", str([t["cpu_ms"] for t in threads]))
        small = np.load(os.path.join(out, "small.npz"))
        checks.check(small["Combined"].shape == (44, 80, 4), "the .npz output", str(small["Combined"].shape))
    code, stdout, stderr = replay(path)
    checks.check(code == 0 and "| run | wall ms |" in stdout, "the default output is a table", stdout[-200:])

    # Not a capture: a message, no traceback.
    bogus = os.path.join(out, "bogus.npz")
    with open(bogus, "wb") as f:
        f.write(b"not a zip file")
    code, stdout, stderr = replay(bogus)
    checks.check(code != 0 and "not a capture" in stderr and "Traceback" not in stderr,
                 "a file that is not a capture fails with a message", stderr.strip()[-200:])

    # Motion blur (instances' and the camera's motion through the shutter:
    # the add_instances motion arrays and the Camera's motion tuple).
    ob = next(o for o in scene.objects if o.type == 'MESH' and o.name != "Floor")
    ob.location.x -= 0.3
    ob.keyframe_insert("location", frame=6)
    ob.location.x += 0.6
    ob.keyframe_insert("location", frame=8)
    scene.camera.keyframe_insert("location", frame=6)
    scene.camera.location.y += 0.2
    scene.camera.keyframe_insert("location", frame=8)
    scene.render.use_motion_blur = True
    scene.frame_set(7)
    os.environ[capture.ENV] = os.path.join(out, "blur.npz")
    try:
        blur_exr = U.render_exr(os.path.join(out, "blender_blur"), scene)
    finally:
        del os.environ[capture.ENV]
    scene.render.use_motion_blur = False
    code, stdout, stderr = replay(os.path.join(out, "blur.npz"), "--out", os.path.join(out, "replay_blur.exr"))
    checks.check(code == 0, "a motion-blurred capture replays", stderr.strip()[-300:])
    if code == 0:
        ours = U.exr_pass(U.read_exr(blur_exr), "ViewLayer", "Combined", "RGBA")
        theirs = U.exr_pass(U.read_exr(os.path.join(out, "replay_blur.exr")), "ViewLayer", "Combined", "RGBA")
        blur_calls = json.loads(bytes(np.load(os.path.join(out, "blur.npz"))["__calls__"]).decode())
        moving = any("motion" in c["kwargs"].get("__dict__", {}) for c in blur_calls if c["method"] == "add_instances")
        checks.check(moving, "the capture holds the instances' motion")
        checks.check(float(np.abs(ours - theirs).max()) == 0.0, "and equals Blender's motion-blurred render",
                     f"largest difference {float(np.abs(ours - theirs).max()):.3g}")

    # Without the variable: nothing written.
    before = set(os.listdir(out))
    scene.frame_current = 8
    U.render_exr(os.path.join(out, "uncaptured"), scene)
    written = set(os.listdir(out)) - before
    checks.check(written == {"uncaptured.exr"}, "without DEFERRED_RENDER_CAPTURE nothing is captured",
                 str(sorted(written)))
    checks.finish()


main()
