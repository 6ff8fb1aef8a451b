"""Accuracy on real content: node materials against Cycles 3.4 (direct light).

Builds four scenes in Blender, renders each with Cycles and with this engine
at the same number of samples, and writes the error (RMSE, relMSE, PSNR),
side-by-side PNGs, per-object figures and the engine's warnings:

    BLENDER_USER_SCRIPTS=$PWD/build/blender_scripts blender -b --factory-startup \\
        --addons deferred_render --python bench/materials/real_content.py -- \\
        [--out out/real_content] [--samples 64] [--ref-factor 4] \\
        [--scenes textured_model gltf_import materials_library everyday_nodes] \\
        [--size 480x270] [--snapshot bench/materials/results]

Scenes (built here; only generated PNG textures and the glTF file are written,
into OUT/assets/):
  textured_model     Suzanne (subdivided, smooth, smart-UV) with a PNG base
                     colour through UV + Mapping, Noise -> ColorRamp roughness,
                     a tangent-space normal map; a brick floor; sun + area
                     light; constant dark-grey world.
  gltf_import        a textured scene exported with the glTF exporter (base
                     colour, metallic-roughness, normal and emissive
                     textures) and imported back into an empty scene.
  materials_library  Blender's bundled materials_library_vx sample_materials
                     .blend (35 materials) on a 9 x 4 grid of UV spheres
                     (9 x 4 fits 16:9 better than 6 x 6: ~53 px per sphere).
  everyday_nodes     one object per everyday setup: image + UV + Mapping,
                     Noise -> ColorRamp, tangent normal map, Voronoi -> Bump,
                     Layer Weight mixing Diffuse and Glossy, a colour
                     attribute, Checker/Brick/Wave + Hue/Saturation + Math,
                     Object Info Random on instances, an emissive checker panel.

Both engines: max_bounces 0 (Cycles), no denoising, no adaptive sampling,
Blackman-Harris filter of cycles.filter_width (default 1.5, which this engine
reads too), N samples (--samples). With --ref-factor K > 0 Cycles also
renders K*N samples with another seed as the reference: then Cycles' own
noise at N (Cycles N vs reference) is printed next to ours, which separates
our bias from Monte Carlo noise. With independent renders,
E[relMSE(a, ref)] ~ bias_a^2 + var_a + var_ref and var_ref = var_cycles_N / K,
so "ours vs ref" close to "Cycles N vs ref" means our error is noise-sized.

Errors: Combined RGB (alpha ignored), scene-linear, 32-bit EXR:
  RMSE = sqrt(mean((x - y)^2)), relMSE = mean((x - y)^2 / (y^2 + 0.01)),
  PSNR = 10 log10(max(y)^2 / MSE); y = Cycles at N (or the reference).
Per object: each object's pixels from our object-index pass (eroded by
one pixel, so filtered edges do not count), mean ratio ours / Cycles and
relMSE.

Output (OUT): real_content.md (tables, warnings), results.json, for each
scene SCENE_cycles.exr, SCENE_deferred.exr, SCENE_cycles_ref.exr,
SCENE.png (Cycles | Deferred | |Deferred - Cycles| x4, Standard view
transform: sRGB encoding of the clipped linear values) and, with a
reference, SCENE_vs_ref.png (reference | |Deferred - ref| x4 |
|Cycles N - ref| x4). --snapshot DIR copies real_content.md and the PNGs
there (the repository keeps bench/materials/results/).

Timing: time.perf_counter() around bpy.ops.render.render() (scene export,
Cycles' BVH / our shader compile included; "compile s" is our share spent
compiling or loading shader programs, from final.last_timings).
"""

import argparse
import json
import math
import os
import shutil
import sys
import time

import numpy

numpy.bool = bool  # Blender 3.4.1's glTF add-on uses numpy.bool (gone from Debian's numpy)

import bpy  # noqa: E402
import mathutils  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
LIBRARY = "/usr/share/blender/scripts/addons/materials_library_vx/sample_materials.blend"
SCENES = ("textured_model", "gltf_import", "materials_library", "everyday_nodes")


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="real_content.py")
    p.add_argument("--out", default=os.path.join(REPO, "out", "real_content"))
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--ref-factor", type=int, default=4,
                   help="Cycles reference at K*samples (0: no reference)")
    p.add_argument("--scenes", nargs="+", default=list(SCENES), choices=SCENES)
    p.add_argument("--size", default="480x270")
    p.add_argument("--snapshot", default=None,
                   help="also copy real_content.md and the PNGs into this folder")
    p.add_argument("--snapshot-scale", type=float, default=0.5,
                   help="scale of the snapshot's PNGs (0.5: half size, 1: as written)")
    p.add_argument("--keep-blend", action="store_true", help="save each built scene as OUT/SCENE.blend")
    p.add_argument("--no-mesh-lights", action="store_true",
                   help="diagnosis: Cycles does not light with emissive meshes (this engine never does): "
                        "materials' sample_as_light off, emissive objects invisible to diffuse/glossy rays")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a scene.deferred_render setting (e.g. shadow_quality=4), repeatable")
    p.add_argument("--no-shadows", action="store_true",
                   help="diagnosis: nothing occludes (no shadows, no occluded BSDF rays) in both engines, "
                        "so what remains is shading (materials, lights)")
    args = p.parse_args(argv)
    args.width, args.height = (int(v) for v in args.size.lower().split("x"))
    args.out = os.path.abspath(args.out)
    return args


# ---------------------------------------------------------------------------
# scene helpers
# ---------------------------------------------------------------------------

def clear_data():
    """An empty scene: every object and the data blocks built before."""
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    for coll in (bpy.data.meshes, bpy.data.materials, bpy.data.images, bpy.data.lights,
                 bpy.data.cameras, bpy.data.node_groups, bpy.data.textures, bpy.data.curves):
        items = [x for x in coll if not (coll is bpy.data.images and x.type in {'RENDER_RESULT', 'COMPOSITING'})]
        if items:
            bpy.data.batch_remove(items)
    scene = bpy.context.scene
    for child in list(scene.collection.children):
        scene.collection.children.unlink(child)
        bpy.data.collections.remove(child)
    return scene


def look_at(ob, target):
    direction = mathutils.Vector(target) - ob.location
    ob.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()


def add_camera(scene, location, target, lens=50.0, ortho_scale=None):
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    cam.location = location
    look_at(cam, target)
    if ortho_scale is not None:
        cam.data.type = 'ORTHO'
        cam.data.ortho_scale = ortho_scale
    else:
        cam.data.lens = lens
    scene.camera = cam
    return cam


def add_light(scene, kind, name, location, target, **props):
    light = bpy.data.lights.new(name, kind)
    for k, v in props.items():
        setattr(light, k, v)
    ob = bpy.data.objects.new(name, light)
    scene.collection.objects.link(ob)
    ob.location = location
    look_at(ob, target)
    return ob


