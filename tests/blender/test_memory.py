"""100 renders in one Blender process: resident memory does not keep growing.

Each render creates and releases a native session (EGL context on its own
thread, GPU scene, G-buffer). RSS (/proc/self/status VmRSS) is sampled
after every render. One sample is noisy: the allocator hands freed pages
back to the system unevenly, so RSS moves by +-8 MB from one render to the
next with no trend (measured over 120 renders; a 25..50 slope fit failed
one CI run that way). So the test compares window medians and fits a slope
over many renders: the median of renders 76..100 may exceed the median of
renders 11..35 (after warm-up: shader compilation, allocator pools) by less
than GROWTH_LIMIT_MB, and the slope over renders 25..100 (standard error
~0.02 MB/render at that noise) must stay under SLOPE_LIMIT_MB. Leaking one
set of passes per render (~2 MB at 160x90) would break both. The figures are
printed (MEMORY line).

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

RENDERS = 100
WINDOW = 25
GROWTH_LIMIT_MB = 8.0  # between the medians of the first and last windows after warm-up
SLOPE_LIMIT_MB = 0.1  # per render, fitted over renders 25..RENDERS


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
    early = float(np.median(rss[11:11 + WINDOW]))
    late = float(np.median(rss[RENDERS + 1 - WINDOW:]))
    growth = late - early
    tail = np.array(rss[25:])
    slope = np.polyfit(np.arange(len(tail)), tail, 1)[0]
    print(f"  MEMORY RSS start {rss[0]:.1f} MB, after 1 render {rss[1]:.1f} MB, median of renders 11..35 {early:.1f} MB, "
          f"of renders {RENDERS + 1 - WINDOW}..{RENDERS} {late:.1f} MB; growth {growth:+.1f} MB; "
          f"slope 25..{RENDERS}: {slope:+.3f} MB/render; render time median {1000 * np.median(times):.0f} ms")
    checks.check(growth < GROWTH_LIMIT_MB, f"median RSS growth, renders 11..35 -> {RENDERS + 1 - WINDOW}..{RENDERS} < {GROWTH_LIMIT_MB} MB",
                 f"{growth:+.1f} MB")
    checks.check(slope < SLOPE_LIMIT_MB, f"no steady growth (slope < {SLOPE_LIMIT_MB} MB/render)",
                 f"{slope:+.3f} MB/render")
    checks.finish()


main()
