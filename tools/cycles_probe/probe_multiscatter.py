"""How much brighter Cycles 3.4 renders the Principled BSDF with its default
distribution, Multiscatter GGX, than with GGX: the energy its random walk
between microfacets (Heitz et al. 2016) returns, which single-scattering GGX
(the engine's lobe) loses at high roughness.

A smooth sphere under a uniform grey world (max_bounces 0, film transparent:
the sphere's pixels only), Principled BSDF defaults but Metallic and
Roughness, rendered with both distributions; the ratio of the sphere's mean
is what a Multiscatter material loses when shaded as GGX, averaged over
view and light directions. --write PATH stores the grid as the Python module
the add-on's warning reads (materials/multiscatter_table.py).

    blender -b --factory-startup --python tools/cycles_probe/probe_multiscatter.py -- \\
        --write addon/deferred_render/materials/multiscatter_table.py
"""

import argparse
import math
import os
import sys
import tempfile

import bpy
import numpy as np

METALLIC = (0.0, 0.5, 1.0)
ROUGHNESS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)


def build(samples):
    scene = bpy.context.scene
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=64, ring_count=32)
    bpy.ops.object.shade_smooth()
    sphere = bpy.context.object
    mat = bpy.data.materials.new("probe")
    mat.use_nodes = True
    sphere.data.materials.append(mat)
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    cam.location = (0.0, -5.0, 0.0)
    cam.rotation_euler = (math.pi / 2, 0.0, 0.0)
    scene.camera = cam
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    scene.render.engine = 'CYCLES'
    scene.cycles.samples = samples
    scene.cycles.max_bounces = 0
    scene.cycles.use_denoising = False
    scene.cycles.seed = 1
    scene.render.resolution_x = scene.render.resolution_y = 96
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    scene.render.image_settings.file_format = 'OPEN_EXR'
    return scene, mat.node_tree.nodes["Principled BSDF"]


def sphere_mean(scene, path):
    bpy.ops.render.render()
    bpy.data.images['Render Result'].save_render(path)
    image = bpy.data.images.load(path)
    px = np.array(image.pixels[:], dtype=np.float64).reshape(-1, 4)
    bpy.data.images.remove(image)
    return float(px[px[:, 3] > 0.999, :3].mean())


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser()
    ap.add_argument("--write", help="write the grid as a Python module here")
    ap.add_argument("--samples", type=int, default=int(os.environ.get("PROBE_SPP", "128")))
    args = ap.parse_args(argv)
    scene, bsdf = build(args.samples)
    path = os.path.join(tempfile.mkdtemp(), "probe.exr")
    grid = []
    for metallic in METALLIC:
        row = []
        for roughness in ROUGHNESS:
            means = {}
            for dist in ('GGX', 'MULTI_GGX'):
                bsdf.distribution = dist
                bsdf.inputs['Metallic'].default_value = metallic
                bsdf.inputs['Roughness'].default_value = roughness
                means[dist] = sphere_mean(scene, path)
            ratio = means['MULTI_GGX'] / means['GGX']
            row.append(round(ratio, 4))
            print(f"[multiscatter] metallic {metallic:.1f} roughness {roughness:.1f}: Multiscatter GGX / GGX "
                  f"{ratio:.4f}")
        grid.append(row)
    print("| metallic \\ roughness | " + " | ".join(f"{r:.1f}" for r in ROUGHNESS) + " |")
    print("| --- | " + " | ".join("---:" for _ in ROUGHNESS) + " |")
    for metallic, row in zip(METALLIC, grid):
        print(f"| {metallic:.1f} | " + " | ".join(f"{v:.3f}" for v in row) + " |")
    if args.write:
        with open(args.write, "w") as f:
            f.write('"""Cycles 3.4: the Principled BSDF\'s mean under a uniform world with Multiscatter GGX over\n'
                    'GGX, by Metallic (rows) and Roughness (columns). Written by\n'
                    'tools/cycles_probe/probe_multiscatter.py --write (do not edit)."""\n\n')
            f.write(f"METALLIC = {METALLIC!r}\nROUGHNESS = {ROUGHNESS!r}\n")
            f.write("RATIO = (\n" + "".join(f"    {tuple(row)!r},\n" for row in grid) + ")\n")
        print(f"[multiscatter] wrote {args.write}")


main()
