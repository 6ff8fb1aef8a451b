#!/usr/bin/python3
"""deferred_render_replay: renders a scene captured from Blender
(DEFERRED_RENDER_CAPTURE=/path/scene.npz, addon/deferred_render/engine/capture.py)
without Blender, through the same native module and the same calls, and
prints where the time went.

    build/tools/deferred_render_replay scene.npz [--size WxH] [--samples N]
        [--passes A,B] [--repeat K] [--json] [--out OUT.exr] [--device N]
        [--light-samples N] [--emission-samples K] [--shadow-rays | --shadow-maps]
        [--filter-splat on|off] [--visibility-buffer on|off] [--count-fragments]
        [--threads]

Each repeat renders the captured frame again on the same renderer (the first
one compiles or loads the programs; later ones are warm). Printed per
repeat: wall time of render() and the engine's stage timings (ms, for the
whole render: geometry, shadows, lighting, ... summed over the samples, and
the readback). With the captured size, samples and passes the image equals
the Blender render's (tests/blender/test_capture_replay.py). --out writes
every pass of the last repeat to a multilayer EXR with Blender's channel
names (ViewLayer.<pass>.<channel>; needs OpenImageIO's Python module), or
to a .npz of (H, W, C) arrays, rows top first.

--threads adds each repeat's CPU time per thread (Linux /proc, 1/100 s
ticks): the render thread ("deferred-gl", the first so named), the GL
driver's other threads (llvmpipe's rasteriser "llvmpipe-N"; its compute
pool, started from the render thread, keeps its name) and the rest
(bench/cpu/thread_load.py tabulates it).

The native module comes from this build (@DEFERRED_ADDON_DIR@) or from
DEFERRED_NATIVE_DIR.
"""

import argparse
import json
import os
import sys
import time

import numpy as np

ADDON_DIR = os.environ.get("DEFERRED_NATIVE_DIR") or "@DEFERRED_ADDON_DIR@"
CHANNEL_LETTERS = {"RGBA": "RGBA", "RGB": "RGB", "Z": "Z", "XYZ": "XYZ", "UVA": "UVA", "X": "X", "XYZW": "XYZW"}
STAGES = ("upload_ms", "geometry_ms", "shadow_ms", "culling_ms", "lighting_ms", "forward_ms", "passes_ms",
          "readback_ms", "compile_ms", "load_ms", "total_ms")


def load_native():
    sys.path.insert(0, ADDON_DIR)
    try:
        import deferred_native
    except ImportError as ex:
        sys.exit(f"deferred_render_replay: cannot import the native module from {ADDON_DIR}: {ex} "
                 "(build the project, or set DEFERRED_NATIVE_DIR)")
    return deferred_native


def load_capture(path):
    try:
        data = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as ex:
        sys.exit(f"deferred_render_replay: {path}: not a capture ({ex})")
    if "__calls__" not in data.files:
        sys.exit(f"deferred_render_replay: {path}: not a capture (no __calls__ entry)")
    calls = json.loads(bytes(data["__calls__"]).decode("utf-8"))
    meta = json.loads(bytes(data["__meta__"]).decode("utf-8")) if "__meta__" in data.files else {}
    if meta.get("format", 1) != 1:
        sys.exit(f"deferred_render_replay: {path}: capture format {meta.get('format')} is not supported (1)")
    return data, calls, meta


class Decoder:
    def __init__(self, data, mod):
        self.data = data
        self.mod = mod

    def __call__(self, value):
        if isinstance(value, list):
            return [self(v) for v in value]
        if isinstance(value, dict):
            if "__array__" in value:
                return self.data[value["__array__"]]
            if "__tuple__" in value:
                return tuple(self(v) for v in value["__tuple__"])
            if "__dict__" in value:
                return {k: self(v) for k, v in value["__dict__"].items()}
            if "__camera__" in value:
                return self.mod.Camera(**self(value["__camera__"]))
            raise ValueError(f"unknown entry {sorted(value)[:3]}")
        return value