def set_world(scene, value):
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    if bg is not None:
        bg.inputs["Color"].default_value = (value, value, value, 1.0)
        bg.inputs["Strength"].default_value = 1.0
    world.color = (value, value, value)


def new_material(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    return mat, mat.node_tree.nodes, mat.node_tree.links


def principled(mat):
    return mat.node_tree.nodes["Principled BSDF"]


def link_object(scene, name, mesh, location=(0, 0, 0), material=None):
    ob = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(ob)
    ob.location = location
    if material is not None:
        mesh.materials.clear()
        mesh.materials.append(material)
    return ob


def primitive(op, **kwargs):
    """A bpy.ops.mesh primitive; returns the new object (selected, active)."""
    op(**kwargs)
    return bpy.context.object


def shade_smooth(ob):
    for p in ob.data.polygons:
        p.use_smooth = True


def floor(scene, size, material, z=0.0):
    ob = primitive(bpy.ops.mesh.primitive_plane_add, size=size, location=(0, 0, z))
    ob.name = "Floor"
    ob.data.materials.append(material)
    return ob


# ---------------------------------------------------------------------------
# generated textures (8-bit PNG, written to OUT/assets)
# ---------------------------------------------------------------------------

def save_png(name, rgba, folder, colorspace='sRGB'):
    """rgba: (H, W, 4) in [0, 1], row 0 = bottom (Blender's order), stored
    as the PNG's 8-bit values (sRGB-encoded for colour images)."""
    h, w = rgba.shape[:2]
    img = bpy.data.images.new(name + "_gen", w, h, alpha=True)
    img.pixels.foreach_set(np.ascontiguousarray(rgba, np.float32).ravel())
    path = os.path.join(folder, name + ".png")
    img.filepath_raw = path
    img.file_format = 'PNG'
    img.save()
    bpy.data.images.remove(img)
    loaded = bpy.data.images.load(path, check_existing=False)
    loaded.name = name
    loaded.colorspace_settings.name = colorspace
    return loaded


def uv_grid(n):
    c = (np.arange(n) + 0.5) / n
    return np.meshgrid(c, c)  # u across, v up


def hsv_to_rgb(h, s, v):
    i = np.floor(h * 6.0) % 6
    f = h * 6.0 - np.floor(h * 6.0)
    p, q, t = v * (1 - s), v * (1 - f * s), v * (1 - (1 - f) * s)
    r = np.choose(i.astype(int), [v, q, p, p, t, v])
    g = np.choose(i.astype(int), [t, v, v, q, p, p])
    b = np.choose(i.astype(int), [p, p, t, v, v, q])
    return np.stack([r, g, b], -1)


def colour_checker(n=512, cells=8):
    """Hue along u, value along v, checker modulation, dark grid lines."""
    u, v = uv_grid(n)
    rgb = hsv_to_rgb(u, 0.75, 0.35 + 0.6 * v)
    check = ((np.floor(u * cells) + np.floor(v * cells)) % 2)[..., None]
    rgb = rgb * (0.55 + 0.45 * check)
    line = (np.minimum((u * cells) % 1, (v * cells) % 1) < 0.04)[..., None]
    rgb = np.where(line, 0.08, rgb)
    return np.concatenate([rgb, np.ones_like(u)[..., None]], -1)


def bump_normal_map(n=512, cells=6, strength=0.6):
    """Tangent-space normal map (OpenGL convention, +Y up) of rounded bumps."""
    u, v = uv_grid(n)
    fu, fv = (u * cells) % 1 - 0.5, (v * cells) % 1 - 0.5
    r2 = fu * fu + fv * fv
    inside = r2 < 0.16
    # height = cos^2 bump; slope per unit of the cell
    k = math.pi / 0.4
    r = np.sqrt(r2) + 1e-9
    dh = np.where(inside, -np.sin(2 * k * r) * k * 0.5, 0.0) * strength * 0.1
    dhdu, dhdv = dh * fu / r, dh * fv / r
    nrm = np.stack([-dhdu, -dhdv, np.ones_like(u)], -1)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    rgb = nrm * 0.5 + 0.5
    return np.concatenate([rgb, np.ones_like(u)[..., None]], -1)


def metal_rough_map(n=256):
    """glTF metallic-roughness: G = roughness (gradient + stripes), B = metallic
    (left half of every other band), R = 1 (occlusion, unused)."""
    u, v = uv_grid(n)
    rough = 0.15 + 0.7 * v + 0.1 * np.sin(u * 40.0)
    rough = np.clip(rough, 0, 1)
    metal = ((np.floor(u * 4) % 2) == 1).astype(np.float64)
    return np.stack([np.ones_like(u), rough, metal, np.ones_like(u)], -1)


def emissive_map(n=256):
    """Mostly black with a few bright coloured squares."""
    u, v = uv_grid(n)
    cu, cv = np.floor(u * 8), np.floor(v * 8)
    on = ((cu * 3 + cv * 5) % 7 == 0)
    inner = (np.abs((u * 8) % 1 - 0.5) < 0.3) & (np.abs((v * 8) % 1 - 0.5) < 0.3)
    rgb = np.where((on & inner)[..., None], hsv_to_rgb((cu / 8 + cv / 13) % 1, 0.8, 1.0), 0.0)
    return np.concatenate([rgb, np.ones_like(u)[..., None]], -1)


def grey_map(n=256):
    u, v = uv_grid(n)
    g = 0.5 + 0.5 * np.sin(u * 25.0) * np.cos(v * 17.0)
    return np.stack([g, g, g, np.ones_like(u)], -1)


# ---------------------------------------------------------------------------
# materials used by several scenes
# ---------------------------------------------------------------------------

def image_node(nodes, links, image, uv_scale=(1, 1, 1), interpolation='Linear', mapping=True):
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.interpolation = interpolation
    if mapping:
        tc = nodes.new("ShaderNodeTexCoord")
        mp = nodes.new("ShaderNodeMapping")
        mp.inputs["Scale"].default_value = uv_scale
        links.new(tc.outputs["UV"], mp.inputs["Vector"])
        links.new(mp.outputs["Vector"], tex.inputs["Vector"])
    return tex


def brick_floor_material():
    mat, nodes, links = new_material("Brick floor")
    bsdf = principled(mat)
    tc = nodes.new("ShaderNodeTexCoord")
    mp = nodes.new("ShaderNodeMapping")
    mp.inputs["Scale"].default_value = (0.35, 0.35, 0.35)
    brick = nodes.new("ShaderNodeTexBrick")
    brick.inputs["Color1"].default_value = (0.45, 0.12, 0.06, 1)
    brick.inputs["Color2"].default_value = (0.3, 0.2, 0.15, 1)
    brick.inputs["Mortar"].default_value = (0.6, 0.6, 0.55, 1)
    links.new(tc.outputs["Object"], mp.inputs["Vector"])
    links.new(mp.outputs["Vector"], brick.inputs["Vector"])
    links.new(brick.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.6
    return mat


def grey_material(name="Grey", value=0.5, roughness=0.5):
    mat, nodes, links = new_material(name)
    bsdf = principled(mat)
    bsdf.inputs["Base Color"].default_value = (value, value, value, 1)
    bsdf.inputs["Roughness"].default_value = roughness
    return mat


# ---------------------------------------------------------------------------
# scene 1: textured model
# ---------------------------------------------------------------------------

def smart_uv(ob):
    """Smart UV Project in edit mode; the primitive's own UVs if that fails."""
    bpy.context.view_layer.objects.active = ob
    ob.select_set(True)
    try:
        bpy.ops.object.mode_set(mode='EDIT')
        bpy.ops.mesh.select_all(action='SELECT')
        bpy.ops.uv.smart_project(angle_limit=math.radians(66.0), island_margin=0.02)
        bpy.ops.object.mode_set(mode='OBJECT')
        return "smart_project"
    except Exception as ex:  # headless without the operator's context
        print(f"smart_project failed ({ex}); primitive UVs kept")
        if ob.mode != 'OBJECT':
            bpy.ops.object.mode_set(mode='OBJECT')
        return "primitive UVs"


def build_textured_model(scene, assets):
    notes = []
    base = save_png("model_base_color", colour_checker(), assets)
    normal = save_png("model_normal", bump_normal_map(), assets, 'Non-Color')

    suzanne = primitive(bpy.ops.mesh.primitive_monkey_add, size=2.0, location=(0, 0, 1.0),
                        calc_uvs=True)
    suzanne.name = "Suzanne"
    suzanne.rotation_euler = (math.radians(-10), 0, math.radians(20))
    notes.append(f"UVs: {smart_uv(suzanne)}")
    mod = suzanne.modifiers.new("Subdivision", 'SUBSURF')
    mod.levels = mod.render_levels = 1
    shade_smooth(suzanne)

    mat, nodes, links = new_material("Suzanne textured")
    bsdf = principled(mat)
    tex = image_node(nodes, links, base, uv_scale=(2, 2, 1))
    links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 6.0
    noise.inputs["Detail"].default_value = 4.0
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].position = 0.35
    ramp.color_ramp.elements[0].color = (0.15, 0.15, 0.15, 1)
    ramp.color_ramp.elements[1].position = 0.65
    ramp.color_ramp.elements[1].color = (0.7, 0.7, 0.7, 1)
    links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], bsdf.inputs["Roughness"])
    ntex = image_node(nodes, links, normal, uv_scale=(2, 2, 1))
    nmap = nodes.new("ShaderNodeNormalMap")
    nmap.space = 'TANGENT'
    nmap.inputs["Strength"].default_value = 1.0
    links.new(ntex.outputs["Color"], nmap.inputs["Color"])
    links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])
    suzanne.data.materials.append(mat)

    floor(scene, 12.0, brick_floor_material())
    add_camera(scene, (0.6, -5.2, 2.4), (0, 0, 0.9), lens=42)
    add_light(scene, 'SUN', "Sun", (3, -2, 6), (0, 0, 0), energy=3.0)
    add_light(scene, 'AREA', "Area", (-3.0, -2.0, 3.0), (0, 0, 1.0), energy=250.0, size=1.5)
    set_world(scene, 0.03)
    return notes


