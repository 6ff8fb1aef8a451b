#!/usr/bin/python3
"""The GPU benchmark in one command, without Blender: replays the captured
sample scenes and the node-materials scene (bench/gpu/captures/*.npz, made by
capture_scenes.sh and capture_materials.py) with
build/tools/deferred_render_replay at 1920x1080 and prints a markdown table
per scene and setting: the warm render's wall time (the best of the repeats
after the first, which compiles), its stage times per film sample, the
readback, and the issue's targets beside them.

    /usr/bin/python3 bench/gpu/replay_bench.py [--build build] [--size 1920x1080]
        [--samples 64] [--repeat 3] [--out bench/gpu/results/<gpu>.md] [--quick]

--quick: 320x180, 4 samples, 2 repeats; --check: 64x36, 1 sample (the test
replay_bench_captures: every committed capture still replays with this
build; if not, re-capture with capture_scenes.sh).
"""

import argparse
import datetime
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))

# (scene, label, extra replay arguments, target per sample ms or None, what the target is)
CASES = [
    ("box_room", "shadow maps", ["--shadow-maps"], 1.0, "box room <= 1 ms per sample"),
    ("box_room", "shadow rays", ["--shadow-rays"], None, ""),
    ("box_room", "Combined + all passes", ["--passes", "all"], None, "16 passes read back <= 30 ms"),
    ("many_lights", "every light", ["--light-samples", "0"], 2.0, "1 000 lights <= 2 ms per sample"),
    ("many_lights", "16 light samples", ["--light-samples", "16"], 2.0, "1 000 lights <= 2 ms per sample"),
    ("showcase", "shadow maps", ["--shadow-maps"], None, ""),
    ("instancing", "shadow maps", ["--shadow-maps"], None, ""),
    # Three emissive meshes (5 000 fairy-light triangles among them): one
    # shadow ray a pixel and sample for all of them (light_lib.glsl).
    ("emitters", "shadow rays", ["--shadow-rays"], None, ""),
    # Node materials (capture_materials.py): the geometry pass with texture-heavy
    # materials against constant ones, the node-materials issue's <= 1.5x.
    ("materials_constant", "constant Principled", [], None, ""),
    ("materials_textured", "image + noise + normal map", [], "geometry", "geometry pass <= 1.5x constant's"),
]
STAGES = ("geometry_ms", "shadow_ms", "culling_ms", "lighting_ms", "passes_ms")


def all_passes(build):
    sys.path.insert(0, os.path.join(build, "blender_scripts", "addons", "deferred_render"))
    import deferred_native
    return ",".join(name for name, _, _ in deferred_native.PASSES)


def run_case(tool, capture, args, size, samples, repeat):
    cmd = [tool, capture, "--size", size, "--samples", str(samples), "--repeat", str(repeat), "--json", *args]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=3600)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: {proc.stderr.decode(errors='replace').strip()[-400:]}")
    return json.loads(proc.stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=os.path.join(REPO, "build"))
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--samples", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", help="also write the table to this file")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args()
    if args.quick:
        args.size, args.samples, args.repeat = "320x180", 4, 2
    if args.check:
        args.size, args.samples, args.repeat = "64x36", 1, 2
    tool = os.path.join(args.build, "tools", "deferred_render_replay")
    passes = all_passes(args.build)
    lines, gpu, geometry = [], None, {}
    for scene, label, extra, target, what in CASES:
        capture = os.path.join(HERE, "captures", scene + ".npz")
        extra = [passes if a == "all" else a for a in extra]
        result = run_case(tool, capture, extra, args.size, args.samples, max(2, args.repeat))
        gpu = gpu or f"{result['gl_renderer']} ({result['gl_version']})"
        warm = min(result["runs"][1:], key=lambda r: r["wall_ms"])
        n = result["samples"]
        per_sample = {k: (warm[k] or 0.0) / n for k in STAGES}
        frame = sum(per_sample.values())
        geometry[scene] = per_sample["geometry_ms"]
        if target == "geometry":  # against the constant materials' geometry pass
            ratio = per_sample["geometry_ms"] / max(geometry.get("materials_constant", 0.0), 1e-9)
            verdict = f"{ratio:.2f}x: " + ("met" if ratio <= 1.5 else "not met")
        else:
            verdict = "-" if target is None else ("met" if frame <= target else f"not met ({target:g} ms)")
        lines.append(f"| {scene} | {label} | {n} | {warm['wall_ms']:.1f} | {frame:.3f} | "
                     + " | ".join(f"{per_sample[k]:.3f}" for k in STAGES)
                     + f" | {warm['readback_ms']:.1f} | {result['runs'][0]['wall_ms']:.0f} | {verdict} {what} |")
        print(lines[-1], flush=True)
    header = [f"Replayed captures (bench/gpu/captures), {args.size}, {args.samples} samples, best warm run of "
              f"{max(2, args.repeat) - 1}; {datetime.date.today()}, on {gpu}",
              "",
              "| scene | setting | samples | warm wall ms | frame ms / sample | " + " | ".join(
                  s[:-3] + " / sample" for s in STAGES) + " | readback ms | first (cold) ms | target |",
              "| --- | --- | ---: | ---: | ---: | " + " | ".join("---:" for _ in STAGES) + " | ---: | ---: | --- |"]
    table = "\n".join(header + lines) + "\n"
    print()
    print(table)
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            f.write(table)


if __name__ == "__main__":
    main()
