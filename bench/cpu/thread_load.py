#!/usr/bin/env python3
"""Where a frame's CPU time goes on llvmpipe, by thread, against what Cycles
needs for the same error: is a scene that loses to Cycles at equal time
held back by threads waiting on each other (which better scheduling could
win back) or by the work itself?

Replays captures (bench/gpu/captures) warm, as the speed-vs-error report
renders them (320x180, 4 samples, Combined), with the replay's --threads:
CPU ms per render by thread — the render thread, which runs every GL call
and, on llvmpipe, the vertex work and triangle setup of every draw; the
rasteriser threads (llvmpipe-N: fragments); the driver's compute pool
(lighting, the visibility buffer's resolve, passes) — and compares the
render's CPU time spread over every core (its wall time if no core ever
idled) with Cycles' wall time at the same RMSE, both from the committed
report (bench/report/results/results.csv: our 4-sample RMSE and Blender
time, Cycles' measured curve; bench/report/metrics.py's interpolation).

    /usr/bin/python3 bench/cpu/thread_load.py [--scenes instancing transparency]
        [--size 320x180] [--samples 4] [--repeat 3] [--build DIR]
        [--results bench/report/results/results.csv]

Prints one markdown table. "Blender overhead" is the report's 4-sample
time less this replay's wall time (the export and Blender's own work).
"""
import argparse
import csv
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "bench", "report"))
from metrics import Curve  # noqa: E402

CONF = "muzzy_decay_ms:-1,lg_extent_max_active_fit:20"  # native/src/cpu_rasteriser.h kJemallocConf
ROLES = ("render", "raster", "compute", "main", "other")


def replay(args, scene):
    cmd = [os.path.join(args.build, "tools", "deferred_render_replay"),
           os.path.join(REPO, "bench", "gpu", "captures", scene + ".npz"), "--size", args.size,
           "--samples", str(args.samples), "--repeat", str(args.repeat), "--passes", "Combined", "--threads",
           "--json"]
    env = dict(os.environ, MALLOC_CONF=CONF)
    out = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def report_rows(path, scene):
    """Our 4-sample row and Cycles' curve for `scene` from the report's CSV."""
    ours, cycles = None, []
    with open(path) as f:
        for r in csv.DictReader(f):
            if r["scene"] != scene:
                continue
            if r["engine"] == "ours" and int(r["samples"]) == 4:
                ours = r
            elif r["engine"] == "cycles":
                cycles.append((int(r["samples"]), float(r["seconds"]), float(r["rmse"])))
    return ours, cycles


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", nargs="+", default=["instancing", "transparency"])
    ap.add_argument("--size", default="320x180")
    ap.add_argument("--samples", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=3, help="renders per scene; the first (cold) is left out")
    ap.add_argument("--build", default=os.path.join(REPO, "build"))
    ap.add_argument("--results", default=os.path.join(REPO, "bench", "report", "results", "results.csv"))
    args = ap.parse_args(argv)
    if args.repeat < 2:
        ap.error("--repeat must be at least 2 (the first render is cold)")
    cores = os.cpu_count() or 1

    print(f"{args.size}, {args.samples} samples, Combined; warm renders 2..{args.repeat}, mean; {cores} cores; "
          f"CPU in ms per render")
    print()
    print("| scene | wall ms | render thread | rasteriser | compute pool | other | CPU | CPU / wall "
          "| CPU / cores | report: ours s | Blender overhead s | Cycles s at our RMSE | ours with no idle core s |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for scene in args.scenes:
        result = replay(args, scene)
        warm = result["runs"][1:]
        wall = sum(r["wall_ms"] for r in warm) / len(warm)
        by_role = dict.fromkeys(ROLES, 0.0)
        for r in warm:
            for t in r.get("threads", []):
                by_role[t["role"]] += t["cpu_ms"] / len(warm)
        cpu = sum(by_role.values())
        ours, cycles = report_rows(args.results, scene)
        cells = ["–"] * 4
        if ours is not None and cycles:
            ours_s = float(ours["seconds"])
            overhead = max(ours_s - wall / 1e3, 0.0)
            cycles_s, kind = Curve(cycles).time_for_error(float(ours["rmse"]))
            ideal = overhead + cpu / cores / 1e3
            cells = [f"{ours_s:.3f}", f"{overhead:.3f}",
                     f"{kind if kind != '=' else ''}{cycles_s:.3f}" if cycles_s is not None else kind,
                     f"{ideal:.3f}"]
        print(f"| {scene} | {wall:.0f} | {by_role['render']:.0f} | {by_role['raster']:.0f} | "
              f"{by_role['compute']:.0f} | {by_role['main'] + by_role['other']:.0f} | {cpu:.0f} | "
              f"{cpu / wall:.2f} | {cpu / cores:.0f} | " + " | ".join(cells) + " |")
    print()
    print("ours with no idle core: the Blender overhead plus the render's CPU time over the cores, the fastest "
          "this work could run here; where it exceeds Cycles' time at our RMSE, no scheduling of the same work "
          "wins at equal time.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