# ---------------------------------------------------------------------------
# scene 2: glTF round trip
# ---------------------------------------------------------------------------

def gltf_source_material(name, base, mr, normal, emissive, uv_scale=(1, 1, 1)):
    """A material the glTF exporter understands: Image -> Base Color,
    Image -> Separate Color (G roughness, B metallic), Image -> Normal Map,
    Image -> Emission (strength 1)."""
    mat, nodes, links = new_material(name)
    bsdf = principled(mat)
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = base
    links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    if mr is not None:
        mrt = nodes.new("ShaderNodeTexImage")
        mrt.image = mr
        sep = nodes.new("ShaderNodeSeparateColor")
        links.new(mrt.outputs["Color"], sep.inputs["Color"])
        links.new(sep.outputs["Green"], bsdf.inputs["Roughness"])
        links.new(sep.outputs["Blue"], bsdf.inputs["Metallic"])
    if normal is not None:
        nt = nodes.new("ShaderNodeTexImage")
        nt.image = normal
        nm = nodes.new("ShaderNodeNormalMap")
        links.new(nt.outputs["Color"], nm.inputs["Color"])
        links.new(nm.outputs["Normal"], bsdf.inputs["Normal"])
    if emissive is not None:
        et = nodes.new("ShaderNodeTexImage")
        et.image = emissive
        links.new(et.outputs["Color"], bsdf.inputs["Emission"])
        bsdf.inputs["Emission Strength"].default_value = 1.0
    return mat


def build_gltf_import(scene, assets):
    notes = []
    base = save_png("gltf_base_color", colour_checker(256, 4), assets)
    mr = save_png("gltf_metal_rough", metal_rough_map(), assets, 'Non-Color')
    normal = save_png("gltf_normal", bump_normal_map(256, 4), assets, 'Non-Color')
    emissive = save_png("gltf_emissive", emissive_map(), assets)
    floor_tex = save_png("gltf_floor", grey_map(), assets)

    mat = gltf_source_material("glTF textured", base, mr, normal, emissive)
    cube = primitive(bpy.ops.mesh.primitive_cube_add, size=1.4, location=(-1.2, 0.2, 0.7))
    cube.name = "Crate"
    cube.rotation_euler = (0, 0, math.radians(30))
    bev = cube.modifiers.new("Bevel", 'BEVEL')
    bev.width, bev.segments = 0.08, 3
    cube.data.materials.append(mat)
    sphere = primitive(bpy.ops.mesh.primitive_uv_sphere_add, segments=48, ring_count=24, radius=0.8,
                       location=(1.1, 0.0, 0.8))
    sphere.name = "Ball"
    shade_smooth(sphere)
    sphere.data.materials.append(mat)
    fl = primitive(bpy.ops.mesh.primitive_plane_add, size=8.0)
    fl.name = "Floor"
    fl.data.materials.append(gltf_source_material("glTF floor", floor_tex, None, None, None))

    path = os.path.join(assets, "scene.glb")
    bpy.ops.export_scene.gltf(filepath=path, export_format='GLB', use_selection=False,
                              export_apply=True, export_cameras=False, export_lights=False)
    notes.append(f"exported {os.path.getsize(path) // 1024} KiB")
    clear_data()
    bpy.ops.import_scene.gltf(filepath=path)
    imported = sorted(o.name for o in scene.objects)
    notes.append("imported: " + ", ".join(imported))
    for m in bpy.data.materials:
        if m.node_tree:
            kinds = sorted({n.bl_idname.replace("ShaderNode", "") for n in m.node_tree.nodes})
            notes.append(f"material '{m.name}': " + " ".join(kinds))
    add_camera(scene, (0.5, -5.0, 2.6), (0, 0, 0.6), lens=40)
    add_light(scene, 'SUN', "Sun", (2, -3, 6), (0, 0, 0), energy=3.0)
    add_light(scene, 'AREA', "Area", (3.0, -1.5, 2.5), (0, 0, 0.7), energy=200.0, size=1.0)
    set_world(scene, 0.0)
    return notes


