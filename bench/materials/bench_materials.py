"""Benchmark: node materials (issue: real materials). Prints a table.

1. Geometry-pass cost of texture-heavy node materials against constant
   materials on the same scene at 1920x1080 (per film sample, from the
   engine's own stage timings): a grid of spheres filling the frame, either
   constant Principled or Principled fed by an image texture (UV + Mapping),
   Noise -> ColorRamp roughness and a tangent-space normal map.
2. Shader compile for Blender's bundled materials library (35 materials):
   cold (empty program cache), warm (a new renderer, disk cache filled) and
   kept (Persistent Data: the renderer of the previous render reused).
3. Export of a 1M-triangle mesh with 2 UV maps, tangents and a colour
   attribute read by its material (Blender -> numpy -> native).

    BLENDER_USER_SCRIPTS=build/blender_scripts blender -b --factory-startup \\
        --addons deferred_render -E DEFERRED_RENDER --python bench/materials/bench_materials.py

Environment: BENCH_SAMPLES (default 4), BENCH_SIZE ("1920x1080"), BENCH_PARTS
(the textured material's parts, default "image,noise,normal"), BENCH_ONLY_GEOMETRY=1
(the first table only), BENCH_ONLY_EXPORT=1 (the export table only),
BENCH_EXPORT_REPEAT (exports of the mesh in one process, default 1).
"""

import os
import sys
import tempfile
import time

import bpy
import numpy as np

LIBRARY = "/usr/share/blender/scripts/addons/materials_library_vx/sample_materials.blend"
SAMPLES = int(os.environ.get("BENCH_SAMPLES", "4"))
WIDTH, HEIGHT = (int(v) for v in os.environ.get("BENCH_SIZE", "1920x1080").split("x"))


def clear_scene():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    scene = bpy.context.scene
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    cam.location = (0, 0, 14)
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.rotation_euler = (0.5, 0.3, 0)
    scene.collection.objects.link(sun)
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100
    scene.deferred_render.samples = SAMPLES
    scene.render.filepath = os.path.join(tempfile.gettempdir(), "bench_materials_")
    return scene


def sphere_grid(materials, n=8):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.95)
    base = bpy.context.object
    base.data.calc_loop_triangles()
    k = 0
    for i in range(n):
        for j in range(n):
            ob = base.copy()
            ob.data = base.data.copy()
            ob.location = (2 * i - n + 1, (2 * j - n + 1) * 0.6, 0)
            ob.data.materials.append(materials[k % len(materials)])
            bpy.context.scene.collection.objects.link(ob)
            k += 1
    bpy.data.objects.remove(base)


PARTS = os.environ.get("BENCH_PARTS", "image,noise,normal").split(",")


def textured_material(image, parts=PARTS):
    """Principled fed by the parts named: 'image' (UV + Mapping -> Image
    Texture -> Base Color), 'noise' (Noise -> ColorRamp -> Roughness),
    'normal' (the image through a tangent-space Normal Map)."""
    mat = bpy.data.materials.new("textured")
    mat.use_nodes = True
    nt = mat.node_tree
    bsdf = nt.nodes["Principled BSDF"]
    tc = nt.nodes.new("ShaderNodeTexCoord")
    mp = nt.nodes.new("ShaderNodeMapping")
    mp.inputs["Scale"].default_value = (4, 2, 1)
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image
    nt.links.new(tc.outputs["UV"], mp.inputs["Vector"])
    nt.links.new(mp.outputs["Vector"], tex.inputs["Vector"])
    if "image" in parts:
        nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    if "noise" in parts:
        noise = nt.nodes.new("ShaderNodeTexNoise")
        noise.inputs["Scale"].default_value = 8
        ramp = nt.nodes.new("ShaderNodeValToRGB")
        nt.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
        nt.links.new(ramp.outputs["Color"], bsdf.inputs["Roughness"])
    if "normal" in parts:
        nmap = nt.nodes.new("ShaderNodeNormalMap")
        nt.links.new(tex.outputs["Color"], nmap.inputs["Color"])
        nt.links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])
    return mat


def constant_material():
    mat = bpy.data.materials.new("constant")
    mat.use_nodes = True
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.6, 0.4, 0.3, 1)
    return mat


def render_timings():
    from deferred_render.engine import final
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    timings = dict(final.last_timings)
    timings["wall_s"] = time.perf_counter() - t0
    return timings


def geometry_cost():
    scene = clear_scene()
    image = bpy.data.images.new("bench_texture", 2048, 2048)
    pixels = np.random.default_rng(1).random(2048 * 2048 * 4, dtype=np.float32)
    image.pixels.foreach_set(pixels)
    image.pack()
    rows = []
    for label, mats in (("constant Principled", [constant_material()]),
                        (" + ".join(PARTS), [textured_material(image)])):
        for ob in [o for o in scene.objects if o.type == "MESH"]:
            bpy.data.objects.remove(ob)
        sphere_grid(mats)
        render_timings()  # compile and warm up
        t = render_timings()
        rows.append((label, t["geometry_ms"] / SAMPLES, t["total_ms"] / SAMPLES))
    return rows


