"""Warm renders (Persistent Data): the time a render spends beyond its
samples, render after render of an unchanged scene. Prints a table.

    BLENDER_USER_SCRIPTS=build/blender_scripts blender -b --factory-startup --addons deferred_render \\
        blend_samples/box_room.blend -E DEFERRED_RENDER --python bench/warm/bench_warm.py \\
        [-- --size 480x360 --samples 4 --renders 4 --persistent on|off]

"Beyond the samples" = wall time of bpy.ops.render.render() minus the engine's
per-sample stages (geometry, shadows, culling, lighting, forward, passes):
Blender's own render setup, the depsgraph export, the upload, the readback
and the hand-over to the RenderResult. The three largest stages (shadow
maps, G-buffer, lighting) are printed apart. The first render starts the renderer
(GL context, programs from the disk cache); the later ones reuse it: all
of it with Persistent Data on, its context and programs only with it off
(engine/session.py).
"""

import argparse
import sys
import time

import bpy

STAGES = ("geometry_ms", "shadow_ms", "culling_ms", "lighting_ms", "forward_ms", "passes_ms")


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", default="480x360")
    ap.add_argument("--samples", type=int, default=4)
    ap.add_argument("--renders", type=int, default=4)
    ap.add_argument("--persistent", choices=("on", "off"), default="on")
    args = ap.parse_args(argv)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = (int(v) for v in args.size.split("x"))
    scene.render.resolution_percentage = 100
    scene.deferred_render.samples = args.samples
    scene.render.use_persistent_data = args.persistent == "on"
    from deferred_render.engine import final
    print(f"{bpy.data.filepath}: {args.size}, {args.samples} samples, Persistent Data {args.persistent}")
    print("| render | wall s | samples' stages s | beyond the samples s | shadows s | geometry s | lighting s | "
          "upload ms | readback ms | programs loaded |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for i in range(args.renders):
        t0 = time.perf_counter()
        bpy.ops.render.render()
        wall = time.perf_counter() - t0
        t = dict(final.last_timings)
        loop = sum(t.get(k, 0.0) for k in STAGES) / 1e3
        print(f"| {i + 1} | {wall:.3f} | {loop:.3f} | {wall - loop:.3f} | {t.get('shadow_ms', 0) / 1e3:.3f} | "
              f"{t.get('geometry_ms', 0) / 1e3:.3f} | {t.get('lighting_ms', 0) / 1e3:.3f} | "
              f"{t.get('upload_ms', 0):.0f} | {t.get('readback_ms', 0):.0f} | {t.get('programs_loaded', 0)} |")


main()