# ---------------------------------------------------------------------------
# scene 3: Blender's materials library
# ---------------------------------------------------------------------------

def build_materials_library(scene, assets):
    with bpy.data.libraries.load(LIBRARY) as (src, dst):
        dst.materials = src.materials
    mats = sorted((m for m in dst.materials if m is not None), key=lambda m: m.name.lower())
    cols, rows = 9, 4
    sphere = primitive(bpy.ops.mesh.primitive_uv_sphere_add, segments=48, ring_count=24, radius=0.9)
    shade_smooth(sphere)
    base_mesh = sphere.data
    base_mesh.name = "sphere"
    bpy.data.objects.remove(sphere)
    k = 0
    for r in range(rows):
        for c in range(cols):
            if k >= len(mats):
                break
            mesh = base_mesh.copy()
            ob = link_object(scene, f"S{k:02d} {mats[k].name}", mesh,
                             ((c - (cols - 1) / 2) * 2.0, 0.0, ((rows - 1) / 2 - r) * 2.0), mats[k])
            ob.rotation_euler = (0, 0, math.radians(-30))
            k += 1
    add_camera(scene, (0, -30, 0), (0, 0, 0), ortho_scale=18.6)
    add_light(scene, 'SUN', "Sun", (-4, -6, 6), (0, 0, 0), energy=3.0)
    add_light(scene, 'AREA', "Area", (8, -8, 4), (0, 0, 0), energy=1500.0, size=4.0)
    set_world(scene, 0.0)
    return [f"{len(mats)} materials"]


# ---------------------------------------------------------------------------
# scene 4: everyday node setups
# ---------------------------------------------------------------------------

