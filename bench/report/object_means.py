"""Per-object mean Combined of EXRs against a reference, as the report's
per-object table takes it (figures.per_object): the reference's IndexOB,
interior pixels only (the 3x3 neighbourhood holds one index), sum of RGB.

    /usr/bin/python3 bench/report/object_means.py --reference REF.exr IMAGE.exr [IMAGE.exr ...]

REF.exr: a multilayer EXR with Combined and IndexOB (the report's cached
Cycles reference, bench/report/cache/<scene>-*/ref_a.exr); each IMAGE.exr
the same size (a report render, or deferred_render_replay --out). Prints
one row per pass index with at least --min-pixels interior pixels.
"""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from figures import _interior  # noqa: E402
from metrics import read_rgb  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reference", required=True)
    ap.add_argument("--min-pixels", type=int, default=40)
    ap.add_argument("images", nargs="+")
    args = ap.parse_args(argv)
    ref, channels = read_rgb(args.reference)
    index_name = next((n for n in channels if n.endswith("IndexOB.X")), None)
    if index_name is None:
        sys.exit(f"{args.reference}: no IndexOB channel")
    index = np.rint(channels[index_name]).astype(np.int64)
    interior = _interior(index)
    images = [(path, read_rgb(path)[0]) for path in args.images]
    for path, img in images:
        if img.shape != ref.shape:
            sys.exit(f"{path}: {img.shape[1]}x{img.shape[0]}, the reference is {ref.shape[1]}x{ref.shape[0]}")
    print("| pass index | pixels | " + " | ".join(os.path.basename(p) for p, _ in images) + " |")
    print("| ---: | ---: | " + " | ".join("---:" for _ in images) + " |")
    for value in np.unique(index):
        mask = interior & (index == value)
        if mask.sum() < args.min_pixels:
            continue
        rm = float(ref[mask].sum())
        if rm <= 1e-4 * mask.sum():
            continue
        cells = [f"{float(img[mask].sum()) / rm:.4f}" for _, img in images]
        print(f"| {int(value)} | {int(mask.sum())} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
