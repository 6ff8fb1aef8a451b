"""150 renders in one Blender process: resident memory does not keep growing.

Each render releases its scene, images and targets and keeps the native
renderer's GL context and programs for the next (engine/session.py). RSS
(/proc/self/status VmRSS) is sampled after every render, after
gc.collect() and glibc's malloc_trim(0). RSS is noisy even so: it rises
and falls by up to 20 MB over tens of renders with no trend (Mesa's and
Python's own pools), and with the context kept it climbs over the first
~50-100 renders before it levels (over 300 renders the lowest RSS of each
25-render window from render 11: 395, 401, 406, 414, then 410-418 to the
end; DEFERRED_MEMORY_RENDERS=300 runs that and prints the window minima).
So the test compares the lowest RSS of renders 51..75 (after that warm-up)
with the lowest of the last 25, which may rise by less than
GROWTH_LIMIT_MB: a leak of 0.4 MB per render (one 160x90 pass set is
~2 MB) breaks it. The figures are printed (MEMORY line).

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_memory.py
"""

import ctypes
import gc
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

LIBC = ctypes.CDLL("libc.so.6")
RENDERS = max(int(os.environ.get("DEFERRED_MEMORY_RENDERS", "150")), 125)  # more: a longer look
WINDOW = 25
WARMUP = 50  # renders before the first window
GROWTH_LIMIT_MB = 25.0  # between the lowest RSS of the first and the last window after warm-up


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
        LIBC.malloc_trim(0)  # hand freed heap pages back, so RSS shows what is still held
        rss.append(U.rss_mb())
    errors = [m for level, m in U.last_messages() if level == "ERROR"]
    checks.check(not errors, f"{RENDERS} renders without error", "; ".join(errors[:2]))
    early = float(np.min(rss[WARMUP + 1:WARMUP + 1 + WINDOW]))
    late = float(np.min(rss[RENDERS + 1 - WINDOW:]))
    growth = late - early
    print("  MEMORY lowest RSS of each 25 renders from render 11 (MB):",
          " ".join(f"{min(rss[k:k + WINDOW]):.1f}" for k in range(11, RENDERS + 2 - WINDOW, WINDOW)))
    print(f"  MEMORY RSS start {rss[0]:.1f} MB, after 1 render {rss[1]:.1f} MB, lowest of renders {WARMUP + 1}..{WARMUP + WINDOW} {early:.1f} MB, "
          f"of renders {RENDERS + 1 - WINDOW}..{RENDERS} {late:.1f} MB; growth {growth:+.1f} MB; "
          f"render time median {1000 * np.median(times):.0f} ms")
    checks.check(growth < GROWTH_LIMIT_MB, f"lowest RSS, renders {WARMUP + 1}..{WARMUP + WINDOW} -> {RENDERS + 1 - WINDOW}..{RENDERS}: "
                 f"grows < {GROWTH_LIMIT_MB} MB",
                 f"{growth:+.1f} MB")
    checks.finish()


main()
