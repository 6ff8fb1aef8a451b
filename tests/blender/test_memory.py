"""50 renders in one Blender process: resident memory does not keep growing.

Each render creates and releases a native session (EGL context on its own
thread, GPU scene, G-buffer). RSS (/proc/self/status VmRSS) is sampled
after every render; the growth between render 10 (after warm-up: shader
compilation, allocator pools) and render 50 must stay under GROWTH_LIMIT_MB,
and the second half must not grow faster than a small per-render slope.
The figures are printed (MEMORY line) for the report.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_memory.py
"""

import gc
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

RENDERS = 50
GROWTH_LIMIT_MB = 20.0
SLOPE_LIMIT_MB = 0.25  # per render, fitted over renders 25..50


def main():
    checks = U.Checks("test_memory")
    if not U.require_engine(checks):
        checks.finish()
    scene = bpy.context.scene
    scene.render.resolution_percentage = 50
    scene.deferred_render.samples = 1
    U.set_all_passes(scene.view_layers[0], True)
    rss = [U.rss_mb()]
    times = []
    for i in range(RENDERS):
        t0 = time.perf_counter()
        bpy.ops.render.render()
        times.append(time.perf_counter() - t0)
        gc.collect()
        rss.append(U.rss_mb())
    errors = [m for level, m in U.last_messages() if level == "ERROR"]
    checks.check(not errors, f"{RENDERS} renders without error", "; ".join(errors[:2]))
    growth = rss[RENDERS] - rss[10]
    tail = np.array(rss[25:])
    slope = np.polyfit(np.arange(len(tail)), tail, 1)[0]
    print(f"  MEMORY RSS start {rss[0]:.1f} MB, after 1 render {rss[1]:.1f} MB, after 10 {rss[10]:.1f} MB, "
          f"after {RENDERS} {rss[RENDERS]:.1f} MB; growth 10->{RENDERS}: {growth:+.1f} MB; "
          f"slope 25..{RENDERS}: {slope:+.3f} MB/render; render time median {1000 * np.median(times):.0f} ms")
    checks.check(growth < GROWTH_LIMIT_MB, f"RSS growth render 10 -> {RENDERS} < {GROWTH_LIMIT_MB} MB",
                 f"{growth:+.1f} MB")
    checks.check(slope < SLOPE_LIMIT_MB, f"no steady growth (slope < {SLOPE_LIMIT_MB} MB/render)",
                 f"{slope:+.3f} MB/render")
    checks.finish()


main()
