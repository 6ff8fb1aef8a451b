"""Benchmark: stochastic transparency (issue: transparency). Prints a table.

A foliage-like scene at BENCH_SIZE (default 1920x1080): a floor and a grid
of N x N upright quads (two triangles each) in front of a wall, under a sun
(shadow maps on), rendered with the quads' material
  * opaque          Principled, Alpha 1 (no transparency variant compiled),
  * constant alpha  Principled, Alpha 0.5 (constant material, SCENE_ALPHA),
  * textured alpha  Principled, Alpha from a Checker (node material,
                    MATERIAL_ALPHA: own depth pre-pass and shadow casters),
and the engine's own stage timings per film sample: geometry pass (with
the data-pass G-buffer when Depth is on), shadow maps, whole frame; the
ratio to the opaque scene is what transparency costs. A second table: the
same with the Depth pass on (Alpha Threshold data G-buffer per sample).
A third: Blend mode (the forward pass) against stochastic alpha 0.5, the
quads as one object and as GRID x GRID objects: the forward pass's time
per sample, per transparent object and per covered pixel (pixels whose
first hit is a quad; overdraw makes the per-pixel figure an upper bound of
a single layer's cost).

    BLENDER_USER_SCRIPTS=build/blender_scripts blender -b --factory-startup \\
        --addons deferred_render -E DEFERRED_RENDER --python bench/transparency/bench_transparency.py

Environment: BENCH_SAMPLES (default 4), BENCH_SIZE ("1920x1080"), BENCH_GRID (default 20).
"""

import math
import os
import sys
import tempfile

import bpy

SAMPLES = int(os.environ.get("BENCH_SAMPLES", "4"))
WIDTH, HEIGHT = (int(v) for v in os.environ.get("BENCH_SIZE", "1920x1080").split("x"))
GRID = int(os.environ.get("BENCH_GRID", "20"))


def build_scene():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100
    scene.deferred_render.samples = SAMPLES
    scene.render.filepath = os.path.join(tempfile.gettempdir(), "bench_transparency_")
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    cam.location = (0.0, -12.0, 3.0)
    cam.rotation_euler = (math.radians(80), 0.0, 0.0)
    scene.camera = cam
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.rotation_euler = (math.radians(40), 0.0, math.radians(30))
    scene.collection.objects.link(sun)
    bpy.ops.mesh.primitive_plane_add(size=40)
    bpy.ops.mesh.primitive_cube_add(location=(0, 8, 3), scale=(12, 0.2, 3))
    verts, faces = [], []
    for i in range(GRID):
        for j in range(GRID):
            x, y = -8 + 16 * i / (GRID - 1), -4 + 10 * j / (GRID - 1)
            b = len(verts)
            verts += [(x - 0.5, y, 0.0), (x + 0.5, y, 0.0), (x + 0.5, y, 2.5), (x - 0.5, y, 2.5)]
            faces.append((b, b + 1, b + 2, b + 3))
    mesh = bpy.data.meshes.new("quads")
    mesh.from_pydata(verts, [], faces)
    mesh.uv_layers.new(name="UVMap")
    ob = bpy.data.objects.new("quads", mesh)
    scene.collection.objects.link(ob)
    return scene, mesh


def quad_material(kind):
    mat = bpy.data.materials.new(kind)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.2, 0.6, 0.2, 1.0)
    if kind == "constant alpha":
        bsdf.inputs["Alpha"].default_value = 0.5
    elif kind == "textured alpha":
        checker = mat.node_tree.nodes.new("ShaderNodeTexChecker")
        checker.inputs["Scale"].default_value = 4.0
        mat.node_tree.links.new(checker.outputs["Fac"], bsdf.inputs["Alpha"])
    return mat


