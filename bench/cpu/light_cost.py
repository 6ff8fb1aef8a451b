#!/usr/bin/env python3
"""What a captured frame's lights cost and what their sampling adds to its
error: the question behind a scene that loses to Cycles at equal time on
llvmpipe (is the time in the shadow maps of soft lights, whose maps are
drawn again every sample, and is the error theirs or the pixel's?).

Replays a capture (bench/gpu/captures) warm at the report's size, as
captured and in variants written beside it with its recorded calls edited:

  as captured
  sizes 0        every light's radius / sun angle / area size 0: each map is
                 drawn once per frame (shadow_module.h), and what is left of
                 the error at N samples is the pixel's (anti-aliasing,
                 stochastic transparency), not the light points'
  no world       the world black: no world occlusion maps (cost only; the
                 image changes)
  no shadow L    light L's cast_shadow off (cost only)

Each row: per sample, wall ms and the engine's stage split; shadow
instances drawn per sample; and the RMSE at N samples (Combined) against
the same variant at --converged samples, the noise at N. Where "sizes 0"
keeps the noise of "as captured", the light points' sampling is not what a
sample buys down there, and drawing maps less often would not cost error.

    /usr/bin/python3 bench/cpu/light_cost.py bench/gpu/captures/instancing.npz \\
        [--size 320x180] [--samples 4] [--converged 256] [--repeat 2] [--build build]

Prints one markdown table (about 5 minutes for the instancing capture, most
of it the converged renders).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "bench", "report"))
import metrics  # noqa: E402

CONF = "muzzy_decay_ms:-1,lg_extent_max_active_fit:20"  # native/src/cpu_rasteriser.h kJemallocConf
SIZE_KEYS = ("radius", "angle", "size", "size_y")


def load(path):
    z = np.load(path, allow_pickle=False)
    arrays = {k: z[k] for k in z.files}
    calls = json.loads(bytes(arrays["__calls__"]).decode())
    return arrays, calls


def write_variant(arrays, calls, path):
    out = dict(arrays)
    out["__calls__"] = np.frombuffer(json.dumps(calls).encode(), dtype=np.uint8)
    np.savez(path, **out)


def kwargs(call):
    return call["kwargs"]["__dict__"]


def variants(calls):
    """(name, edited calls) pairs; the edits are copies."""
    yield "as captured", calls
    sized = json.loads(json.dumps(calls))
    changed = False
    for c in sized:
        if c["method"] == "add_light":
            for k in SIZE_KEYS:
                if kwargs(c).get(k):
                    kwargs(c)[k] = 0.0
                    changed = True
    if changed:
        yield "sizes 0", sized
    dark = json.loads(json.dumps(calls))
    world = [c for c in dark if c["method"] == "set_world"]
    if world:
        # A black constant world: no world light, so no occlusion maps.
        for c in world:
            c["kwargs"]["__dict__"] = {"color": {"__tuple__": [0.0, 0.0, 0.0]}}
        yield "no world", dark
    lights = [i for i, c in enumerate(calls) if c["method"] == "add_light"]
    for n, i in enumerate(lights):
        if not kwargs(calls[i]).get("cast_shadow", True):
            continue
        off = json.loads(json.dumps(calls))
        kwargs(off[i])["cast_shadow"] = False
        yield "no shadow %d (%s)" % (n, kwargs(calls[i]).get("type", "?").lower()), off


def replay(args, capture, samples, repeat, out=None):
    cmd = [os.path.join(args.build, "tools", "deferred_render_replay"), capture, "--size", args.size,
           "--samples", str(samples), "--repeat", str(repeat), "--passes", "Combined", "--json"]
    if out:
        cmd += ["--out", out]
    env = dict(os.environ, MALLOC_CONF=CONF)
    res = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True).stdout
    return json.loads(res)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("capture")
    ap.add_argument("--size", default="320x180")
    ap.add_argument("--samples", type=int, default=4)
    ap.add_argument("--converged", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=2, help="renders per timing; the fastest counts")
    ap.add_argument("--build", default=os.path.join(REPO, "build"))
    args = ap.parse_args()
    arrays, calls = load(args.capture)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, (name, edited) in enumerate(variants(calls)):
            path = os.path.join(tmp, "v%d.npz" % k)
            write_variant(arrays, edited, path)
            image, converged = os.path.join(tmp, "n.exr"), os.path.join(tmp, "c.exr")
            timed = replay(args, path, args.samples, args.repeat, image)
            replay(args, path, args.converged, 1, converged)
            run = min(timed["runs"], key=lambda r: r["wall_ms"])
            a, _ = metrics.read_rgb(image)
            b, _ = metrics.read_rgb(converged)
            n = float(args.samples)
            rows.append((name, run["wall_ms"] / n, run["geometry_ms"] / n, run["shadow_ms"] / n,
                         run["lighting_ms"] / n, run.get("shadow_instances", 0) / n,
                         float(np.sqrt(np.mean((a - b) ** 2)))))
    print("%s at %s, %d samples (noise: RMSE against the same variant at %d), %s" %
          (os.path.basename(args.capture), args.size, args.samples, args.converged, timed["gl_renderer"]))
    print()
    print("| variant | ms / sample | geometry | shadow | lighting | shadow instances / sample | noise RMSE |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in rows:
        print("| %s | %.1f | %.1f | %.1f | %.1f | %.0f | %.4g |" % r)


if __name__ == "__main__":
    main()
