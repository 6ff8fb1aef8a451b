#!/usr/bin/env python3
"""Blender's allocator on the CPU rasteriser: the same scene rendered by the
Deferred engine in two Blender processes, one with jemalloc's defaults and
one with the MALLOC_CONF the README gives ("Rendering on the CPU",
native/src/cpu_rasteriser.h), printing each render's time, and each
process's page faults and peak resident memory.

    /usr/bin/python3 bench/cpu/bench_malloc_conf.py [--blend FILE] [--renders N]
        [--size WxH] [--samples N] [--build DIR]
"""
import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
CONF = "muzzy_decay_ms:-1,lg_extent_max_active_fit:20"  # native/src/cpu_rasteriser.h kJemallocConf

RENDER_SCRIPT = """
import bpy, sys, time
w, h, samples, renders = (int(a) for a in sys.argv[sys.argv.index("--") + 1:])
s = bpy.context.scene
s.render.engine = 'DEFERRED_RENDER'
s.render.resolution_x, s.render.resolution_y, s.render.resolution_percentage = w, h, 100
s.deferred_render.samples = samples
for k in range(renders):
    t = time.perf_counter()
    bpy.ops.render.render()
    print("BENCH_RENDER", k, time.perf_counter() - t, flush=True)
"""


def run(args, conf):
    env = dict(os.environ, BLENDER_USER_SCRIPTS=os.path.join(args.build, "blender_scripts"))
    env.pop("MALLOC_CONF", None)
    if conf:
        env["MALLOC_CONF"] = conf
    w, h = args.size.split("x")
    with tempfile.NamedTemporaryFile("w", suffix=".py", delete=False) as f:
        f.write(RENDER_SCRIPT)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run([args.blender, "-b", "--factory-startup", args.blend, "--addons", "deferred_render",
                          "--python-exit-code", "1", "--python", f.name, "--", w, h, str(args.samples),
                          str(args.renders)], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    os.unlink(f.name)
    if out.returncode != 0:
        sys.exit(out.stdout[-3000:])
    times = [float(line.split()[2]) for line in out.stdout.splitlines() if line.startswith("BENCH_RENDER")]
    # ru_maxrss of the children is the largest of them (kB): one Blender at a time here.
    return times, after.ru_minflt - before.ru_minflt, after.ru_maxrss / 1024.0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--blend", default=os.path.join(REPO, "blend_samples", "instancing.blend"))
    p.add_argument("--renders", type=int, default=3)
    p.add_argument("--size", default="320x180")
    p.add_argument("--samples", type=int, default=4)
    p.add_argument("--build", default=os.path.join(REPO, "build"))
    p.add_argument("--blender", default=shutil.which("blender") or "blender")
    args = p.parse_args()
    print(f"{os.path.basename(args.blend)}, {args.size}, {args.samples} samples, {args.renders} renders per process")
    print("| MALLOC_CONF | renders s | page faults | peak RSS MB |")
    print("| --- | --- | ---: | ---: |")
    for conf in ("", CONF):
        times, faults, rss = run(args, conf)
        print(f"| {conf or '(jemalloc defaults)'} | {', '.join(f'{t:.2f}' for t in times)} | {faults} | {rss:.0f} |",
              flush=True)


if __name__ == "__main__":
    main()
