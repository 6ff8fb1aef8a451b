#!/usr/bin/env python3
"""Checks that every frame of a farm render exists and reports per-frame time
and the GPU each frame ran on (from render_frames.py's records).

    python3 scripts/cluster/farm_summary.py OUTDIR START END [--since EPOCH] [--json FILE]
    python3 scripts/cluster/farm_summary.py OUTDIR START END --missing-tasks FRAMES_PER_TASK

A frame is done when its record ``OUTDIR/.deferred_farm/<frame>.json`` and
the file it names both exist (render_frames.py writes the record, then
renames the finished frame onto its name). Exit status 0 when every frame of
START..END is done, 1 when some are missing (they are listed).
``--since`` (the submission time) makes frames per hour count from it, so
that start-up and queueing are part of the figure; otherwise it counts from
the first frame's start.
"""

import argparse
import collections
import json
import os
import sys

RECORD_DIR = ".deferred_farm"


def load_records(out_dir, frames):
    done, missing = {}, []
    for frame in frames:
        path = os.path.join(out_dir, RECORD_DIR, f"{frame}.json")
        try:
            with open(path) as f:
                record = json.load(f)
        except (OSError, ValueError):
            missing.append(frame)
            continue
        if not os.path.isfile(os.path.join(out_dir, record.get("file", ""))):
            missing.append(frame)
            continue
        done[frame] = record
    return done, missing


def ranges(frames):
    """[1,2,3,7,9,10] -> '1-3,7,9-10'."""
    out, start, prev = [], None, None
    for f in frames:
        if start is None:
            start = prev = f
        elif f == prev + 1:
            prev = f
        else:
            out.append(f"{start}-{prev}" if prev != start else f"{start}")
            start = prev = f
    if start is not None:
        out.append(f"{start}-{prev}" if prev != start else f"{start}")
    return ",".join(out)


def summarize(out_dir, first, last, since=None):
    frames = list(range(first, last + 1))
    done, missing = load_records(out_dir, frames)
    summary = {"out_dir": out_dir, "frames": len(frames), "done": len(done), "missing": missing,
               "per_frame": [done[f] for f in sorted(done)]}
    if done:
        # Throughput of what this submission rendered: the frames finished
        # since it was submitted, over the time since (start-up and queueing
        # included); without --since, every frame from the first start.
        recent = [r for r in done.values() if since is None or r["finished"] >= since]
        if recent:
            start = since if since is not None else min(r["finished"] - r["seconds"] for r in recent)
            wall = max(max(r["finished"] for r in recent) - start, 1e-6)
            summary.update(rendered=len(recent), wall_s=round(wall, 2),
                           frames_per_hour=round(len(recent) * 3600.0 / wall, 1))
        summary["render_s"] = round(sum(r["seconds"] for r in done.values()), 2)
        per_gpu = collections.defaultdict(list)
        for r in done.values():
            per_gpu[(r.get("host", "?"), r.get("gpu", "?"), r.get("cuda_visible_devices"))].append(r["seconds"])
        summary["per_gpu"] = [{"host": h, "gpu": g, "cuda_visible_devices": c, "frames": len(t),
                               "mean_s": round(sum(t) / len(t), 3)} for (h, g, c), t in sorted(per_gpu.items(),
                                                                                             key=str)]
    return summary


def print_summary(s):
    print(f"{'frame':>6} {'seconds':>8}  {'host':<16} {'CUDA_VISIBLE_DEVICES':<20} gpu")
    for r in s["per_frame"]:
        cvd = r.get("cuda_visible_devices")
        print(f"{r['frame']:>6} {r['seconds']:>8.2f}  {r.get('host', '?'):<16} "
              f"{'-' if cvd is None else repr(cvd):<20} {r.get('gpu', '?')}")
    for g in s.get("per_gpu", []):
        print(f"per GPU: {g['host']} {g['gpu']} (CUDA_VISIBLE_DEVICES={g['cuda_visible_devices']}): "
              f"{g['frames']} frame(s), {g['mean_s']:.2f} s each")
    if s["done"]:
        print(f"{s['done']}/{s['frames']} frames in {s['out_dir']}, {s['render_s']:.1f} s of rendering in all")
    if s.get("rendered"):
        print(f"{s['rendered']} frame(s) rendered by this run in {s['wall_s']:.1f} s wall: "
              f"{s['frames_per_hour']:.0f} frames per hour")
    if s["missing"]:
        print(f"MISSING {len(s['missing'])} frame(s): {ranges(s['missing'])}")
    else:
        print("every frame exists")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out_dir")
    parser.add_argument("start", type=int)
    parser.add_argument("end", type=int)
    parser.add_argument("--since", type=float, default=None, help="submission time (epoch seconds)")
    parser.add_argument("--json", default=None, help="also write the summary here")
    parser.add_argument("--missing-tasks", type=int, default=None, metavar="FRAMES_PER_TASK",
                        help="print only the task indices (0-based, FRAMES_PER_TASK frames each) "
                             "that still miss frames, comma-separated, for sbatch --array")
    args = parser.parse_args(argv)
    if args.missing_tasks is not None:
        if args.missing_tasks < 1:
            parser.error("--missing-tasks needs a positive FRAMES_PER_TASK")
        _, missing = load_records(os.path.abspath(args.out_dir), range(args.start, args.end + 1))
        print(",".join(str(i) for i in sorted({(f - args.start) // args.missing_tasks for f in missing})))
        return 0
    s = summarize(os.path.abspath(args.out_dir), args.start, args.end, args.since)
    print_summary(s)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(s, f, indent=1)
    return 0 if not s["missing"] else 1


if __name__ == "__main__":
    sys.exit(main())