def write_images(path, images, mod):
    """Every pass to a multilayer EXR (Blender's channel names) or a .npz."""
    flipped = {name: np.ascontiguousarray(np.asarray(img)[::-1]) for name, img in images.items()}
    if path.endswith(".npz"):
        np.savez(path, **flipped)
        return
    try:
        import OpenImageIO as oiio
    except ImportError:
        sys.exit("deferred_render_replay: writing EXR needs OpenImageIO's Python module "
                 "(Debian: python3-openimageio); or give --out a .npz path")
    chan_ids = {name: chan_id for name, chan_id, _ in mod.PASSES}
    names, planes = [], []
    for name, img in flipped.items():
        img = img if img.ndim == 3 else img[:, :, None]
        letters = CHANNEL_LETTERS.get(chan_ids.get(name, ""), "")
        if len(letters) != img.shape[2]:
            letters = "RGBA"[:img.shape[2]] if img.shape[2] <= 4 else [str(c) for c in range(img.shape[2])]
        for c in range(img.shape[2]):
            names.append(f"ViewLayer.{name}.{letters[c]}")
            planes.append(img[:, :, c])
    h, w = planes[0].shape
    spec = oiio.ImageSpec(w, h, len(names), oiio.FLOAT)
    spec.channelnames = tuple(names)
    spec.attribute("compression", "zip")
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec):
        sys.exit(f"deferred_render_replay: cannot write {path}: {oiio.geterror()}")
    out.write_image(np.stack(planes, axis=-1).astype(np.float32))
    out.close()


def thread_cpu_ms():
    """{tid: (name, CPU ms so far)} for this process's threads (Linux /proc;
    utime + stime, whose tick is 1/SC_CLK_TCK s). Empty without /proc."""
    tick_ms = 1000.0 / os.sysconf("SC_CLK_TCK")
    threads = {}
    try:
        tids = os.listdir("/proc/self/task")
    except OSError:
        return threads
    for tid in tids:
        try:
            with open(f"/proc/self/task/{tid}/stat") as f:
                stat = f.read()
            with open(f"/proc/self/task/{tid}/comm") as f:
                name = f.read().strip()
        except OSError:
            continue  # the thread ended
        fields = stat[stat.rfind(")") + 2:].split()  # from field 3 (state) on
        threads[int(tid)] = (name, (int(fields[11]) + int(fields[12])) * tick_ms)  # fields 14, 15
    return threads


def thread_roles(threads):
    """Each tid's role: "main", "render" (the first "deferred-gl" thread),
    "compute" (later ones: llvmpipe's compute pool inherits the name),
    "raster" (llvmpipe-N) or "other"."""
    main = os.getpid()
    gl = sorted(t for t, (name, _) in threads.items() if name == "deferred-gl")
    roles = {}
    for tid, (name, _) in threads.items():
        if tid == main:
            roles[tid] = "main"
        elif gl and tid == gl[0]:
            roles[tid] = "render"
        elif name == "deferred-gl":
            roles[tid] = "compute"
        elif name.startswith("llvmpipe-"):
            roles[tid] = "raster"
        else:
            roles[tid] = "other"
    return roles