def build_everyday_nodes(scene, assets):
    notes = []
    base = save_png("everyday_base_color", colour_checker(256, 4), assets)
    normal = save_png("everyday_normal", bump_normal_map(256, 4), assets, 'Non-Color')
    cells = {}
    xs, ys = (-3.0, 0.0, 3.0), (2.6, 0.0, -2.6)
    for i, y in enumerate(ys):
        for j, x in enumerate(xs):
            cells[i * 3 + j] = (x, y)

    def sphere(name, cell, mat, r=0.9):
        ob = primitive(bpy.ops.mesh.primitive_uv_sphere_add, segments=48, ring_count=24, radius=r,
                       location=(*cells[cell], r))
        ob.name = name
        shade_smooth(ob)
        ob.data.materials.append(mat)
        return ob

    # 0 image texture through UV + Mapping (a cube shows the UV layout)
    mat, nodes, links = new_material("Image UV Mapping")
    tex = image_node(nodes, links, base, uv_scale=(2, 2, 1))
    mp = [n for n in nodes if n.bl_idname == "ShaderNodeMapping"][0]
    mp.inputs["Rotation"].default_value = (0, 0, math.radians(15))
    mp.inputs["Location"].default_value = (0.1, 0.05, 0)
    links.new(tex.outputs["Color"], principled(mat).inputs["Base Color"])
    principled(mat).inputs["Roughness"].default_value = 0.4
    cube = primitive(bpy.ops.mesh.primitive_cube_add, size=1.5, location=(*cells[0], 0.75))
    cube.name = "Image cube"
    cube.rotation_euler = (0, 0, math.radians(35))
    cube.data.materials.append(mat)

    # 1 Noise -> ColorRamp base colour
    mat, nodes, links = new_material("Noise ColorRamp")
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 4.0
    noise.inputs["Detail"].default_value = 6.0
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (0.05, 0.1, 0.4, 1)
    ramp.color_ramp.elements[1].color = (0.9, 0.7, 0.2, 1)
    e = ramp.color_ramp.elements.new(0.5)
    e.color = (0.8, 0.1, 0.1, 1)
    links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], principled(mat).inputs["Base Color"])
    sphere("Noise sphere", 1, mat)

    # 2 tangent-space normal map
    mat, nodes, links = new_material("Tangent normal map")
    ntex = image_node(nodes, links, normal, uv_scale=(3, 2, 1))
    nmap = nodes.new("ShaderNodeNormalMap")
    links.new(ntex.outputs["Color"], nmap.inputs["Color"])
    links.new(nmap.outputs["Normal"], principled(mat).inputs["Normal"])
    principled(mat).inputs["Base Color"].default_value = (0.6, 0.6, 0.65, 1)
    principled(mat).inputs["Roughness"].default_value = 0.35
    sphere("Normal map sphere", 2, mat)

    # 3 Voronoi -> Bump
    mat, nodes, links = new_material("Voronoi Bump")
    vor = nodes.new("ShaderNodeTexVoronoi")
    vor.inputs["Scale"].default_value = 6.0
    bump = nodes.new("ShaderNodeBump")
    bump.inputs["Strength"].default_value = 0.6
    bump.inputs["Distance"].default_value = 0.1
    links.new(vor.outputs["Distance"], bump.inputs["Height"])
    links.new(bump.outputs["Normal"], principled(mat).inputs["Normal"])
    principled(mat).inputs["Base Color"].default_value = (0.7, 0.5, 0.3, 1)
    principled(mat).inputs["Roughness"].default_value = 0.4
    sphere("Bump sphere", 3, mat)

    # 4 Layer Weight mixing Diffuse and Glossy
    mat, nodes, links = new_material("LayerWeight Diffuse Glossy")
    out = nodes["Material Output"]
    nodes.remove(principled(mat))
    lw = nodes.new("ShaderNodeLayerWeight")
    lw.inputs["Blend"].default_value = 0.3
    dif = nodes.new("ShaderNodeBsdfDiffuse")
    dif.inputs["Color"].default_value = (0.7, 0.1, 0.1, 1)
    glo = nodes.new("ShaderNodeBsdfGlossy")
    glo.inputs["Roughness"].default_value = 0.2
    mix = nodes.new("ShaderNodeMixShader")
    links.new(lw.outputs["Fresnel"], mix.inputs["Fac"])
    links.new(dif.outputs["BSDF"], mix.inputs[1])
    links.new(glo.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], out.inputs["Surface"])
    sphere("LayerWeight sphere", 4, mat)

    # 5 colour attribute (per corner, from the position)
    mat, nodes, links = new_material("Color Attribute")
    va = nodes.new("ShaderNodeVertexColor")
    va.layer_name = "Col"
    links.new(va.outputs["Color"], principled(mat).inputs["Base Color"])
    ob = sphere("Vertex colour sphere", 5, mat)
    me = ob.data
    attr = me.color_attributes.new("Col", 'BYTE_COLOR', 'CORNER')
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    vi = np.empty(len(me.loops), np.int32)
    me.loops.foreach_get("vertex_index", vi)
    p = co[vi] / 0.9
    col = np.stack([0.5 + 0.5 * p[:, 0], 0.5 + 0.5 * p[:, 1], 0.5 + 0.5 * p[:, 2], np.ones(len(p))], -1)
    attr.data.foreach_set("color", col.astype(np.float32).ravel())

    # 6 Checker / Brick / Wave with Hue/Saturation and Math
    mat, nodes, links = new_material("Checker Brick Wave HSV Math")
    tc = nodes.new("ShaderNodeTexCoord")
    chk = nodes.new("ShaderNodeTexChecker")
    chk.inputs["Scale"].default_value = 4.0
    brk = nodes.new("ShaderNodeTexBrick")
    brk.inputs["Scale"].default_value = 4.0
    wav = nodes.new("ShaderNodeTexWave")
    wav.inputs["Scale"].default_value = 3.0
    wav.inputs["Distortion"].default_value = 2.0
    for t in (chk, brk, wav):
        links.new(tc.outputs["Object"], t.inputs["Vector"])
    m1 = nodes.new("ShaderNodeMath")
    m1.operation = 'MULTIPLY_ADD'
    m1.inputs[1].default_value = 0.6
    m1.inputs[2].default_value = 0.2
    links.new(wav.outputs["Fac"], m1.inputs[0])
    mixc = nodes.new("ShaderNodeMix")
    mixc.data_type = 'RGBA'
    links.new(m1.outputs["Value"], mixc.inputs["Factor"])
    links.new(chk.outputs["Color"], mixc.inputs[6])
    links.new(brk.outputs["Color"], mixc.inputs[7])
    hsv = nodes.new("ShaderNodeHueSaturation")
    hsv.inputs["Hue"].default_value = 0.6
    hsv.inputs["Saturation"].default_value = 1.4
    links.new(mixc.outputs[2], hsv.inputs["Color"])
    links.new(hsv.outputs["Color"], principled(mat).inputs["Base Color"])
    m2 = nodes.new("ShaderNodeMath")
    m2.operation = 'MULTIPLY'
    m2.inputs[1].default_value = 0.5
    links.new(brk.outputs["Fac"], m2.inputs[0])
    links.new(m2.outputs["Value"], principled(mat).inputs["Roughness"])
    cube = primitive(bpy.ops.mesh.primitive_cube_add, size=1.5, location=(*cells[6], 0.75))
    cube.name = "Procedural cube"
    cube.rotation_euler = (0, 0, math.radians(-25))
    bev = cube.modifiers.new("Bevel", 'BEVEL')
    bev.width, bev.segments = 0.1, 3
    cube.data.materials.append(mat)

    # 7 Object Info Random on instances (linked duplicates share one mesh)
    mat, nodes, links = new_material("ObjectInfo Random")
    oi = nodes.new("ShaderNodeObjectInfo")
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (0.9, 0.2, 0.1, 1)
    ramp.color_ramp.elements[1].color = (0.1, 0.3, 0.9, 1)
    links.new(oi.outputs["Random"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], principled(mat).inputs["Base Color"])
    base_cube = primitive(bpy.ops.mesh.primitive_cube_add, size=0.6)
    base_cube.data.materials.append(mat)
    mesh = base_cube.data
    bpy.data.objects.remove(base_cube)
    x0, y0 = cells[7]
    for a in range(3):
        for b in range(3):
            link_object(scene, f"Random cube {a}{b}", mesh, (x0 + (a - 1) * 0.8, y0 + (b - 1) * 0.8, 0.3))

    # 8 emissive checker panel (lights the floor in Cycles: an emissive mesh
    # is a light there; this engine does not light with emissive meshes)
    mat, nodes, links = new_material("Emissive checker")
    out = nodes["Material Output"]
    nodes.remove(principled(mat))
    em = nodes.new("ShaderNodeEmission")
    em.inputs["Strength"].default_value = 2.0
    chk = nodes.new("ShaderNodeTexChecker")
    chk.inputs["Scale"].default_value = 6.0
    chk.inputs["Color1"].default_value = (1.0, 0.6, 0.2, 1)
    chk.inputs["Color2"].default_value = (0.1, 0.2, 0.8, 1)
    links.new(chk.outputs["Color"], em.inputs["Color"])
    links.new(em.outputs["Emission"], out.inputs["Surface"])
    panel = primitive(bpy.ops.mesh.primitive_plane_add, size=1.6, location=(*cells[8], 0.9))
    panel.name = "Emissive panel"
    panel.rotation_euler = (math.radians(90), 0, math.radians(20))
    panel.data.materials.append(mat)

    floor(scene, 14.0, grey_material("Floor grey", 0.4, 0.6))
    add_camera(scene, (0.0, -11.5, 7.5), (0, 0.3, 0.2), lens=36)
    add_light(scene, 'SUN', "Sun", (4, -3, 8), (0, 0, 0), energy=3.0)
    add_light(scene, 'AREA', "Area", (-5, -4, 4), (0, 0, 0.5), energy=600.0, size=2.0)
    set_world(scene, 0.0)
    return notes


BUILDERS = {
    "textured_model": build_textured_model,
    "gltf_import": build_gltf_import,
    "materials_library": build_materials_library,
    "everyday_nodes": build_everyday_nodes,
}


# ---------------------------------------------------------------------------
# rendering
# ---------------------------------------------------------------------------

def common_settings(scene, args):
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = args.width, args.height, 100
    r.film_transparent = False
    r.use_border = False
    r.use_persistent_data = False
    scene.view_settings.view_transform = 'Standard'
    scene.view_settings.look = 'None'
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    for layer in scene.view_layers:
        layer.use = layer == scene.view_layers[0]
    layer = scene.view_layers[0]
    for flag in dir(layer):
        if flag.startswith("use_pass_") and flag != "use_pass_combined":
            try:
                setattr(layer, flag, False)
            except (AttributeError, TypeError):
                pass
    layer.use_pass_combined = True
    cy = scene.cycles
    cy.device = 'CPU'
    cy.use_adaptive_sampling = False
    cy.max_bounces = 0
    cy.use_denoising = False
    cy.pixel_filter_type = 'BLACKMAN_HARRIS'   # filter_width left at its default (1.5)
    # pass indices for the per-object table
    for i, ob in enumerate(sorted((o for o in scene.objects if o.type == 'MESH'), key=lambda o: o.name)):
        ob.pass_index = i + 1


