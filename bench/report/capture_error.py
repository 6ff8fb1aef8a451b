#!/usr/bin/python3
"""A replayed capture's error against the report's cached Cycles reference,
and where it lies: RMSE, relMSE and mean/ref of each render (the report's
metrics), and with --converged (the same capture at many samples) each
render's squared error split by the reference's IndexOB into noise (the
render against the converged one) and bias (the converged one against the
reference), as shares of the render's whole squared error.

    build/tools/deferred_render_replay bench/gpu/captures/transparency.npz --size 320x180 \\
        --samples 4 --passes Combined --out /tmp/t4.exr        # and --samples 1024 --out /tmp/t1024.exr
    /usr/bin/python3 bench/report/capture_error.py bench/report/cache/transparency-<hash> \\
        /tmp/t4.exr --converged /tmp/t1024.exr

The replay writes its EXR top row first, as the reference is stored.
"""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import metrics  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("reference_dir", help="a bench/report/cache/<scene>-<hash> directory")
    ap.add_argument("renders", nargs="+", help="EXRs of the replayed capture at the reference's size")
    ap.add_argument("--converged", help="the same capture at many samples: split the error by object")
    args = ap.parse_args()
    a, channels = metrics.read_rgb(os.path.join(args.reference_dir, "ref_a.exr"))
    b, _ = metrics.read_rgb(os.path.join(args.reference_dir, "ref_b.exr"))
    ref = (a + b) / 2
    converged = metrics.read_rgb(args.converged)[0] if args.converged else None
    index = next((v for k, v in channels.items() if k.endswith("IndexOB.X")), None)
    for path in args.renders:
        x, _ = metrics.read_rgb(path)
        if x.shape != ref.shape:
            raise SystemExit(f"{path}: {x.shape[1]}x{x.shape[0]}, the reference is {ref.shape[1]}x{ref.shape[0]}")
        e = metrics.errors(x, ref)
        print(f"{path}: RMSE {e['rmse']:.4f} relMSE {e['relmse']:.4g} mean/ref {e['mean_ratio']:.4f}")
        if converged is None:
            continue
        sq = ((x - ref) ** 2).sum(-1)
        noise = ((x - converged) ** 2).sum(-1)
        bias = ((converged - ref) ** 2).sum(-1)
        total = sq.sum()
        print(f"  noise {noise.sum() / total:.3f}, bias {bias.sum() / total:.3f} of the squared error")
        if index is None:
            print("  (no IndexOB in the reference: no split by object)")
            continue
        for v in np.unique(index):
            m = index == v
            print(f"  IndexOB {v:g}: {m.sum():6d} px, {sq[m].sum() / total:.3f} of the squared error "
                  f"(noise {noise[m].sum() / total:.3f}, bias {bias[m].sum() / total:.3f})")


if __name__ == "__main__":
    main()
