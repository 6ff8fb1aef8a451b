#!/usr/bin/env python3
"""README's real-content table from the committed report's results.json.

    python3 tools/real_content_table.py [--results bench/materials/results/results.json] [--readme README.md]

Rewrites the lines between <!-- real-content:begin --> and
<!-- real-content:end -->: per scene, relMSE of this engine against Cycles
at the same samples, Cycles' own relMSE against its reference (more
samples, another seed: the noise level) and the mean ratio. The report is
written by bench/materials/real_content.py --snapshot bench/materials/results.
"""

import argparse
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
BEGIN, END = "<!-- real-content:begin -->", "<!-- real-content:end -->"


def fmt(x):
    if x is None:
        return "–"
    return f"{x:.2g}" if abs(x) >= 0.01 else f"{x:.2e}"


def table(report):
    ref_factor = report["args"].get("ref_factor", 4)
    samples = report["args"].get("samples", 64)
    lines = [f"| scene | relMSE vs Cycles {samples} | Cycles {samples} vs {samples * ref_factor} "
             f"| mean ours / Cycles |", "| --- | ---: | ---: | ---: |"]
    for r in report["results"]:
        if "error" in r:
            lines.append(f"| {r['scene']} | failed: {r['error']} | | |")
            continue
        v, cn = r["vs_cycles"], r.get("cycles_vs_ref", {})
        lines.append(f"| {r['scene'].replace('_', ' ')} | {fmt(v['relmse'])} | {fmt(cn.get('relmse'))} "
                     f"| {v['mean_ratio']:.3f} |")
    return lines


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--results", default=os.path.join(REPO, "bench", "materials", "results", "results.json"))
    p.add_argument("--readme", default=os.path.join(REPO, "README.md"))
    args = p.parse_args()
    with open(args.results) as f:
        report = json.load(f)
    with open(args.readme) as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        raise SystemExit(f"{args.readme}: no {BEGIN} ... {END} block")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    with open(args.readme, "w") as f:
        f.write(head + BEGIN + "\n" + "\n".join(table(report)) + "\n" + END + tail)
    print("\n".join(table(report)))


if __name__ == "__main__":
    main()
