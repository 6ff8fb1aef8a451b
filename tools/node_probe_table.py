#!/usr/bin/env python3
"""Measure every supported shader node against Cycles and update README's table.

    python3 tools/node_probe_table.py [--out DIR] [--readme FILE] [--no-cache]
    python3 tools/node_probe_table.py --sensitivity [PX]

Runs the probes of tests/blender/node_probes.py (the ones blender_node_probes
asserts) in Blender with this engine (BLENDER_USER_SCRIPTS = --scripts,
default build/blender_scripts; Blender from --blender, $BLENDER_EXECUTABLE or
PATH), then writes:
  * README.md: the table between <!-- node-table:begin --> and
    <!-- node-table:end --> (per node, and per case: max, mean and 99th
    percentile of |ours - Cycles| on the tile's interior, pass/fail);
  * OUT/node_probes.png: Cycles | ours | |difference| x 10 of the whole grid
    (sRGB, clipped), OUT/node_probes.csv: each case's tile (column and row
    from the top left) and figures. OUT defaults to out/node_probes; the
    Cycles render is cached there (cycles_<hash>.npy).
--sensitivity renders Cycles a second time with every pixel centre moved by
PX (default 1e-4 px, i.e. UV moved by ~3e-6, about 25x Cycles' own UV
rounding) and prints the cases that move by more than 10x their tolerance:
inputs too close to a discontinuity or too steep to compare. Nothing is
written then.

Also runs inside Blender: blender -b --factory-startup --addons deferred_render
-E DEFERRED_RENDER --python tools/node_probe_table.py -- [options].
"""

import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
BEGIN, END = "<!-- node-table:begin -->", "<!-- node-table:end -->"
SENSITIVITY_REFERENCE_PX = 1e-5   # limits scale linearly from here (--sensitivity)


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=os.path.join(REPO, "out", "node_probes"))
    p.add_argument("--readme", default=os.path.join(REPO, "README.md"))
    p.add_argument("--no-cache", action="store_true", help="render Cycles again")
    p.add_argument("--sensitivity", nargs="?", type=float, const=1e-4, default=None, metavar="PX")
    p.add_argument("--blender", default=os.environ.get("BLENDER_EXECUTABLE", "blender"))
    p.add_argument("--scripts", default=os.path.join(REPO, "build", "blender_scripts"))
    return p.parse_args(argv)


def launch(argv):
    """Outside Blender: run this script in Blender with the built add-on."""
    args = parse_args(argv)
    env = dict(os.environ, BLENDER_USER_SCRIPTS=os.path.abspath(args.scripts))
    # As tests/blender/run_blender_test.py: a pyenv python3 puts its bin/ first
    # on PATH, and Blender's embedded Python would take that prefix (no numpy).
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep)
                                  if "/.pyenv/versions/" not in p and not p.endswith("/.pyenv/libexec"))
    cmd = [args.blender, "-b", "--factory-startup", "--addons", "deferred_render", "-E", "DEFERRED_RENDER",
           "--python-exit-code", "1", "--python", os.path.abspath(__file__), "--", *argv]
    return subprocess.call(cmd, env=env)


# ---------------------------------------------------------------------------
# inside Blender
# ---------------------------------------------------------------------------

def node_label(idname):
    import bpy
    cls = getattr(bpy.types, idname, None)
    return cls.bl_rna.name if cls is not None else idname


def fmt(value):
    return f"{value:.1e}" if value != float("inf") else "inf"


def short(limit):
    return f"{limit:.0e}".replace("e-0", "e-")


def below_zero_note(P, result):
    names = P.failing_only_below_zero(result)
    return (f" {len(names)} of the failing cases would pass if Cycles' negative values were 0: this engine "
            "shows 0 there (`value_negative`)." if names else "")


def markdown(P, result):
    rows = P.table_rows(result)
    verdicts = [r[6] for r in rows]
    import bpy
    lines = [BEGIN, "",
             f"`python3 tools/node_probe_table.py` (Blender {bpy.app.version_string}, "
             f"{len(rows)} cases: {verdicts.count('pass')} pass, {verdicts.count('FAIL')} fail, "
             f"{verdicts.count('unsupported')} known unsupported"
             + (f", {verdicts.count('UNEXPECTED PASS')} marked unsupported but passing" if
                'UNEXPECTED PASS' in verdicts else "") + ").",
             f"Tolerances: **exact** (max ≤ {short(P.LIMITS[P.EXACT]['max'])}) for math, colour, converter "
             f"and input nodes; **texture** (mean ≤ {short(P.LIMITS[P.STATISTICAL]['mean'])}, 99th percentile "
             f"≤ {short(P.LIMITS[P.STATISTICAL]['p99'])}) for textures, procedurals, normals and derivatives. "
             "Errors are |ours − Cycles| over each tile's interior, all three channels."
             + below_zero_note(P, result), "",
             "| node | cases | pass | worst max | worst mean | worst p99 |",
             "| --- | ---: | ---: | ---: | ---: | ---: |"]
    by_node = {}
    for row in rows:
        by_node.setdefault(row[1], []).append(row)
    for node, node_rows in by_node.items():
        passed = sum(r[6] == "pass" for r in node_rows)
        lines.append(f"| {node_label(node)} | {len(node_rows)} | {passed} | "
                     + " | ".join(fmt(max(r[k] for r in node_rows)) for k in (3, 4, 5)) + " |")
    lines += ["", f"<details><summary>All {len(rows)} cases</summary>", "",
              "| node | case | class | max abs | mean abs | p99 | result |",
              "| --- | --- | --- | ---: | ---: | ---: | --- |"]
    for name, node, kind, mx, mean, p99, v in rows:
        note = f" ({P.KNOWN_UNSUPPORTED[name]})" if name in P.KNOWN_UNSUPPORTED else ""
        lines.append(f"| {node_label(node)} | `{name}` | {kind} | {fmt(mx)} | {fmt(mean)} | {fmt(p99)} | {v}{note} |")
    lines += ["", "</details>", "", END]
    return "\n".join(lines)


