#!/usr/bin/env python3
"""Run the Blender tests (tests/blender/test_*.py) outside CTest.

    python3 tests/blender/run_blender_test.py                 # all tests
    python3 tests/blender/run_blender_test.py analytic_passes memory
    python3 tests/blender/run_blender_test.py --list

Each test is one Blender process, exactly as CTest runs it (tests.cmake):

    BLENDER_USER_SCRIPTS=<build>/blender_scripts DEFERRED_TEST_OUT=<out> \
    blender -b --factory-startup blend_samples/analytic.blend \
        --addons deferred_render -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_X.py

Options: --blender PATH (default: blender on PATH or $BLENDER_EXECUTABLE),
--scripts DIR (default: <repo>/build/blender_scripts, which the build fills
with the add-on and its native module), --out DIR (default:
<repo>/build/test_out/blender). Prints one line per test and
"N passed, N failed"; exits non-zero if any test failed.
"""

import argparse
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
ANALYTIC = os.path.join(REPO, "blend_samples", "analytic.blend")

# name -> (blend file, enable the add-on from the command line)
TESTS = {
    "export": (ANALYTIC, True),
    "registration": (ANALYTIC, True),
    "native_missing": (ANALYTIC, False),
    "analytic_passes": (ANALYTIC, True),
    "samples": (ANALYTIC, True),
    "compositor": (ANALYTIC, True),
    "animation": (ANALYTIC, True),
    "film_view_layers": (ANALYTIC, True),
    "border": (ANALYTIC, True),
    "alignment_cycles": (ANALYTIC, True),
    "bad_scenes": (ANALYTIC, True),
    "memory": (ANALYTIC, True),
    "light_culling": (ANALYTIC, True),
    "world_ao": (ANALYTIC, True),
    "node_materials": (ANALYTIC, True),
    "node_probes": (ANALYTIC, True),
    "transparency": (ANALYTIC, True),
    "bump_lighting": (ANALYTIC, True),
    "world_map": (ANALYTIC, True),
    "sky_models": (ANALYTIC, True),
    "cryptomatte": (ANALYTIC, True),
    "holdout": (ANALYTIC, True),
    "aovs": (ANALYTIC, True),
    "light_groups": (ANALYTIC, True),
    "emissive": (ANALYTIC, True),
    "shadow_terminator": (ANALYTIC, True),
}
BENCHMARKS = {"bench_export": (None, True)}


def command(blender, name, blend, addons):
    script = os.path.join(HERE, f"{name}.py" if name.startswith("bench_") else f"test_{name}.py")
    cmd = [blender, "-b", "--factory-startup"]
    if blend:
        cmd.append(blend)
    if addons:
        cmd += ["--addons", "deferred_render", "-E", "DEFERRED_RENDER"]
    return cmd + ["--python-exit-code", "1", "--python", script]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tests", nargs="*", help="test names (default: all tests, no benchmarks)")
    parser.add_argument("--blender", default=os.environ.get("BLENDER_EXECUTABLE") or shutil.which("blender"))
    parser.add_argument("--scripts", default=os.path.join(REPO, "build", "blender_scripts"))
    parser.add_argument("--out", default=os.path.join(REPO, "build", "test_out", "blender"))
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--verbose", "-v", action="store_true", help="print each test's full output")
    args = parser.parse_args()

    table = dict(TESTS, **BENCHMARKS)
    if args.list:
        print("\n".join(table))
        return 0
    names = args.tests or list(TESTS)
    unknown = [n for n in names if n not in table]
    if unknown:
        parser.error(f"unknown test(s): {', '.join(unknown)}; --list shows them")
    if not args.blender:
        parser.error("blender not found: pass --blender or set BLENDER_EXECUTABLE")
    addon = os.path.join(args.scripts, "addons", "deferred_render")
    if not os.path.isdir(addon):
        print(f"warning: {addon} does not exist (build first: cmake --build build)", file=sys.stderr)

    env = dict(os.environ, BLENDER_USER_SCRIPTS=os.path.abspath(args.scripts),
               DEFERRED_TEST_OUT=os.path.abspath(args.out))
    # A pyenv-run python3 puts its interpreter's bin/ first on PATH; Blender's
    # embedded Python then takes that prefix and loses the system numpy.
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep)
                                  if "/.pyenv/versions/" not in p and not p.endswith("/.pyenv/libexec"))
    os.makedirs(args.out, exist_ok=True)
    passed, failed = [], []
    t_all = time.perf_counter()
    for name in names:
        blend, addons = table[name]
        cmd = command(args.blender, name, blend, addons)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, cwd=REPO)
        dt = time.perf_counter() - t0
        output = proc.stdout.decode("utf-8", "replace")
        log = os.path.join(args.out, f"{name}.log")
        with open(log, "w") as f:
            f.write(" ".join(cmd) + "\n\n" + output)
        summary = next((l for l in reversed(output.splitlines()) if l.endswith(" failed")), "")
        ok = proc.returncode == 0
        (passed if ok else failed).append(name)
        print(f"{'PASS' if ok else 'FAIL'}  {name:18s} {dt:6.1f} s  {summary}  (log: {log})")
        for line in output.splitlines():
            if args.verbose or line.startswith(("  FAIL", "  BENCH", "  MEMORY", "  ALIGN")):
                print("      " + line.strip())
    print(f"total {time.perf_counter() - t_all:.1f} s")
    print(f"{len(passed)} passed, {len(failed)} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