def covered_pixels(scene, mesh):
    """Pixels whose first hit is a quad (Object Index of an opaque render)."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests", "blender"))
    import blender_test_utils as U
    mesh.materials.clear()
    mesh.materials.append(quad_material("opaque"))
    layer = scene.view_layers[0]
    layer.use_pass_object_index = True
    for ob in scene.objects:
        ob.pass_index = 7 if ob.data is mesh or getattr(ob.data, "name", "").startswith("quad") else 0
    channels = U.read_exr(U.render_exr(os.path.join(tempfile.gettempdir(), "bench_transparency_index"), scene))
    layer.use_pass_object_index = False
    return int((channels["ViewLayer.IndexOB.X"] == 7).sum())


def separate_quads(scene, mesh):
    """The quads as GRID x GRID objects of one quad each (the forward pass
    sorts and draws per object)."""
    objects = []
    for k, poly in enumerate(mesh.polygons):
        verts = [tuple(mesh.vertices[v].co) for v in poly.vertices]
        one = bpy.data.meshes.new(f"quad{k}")
        one.from_pydata(verts, [], [(0, 1, 2, 3)])
        one.uv_layers.new(name="UVMap")
        ob = bpy.data.objects.new(f"quad{k}", one)
        scene.collection.objects.link(ob)
        objects.append(ob)
    return objects


def blend_table(scene, mesh):
    """Blend mode (the forward pass): its cost per sample, per transparent
    object and per covered pixel, against the stochastic constant alpha."""
    covered = covered_pixels(scene, mesh)
    rows = []
    stochastic = quad_material("constant alpha")
    blend = quad_material("constant alpha")
    blend.blend_method = 'BLEND'
    quads = bpy.data.objects["quads"]
    for layout in ("one object", "separate objects"):
        if layout == "separate objects":
            quads.hide_render = True
            parts = separate_quads(scene, mesh)
        for name, mat in (("stochastic alpha 0.5", stochastic), ("Blend mode alpha 0.5", blend)):
            targets = [mesh] if layout == "one object" else [ob.data for ob in parts]
            for m in targets:
                m.materials.clear()
                m.materials.append(mat)
            render_timings()
            t = render_timings()
            rows.append((layout, name, t.get("forward_ms", 0.0) / SAMPLES, t["total_ms"] / SAMPLES))
    objects = {"one object": 1, "separate objects": GRID * GRID}
    print(f"| quads ({covered} covered pixels) | material | forward pass ms / sample | per object us | "
          "per covered pixel ns | frame ms / sample | frame vs stochastic |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for i, (layout, name, forward, total) in enumerate(rows):
        base = rows[i - 1][3] if i % 2 else total
        per_object = f"{1000 * forward / objects[layout]:.1f}" if forward else "-"
        per_pixel = f"{1e6 * forward / max(covered, 1):.1f}" if forward else "-"
        print(f"| {layout} | {name} | {forward:.1f} | {per_object} | {per_pixel} | {total:.1f} | {total / base:.2f}x |")


def render_timings():
    from deferred_render.engine import final
    bpy.ops.render.render(write_still=False)
    return dict(final.last_timings)


def main():
    scene, mesh = build_scene()
    print(f"BENCH transparency at {WIDTH}x{HEIGHT}, {SAMPLES} samples, {GRID * GRID} quads")
    for depth_pass in (False, True):
        scene.view_layers[0].use_pass_z = depth_pass
        rows = []
        for kind in ("opaque", "constant alpha", "textured alpha"):
            mesh.materials.clear()
            mesh.materials.append(quad_material(kind))
            render_timings()  # compile and warm up
            t = render_timings()
            rows.append((kind, t["geometry_ms"] / SAMPLES, t["shadow_ms"] / SAMPLES, t["total_ms"] / SAMPLES))
        print("| quads" + (" (Depth pass on)" if depth_pass else "") +
              " | geometry ms / sample | shadow maps ms / sample | frame ms / sample | frame vs opaque |")
        print("| --- | --- | --- | --- | --- |")
        for kind, geometry, shadow, total in rows:
            print(f"| {kind} | {geometry:.1f} | {shadow:.1f} | {total:.1f} | {total / rows[0][3]:.2f}x |")
    scene.view_layers[0].use_pass_z = False
    blend_table(scene, mesh)
    sys.stdout.flush()


main()