def disable_shadows():
    """Nothing blocks light in either engine (as bench/report/blender_job.py's
    unoccluded reference): visible_shadow off, and for Cycles' MIS the BSDF
    rays see no object either (diffuse/glossy/transmission visibility off);
    lights cast no shadow."""
    for ob in bpy.data.objects:
        if ob.type == 'LIGHT':
            continue
        for flag in ("visible_shadow", "visible_diffuse", "visible_glossy", "visible_transmission",
                     "visible_volume_scatter"):
            if hasattr(ob, flag):
                setattr(ob, flag, False)
    for light in bpy.data.lights:
        if hasattr(light, "cycles"):
            light.cycles.cast_shadow = False
        light.use_shadow = False


def _emits(mat):
    if mat is None or not mat.use_nodes or mat.node_tree is None:
        return False
    for n in mat.node_tree.nodes:
        if n.bl_idname == "ShaderNodeEmission":
            return True
        if n.bl_idname == "ShaderNodeBsdfPrincipled":
            e, s = n.inputs["Emission"], n.inputs["Emission Strength"]
            if e.is_linked or (s.is_linked or s.default_value != 0.0) and any(e.default_value[:3]):
                return True
    return False


def disable_mesh_lights():
    """Cycles lights with emissive meshes (light sampling and BSDF rays that
    hit them); this engine does not: take that light out of Cycles."""
    names = []
    for mat in bpy.data.materials:
        mat.cycles.sample_as_light = False
    for ob in bpy.data.objects:
        if ob.type == 'MESH' and any(_emits(slot.material) for slot in ob.material_slots):
            for flag in ("visible_diffuse", "visible_glossy", "visible_transmission"):
                setattr(ob, flag, False)
            names.append(ob.name)
    return names


def render_exr(scene, path_without_ext):
    img = scene.render.image_settings
    img.file_format = 'OPEN_EXR_MULTILAYER'
    img.color_depth = '32'
    img.exr_codec = 'ZIP'
    scene.render.use_file_extension = True
    scene.render.filepath = path_without_ext
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return path_without_ext + ".exr", time.perf_counter() - t0


def render_cycles(scene, samples, seed, path, index_pass):
    scene.render.engine = 'CYCLES'
    scene.cycles.samples = samples
    scene.cycles.seed = seed
    scene.view_layers[0].use_pass_object_index = index_pass
    out, seconds = render_exr(scene, path)
    scene.view_layers[0].use_pass_object_index = False
    return out, seconds


def render_deferred(scene, samples, path, retries=3):
    """Our render, with the object-index pass (sample 0, pixel centres; every
    surface is opaque here, so each object has its pixels even where Cycles
    sees through it) for the per-object table."""
    from deferred_render.engine import final
    scene.render.engine = 'DEFERRED_RENDER'
    scene.deferred_render.samples = samples
    scene.view_layers[0].use_pass_object_index = True
    for attempt in range(retries + 1):
        final.last_messages.clear()
        final.last_timings.clear()
        out, seconds = render_exr(scene, path)
        messages = list(final.last_messages)
        timings = dict(final.last_timings)
        errors = [m for lvl, m in messages if lvl == 'ERROR']
        if errors and attempt < retries and any("native" in e.lower() or "module" in e.lower() for e in errors):
            print(f"Deferred render failed ({errors[0]}); the build may be in progress, retrying in 60 s")
            time.sleep(60)
            continue
        break
    scene.view_layers[0].use_pass_object_index = False
    return out, seconds, messages, timings


# ---------------------------------------------------------------------------
# images and metrics
# ---------------------------------------------------------------------------

def read_exr(path):
    """{channel: (H, W) float32}, row 0 = top (file order): the tests'
    reader (bottom row first, Blender's order), flipped."""
    sys.path.insert(0, os.path.join(REPO, "tests", "blender"))
    import blender_test_utils
    return {k: v[::-1] for k, v in blender_test_utils.read_exr(path).items()}


def combined(channels):
    for name in channels:
        if name.endswith("Combined.R"):
            base = name[:-1]
            return np.stack([channels[base + c] for c in "RGB"], -1).astype(np.float64)
    raise RuntimeError(f"no Combined pass among {sorted(channels)[:10]}")


def object_index(channels):
    for name in channels:
        if name.endswith("IndexOB.X"):
            return np.rint(channels[name]).astype(np.int32)
    return None


def errors(x, ref):
    d2 = (x - ref) ** 2
    mse = float(d2.mean())
    peak = float(ref.max())
    return {"rmse": math.sqrt(mse),
            "relmse": float((d2 / (ref ** 2 + 0.01)).mean()),
            "psnr": 10 * math.log10(peak * peak / mse) if mse > 0 else float("inf"),
            "mean_ratio": float(x.mean() / ref.mean()) if ref.mean() != 0 else float("nan")}


def srgb8(linear):
    x = np.clip(linear, 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (np.clip(s, 0, 1) * 255 + 0.5).astype(np.uint8)


def write_png(path, panels, gap=4):
    import OpenImageIO as oiio
    h = panels[0].shape[0]
    sep = np.full((h, gap, 3), 255, np.uint8)
    row = [srgb8(panels[0])]
    for p in panels[1:]:
        row += [sep, srgb8(p)]
    img = np.ascontiguousarray(np.concatenate(row, 1))
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.UINT8))
    out.write_image(img)
    out.close()


def warned_materials(messages):
    """Names of the materials the engine's warnings name ("Material 'X': ...")."""
    names = set()
    for _, m in messages:
        rest = m
        while "Material '" in rest:
            rest = rest.split("Material '", 1)[1]
            names.add(rest.split("'", 1)[0])
    return names


def per_object(scene, index, ours, cyc, ref, warned=(), masks=None):
    """Per-object figures on each object's eroded pixel set (masks: filled
    with {object name: (mask, warned)} when given)."""
    if index is None:
        return []
    h, w = index.shape
    same = np.ones_like(index, bool)
    pad = np.pad(index, 1, mode='edge')
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            same &= pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] == index
    rows = []
    by_index = {ob.pass_index: ob for ob in scene.objects if ob.type == 'MESH'}
    for idx, ob in sorted(by_index.items()):
        mask = same & (index == idx)
        n = int(mask.sum())
        if n < 20:
            continue
        x, y = ours[mask], cyc[mask]
        mat = ob.active_material.name if ob.active_material else "-"
        if masks is not None:
            masks[ob.name] = (mask, mat in warned)
        row = {"object": ob.name, "material": mat, "pixels": n, "warned": mat in warned,
               "cycles_mean": float(y.mean()), "ours_mean": float(x.mean()),
               "ratio": float(x.mean() / y.mean()) if y.mean() > 0 else float("nan"),
               "relmse": float(((x - y) ** 2 / (y ** 2 + 0.01)).mean())}
        if ref is not None:
            r = ref[mask]
            row["relmse_ours_ref"] = float(((x - r) ** 2 / (r ** 2 + 0.01)).mean())
            row["relmse_cycles_ref"] = float(((y - r) ** 2 / (r ** 2 + 0.01)).mean())
            row["ratio_ref"] = float(x.mean() / r.mean()) if r.mean() > 0 else float("nan")
        rows.append(row)
    return rows