def main(argv=None):
    ap = argparse.ArgumentParser(description="Render a scene captured by DEFERRED_RENDER_CAPTURE without Blender.")
    ap.add_argument("capture", help="the .npz a capturing render wrote")
    ap.add_argument("--size", help="WxH instead of the captured resolution")
    ap.add_argument("--samples", type=int, help="film samples instead of the captured count")
    ap.add_argument("--passes", help="comma-separated passes instead of the captured ones (Combined is always made)")
    ap.add_argument("--repeat", type=int, default=1, help="renders of the frame (default 1)")
    ap.add_argument("--json", action="store_true", help="print the results as one JSON object")
    ap.add_argument("--out", help="write the last render's passes here (.exr multilayer, or .npz)")
    ap.add_argument("--device", type=int, default=-1, help="EGL device index (default: the best one)")
    ap.add_argument("--light-samples", type=int, help="lights per pixel and sample (0: every light) instead of "
                    "the captured setting")
    ap.add_argument("--emission-samples", type=int, help="camera samples of directly seen emission per sample "
                    "(1: none) instead of the captured setting")
    rays = ap.add_mutually_exclusive_group()
    rays.add_argument("--shadow-rays", action="store_true", help="shadow rays instead of the captured method")
    rays.add_argument("--shadow-maps", action="store_true", help="shadow maps instead of the captured method")
    ap.add_argument("--shadow-quality", type=float,
                    help="shadow map texels per pixel of the surfaces a light reaches (native "
                         "RenderSettings.shadow_quality) instead of the captured setting")
    ap.add_argument("--shadow-resolution", type=int,
                    help="the most texels per side of a shadow map (native RenderSettings.shadow_resolution) instead "
                         "of the captured setting")
    ap.add_argument("--filter-splat", choices=["on", "off"],
                    help="the film's filter splatting (native RenderSettings.filter_splat) instead of the captured "
                         "setting")
    ap.add_argument("--visibility-buffer", choices=["on", "off"],
                    help="the G-buffer from the visibility buffer, in compute (native "
                         "RenderSettings.visibility_buffer), or the raster path, instead of the captured setting")
    ap.add_argument("--transparent-planes", choices=["exact", "stochastic"],
                    help="partly transparent planes as exact forward layers where the frame allows (native "
                         "RenderSettings.exact_transparent_planes, the default), or every partly transparent "
                         "surface by stochastic coverage")
    ap.add_argument("--count-fragments", action="store_true",
                    help="count the fragments the shadow maps' draws shade in every repeat (a pipeline-statistics "
                         "query around each map layer: native RenderSettings.count_shadow_fragments; it may cost a "
                         "GPU time)")
    ap.add_argument("--threads", action="store_true",
                    help="each repeat's CPU time per thread (Linux /proc): the render thread, the driver's threads")
    args = ap.parse_args(argv)

    data, calls, meta = load_capture(args.capture)
    renders = [c for c in calls if c["method"] == "render"]
    if not renders:
        sys.exit(f"deferred_render_replay: {args.capture}: no render call captured")
    mod = load_native()
    decode = Decoder(data, mod)

    t0 = time.perf_counter()
    renderer = mod.Renderer(device_index=args.device)
    t_context = time.perf_counter() - t0
    t0 = time.perf_counter()
    for call in calls:
        if call["method"] == "render":
            continue
        getattr(renderer, call["method"])(*decode(call["args"]), **decode(call["kwargs"]))
    t_scene = time.perf_counter() - t0

    call = renders[-1]
    camera, width, height = decode(call["args"])[:3]
    kwargs = decode(call["kwargs"])
    if args.size:
        try:
            width, height = (int(v) for v in args.size.lower().split("x"))
        except ValueError:
            sys.exit(f"deferred_render_replay: --size {args.size!r}: expected WxH")
    if args.samples is not None:
        kwargs["samples"] = args.samples
    if args.passes:
        kwargs["passes"] = [p.strip() for p in args.passes.split(",") if p.strip()]
    if args.light_samples is not None:
        kwargs["light_samples"] = args.light_samples
    if args.emission_samples is not None:
        kwargs["emission_samples"] = args.emission_samples
    if args.shadow_rays or args.shadow_maps:
        kwargs["shadow_rays"] = bool(args.shadow_rays)
    if args.shadow_quality is not None:
        kwargs["shadow_quality"] = args.shadow_quality
    if args.shadow_resolution is not None:
        kwargs["shadow_resolution"] = args.shadow_resolution
    if args.filter_splat:
        kwargs["filter_splat"] = args.filter_splat == "on"
    if args.visibility_buffer:
        kwargs["visibility_buffer"] = args.visibility_buffer == "on"
    if args.transparent_planes:
        kwargs["exact_transparent_planes"] = args.transparent_planes == "exact"
    if args.count_fragments:
        kwargs["count_shadow_fragments"] = True
    kwargs["preview_interval_ms"] = -1

    info = dict(renderer.gl_info)
    runs = []
    images = None
    for _ in range(max(1, args.repeat)):
        before = thread_cpu_ms() if args.threads else {}
        t0 = time.perf_counter()
        images = renderer.render(camera, width, height, **kwargs)
        wall = time.perf_counter() - t0
        threads = None
        if args.threads:
            after = thread_cpu_ms()
            roles = thread_roles(after)
            threads = [{"tid": tid, "name": name, "role": roles[tid],
                        "cpu_ms": cpu - (before[tid][1] if tid in before else 0.0)}
                       for tid, (name, cpu) in sorted(after.items())]
        timings = dict(renderer.last_timings)
        runs.append({"wall_ms": wall * 1e3, **{k: timings.get(k) for k in STAGES},
                     "visibility_buffer": bool(timings.get("visibility_buffer")),
                     "emission_samples": timings.get("emission_samples", 1),
                     "exact_layers": timings.get("exact_layers", 0),
                     "shadow_layers": timings.get("shadow_layers_rendered"),
                     "shadow_texels": timings.get("shadow_texels_rendered"),
                     "shadow_fragments": timings.get("shadow_fragments"),
                     "shadow_instances": timings.get("shadow_instances_drawn"),
                     "shadow_instances_one_sided": timings.get("shadow_instances_one_sided"),
                     "shadow_resolutions": list(timings.get("shadow_resolutions") or [])})
        if threads is not None:
            runs[-1]["threads"] = threads
    warnings = list(renderer.last_warnings)

    result = {"capture": os.path.abspath(args.capture), "gl_renderer": info.get("renderer"),
              "gl_version": info.get("version"), "size": [width, height], "samples": kwargs.get("samples"),
              "light_samples": kwargs.get("light_samples", 0), "shadow_rays": kwargs.get("shadow_rays", False),
              "emission_samples": runs[-1].get("emission_samples", 1) if runs else 1,
              "filter_splat": kwargs.get("filter_splat", True),
              "shadow_quality": kwargs.get("shadow_quality"), "shadow_resolution": kwargs.get("shadow_resolution"),
              "fragments_counted": bool(args.count_fragments),
              "visibility_buffer": bool(runs and runs[-1].get("visibility_buffer")),
              "exact_layers": runs[-1].get("exact_layers", 0) if runs else 0,
              "passes": sorted(images), "context_ms": t_context * 1e3, "scene_ms": t_scene * 1e3,
              "runs": runs, "warnings": warnings, "captured": meta}
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print(f"{args.capture}: captured from {meta.get('file') or '(unsaved file)'}, frame {meta.get('frame')}, "
              f"on {meta.get('gl_renderer')}")
        print(f"replayed on {info.get('renderer')} ({info.get('version')}): {width}x{height}, "
              f"{kwargs.get('samples')} samples, passes {', '.join(sorted(images))}"
              + (f", {runs[-1]['emission_samples']} emission samples each" if runs and runs[-1].get("emission_samples", 1) > 1
                 else ""))
        print(f"GL context {t_context * 1e3:.0f} ms, scene upload {t_scene * 1e3:.0f} ms")
        if runs and runs[-1].get("exact_layers"):
            print(f"exact layers: {runs[-1]['exact_layers']} partly transparent surfaces (planes, convex solids) "
                  f"composited by the forward pass")
        print("| run | wall ms | " + " | ".join(s[:-3] for s in STAGES) + " |")
        print("| ---: | ---: | " + " | ".join("---:" for _ in STAGES) + " |")
        for k, r in enumerate(runs):
            cells = [f"{r[s]:.1f}" if isinstance(r[s], (int, float)) else "-" for s in STAGES]
            print(f"| {k + 1} | {r['wall_ms']:.1f} | " + " | ".join(cells) + " |")
        for k, r in enumerate(runs):
            if "threads" in r:
                by_role = {}
                for t in r["threads"]:
                    by_role[t["role"]] = by_role.get(t["role"], 0.0) + t["cpu_ms"]
                print(f"run {k + 1} CPU ms by thread: " +
                      ", ".join(f"{role} {ms:.0f}" for role, ms in sorted(by_role.items()) if ms > 0))
        if runs and runs[-1].get("shadow_layers"):
            fragments = (f"{(runs[-1]['shadow_fragments'] or 0) / 1e6:.1f} M fragments shaded"
                         if args.count_fragments else "fragments not counted (--count-fragments)")
            print(f"shadow maps: {runs[-1]['shadow_layers']} layers drawn, "
                  f"{runs[-1]['shadow_texels'] / 1e6:.1f} Mtexels inside their scissors, {fragments}, "
                  f"{runs[-1]['shadow_instances']} instances drawn, {runs[-1]['shadow_instances_one_sided']} of them "
                  f"without back faces (last run)")
        for w in warnings:
            print(f"warning: {w}")
    if args.out:
        write_images(args.out, images, mod)
        if not args.json:
            print(f"wrote {args.out}")
    renderer.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
