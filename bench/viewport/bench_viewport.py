#!/usr/bin/env python3
"""Benchmark: the Rendered viewport at 1280x720 (issue: viewport).

For each sample scene, Blender's real UI under Xvfb (a 1280x720 screen, the
3D view maximised with its panels hidden, so the view's region is the whole
screen) switches to Rendered shading through the scene camera and measures

  * first image      Rendered switched on -> the first sample on screen
                     (renderer start, GL context, programs, export included);
  * edit -> sample   an object moved -> the first sample of the new
                     accumulation drawn (re-sync with kept meshes, restart);
                     median of EDITS moves;
  * UI wait          an edit while samples run: how long view_update waits
                     for the running stage to stop;
  * samples/s        viewport samples per second while accumulating, wall
                     clock from the first to the last sample drawn, and the
                     renderer's own per-sample time (its stage timings).

    /usr/bin/python3 bench/viewport/bench_viewport.py [--out bench/viewport/results/llvmpipe.md]

Environment: BENCH_SCENES (default "analytic box_room showcase"),
BENCH_SAMPLES (viewport samples, default 32), BENCH_EDITS (default 5).
The add-on comes from BLENDER_USER_SCRIPTS (default build/blender_scripts).
"""

import json
import os
import statistics
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

try:
    import bpy  # noqa: F401
    INSIDE_BLENDER = True
except ImportError:
    INSIDE_BLENDER = False


# ---------------------------------------------------------------------------
# inside Blender: the probe
# ---------------------------------------------------------------------------

def probe():
    import traceback

    samples = int(os.environ.get("BENCH_SAMPLES", "32"))
    edits = int(os.environ.get("BENCH_EDITS", "5"))
    result_path = os.environ["BENCH_RESULT"]

    def steps():
        from deferred_render.engine import viewport
        scene = bpy.context.scene
        scene.render.engine = 'DEFERRED_RENDER'
        scene.deferred_render.viewport_samples = samples
        window = bpy.context.window_manager.windows[0]
        area = max((a for a in window.screen.areas if a.type == 'VIEW_3D'), key=lambda a: a.width * a.height)
        with bpy.context.temp_override(window=window, area=area):
            bpy.ops.screen.screen_full_area(use_hide_panels=True)
        yield
        window = bpy.context.window_manager.windows[0]
        area = next(a for a in window.screen.areas if a.type == 'VIEW_3D')
        region = next(r for r in area.regions if r.type == 'WINDOW')
        space = area.spaces.active
        for attr in ("show_region_header", "show_region_toolbar", "show_region_ui", "show_region_tool_header",
                     "show_gizmo"):
            setattr(space, attr, False)
        space.overlay.show_overlays = False
        space.region_3d.view_perspective = 'CAMERA'
        yield
        start = time.perf_counter()
        space.shading.type = 'RENDERED'

        def session():
            live = viewport.sessions()
            return live[0] if live else None

        def wait(condition, limit=600):
            t0 = time.perf_counter()
            while time.perf_counter() - t0 < limit:
                s = session()
                if s is not None and s.error:
                    raise RuntimeError(s.error)
                if s is not None and condition(s):
                    return s
                yield
            raise RuntimeError("timed out")

        s = yield from wait(lambda s: s.samples_done >= 1)
        first_image = time.perf_counter() - start
        s = yield from wait(lambda s: s.samples_done == s.samples_total and not s._worker.is_alive())
        moved = [o for o in scene.objects if o.type == 'MESH'][-1]
        edit_times, rates, native_ms = [], [], []
        for k in range(edits):
            generation = s.generation
            moved.location.x += 0.05 if k % 2 == 0 else -0.05
            edited = time.perf_counter()
            s = yield from wait(lambda s: s.generation > generation and s.shown_generation == s.generation
                                and s.samples_done >= 1)
            edit_times.append(time.perf_counter() - edited)
            t_first, first_done = time.perf_counter(), s.samples_done
            s = yield from wait(lambda s: s.samples_done == s.samples_total and not s._worker.is_alive())
            elapsed = time.perf_counter() - t_first
            if s.samples_total > first_done and elapsed > 0:
                rates.append((s.samples_total - first_done) / elapsed)
            timings = dict(s.renderer.last_timings)
            native_ms.append(timings.get("total_ms", 0.0) / s.samples_total)
        # An edit while samples run: how long the UI waits for the running
        # stage to stop (view_update joins the worker).
        generation = s.generation
        moved.location.x += 0.05
        s = yield from wait(lambda s: s.generation > generation and s.shown_generation == s.generation
                            and 1 <= s.samples_done < s.samples_total)
        stops = s.stats["stops"]
        s.stats["stop_seconds_max"] = 0.0
        moved.location.x -= 0.05
        s = yield from wait(lambda s: s.stats["stops"] > stops)
        ui_wait = s.stats["stop_seconds_max"]
        out = {"region": [region.width, region.height], "samples": samples, "ui_wait_s": ui_wait,
               "first_image_s": first_image, "edit_to_sample_s": statistics.median(edit_times),
               "samples_per_s": statistics.median(rates) if rates else None,
               "native_ms_per_sample": statistics.median(native_ms),
               "gpu": dict(s.renderer.gl_info).get("renderer", "?")}
        with open(result_path, "w") as f:
            json.dump(out, f)
        os._exit(0)

    state = {}

    def tick():
        try:
            if "steps" not in state:
                state["steps"] = steps()
            next(state["steps"])
        except Exception:
            traceback.print_exc()
            sys.stdout.flush()
            os._exit(1)
        return 0.01  # polled often: the times are measured by this loop

    bpy.app.timers.register(tick, first_interval=0.5)


