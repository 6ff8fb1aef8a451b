"""Every sample scene renders from the command line to a multilayer EXR.

For each blend_samples/*.blend this runs the user's command

    blender -b FILE --addons deferred_render -E DEFERRED_RENDER \
        -o OUT/NAME_ -F OPEN_EXR_MULTILAYER -f 1

(with samples and resolution lowered by --python-expr so the suite stays
fast on llvmpipe), then checks: exit code 0, no error reported, and the EXR
holds exactly the channels of the passes the engine registers for the
scene's view layer (names and channel letters), with finite pixels and a
lit image.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_samples.py
"""

import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

from deferred_render.engine import passes as pass_table  # noqa: E402

# sample -> resolution percentage for the test (samples = 1 everywhere)
SAMPLES = {"analytic": 100, "showcase": 50, "box_room": 50, "instancing": 50, "many_lights": 25, "materials": 50}


def expected_channels(sample, native_passes):
    """Channel names the EXR must hold: the registered passes of every view layer."""
    bpy.ops.wm.open_mainfile(filepath=os.path.join(U.SAMPLES, sample + ".blend"))
    names = set()
    for layer in bpy.context.scene.view_layers:
        if not layer.use:
            continue
        specs = pass_table.enabled_passes(layer, native_passes)
        names |= U.expected_channel_names(layer.name, [(s.name, s.chan_id, s.channels) for s in specs])
    return names


def render_sample(checks, sample, percentage, native_passes, out):
    expected = expected_channels(sample, native_passes)
    prefix = os.path.join(out, sample + "_")
    expr = ("import bpy; s = bpy.context.scene; s.deferred_render.samples = 1; "
            f"s.render.resolution_percentage = {percentage}")
    cmd = U.blender_command(os.path.join(U.SAMPLES, sample + ".blend"), "--python-expr", expr,
                            "-o", prefix, "-F", "OPEN_EXR_MULTILAYER", "-f", "1")
    t0 = time.perf_counter()
    code, output = U.run_blender(cmd)
    dt = time.perf_counter() - t0
    errors = [line for line in output.splitlines() if "Error" in line or "Traceback" in line]
    checks.check(code == 0, f"{sample}: blender exits 0", f"{dt:.1f} s")
    checks.check(not errors, f"{sample}: no error reported", " | ".join(errors[:3]))
    stats = [line for line in output.splitlines() if "done in" in line]
    if stats:
        print("   ", stats[-1].split("|", 3)[-1].strip())
    path = prefix + "0001.exr"
    if not checks.check(os.path.exists(path), f"{sample}: wrote {os.path.basename(path)}"):
        print(output[-3000:])
        return
    ch = U.read_exr(path)
    got = set(ch)
    checks.check(got == expected, f"{sample}: EXR channels = registered passes ({len(expected)} channels)",
                 f"missing {sorted(expected - got)}, extra {sorted(got - expected)}")
    finite = all(np.isfinite(a).all() for a in ch.values())
    checks.check(finite, f"{sample}: every channel finite")
    rgb = np.stack([ch[f"ViewLayer.Combined.{c}"] for c in "RGB"], axis=-1)
    checks.check(rgb.mean() > 0.01, f"{sample}: image is lit", f"mean {rgb.mean():.3f}")
    width = ch["ViewLayer.Combined.R"].shape[1]
    checks.check(width == bpy.context.scene.render.resolution_x * percentage // 100,
                 f"{sample}: resolution percentage honoured", f"{width} px wide")


def main():
    checks = U.Checks("test_samples")
    mod = U.native_module()
    if not checks.check(mod is not None, "native module importable"):
        checks.finish()
    out = U.out_dir("samples")
    for sample, percentage in SAMPLES.items():
        checks.run(sample, render_sample, checks, sample, percentage, mod.PASSES, out)
    checks.finish()


main()
