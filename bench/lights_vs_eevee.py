"""Many-lights benchmark through Blender: the same scene rendered by this
engine (tiled culling and brute force) and by EEVEE, at 1920x1080, for
1 ... 65536 small point lights (EEVEE 3.4 shades at most 128 lights, so it
stops there). Times are measured inside Blender around
bpy.ops.render.render() (Blender start-up and scene building excluded), the
median of `--repeats` renders after one warm-up render.

    BLENDER_USER_SCRIPTS=$PWD/build/blender_scripts blender -b --factory-startup \
        --addons deferred_render --python bench/lights_vs_eevee.py -- \
        [--size 1920 1080] [--counts 1 16 128 1000 10000 65536] [--brute-max 128] \
        [--csv bench/out/lights_vs_eevee.csv]

then `python3 bench/plot_lights.py bench/out/lights_vs_eevee.csv bench/out/lights_vs_eevee.png`.
Scene: a 60 m floor and 8 boxes, lights at 0.1-3.1 m height, 0.05-0.55 W,
radius <= 2 cm, random colours (numpy seed 99); one sample; EEVEE with the
fair settings of shared/REFERENCE.md section 2 (light threshold 1e-4, soft
shadows off here since our engine has none yet, no GTAO/SSR/bloom).
"""

import argparse
import os
import statistics
import sys
import time

import bpy
import numpy as np


def clear_data():
    # Not read_factory_settings: that would unregister the add-on.
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.lights, bpy.data.cameras,
                       bpy.data.materials, bpy.data.worlds):
        for block in list(collection):
            collection.remove(block)
    for coll in list(bpy.data.collections):
        bpy.data.collections.remove(coll)


def build_scene(count, width, height):
    clear_data()
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    world = bpy.data.worlds.new("Black")
    world.color = (0, 0, 0)
    scene.world = world
    mat = bpy.data.materials.new("Grey")
    mat.diffuse_color = (0.8, 0.8, 0.8, 1)
    bpy.ops.mesh.primitive_plane_add(size=60)
    bpy.context.object.data.materials.append(mat)
    for i in range(8):
        bpy.ops.mesh.primitive_cube_add(size=2, location=(-14 + 4 * i, 3 * (i % 3) - 3, 1))
        bpy.context.object.data.materials.append(mat)
    rng = np.random.default_rng(99)
    pos = np.column_stack([rng.uniform(-28, 28, count), rng.uniform(-28, 28, count), rng.uniform(0.1, 3.1, count)])
    energy = rng.uniform(0.05, 0.55, count)
    radius = rng.uniform(0.0, 0.02, count)
    color = rng.uniform(0.0, 1.0, (count, 3))
    coll = bpy.data.collections.new("Lights")
    scene.collection.children.link(coll)
    for k in range(count):
        data = bpy.data.lights.new(f"L{k}", 'POINT')
        data.energy = float(energy[k])
        data.shadow_soft_size = float(radius[k])
        data.color = color[k]
        data.use_shadow = False
        ob = bpy.data.objects.new(f"L{k}", data)
        ob.location = pos[k]
        coll.objects.link(ob)
    cam_data = bpy.data.cameras.new("Cam")
    cam_data.lens = 30
    cam_data.clip_end = 200
    cam = bpy.data.objects.new("Cam", cam_data)
    cam.location = (0, -22, 12)
    direction = -cam.location
    cam.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()
    scene.collection.objects.link(cam)
    scene.camera = cam
    ee = scene.eevee
    ee.taa_render_samples = 1
    ee.light_threshold = 1e-4
    ee.use_gtao = ee.use_ssr = ee.use_bloom = False
    ee.use_soft_shadows = False
    scene.deferred_render.samples = 1
    return scene


def time_render(scene, engine, repeats, **settings):
    scene.render.engine = engine
    for key, value in settings.items():
        setattr(scene.deferred_render, key, value)
    bpy.ops.render.render()  # warm-up: shaders, GL context, caches
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        bpy.ops.render.render()
        times.append(1000 * (time.perf_counter() - t0))
    return statistics.median(times)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser()
    p.add_argument("--size", type=int, nargs=2, default=[1920, 1080])
    p.add_argument("--counts", type=int, nargs="+", default=[1, 16, 128, 1000, 10000, 65536])
    p.add_argument("--brute-max", type=int, default=128)
    p.add_argument("--repeats", type=int, default=1)
    p.add_argument("--csv", default="bench/out/lights_vs_eevee.csv")
    args = p.parse_args(argv)
    os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
    rows = []
    print("| lights | Deferred culled (ms) | Deferred brute force (ms) | EEVEE (ms) |")
    print("|---:|---:|---:|---:|")
    for n in args.counts:
        scene = build_scene(n, *args.size)
        culled = time_render(scene, "DEFERRED_RENDER", args.repeats, light_culling=True)
        brute = time_render(scene, "DEFERRED_RENDER", args.repeats, light_culling=False) if n <= args.brute_max else None
        eevee = time_render(scene, "BLENDER_EEVEE", args.repeats) if n <= 128 else None
        rows.append((n, culled, brute, eevee))
        fmt = lambda v: "-" if v is None else f"{v:.0f}"
        print(f"| {n} | {culled:.0f} | {fmt(brute)} | {fmt(eevee)} |", flush=True)
    with open(args.csv, "w") as f:
        f.write("lights,deferred_culled_ms,deferred_brute_ms,eevee_ms\n")
        for n, c, b, e in rows:
            f.write(f"{n},{c:.2f},{'' if b is None else f'{b:.2f}'},{'' if e is None else f'{e:.2f}'}\n")
    print(f"wrote {args.csv}")


main()
