#!/usr/bin/python3
"""Two speed-vs-error reports side by side at one sample count: the
equal-time / equal-error table of each report.md (run_report.py), a row per
scene and shadow method, "before → after".

    /usr/bin/python3 bench/report/compare_reports.py BEFORE.md AFTER.md [--samples 4]

A committed snapshot's earlier version: `git show REV:bench/report/results/report.md > BEFORE.md`.
"""

import argparse

# The columns of report.md's equal-time table (run_report.py markdown()).
COLUMNS = ["scene", "ours", "samples", "time", "rmse", "eevee_time", "cycles_time", "eevee_error", "cycles_error"]


def equal_time_rows(path, samples):
    rows = {}
    with open(path) as f:
        for line in f:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) != len(COLUMNS) or cells[1] not in ("maps", "rays"):
                continue
            row = dict(zip(COLUMNS, cells))
            if row["samples"] == str(samples):
                rows[(row["scene"], row["ours"])] = row
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("before")
    p.add_argument("after")
    p.add_argument("--samples", type=int, default=4)
    a = p.parse_args()
    before, after = equal_time_rows(a.before, a.samples), equal_time_rows(a.after, a.samples)
    if not after:
        raise SystemExit(f"{a.after}: no equal-time rows at {a.samples} samples")
    print(f"| scene | shadows | ours {a.samples} samples s | RMSE | Cycles err ratio @ equal time "
          "| Cycles time ratio @ equal error |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    for key, row in after.items():
        old = before.get(key)
        cell = (lambda k: f"{old[k]} → {row[k]}") if old else (lambda k: row[k])
        print(f"| {key[0]} | {key[1]} | {cell('time')} | {cell('rmse')} | {cell('cycles_time')} "
              f"| {cell('cycles_error')} |")


if __name__ == "__main__":
    main()
