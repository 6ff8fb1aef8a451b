#!/usr/bin/env python3
"""Benchmark: frames per hour of an animation, one process against the farm
paths (issue: scale-out). Prints a table (and writes it as Markdown).

The turntable sample (blend_samples/turntable.blend, 24 frames) rendered
  * one process       render_task.sh with every frame (one Blender, frames in turn),
  * render_gpus.sh    one process per GPU (here: per CUDA_VISIBLE_DEVICES entry
                      of BENCH_GPUS; on llvmpipe they share the CPU),
  * Slurm array       slurm_render.sh on the local single-node cluster
                      (local_slurm.sh), BENCH_PER_TASK frames per task, one GPU each,
each from an empty output folder; wall time from start to the last frame,
start-up and scheduling included. Ratios are against the one-process run of
the same invocation (these machines are noisy; compare within one table).

    /usr/bin/python3 bench/farm/bench_farm.py [--out bench/farm/results/llvmpipe.md]

Environment: BENCH_FRAMES (default 1-24), BENCH_PER_TASK (6), BENCH_GPUS
(default "0,1" here; on a GPU machine the GPUs nvidia-smi lists), BENCH_SLURM
(1: include the Slurm array; needs root and the slurm packages).
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CLUSTER = os.path.join(REPO, "scripts", "cluster")
BLEND = os.path.join(REPO, "blend_samples", "turntable.blend")


def run(cmd, env):
    p = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode != 0:
        print(p.stdout[-4000:])
        raise SystemExit(f"{' '.join(cmd[:3])} failed ({p.returncode})")
    return p.stdout


def summary(out, first, last):
    path = os.path.join(out, "summary.json")
    run([sys.executable, os.path.join(CLUSTER, "farm_summary.py"), out, str(first), str(last), "--json", path],
        os.environ)
    return json.load(open(path))


def gpu_of(s):
    gpus = sorted({r.get("gpu", "?") for r in s["per_frame"]})
    return ", ".join(gpus)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", default=None, help="also write the table (Markdown) here")
    args = parser.parse_args()
    first, last = (int(v) for v in os.environ.get("BENCH_FRAMES", "1-24").split("-"))
    frames = last - first + 1
    per_task = int(os.environ.get("BENCH_PER_TASK", "6"))
    gpus = os.environ.get("BENCH_GPUS")
    if not gpus:
        try:
            gpus = subprocess.run(["nvidia-smi", "--query-gpu=index", "--format=csv,noheader"],
                                  stdout=subprocess.PIPE, text=True, check=True).stdout.split()
            gpus = ",".join(gpus)
        except (OSError, subprocess.CalledProcessError):
            gpus = "0,1"
    with_slurm = os.environ.get("BENCH_SLURM", "1") == "1" and shutil.which("sbatch") is not None

    tmp = tempfile.mkdtemp(prefix="bench-farm-")
    env = dict(os.environ)
    env.setdefault("BLENDER_USER_SCRIPTS", os.path.join(REPO, "build", "blender_scripts"))
    env.pop("CUDA_VISIBLE_DEVICES", None)
    rows = []

    def record(name, processes, out, wall):
        s = summary(out, first, last)
        if s["missing"]:
            raise SystemExit(f"{name}: frames missing {s['missing']}")
        rows.append({"mode": name, "processes": processes, "wall_s": wall, "fph": frames * 3600.0 / wall,
                     "per_frame_s": s["render_s"] / frames, "gpu": gpu_of(s)})
        print(f"{name}: {wall:.1f} s", flush=True)

    try:
        out = os.path.join(tmp, "one")
        t0 = time.time()
        run(["bash", os.path.join(CLUSTER, "render_task.sh"), BLEND, out, str(first), str(last), str(frames), "0"],
            env)
        record("one process", 1, out, time.time() - t0)

        out = os.path.join(tmp, "gpus")
        t0 = time.time()
        run(["bash", os.path.join(CLUSTER, "render_gpus.sh"), BLEND, out, str(first), str(last), gpus], env)
        record(f"render_gpus.sh ({gpus})", len(gpus.split(",")), out, time.time() - t0)

        if with_slurm:
            env["LOCAL_SLURM_DIR"] = os.path.join(tmp, "slurm")
            env["SLURM_CONF"] = os.path.join(env["LOCAL_SLURM_DIR"], "slurm.conf")
            env["DEFERRED_FARM_STATE"] = os.path.join(tmp, "jobs")
            env["SLURM_RENDER_POLL_S"] = "0.5"
            run(["bash", os.path.join(CLUSTER, "local_slurm.sh"), "start"], env)
            try:
                out = os.path.join(tmp, "slurm-out")
                t0 = time.time()
                job = run(["bash", os.path.join(CLUSTER, "slurm_render.sh"), BLEND, out, str(first), str(last),
                           str(per_task)], env).split()[-1]
                run(["bash", os.path.join(CLUSTER, "slurm_render.sh"), "--wait", job], env)
                tasks = (frames + per_task - 1) // per_task
                record(f"Slurm array ({tasks} tasks x {per_task} frames)", tasks, out, time.time() - t0)
            finally:
                subprocess.run(["bash", os.path.join(CLUSTER, "local_slurm.sh"), "stop"], env=env)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    base = rows[0]["wall_s"]
    lines = [f"Turntable, {frames} frames ({os.path.basename(BLEND)}), "
             f"{time.strftime('%Y-%m-%d')}, on {rows[0]['gpu']}, {os.cpu_count()} CPU cores",
             "",
             "| mode | processes | wall (s) | frames per hour | vs one process | render s/frame |",
             "| --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(f"| {r['mode']} | {r['processes']} | {r['wall_s']:.1f} | {r['fph']:.0f} | "
                     f"{base / r['wall_s']:.2f}x | {r['per_frame_s']:.2f} |")
    text = "\n".join(lines)
    print(text)
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