# ---------------------------------------------------------------------------
# outside: the driver
# ---------------------------------------------------------------------------

def main():
    import argparse
    import tempfile
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", help="also write the table as Markdown here")
    args = parser.parse_args()
    scenes = os.environ.get("BENCH_SCENES", "analytic box_room showcase").split()
    env = dict(os.environ)
    env.setdefault("BLENDER_USER_SCRIPTS", os.path.join(REPO, "build", "blender_scripts"))
    rows = []
    for name in scenes:
        with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
            result = f.name
        env["BENCH_RESULT"] = result
        cmd = ["xvfb-run", "-a", "-s", "-screen 0 1280x720x24", "blender", "--factory-startup",
               os.path.join(REPO, "blend_samples", f"{name}.blend"), "--addons", "deferred_render",
               "--python", os.path.abspath(__file__)]
        t0 = time.perf_counter()
        p = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if p.returncode != 0:
            print(p.stdout[-3000:])
            raise SystemExit(f"{name}: Blender failed ({p.returncode})")
        with open(result) as f:
            row = json.load(f)
        os.unlink(result)
        row["scene"] = name
        rows.append(row)
        print(f"{name}: {row} ({time.perf_counter() - t0:.0f} s)", flush=True)
    gpu = rows[0]["gpu"] if rows else "?"
    lines = [f"Rendered viewport, {gpu}; region {rows[0]['region'][0]}x{rows[0]['region'][1]}, "
             f"{rows[0]['samples']} viewport samples (bench/viewport/bench_viewport.py)", "",
             "| scene | first image (s) | edit -> first sample (s) | UI wait on an edit while sampling (s) "
             "| samples/s (wall) | ms/sample (renderer) |",
             "| --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        rate = f"{r['samples_per_s']:.1f}" if r["samples_per_s"] else "-"
        lines.append(f"| {r['scene']} | {r['first_image_s']:.2f} | {r['edit_to_sample_s']:.3f} | "
                     f"{r['ui_wait_s']:.3f} | {rate} | {r['native_ms_per_sample']:.0f} |")
    table = "\n".join(lines)
    print(table)
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            f.write(table + "\n")


if INSIDE_BLENDER:
    probe()
elif __name__ == "__main__":
    main()
