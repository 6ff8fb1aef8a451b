#!/usr/bin/python3
"""Bit-for-bit regression check over scene captures, for changes that must
not change an image (a refactor of the frame): replay every capture of a
folder with the build into .npz files, before and after the change, and
compare every channel.

    tools/replay_regress.py render CAPTURES OUT [--build build]
        each CAPTURES/*.npz as captured, with --shadow-maps, with
        --shadow-rays and with 4 light samples, into
        OUT/<name>[_maps|_rays|_ls4].npz
    tools/replay_regress.py compare OUT_BEFORE OUT_AFTER
        exit 1 when a file, a channel or a value differs (NaN equals NaN)

Captures of the sample scenes with every pass (DEFERRED_RENDER_CAPTURE,
see README "Scene capture and replay"), small and with few samples, make
a run take about a minute.
"""
import argparse
import glob
import os
import subprocess
import sys

import numpy as np

VARIANTS = (("", []), ("_maps", ["--shadow-maps"]), ("_rays", ["--shadow-rays"]),
            ("_ls4", ["--light-samples", "4"]))


def render(args):
    replay = os.path.join(args.build, "tools", "deferred_render_replay")
    os.makedirs(args.out, exist_ok=True)
    failed = 0
    for capture in sorted(glob.glob(os.path.join(args.captures, "*.npz"))):
        name = os.path.splitext(os.path.basename(capture))[0]
        for suffix, flags in VARIANTS:
            out = os.path.join(args.out, name + suffix + ".npz")
            r = subprocess.run([replay, capture, "--out", out] + flags, capture_output=True, text=True)
            if r.returncode != 0:
                failed += 1
                print(f"FAILED {name}{suffix}: {r.stderr.strip()[-300:]}")
    return 1 if failed else 0


def compare(args):
    bad = 0
    files = sorted(glob.glob(os.path.join(args.before, "*.npz")))
    for f in files:
        g = os.path.join(args.after, os.path.basename(f))
        if not os.path.exists(g):
            print(f"missing {g}")
            bad += 1
            continue
        x, y = np.load(f), np.load(g)
        if sorted(x.files) != sorted(y.files):
            print(f"{os.path.basename(f)}: channels differ: {sorted(set(x.files) ^ set(y.files))}")
            bad += 1
            continue
        for k in x.files:
            a, b = x[k], y[k]
            if a.shape != b.shape or not np.array_equal(a, b, equal_nan=a.dtype.kind == "f"):
                diff = "shape" if a.shape != b.shape else f"max |diff| {np.nanmax(np.abs(a.astype(float) - b.astype(float))):.3g}"
                print(f"{os.path.basename(f)} {k}: {diff}")
                bad += 1
    print(f"{len(files)} files, {bad} differences")
    return 1 if bad or not files else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render")
    r.add_argument("captures")
    r.add_argument("out")
    r.add_argument("--build", default=os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "build"))
    c = sub.add_parser("compare")
    c.add_argument("before")
    c.add_argument("after")
    args = ap.parse_args()
    return render(args) if args.command == "render" else compare(args)


if __name__ == "__main__":
    sys.exit(main())
