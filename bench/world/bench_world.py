"""Benchmark: light from the world (issue: world, HDRI, emissive). Prints a table.

A floor, a diffuse and a rough metal sphere at BENCH_SIZE (default
1920x1080), shadow maps on, lit only by the world:
  * constant      a constant Background colour (analytic unoccluded light),
  * HDRI          a bundled studio HDRI through an Environment Texture
                  (baked map, importance-sampled per pixel, map-drawn
                  occlusion directions),
  * HDRI rotated  the same through Texture Coordinate -> Mapping,
and the engine's own timings: the world bake (map + CDF, once per render),
the lighting pass and the whole frame per film sample (without the bake);
the last column is the frame's cost against the constant world.

    BLENDER_USER_SCRIPTS=build/blender_scripts blender -b --factory-startup \\
        --addons deferred_render -E DEFERRED_RENDER --python bench/world/bench_world.py

Environment: BENCH_SAMPLES (default 8), BENCH_SIZE ("1920x1080"), BENCH_HDRI (default forest.exr).
"""

import math
import os
import sys
import tempfile

import bpy

SAMPLES = int(os.environ.get("BENCH_SAMPLES", "8"))
WIDTH, HEIGHT = (int(v) for v in os.environ.get("BENCH_SIZE", "1920x1080").split("x"))
HDRI = os.path.join(bpy.utils.system_resource('DATAFILES'), "studiolights", "world",
                    os.environ.get("BENCH_HDRI", "forest.exr"))


def build_scene():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100
    scene.deferred_render.samples = SAMPLES
    scene.render.filepath = os.path.join(tempfile.gettempdir(), "bench_world_")
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    cam.location = (0.0, -6.0, 2.5)
    cam.rotation_euler = (1.2, 0.0, 0.0)
    scene.camera = cam
    bpy.ops.mesh.primitive_plane_add(size=8)
    for x, metallic in ((-1.0, 0.0), (1.0, 1.0)):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.8, location=(x, 0.0, 0.8), segments=64, ring_count=32)
        bpy.ops.object.shade_smooth()
        mat = bpy.data.materials.new(f"m{x}")
        mat.use_nodes = True
        mat.node_tree.nodes["Principled BSDF"].inputs["Metallic"].default_value = metallic
        bpy.context.object.data.materials.append(mat)
    scene.world = bpy.data.worlds.new("bench world")
    scene.world.use_nodes = True
    return scene


def set_world(scene, kind):
    nt = scene.world.node_tree
    for node in list(nt.nodes):
        if node.bl_idname not in {"ShaderNodeOutputWorld", "ShaderNodeBackground"}:
            nt.nodes.remove(node)
    bg = nt.nodes["Background"]
    bg.inputs["Color"].default_value = (0.6, 0.7, 0.8, 1.0)
    if kind == "constant":
        return
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(HDRI, check_existing=True)
    nt.links.new(env.outputs["Color"], bg.inputs["Color"])
    if kind == "HDRI rotated":
        coords = nt.nodes.new("ShaderNodeTexCoord")
        mapping = nt.nodes.new("ShaderNodeMapping")
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(60))
        nt.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        nt.links.new(mapping.outputs["Vector"], env.inputs["Vector"])


def render_timings():
    from deferred_render.engine import final
    bpy.ops.render.render(write_still=False)
    return dict(final.last_timings)


def main():
    scene = build_scene()
    print(f"BENCH world light at {WIDTH}x{HEIGHT}, {SAMPLES} samples")
    rows = []
    for kind in ("constant", "HDRI", "HDRI rotated"):
        set_world(scene, kind)
        render_timings()  # compile and warm up
        t = render_timings()
        rows.append((kind, t.get("world_bake_ms", 0.0), t.get("world_map_width", 0), t["lighting_ms"] / SAMPLES,
                     t["shadow_ms"] / SAMPLES, (t["total_ms"] - t.get("world_bake_ms", 0.0)) / SAMPLES))
    print("| world | bake ms (once) | map width | lighting ms / sample | shadow maps ms / sample "
          "| frame ms / sample | frame vs constant |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for kind, bake, width, lighting, shadow, total in rows:
        print(f"| {kind} | {bake:.1f} | {width} | {lighting:.1f} | {shadow:.1f} | {total:.1f} "
              f"| {total / rows[0][5]:.2f}x |")
    sys.stdout.flush()


main()