def update_readme(path, table):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    start, end = text.find(BEGIN), text.find(END)
    if start < 0 or end < start:
        raise SystemExit(f"{path}: no {BEGIN} ... {END} markers")
    with open(path, "w", encoding="utf-8") as f:
        f.write(text[:start] + table + text[end + len(END):])


def write_side_by_side(U, path, reference, ours, gap=8):
    """Cycles | ours | |diff| x 10, sRGB 8-bit, clipped (rows top first)."""
    import numpy as np

    def srgb(x):
        x = np.clip(np.nan_to_num(x, nan=1.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
        return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)

    h, w, _ = reference.shape
    panel = np.full((h, 3 * w + 2 * gap, 3), 0.5)
    for k, image in enumerate((reference, ours, 10.0 * np.abs(reference - ours))):
        panel[:, k * (w + gap):k * (w + gap) + w] = srgb(image)
    pixels = np.ascontiguousarray((panel[::-1] * 255 + 0.5).astype(np.uint8))
    oiio = U._oiio()
    out = oiio.ImageOutput.create(path)
    if not out or not out.open(path, oiio.ImageSpec(pixels.shape[1], pixels.shape[0], 3, oiio.UINT8)) \
            or not out.write_image(pixels):
        raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
    out.close()


def write_csv(P, path, result):
    import csv
    probes = result.probes
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "node", "class", "column", "row", "max_abs", "mean_abs", "p99_abs", "result"])
        for index, (name, node, kind, mx, mean, p99, v) in enumerate(P.table_rows(result)):
            w.writerow([name, node, kind, index % probes.cols, index // probes.cols,
                        f"{mx:.3e}", f"{mean:.3e}", f"{p99:.3e}", v])


def sensitivity_report(P, result, shift_px):
    scale = shift_px / SENSITIVITY_REFERENCE_PX
    print(f"  Cycles vs Cycles with pixel centres moved by {shift_px:g} px; flagged: a figure over "
          f"{scale:g} x its tolerance")
    flagged = []
    for case, m in zip(result.probes.cases, result.metrics):
        over = [k for k, limit in P.LIMITS[case.tolerance_class].items() if getattr(m, k) > scale * limit]
        if over:
            flagged.append(case.name)
            print(f"  SENSITIVE {case.name:<44} max {m.max:.2e} mean {m.mean:.2e} p99 {m.p99:.2e} ({', '.join(over)})")
    print(f"  {len(flagged)} of {len(result.probes.cases)} cases sensitive")
    return not flagged


def main_in_blender(argv):
    sys.path.insert(0, os.path.join(REPO, "tests", "blender"))
    import blender_test_utils as U
    import node_probes as P
    args = parse_args(argv)
    out = os.path.abspath(args.out)
    if args.sensitivity is not None:
        result = P.run(out, use_cache=not args.no_cache, moved_reference=args.sensitivity)
        return 0 if sensitivity_report(P, result, args.sensitivity) else 1
    result = P.run(out, use_cache=not args.no_cache)
    s = result.seconds
    print(f"  {len(result.probes.cases)} cases; scene {s['build']:.1f} s, Cycles {s['cycles']:.1f} s"
          f"{' (cached)' if result.reference_cached else ''}, ours {s['ours']:.1f} s")
    P.print_table(result)
    update_readme(args.readme, markdown(P, result))
    write_side_by_side(U, os.path.join(out, "node_probes.png"), result.reference, result.ours)
    write_csv(P, os.path.join(out, "node_probes.csv"), result)
    print(f"  wrote the table in {args.readme}; {out}/node_probes.png (Cycles | ours | |diff| x10), "
          f"{out}/node_probes.csv")
    return 0


if __name__ == "__main__":
    try:
        import bpy  # noqa: F401
    except ImportError:
        sys.exit(launch(sys.argv[1:]))
    sys.exit(main_in_blender(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []))
