#!/usr/bin/python3.11
"""Plot of bench/lights_vs_eevee.py's CSV: frame time against light count
(log-log). Usage: plot_lights.py IN.csv OUT.png"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(src, dst):
    cols = {"deferred_culled_ms": "Deferred, tiled culling", "deferred_brute_ms": "Deferred, brute force",
            "eevee_ms": "EEVEE 3.4 (max 128 lights)"}
    rows = list(csv.DictReader(open(src)))
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for key, label in cols.items():
        pts = [(int(r["lights"]), float(r[key])) for r in rows if r.get(key)]
        if pts:
            ax.plot(*zip(*pts), marker="o", label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("point lights")
    ax.set_ylabel("frame time (ms), inside Blender")
    ax.set_title("Many lights, 1 sample (llvmpipe, 2 cores)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(dst, dpi=120)
    print(f"wrote {dst}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
