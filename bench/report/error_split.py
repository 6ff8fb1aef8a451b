#!/usr/bin/python3
"""Where a render's error against the report's Cycles reference sits: the
whole image's relMSE, the same without the pixels next to very bright
reference pixels (highlights whose edges the film's jitter samples), the
reference's own noise in both, the share of the worst pixels, and the
report's RMSE, with and without those pixels, and their share of its
squared error.

    /usr/bin/python3 bench/report/error_split.py bench/report/cache/box_room-<hash> \\
        OUT/renders/box_room/ours_rays_0256.exr [more renders] [--hot 5] [--grow 3]

--hot: a reference value (any channel) above which a pixel is a highlight;
--grow: pixels of dilation around them. The reference is the mean of the
cache's ref_a.exr and ref_b.exr; its noise is rms((a - b) / 2) (metrics.py).
"""

import argparse
import os
import sys

import numpy as np
from scipy import ndimage

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import metrics  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("reference_dir")
    ap.add_argument("renders", nargs="+")
    ap.add_argument("--hot", type=float, default=5.0)
    ap.add_argument("--grow", type=int, default=3)
    args = ap.parse_args()
    a, _ = metrics.read_rgb(os.path.join(args.reference_dir, "ref_a.exr"))
    b, _ = metrics.read_rgb(os.path.join(args.reference_dir, "ref_b.exr"))
    ref = (a + b) / 2
    hot = ndimage.binary_dilation(ref.max(-1) > args.hot, iterations=args.grow)
    noise = (((a - b) / 2) ** 2 / (ref ** 2 + 0.01)).mean(-1)
    print(f"{hot.sum()} of {hot.size} pixels next to reference values above {args.hot:g}")
    print("| render | relMSE | without them | reference noise | without them | worst 20 px share "
          "| RMSE | without them | squared error next to them |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for path in args.renders:
        x, _ = metrics.read_rgb(path)
        e = ((x - ref) ** 2 / (ref ** 2 + 0.01)).mean(-1)
        worst = np.sort(e.ravel())[::-1][:20].sum() / e.sum()
        # The report's RMSE and the share of its squared error in those pixels.
        se = ((x - ref) ** 2).mean(-1)
        print(f"| {os.path.basename(path)} | {e.mean():.3g} | {e[~hot].mean():.3g} | {noise.mean():.3g} | "
              f"{noise[~hot].mean():.3g} | {worst:.2f} | {np.sqrt(se.mean()):.4g} | {np.sqrt(se[~hot].mean()):.4g} | "
              f"{se[hot].sum() / se.sum():.3f} |")


main()