# ---------------------------------------------------------------------------
# one scene
# ---------------------------------------------------------------------------

def run_scene(name, args, assets):
    print(f"==== {name}")
    scene = clear_data()
    t0 = time.perf_counter()
    notes = BUILDERS[name](scene, assets)
    scene = bpy.context.scene
    common_settings(scene, args)
    if args.no_shadows:
        disable_shadows()
        notes.append("no shadows (--no-shadows)")
    for item in args.set:
        key, value = item.split("=", 1)
        current = getattr(scene.deferred_render, key)
        setattr(scene.deferred_render, key, type(current)(value))
        notes.append(f"deferred_render.{key} = {value}")
    if args.no_mesh_lights:
        emissive = disable_mesh_lights()
        notes.append("no mesh lights in Cycles (--no-mesh-lights; emissive: " + ", ".join(emissive) + ")")
    build_s = time.perf_counter() - t0
    if args.keep_blend:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(args.out, name + ".blend"), copy=True)
    base = os.path.join(args.out, name)
    res = {"scene": name, "samples": args.samples, "notes": notes, "build_s": build_s,
           "size": f"{args.width}x{args.height}"}

    d_path, d_s, messages, timings = render_deferred(scene, args.samples, base + "_deferred")
    res["deferred_s"] = d_s
    res["deferred_compile_s"] = (timings.get("compile_ms", 0.0) + timings.get("load_ms", 0.0)) / 1000.0
    res["programs_compiled"] = timings.get("programs_compiled")
    res["warnings"] = [(lvl, m) for lvl, m in messages]
    c_path, c_s = render_cycles(scene, args.samples, 1, base + "_cycles", index_pass=False)
    res["cycles_s"] = c_s
    ref = None
    if args.ref_factor > 0:
        r_path, r_s = render_cycles(scene, args.samples * args.ref_factor, 2, base + "_cycles_ref", False)
        res["ref_samples"] = args.samples * args.ref_factor
        res["ref_s"] = r_s
        ref = combined(read_exr(r_path))

    cyc = combined(read_exr(c_path))
    ours_ch = read_exr(d_path)
    ours = combined(ours_ch)
    finite = np.isfinite(ours).all()
    res["ours_finite"] = bool(finite)
    ours = np.nan_to_num(ours, nan=0.0, posinf=0.0, neginf=0.0)
    res["vs_cycles"] = errors(ours, cyc)
    if ref is not None:
        res["ours_vs_ref"] = errors(ours, ref)
        res["cycles_vs_ref"] = errors(cyc, ref)
    masks = {}
    res["objects"] = per_object(scene, object_index(ours_ch), ours, cyc, ref, warned_materials(messages), masks)
    clean = [m for m, w in masks.values() if not w]
    if clean and len(clean) < len(masks):
        # the same figures over the objects whose materials have no warning
        # (interiors only: no background, no edges)
        sel = np.any(clean, axis=0)
        res["unwarned"] = {"objects": len(clean), "of": len(masks),
                           "vs_cycles": errors(ours[sel], cyc[sel])}
        if ref is not None:
            res["unwarned"]["ours_vs_ref"] = errors(ours[sel], ref[sel])
            res["unwarned"]["cycles_vs_ref"] = errors(cyc[sel], ref[sel])

    write_png(base + ".png", [cyc, ours, np.abs(ours - cyc) * 4.0])
    res["png"] = base + ".png"
    if ref is not None:
        write_png(base + "_vs_ref.png", [ref, np.abs(ours - ref) * 4.0, np.abs(cyc - ref) * 4.0])
        res["png_ref"] = base + "_vs_ref.png"
    v = res["vs_cycles"]
    print(f"{name}: RMSE {v['rmse']:.4g} relMSE {v['relmse']:.4g} PSNR {v['psnr']:.1f} "
          f"mean ratio {v['mean_ratio']:.4f}; Deferred {d_s:.1f} s, Cycles {c_s:.1f} s")
    return res


# ---------------------------------------------------------------------------
# report
# ---------------------------------------------------------------------------

def fmt(x, digits=3):
    if x is None:
        return "-"
    if isinstance(x, float) and (math.isnan(x) or math.isinf(x)):
        return str(x)
    return f"{x:.{digits}g}"


