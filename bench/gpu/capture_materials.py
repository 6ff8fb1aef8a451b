"""Captures the node-materials benchmark scene (bench/materials/bench_materials.py's
geometry-pass case) for the GPU benchmark: 64 spheres of 2 304 triangles
filling the frame under a sun, once with a constant Principled BSDF
(materials_constant.npz) and once with the textured material (UV + Mapping ->
Image Texture -> Base Color, Noise -> ColorRamp -> Roughness, the image
through a tangent-space Normal Map: materials_textured.npz). The spheres share
one mesh here and the image is 512 x 512, 8-bit (bench_materials uses 2048),
so the captures stay small enough to commit (bench/gpu/captures/).

    BLENDER_USER_SCRIPTS=build/blender_scripts blender -b --factory-startup --addons deferred_render \\
        -E DEFERRED_RENDER --python bench/gpu/capture_materials.py
"""

import os
import sys

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "captures")
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "materials"))
import bench_materials  # noqa: E402
from bench_materials import constant_material, textured_material  # noqa: E402  (the benchmark's own materials)


def clear_scene():
    """The benchmark's scene set-up (camera, sun), small: replayed at 1920x1080."""
    scene = bench_materials.clear_scene()
    scene.render.engine = "DEFERRED_RENDER"
    scene.render.resolution_x, scene.render.resolution_y = 192, 108
    scene.deferred_render.samples = 1
    return scene


def sphere_grid(material, n=8):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.95)
    base = bpy.context.object
    mesh = base.data
    mesh.materials.append(material)
    bpy.data.objects.remove(base)
    for i in range(n):
        for j in range(n):
            ob = bpy.data.objects.new(f"sphere_{i}_{j}", mesh)
            ob.location = (2 * i - n + 1, (2 * j - n + 1) * 0.6, 0)
            bpy.context.scene.collection.objects.link(ob)


def capture(name, material):
    clear_scene()
    sphere_grid(material)
    os.environ["DEFERRED_RENDER_CAPTURE"] = os.path.join(OUT, name + ".npz")
    try:
        bpy.ops.render.render()
    finally:
        del os.environ["DEFERRED_RENDER_CAPTURE"]
    print(f"captured {name}: {os.path.getsize(os.path.join(OUT, name + '.npz')) >> 10} KiB")


def main():
    image = bpy.data.images.new("bench_texture", 512, 512)
    image.pixels.foreach_set(np.random.default_rng(1).random(512 * 512 * 4, dtype=np.float32))
    image.pack()
    capture("materials_constant", constant_material())
    capture("materials_textured", textured_material(image))


main()