def library_compile():
    scene = clear_scene()
    with bpy.data.libraries.load(LIBRARY) as (src, dst):
        dst.materials = src.materials
    sphere_grid([m for m in dst.materials if m is not None], n=6)
    scene.deferred_render.samples = 1
    scene.render.resolution_x, scene.render.resolution_y = 320, 180
    os.environ["DEFERRED_SHADER_CACHE"] = tempfile.mkdtemp(prefix="bench_programs_")
    cold = render_timings()
    warm = render_timings()
    # Persistent Data: the first render keeps its renderer, the second reuses it.
    scene.render.use_persistent_data = True
    render_timings()
    kept = render_timings()
    scene.render.use_persistent_data = False
    from deferred_render.engine import session
    session.release()
    del os.environ["DEFERRED_SHADER_CACHE"]
    return cold, warm, kept


def export_attributes(repeat=1):
    """(triangles, [Blender -> numpy s per export], numpy -> native s of the first)."""
    from deferred_render.export import mesh as mesh_export
    clear_scene()
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=708, y_subdivisions=708, size=10)  # ~1M triangles
    ob = bpy.context.object
    mesh = ob.data
    mesh.uv_layers.new(name="UVMap")
    mesh.uv_layers.new(name="Second")
    mesh.color_attributes.new("Col", "FLOAT_COLOR", "CORNER")
    keys = ("uv:UVMap", "uv:Second", "tangent:UVMap", "color:Col")
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = ob.evaluated_get(depsgraph)
    from deferred_render import native
    native.load()  # the module's import is not the export's
    t0 = time.perf_counter()
    arrays = mesh_export.object_mesh_arrays(evaluated, keys)
    t1 = time.perf_counter()
    # The renderer after the export, so that the export is timed alone.
    renderer = native.try_load().Renderer()
    t_upload = time.perf_counter()
    renderer.add_mesh(arrays.positions, arrays.indices, corner_normals=arrays.corner_normals,
                      corner_uvs=arrays.corner_uvs, material_indices=arrays.material_indices,
                      attributes=arrays.attributes, texspace_location=arrays.texspace_location,
                      texspace_size=arrays.texspace_size)
    t2 = time.perf_counter()
    renderer.close()
    tris = arrays.triangle_count
    exports = [t1 - t0]
    del arrays
    # The same export again in this process (warm: what an animation's
    # re-export of a deforming mesh sees).
    for _ in range(repeat - 1):
        t = time.perf_counter()
        arrays = mesh_export.object_mesh_arrays(evaluated, keys)
        exports.append(time.perf_counter() - t)
        del arrays
    return tris, exports, t2 - t_upload


def print_export():
    tris, exports, t_native = export_attributes(int(os.environ.get("BENCH_EXPORT_REPEAT", "1")))
    print("| export | triangles | Blender -> numpy s | numpy -> native s | total s |")
    print("| --- | --- | --- | --- | --- |")
    print(f"| 2 UV maps + tangents + colour | {tris} | {exports[0]:.2f} | {t_native:.2f} | {exports[0] + t_native:.2f} |")
    for k, t in enumerate(exports[1:], 2):
        print(f"| the same, export {k} in this process | {tris} | {t:.2f} | | |")


def main():
    if os.environ.get("BENCH_ONLY_EXPORT"):
        print_export()
        return
    print(f"BENCH node materials at {WIDTH}x{HEIGHT}, {SAMPLES} samples")
    rows = geometry_cost()
    if os.environ.get("BENCH_ONLY_GEOMETRY"):
        for label, geometry, total in rows:
            print(f"| {label} | {geometry:.1f} | {total:.1f} | {geometry / rows[0][1]:.2f}x |")
        return
    base = rows[0][1]
    print("| materials | geometry ms / sample | frame ms / sample | geometry vs constant |")
    print("| --- | --- | --- | --- |")
    for label, geometry, total in rows:
        print(f"| {label} | {geometry:.1f} | {total:.1f} | {geometry / base:.2f}x |")
    cold, warm, kept = library_compile()
    print("| materials library (35), 320x180, 1 sample | programs | compile/load ms | render wall s |")
    print("| --- | --- | --- | --- |")
    print(f"| cold: compiled | {cold['programs_compiled']} | {cold['compile_ms']:.0f} | {cold['wall_s']:.2f} |")
    print(f"| warm: loaded from the disk cache | {warm['programs_loaded']} | {warm['load_ms']:.0f} | "
          f"{warm['wall_s']:.2f} |")
    print(f"| kept renderer (Persistent Data) | {kept['programs_compiled'] + kept['programs_loaded']} | 0 | "
          f"{kept['wall_s']:.2f} |")
    print_export()
    sys.stdout.flush()


if __name__ == "__main__":  # run by --python; bench/gpu/capture_materials.py imports the materials
    main()