def build_info():
    """Commit of the working tree, whether it differs from it, and when the
    engine's native module was built."""
    import subprocess
    try:
        head = subprocess.run(["git", "-C", REPO, "log", "-1", "--format=%h %ci"], capture_output=True,
                              text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", REPO, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        head, dirty = "?", ""
    import deferred_render
    folder = os.path.dirname(deferred_render.__file__)
    so = [f for f in os.listdir(folder) if f.startswith("deferred_native") and f.endswith(".so")]
    built = time.strftime("%Y-%m-%d %H:%M", time.gmtime(os.path.getmtime(os.path.join(folder, so[0])))) \
        if so else "?"
    return f"commit {head}{' + local changes' if dirty else ''}, native module built {built} UTC"


def snapshot_png(src, dst, scale):
    """Copy a PNG, box-filtered down by 1/scale (integer factor) when scale < 1."""
    import OpenImageIO as oiio
    k = int(round(1.0 / scale)) if scale < 1.0 else 1
    if k <= 1:
        shutil.copy(src, dst)
        return
    inp = oiio.ImageInput.open(src)
    spec = inp.spec()
    px = np.asarray(inp.read_image(0, 3, oiio.FLOAT), np.float32).reshape(spec.height, spec.width, 3)
    inp.close()
    h, w = spec.height // k * k, spec.width // k * k
    small = px[:h, :w].reshape(h // k, k, w // k, k, 3).mean((1, 3))
    img = np.ascontiguousarray((np.clip(small, 0, 1) * 255 + 0.5).astype(np.uint8))
    out = oiio.ImageOutput.create(dst)
    out.open(dst, oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.UINT8))
    out.write_image(img)
    out.close()


def write_markdown(results, args, total_s, path, snapshot_scale=None):
    lines = ["# Node materials on real content: Deferred against Cycles 3.4", ""]
    lines.append(f"Command: `BLENDER_USER_SCRIPTS=$PWD/build/blender_scripts blender -b --factory-startup "
                 f"--addons deferred_render --python bench/materials/real_content.py -- "
                 f"--samples {args.samples} --ref-factor {args.ref_factor}"
                 f"{' --no-shadows' if args.no_shadows else ''}"
                 f"{' --no-mesh-lights' if args.no_mesh_lights else ''}"
                 f"{''.join(' --set ' + x for x in args.set)}`"
                 f" ({total_s / 60:.1f} min on this machine, {os.cpu_count()} cores; Blender {bpy.app.version_string}; "
                 f"engine: {args.build}).")
    lines.append("")
    lines.append(f"{args.width}x{args.height}, Combined RGB, scene-linear. Both engines at N samples; Cycles "
                 "CPU, max_bounces 0, no denoising, no adaptive sampling, Blackman-Harris filter width 1.5. "
                 "relMSE = mean((x-y)^2/(y^2+0.01)); PSNR peak = max of y. "
                 "\"Cycles N vs ref\" is Cycles' own noise at N against Cycles at "
                 f"{args.ref_factor}N (another seed); \"ours vs ref\" is ours against that reference. "
                 "Expected for an unbiased engine with no noise of its own: ours vs ref ~ "
                 f"1/{args.ref_factor + 1} of Cycles N vs ref (the reference's noise); ours vs Cycles N ~ "
                 f"{args.ref_factor}/{args.ref_factor + 1} of it.")
    lines.append("")
    if snapshot_scale is not None and snapshot_scale < 1.0:
        lines.append(f"Images here are scaled by {snapshot_scale:g} (box filter); the run writes them at full size.")
        lines.append("")
    lines.append("| scene | samples | RMSE | relMSE | PSNR dB | mean ours/Cycles | Cycles N vs ref relMSE "
                 "| ours vs ref relMSE | ours vs ref RMSE | Deferred s (compile) | Cycles s | ref s |")
    lines.append("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in results:
        if "error" in r:
            lines.append(f"| {r['scene']} | failed: {r['error']} |")
            continue
        v = r["vs_cycles"]
        cn = r.get("cycles_vs_ref", {})
        ov = r.get("ours_vs_ref", {})
        lines.append(
            f"| {r['scene']} | {r['samples']} | {fmt(v['rmse'])} | {fmt(v['relmse'])} | {v['psnr']:.1f} "
            f"| {v['mean_ratio']:.3f} | {fmt(cn.get('relmse'))} | {fmt(ov.get('relmse'))} "
            f"| {fmt(ov.get('rmse'))} | {r['deferred_s']:.1f} ({r['deferred_compile_s']:.1f}) "
            f"| {r['cycles_s']:.1f} | {fmt(r.get('ref_s'), 3)} |")
    lines.append("")
    for r in results:
        if "error" in r:
            continue
        lines.append(f"## {r['scene']}")
        lines.append("")
        png = os.path.basename(r["png"])
        lines.append(f"![{r['scene']}]({png})")
        lines.append("")
        lines.append("Cycles | Deferred | \\|Deferred − Cycles\\| × 4 (Standard view, sRGB, clipped).")
        if "png_ref" in r:
            lines.append("")
            lines.append(f"![{r['scene']} against the reference]({os.path.basename(r['png_ref'])})")
            lines.append("")
            lines.append(f"Cycles at {r['ref_samples']} samples | \\|Deferred − ref\\| × 4 | "
                         f"\\|Cycles {r['samples']} − ref\\| × 4.")
        lines.append("")
        if r["notes"]:
            lines.append("Scene: " + "; ".join(r["notes"]) + ".")
            lines.append("")
        warns = [m for lvl, m in r["warnings"] if lvl in ('WARNING', 'ERROR')]
        lines.append(f"Engine warnings ({len(warns)}):")
        lines.append("")
        if warns:
            for m in warns:
                lines.append(f"- {m}")
        else:
            lines.append("- none")
        lines.append("")
        if r["objects"]:
            has_ref = "relmse_cycles_ref" in r["objects"][0]
            if "unwarned" in r:
                u = r["unwarned"]
                line = (f"Objects whose material has no warning ({u['objects']} of {u['of']}, interiors): "
                        f"relMSE ours vs Cycles N {fmt(u['vs_cycles']['relmse'])}, mean ratio "
                        f"{u['vs_cycles']['mean_ratio']:.3f}")
                if "ours_vs_ref" in u:
                    line += (f"; ours vs ref {fmt(u['ours_vs_ref']['relmse'])}, Cycles N vs ref "
                             f"{fmt(u['cycles_vs_ref']['relmse'])}")
                lines += [line + ".", ""]
            head = "| object | material | warned | px | Cycles mean | ours/Cycles | relMSE vs Cycles N |"
            sep = "| --- | --- | --- | ---: | ---: | ---: | ---: |"
            if has_ref:
                head += " ours/ref | relMSE ours vs ref | relMSE Cycles N vs ref |"
                sep += " ---: | ---: | ---: |"
            lines += [head, sep]
            for o in sorted(r["objects"], key=lambda o: -o["relmse"]):
                row = (f"| {o['object']} | {o['material']} | {'yes' if o['warned'] else ''} | {o['pixels']} "
                       f"| {fmt(o['cycles_mean'])} "
                       f"| {o['ratio']:.3f} | {fmt(o['relmse'])} |")
                if has_ref:
                    row += (f" {o['ratio_ref']:.3f} | {fmt(o['relmse_ours_ref'])} "
                            f"| {fmt(o['relmse_cycles_ref'])} |")
                lines.append(row)
            lines.append("")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    args = parse_args()
    os.makedirs(args.out, exist_ok=True)
    args.build = build_info()  # at start: what this process loaded
    assets = os.path.join(args.out, "assets")
    os.makedirs(assets, exist_ok=True)
    t0 = time.perf_counter()
    results = []
    for name in args.scenes:
        try:
            results.append(run_scene(name, args, assets))
        except Exception as ex:
            import traceback
            traceback.print_exc()
            results.append({"scene": name, "error": f"{type(ex).__name__}: {ex}"})
    total = time.perf_counter() - t0
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump({"args": vars(args), "total_s": total, "results": results}, f, indent=1, default=str)
    md = os.path.join(args.out, "real_content.md")
    write_markdown(results, args, total, md)
    print(f"wrote {md} ({total:.0f} s)")
    if args.snapshot:
        snap = os.path.abspath(args.snapshot)
        os.makedirs(snap, exist_ok=True)
        write_markdown(results, args, total, os.path.join(snap, "real_content.md"), args.snapshot_scale)
        for r in results:
            for key in ("png", "png_ref"):
                if key in r:
                    snapshot_png(r[key], os.path.join(snap, os.path.basename(r[key])), args.snapshot_scale)
        shutil.copy(os.path.join(args.out, "results.json"), os.path.join(snap, "results.json"))
        print(f"snapshot in {snap} (README's table: python3 tools/real_content_table.py)")


if __name__ == "__main__":
    main()
