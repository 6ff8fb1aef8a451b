"""Depsgraph export -> arrays, checked without a GPU.

The exporter streams into a recorder with the native Renderer's scene API,
so every export path is checked against the sample scenes (needs no
deferred_native). Also times a 1M-triangle mesh.

    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_export.py
"""

import math
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

from deferred_render import export  # noqa: E402
from deferred_render.export import camera as camera_export  # noqa: E402
from deferred_render.export import material as material_export  # noqa: E402
from deferred_render.export import mesh as mesh_export  # noqa: E402
from deferred_render.export import world as world_export  # noqa: E402


class Recorder:
    """Same scene API as deferred_native.Renderer; keeps what it is given."""

    def __init__(self):
        self.clear_scene()

    def clear_scene(self):
        self.meshes, self.materials, self.instances, self.lights = [], [], [], []
        self.world = None

    def add_mesh(self, positions, indices, corner_normals=None, corner_uvs=None, material_indices=None):
        self.meshes.append(dict(positions=positions, indices=indices, corner_normals=corner_normals,
                                corner_uvs=corner_uvs, material_indices=material_indices))
        return len(self.meshes) - 1

    def add_material(self, **params):
        self.materials.append(params)
        return len(self.materials) - 1

    def add_instances(self, mesh_id, matrices, object_indices=None, material_slots=None, cast_shadow=True,
                      terminator_offsets=None):
        self.instances.append(dict(mesh_id=mesh_id, matrices=matrices, object_indices=object_indices,
                                   material_slots=list(material_slots or []), cast_shadow=cast_shadow,
                                   terminator_offsets=terminator_offsets))

    def add_light(self, **params):
        self.lights.append(params)

    def set_world(self, color):
        self.world = tuple(color)


def export_current():
    rec = Recorder()
    warnings = []
    depsgraph = bpy.context.evaluated_depsgraph_get()
    stats, cancelled = export.export_scene(depsgraph, rec, warn=warnings.append)
    return rec, stats, warnings, cancelled


def open_sample(name):
    bpy.ops.wm.open_mainfile(filepath=os.path.join(U.SAMPLES, name + ".blend"))


def instance_of(rec, object_index):
    """(mesh dict, matrix, material slot ids) of the instance with that pass index."""
    for group in rec.instances:
        hits = np.nonzero(group["object_indices"] == object_index)[0]
        if len(hits):
            return rec.meshes[group["mesh_id"]], group["matrices"][hits[0]], group["material_slots"]
    return None, None, None


def check_arrays(checks, rec):
    ok = True
    for m in rec.meshes:
        t = len(m["indices"])
        ok &= m["positions"].dtype == np.float32 and m["positions"].ndim == 2 and m["positions"].shape[1] == 3
        ok &= m["indices"].dtype == np.uint32 and m["indices"].shape == (t, 3)
        ok &= m["corner_normals"].dtype == np.float32 and m["corner_normals"].shape == (t * 3, 3)
        ok &= m["material_indices"].dtype == np.int32 and m["material_indices"].shape == (t,)
        ok &= m["corner_uvs"] is None or (m["corner_uvs"].dtype == np.float32 and m["corner_uvs"].shape == (t * 3, 2))
        ok &= bool(m["indices"].max() < len(m["positions"]))
        ok &= m["positions"].flags.c_contiguous and m["indices"].flags.c_contiguous
        ok &= bool(np.isfinite(m["positions"]).all() and np.isfinite(m["corner_normals"]).all())
        n = np.linalg.norm(m["corner_normals"], axis=1)
        ok &= bool(np.abs(n - 1).max() < 1e-4)
    for g in rec.instances:
        ok &= g["matrices"].dtype == np.float64 and g["matrices"].ndim == 3 and g["matrices"].shape[1:] == (4, 4)
        ok &= g["object_indices"].dtype == np.uint32 and len(g["object_indices"]) == len(g["matrices"])
        ok &= all(0 <= s < len(rec.materials) for s in g["material_slots"])
    checks.check(ok, "all arrays have the native shapes/dtypes, unit normals, contiguous")


def test_analytic(checks):
    open_sample("analytic")
    rec, stats, warnings, cancelled = export_current()
    checks.check(not cancelled, "export completes")
    checks.check(warnings == [], "analytic scene exports without warnings", "; ".join(warnings))
    checks.check(stats.meshes == 6 and stats.instances == 6, "6 meshes, 6 instances", stats.summary())
    checks.check(len(rec.lights) == 2, "2 lights", str([l["type"] for l in rec.lights]))
    check_arrays(checks, rec)
    checks.check(rec.world is not None and np.allclose(rec.world, (0.05, 0.05, 0.05)), "world colour 0.05",
                 str(rec.world))

    floor, m, slots = instance_of(rec, 1)
    checks.check(floor is not None and len(floor["indices"]) == 2, "floor is 2 triangles")
    checks.check(np.allclose(floor["corner_normals"], (0, 0, 1)), "floor normals +Z")
    world_pos = floor["positions"] @ m[:3, :3].T + m[:3, 3]
    checks.check(np.allclose(np.sort(world_pos[:, 0]), [-8, -8, 8, 8]) and np.allclose(world_pos[:, 2], 0),
                 "floor corners at x=+-8, z=0")
    # UVs per corner follow the positions: u = (x + 8) / 16.
    corner_pos = world_pos[floor["indices"].reshape(-1)]
    checks.check(floor["corner_uvs"] is not None
                 and np.allclose(floor["corner_uvs"][:, 0], (corner_pos[:, 0] + 8) / 16, atol=1e-6)
                 and np.allclose(floor["corner_uvs"][:, 1], (corner_pos[:, 1] + 8) / 16, atol=1e-6),
                 "floor UVs follow the corners (per-corner order = indices order)")
    checks.check(rec.materials[slots[0]]["pass_index"] == 11, "floor material pass index 11")

    wall, m, _ = instance_of(rec, 2)
    wn = wall["corner_normals"] @ m[:3, :3].T
    checks.check(np.allclose(wn, (0, -1, 0), atol=1e-6), "wall normals -Y after the object rotation")

    sphere, m, slots = instance_of(rec, 4)
    p = sphere["positions"][sphere["indices"].reshape(-1)]
    radial = p / np.linalg.norm(p, axis=1, keepdims=True)
    dots = np.einsum("ij,ij->i", radial, sphere["corner_normals"])
    checks.check(dots.min() > 0.999, "smooth sphere: corner normals = vertex normals (radial)",
                 f"min dot {dots.min():.5f}")
    checks.check(np.allclose(m[:3, 3], (0.0, 0.5, 1.5)), "SphereB at (0, 0.5, 1.5)")
    checks.check(rec.materials[slots[0]]["pass_index"] == 14, "SphereB material pass index 14")

    box, m, slots = instance_of(rec, 6)
    mi = box["material_indices"]
    tri_n = box["corner_normals"].reshape(-1, 3, 3).mean(axis=1)
    top = tri_n[:, 2] > 0.5
    checks.check(np.all(mi[top] == 1) and np.all(mi[~top] == 0), "box: top triangles use slot 1")
    checks.check(len(slots) == 2 and [rec.materials[s]["pass_index"] for s in slots] == [16, 17],
                 "box: slot -> material ids map to pass indices 16, 17")
    flat_ok = np.allclose(box["corner_normals"].reshape(-1, 3, 3)[:, 0], box["corner_normals"].reshape(-1, 3, 3)[:, 2])
    checks.check(flat_ok, "flat-shaded box: the 3 corners of a triangle share the face normal")

    # Lights.
    kinds = sorted(l["type"] for l in rec.lights)
    checks.check(kinds == ["POINT", "SUN"], "light types", str(kinds))
    point = next(l for l in rec.lights if l["type"] == "POINT")
    checks.check(point["energy"] == 500.0 and abs(point["radius"] - 0.25) < 1e-6
                 and np.allclose(point["matrix"][:3, 3], (2, -4, 4)), "point light power, radius, position")
    checks.check(point["matrix"].dtype == np.float64 and point["matrix"].shape == (4, 4), "light matrix (4,4) f64")

    # Camera (perspective and orthographic).
    scene = bpy.context.scene
    depsgraph = bpy.context.evaluated_depsgraph_get()
    cam_ob = scene.camera.evaluated_get(depsgraph)
    params, cam_warn = camera_export.camera_params(scene, cam_ob)
    checks.check(params["type"] == "PERSP" and params["lens"] == 50.0 and params["sensor_fit"] == "AUTO"
                 and np.allclose(params["matrix"][:3, 3], (0, -14, 5)), "perspective camera params")
    rot = params["matrix"][:3, :3]
    checks.check(np.allclose(rot.T @ rot, np.eye(3), atol=1e-9), "camera matrix is orthonormal (scale removed)")
    ortho = bpy.data.objects["CameraOrtho"].evaluated_get(depsgraph)
    oparams, _ = camera_export.camera_params(scene, ortho)
    checks.check(oparams["type"] == "ORTHO" and oparams["ortho_scale"] == 14.0, "orthographic camera params")
    try:
        camera_export.camera_params(scene, None)
        checks.check(False, "no camera raises CameraError")
    except camera_export.CameraError as ex:
        checks.check("camera" in str(ex), "no camera raises CameraError", str(ex))
    mist = world_export.mist_params(scene.world)
    checks.check(mist == {"mist_start": 5.0, "mist_depth": 25.0, "mist_falloff": "QUADRATIC"}, "mist params", str(mist))

    # Blender's own light setting use_shadow is honoured (hide_render: see test_film_view_layers).
    bpy.data.lights["Point"].use_shadow = False
    rec, stats, _, _ = export_current()
    point = next(l for l in rec.lights if l["type"] == "POINT")
    sun = next(l for l in rec.lights if l["type"] == "SUN")
    checks.check(point["cast_shadow"] is False and sun["cast_shadow"] is True, "light use_shadow -> cast_shadow")
    bpy.data.lights["Point"].use_shadow = True


def test_showcase(checks):
    open_sample("showcase")
    rec, stats, warnings, _ = export_current()
    check_arrays(checks, rec)
    checks.check(warnings == [], "showcase exports without warnings", "; ".join(warnings))
    grid_groups = [g for g in rec.instances if len(g["object_indices"]) and 10 <= g["object_indices"][0] < 35]
    grid_meshes = {g["mesh_id"] for g in grid_groups}
    checks.check(len(grid_meshes) == 1 and sum(len(g["matrices"]) for g in grid_groups) == 25,
                 "25 grid spheres share ONE native mesh", f"{len(grid_meshes)} meshes")
    grid_mats = {rec.materials[g["material_slots"][0]]["roughness"] for g in grid_groups}
    checks.check(len(grid_groups) == 25 and len(grid_mats) == 5, "object-linked materials: 25 groups, 5 roughness values")
    lights = sorted((l["type"], l.get("shape", "")) for l in rec.lights)
    checks.check(lights == sorted([("POINT", ""), ("SPOT", ""), ("SUN", ""), ("AREA", "SQUARE"),
                                   ("AREA", "RECTANGLE"), ("AREA", "DISK"), ("AREA", "ELLIPSE")]),
                 "every light type and area shape", str(lights))
    rect = next(l for l in rec.lights if l.get("shape") == "RECTANGLE")
    checks.check(rect["size"] == 2.0 and rect["size_y"] == 0.5, "rectangle area size 2 x 0.5")
    spot = next(l for l in rec.lights if l["type"] == "SPOT")
    checks.check(abs(spot["spot_size"] - math.radians(35)) < 1e-6 and abs(spot["spot_blend"] - 0.2) < 1e-6,
                 "spot size/blend")

    # Suzanne with a subdivision modifier: the evaluated mesh (not the 500-face original).
    suz, _, _ = instance_of(rec, 2)
    checks.check(suz is not None and len(suz["indices"]) > 10000, "modifiers applied (Suzanne subdivided)",
                 f"{len(suz['indices']) if suz else 0} triangles")
    # The torus uses auto smooth -> split normals path.
    torus, _, slots = instance_of(rec, 6)
    mat = rec.materials[slots[0]]
    checks.check(np.allclose(mat["emission"], (0.6, 1.8, 3.0), atol=1e-5) and mat["emission_strength"] == 1.0
                 and np.allclose(mat["base_color"], (0.1, 0.1, 0.1), atol=1e-6),
                 "Add(Principled, Emission) -> BSDF + emission radiance", str(mat["emission"]))
    cyl, _, slots = instance_of(rec, 4)
    mat = rec.materials[slots[0]]
    # A Lambert Diffuse and a grey Glossy mix as one set, their sum
    # (export/material.py _diffuse_glossy): diffuse 0.7 x its colour, the
    # glossy model with weight 0.3 x 0.8 in specular_tint, no chain.
    checks.check(mat["metallic"] == 0.0 and np.allclose(mat["base_color"], (0.14, 0.49, 0.14), atol=1e-6)
                 and mat.get("glossy_model") == 1 and abs(mat["specular_tint"] - 0.24) < 1e-6
                 and abs(mat["roughness"] - 0.25) < 1e-6 and mat.get("mix_with", -1) == -1,
                 "Mix(Diffuse, Glossy, 0.3) -> one set: diffuse 0.7 x colour, glossy weight 0.3 x 0.8",
                 f"{mat}")


def test_instancing(checks):
    open_sample("instancing")
    t0 = time.perf_counter()
    rec, stats, warnings, _ = export_current()
    dt = time.perf_counter() - t0
    check_arrays(checks, rec)
    checks.check(stats.instances >= 10000, ">= 10000 instances exported", stats.summary())
    checks.check(stats.meshes <= 5, "instances share meshes (<= 5 native meshes)", f"{stats.meshes} meshes")
    big = max(rec.instances, key=lambda g: len(g["matrices"]))
    checks.check(len(big["matrices"]) >= 10000 and big["matrices"].shape[1:] == (4, 4),
                 "geometry-nodes instances arrive as one (N,4,4) add_instances call", str(big["matrices"].shape))
    print(f"  instancing export: {stats.summary()} in {dt:.2f} s")


def _material(name, build):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    build(nodes, links, nodes["Principled BSDF"], nodes["Material Output"])
    return mat


def test_materials(checks):
    checks.check(all(len(names) >= 1 for _, _, names in material_export.PRINCIPLED_INPUTS)
                 and ("Specular IOR Level" in dict((p, n) for p, _, n in material_export.PRINCIPLED_INPUTS)["specular"])
                 and ("Coat Weight" in dict((p, n) for p, _, n in material_export.PRINCIPLED_INPUTS)["clearcoat"])
                 and ("Emission Color" in dict((p, n) for p, _, n in material_export.PRINCIPLED_INPUTS)["emission"]),
                 "one mapping table with 3.x and 4.x Principled input names")

    def rgb_linked(nodes, links, bsdf, out):
        rgb = nodes.new("ShaderNodeRGB")
        rgb.outputs[0].default_value = (0.1, 0.2, 0.3, 1.0)
        links.new(rgb.outputs[0], bsdf.inputs["Base Color"])
        bsdf.inputs["Roughness"].default_value = 0.25
        bsdf.inputs["Metallic"].default_value = 0.5
    params, notes = material_export.material_params(_material("RGBLinked", rgb_linked))
    checks.check(np.allclose(params["base_color"], (0.1, 0.2, 0.3)) and params["roughness"] == 0.25
                 and params["metallic"] == 0.5 and notes == [], "Principled with an RGB node folded", str(notes))

    def textured(nodes, links, bsdf, out):
        tex = nodes.new("ShaderNodeTexChecker")
        links.new(tex.outputs[0], bsdf.inputs["Base Color"])
        bsdf.inputs["Transmission"].default_value = 0.5
    mat = _material("Textured", textured)
    params, notes = material_export.material_params(mat)
    text = material_export.warning_text(mat, notes)
    checks.check(len(notes) == 2 and "Base Color" in text and "Transmission" in text,
                 "texture and transmission listed in one warning", text)

    def diffuse(nodes, links, bsdf, out):
        d = nodes.new("ShaderNodeBsdfDiffuse")
        d.inputs["Color"].default_value = (0.5, 0.25, 0.125, 1)
        links.new(d.outputs[0], out.inputs["Surface"])
    params, notes = material_export.material_params(_material("Diffuse", diffuse))
    checks.check(np.allclose(params["base_color"], (0.5, 0.25, 0.125)) and params["specular"] == 0.0
                 and params["metallic"] == 0.0 and notes == [], "Diffuse BSDF", str(params))

    def glossy(nodes, links, bsdf, out):
        g = nodes.new("ShaderNodeBsdfGlossy")
        g.inputs["Roughness"].default_value = 0.1
        links.new(g.outputs[0], out.inputs["Surface"])
    params, notes = material_export.material_params(_material("Glossy", glossy))
    checks.check(params["metallic"] == 1.0 and abs(params["roughness"] - 0.1) < 1e-6, "Glossy BSDF -> metal")

    def emission(nodes, links, bsdf, out):
        e = nodes.new("ShaderNodeEmission")
        e.inputs["Color"].default_value = (1, 0.5, 0, 1)
        e.inputs["Strength"].default_value = 4.0
        links.new(e.outputs[0], out.inputs["Surface"])
    params, notes = material_export.material_params(_material("Emission", emission))
    checks.check(np.allclose(params["emission"], (1, 0.5, 0)) and params["emission_strength"] == 4.0
                 and np.allclose(params["base_color"], 0), "Emission shader")

    for fac, expect in ((0.0, (1, 0, 0)), (1.0, (0, 0, 1))):
        def mix(nodes, links, bsdf, out, fac=fac):
            a = nodes.new("ShaderNodeBsdfDiffuse")
            a.inputs["Color"].default_value = (1, 0, 0, 1)
            b = nodes.new("ShaderNodeBsdfDiffuse")
            b.inputs["Color"].default_value = (0, 0, 1, 1)
            m = nodes.new("ShaderNodeMixShader")
            m.inputs["Fac"].default_value = fac
            links.new(a.outputs[0], m.inputs[1])
            links.new(b.outputs[0], m.inputs[2])
            links.new(m.outputs[0], out.inputs["Surface"])
        params, _ = material_export.material_params(_material(f"Mix{fac}", mix))
        checks.check(np.allclose(params["base_color"], expect), f"Mix factor {fac} picks one side")

    def add_two(nodes, links, bsdf, out, tint=(1.0, 0.5, 0.2, 1.0)):
        a = nodes.new("ShaderNodeBsdfDiffuse")
        b = nodes.new("ShaderNodeBsdfGlossy")
        b.inputs["Color"].default_value = tint  # a tinted glossy: no one set sums the two
        add = nodes.new("ShaderNodeAddShader")
        links.new(a.outputs[0], add.inputs[0])
        links.new(b.outputs[0], add.inputs[1])
        links.new(add.outputs[0], out.inputs["Surface"])
    mat = _material("AddTwo", add_two)
    mat.diffuse_color = (0.3, 0.6, 0.9, 1)
    params, notes = material_export.material_params(mat)
    checks.check(np.allclose(params["base_color"], (0.3, 0.6, 0.9)) and len(notes) == 1,
                 "Add of two BSDFs -> viewport colour fallback, one note", "; ".join(notes))
    params, notes = material_export.material_params(
        _material("AddGrey", lambda *a: add_two(*a, tint=(0.5, 0.5, 0.5, 1.0))))
    checks.check(params.get("glossy_model") == 1 and params["metallic"] == 0.0
                 and np.allclose(params["base_color"], (0.8, 0.8, 0.8)) and abs(params["specular_tint"] - 0.5) < 1e-6
                 and not notes, "Add(Diffuse, grey Glossy) -> one set, their sum", f"{params}; {notes}")

    def unknown(nodes, links, bsdf, out):
        t = nodes.new("ShaderNodeBsdfTranslucent")
        links.new(t.outputs[0], out.inputs["Surface"])
    mat = _material("Translucent", unknown)
    mat.diffuse_color = (0.9, 0.1, 0.1, 1)
    mat.pass_index = 7
    params, notes = material_export.material_params(mat)
    checks.check(np.allclose(params["base_color"], (0.9, 0.1, 0.1)) and params["pass_index"] == 7
                 and "Translucent" in notes[0], "unknown shader -> viewport colour, keeps pass index", notes[0])

    # Multiscatter GGX, shaded as GGX, is named where Cycles' is measurably
    # brighter (tools/cycles_probe/probe_multiscatter.py's table: a metal
    # at roughness 0.5 11 %, a dielectric at 0.2 0.01 %); a linked
    # Roughness takes its worst value (graph path: roughness 1, 131 %).
    def multiscatter(metallic, roughness):
        def build(nodes, links, bsdf, out):
            bsdf.distribution = 'MULTI_GGX'
            bsdf.inputs["Metallic"].default_value = metallic
            bsdf.inputs["Roughness"].default_value = roughness
        return build
    _, notes = material_export.material_params(_material("MultiMetal", multiscatter(1.0, 0.5)))
    checks.check(len(notes) == 1 and "Multiscatter GGX" in notes[0] and "about 11 %" in notes[0],
                 "Multiscatter GGX on a rough metal: named with Cycles' excess", "; ".join(notes))
    _, notes = material_export.material_params(_material("MultiSmooth", multiscatter(0.0, 0.2)))
    checks.check(notes == [], "Multiscatter GGX on a smooth dielectric: within 2 %, not named", "; ".join(notes))

    def multiscatter_textured(nodes, links, bsdf, out):
        bsdf.distribution = 'MULTI_GGX'
        bsdf.inputs["Metallic"].default_value = 1.0
        links.new(nodes.new("ShaderNodeTexNoise").outputs[0], bsdf.inputs["Roughness"])
    from deferred_render.materials import builder
    graph = builder.build_material_graph(_material("MultiTextured", multiscatter_textured))
    named = [n for n in graph.notes if "Multiscatter GGX" in n]
    checks.check(len(named) == 1 and "up to 131 % brighter (Roughness linked" in named[0],
                 "Multiscatter GGX with a linked Roughness (node graph): its worst case named", "; ".join(graph.notes))

    nonode = bpy.data.materials.new("NoNodes")
    nonode.use_nodes = False
    nonode.diffuse_color = (0.2, 0.4, 0.6, 1)
    params, notes = material_export.material_params(nonode)
    checks.check(np.allclose(params["base_color"], (0.2, 0.4, 0.6)) and notes == [], "material without nodes")

    params, notes = material_export.material_params(None)
    checks.check(params["base_color"] == (0.8, 0.8, 0.8) and notes == [], "empty slot -> default surface")

    # One warning per material, however many objects use it.
    bpy.ops.wm.read_factory_settings(use_empty=True)
    mat = _material("Textured2", textured)
    mesh = bpy.data.meshes.new("Quad")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0)], [], [(0, 1, 2)])
    mesh.materials.append(mat)
    for k in range(3):
        bpy.context.scene.collection.objects.link(bpy.data.objects.new(f"Q{k}", mesh))
    rec, stats, warnings, _ = export_current()
    checks.check(len([w for w in warnings if "Textured2" in w]) == 1, "one warning per material", "; ".join(warnings))


def test_world(checks):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    world = bpy.data.worlds.new("W")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.5, 0.25, 1.0, 1)
    bg.inputs["Strength"].default_value = 2.0
    color, warns = world_export.world_color(world)
    checks.check(np.allclose(color, (1.0, 0.5, 2.0)) and not warns, "world = Background colour x strength")
    sky = world.node_tree.nodes.new("ShaderNodeTexSky")
    world.node_tree.links.new(sky.outputs[0], bg.inputs["Color"])
    world.color = (0.1, 0.2, 0.3)
    color, warns = world_export.world_color(world)
    checks.check(np.allclose(color, (0.2, 0.4, 0.6)) and len(warns) == 1, "sky texture -> viewport colour + warning",
                 warns[0] if warns else "")
    color, warns = world_export.world_color(None)
    checks.check(color == (0.0, 0.0, 0.0), "no world -> black")


def test_bad_geometry(checks):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    coll = bpy.context.scene.collection
    good = bpy.data.meshes.new("Good")
    good.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0)], [], [(0, 1, 2)])
    coll.objects.link(bpy.data.objects.new("Good", good))
    coll.objects.link(bpy.data.objects.new("Empty", bpy.data.meshes.new("EmptyMesh")))
    nan = bpy.data.meshes.new("NaNMesh")
    nan.from_pydata([(0, 0, 0), (float("nan"), 0, 0), (1, 1, 0)], [], [(0, 1, 2)])
    coll.objects.link(bpy.data.objects.new("NaN", nan))
    inf_ob = bpy.data.objects.new("InfScale", good)
    inf_ob.scale = (float("inf"), 1, 1)   # Blender stores FLT_MAX
    coll.objects.link(inf_ob)
    nan_ob = bpy.data.objects.new("NaNLocation", good)
    nan_ob.location = (float("nan"), 0, 0)
    coll.objects.link(nan_ob)
    edges = bpy.data.meshes.new("EdgesOnly")
    edges.from_pydata([(0, 0, 0), (1, 0, 0)], [(0, 1)], [])
    coll.objects.link(bpy.data.objects.new("Edges", edges))
    light = bpy.data.lights.new("ZeroArea", 'AREA')
    light.size = 0.0
    coll.objects.link(bpy.data.objects.new("ZeroArea", light))
    hard = bpy.data.lights.new("HardPoint", 'POINT')
    hard.shadow_soft_size = 0.0
    coll.objects.link(bpy.data.objects.new("HardPoint", hard))
    rec, stats, warnings, _ = export_current()
    text = "\n".join(warnings)
    checks.check(stats.meshes == 1 and stats.instances == 1, "only the good mesh is exported", stats.summary())
    checks.check("'Empty'" in text and "no faces" in text, "empty mesh: warning names it")
    checks.check("'NaN'" in text and "NaN" in text, "NaN vertices: object skipped with warning")
    checks.check("'InfScale'" in text and "'NaNLocation'" in text and "transform" in text,
                 "NaN/Inf transforms: objects skipped with warnings")
    checks.check("'Edges'" in text, "edges-only mesh: skipped with warning")
    checks.check("ZeroArea" in text and len(rec.lights) == 1 and rec.lights[0]["radius"] == 0.0,
                 "zero-size area light skipped with warning; radius-0 point light kept")
    print("  warnings:\n    " + text.replace("\n", "\n    "))


def test_normals_and_uvs(checks):
    """Custom split normals (auto smooth) and the active *render* UV map."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    mesh = bpy.data.meshes.new("Custom")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [], [(0, 1, 2, 3)])
    mesh.use_auto_smooth = True
    custom = [(0.6, 0.0, 0.8), (0.0, 0.6, 0.8), (-0.6, 0.0, 0.8), (0.0, -0.6, 0.8)]
    mesh.normals_split_custom_set(custom)
    first = mesh.uv_layers.new(name="First")
    second = mesh.uv_layers.new(name="Second")
    for i, loop_uv in enumerate(first.data):
        loop_uv.uv = (0.0, 0.0)
    for i, loop_uv in enumerate(second.data):
        loop_uv.uv = (0.25 * i, 0.5)
    mesh.uv_layers.active = first
    second.active_render = True
    bpy.context.scene.collection.objects.link(bpy.data.objects.new("Custom", mesh))
    rec, stats, warnings, _ = export_current()
    m = rec.meshes[0]
    loops = np.empty(len(m["indices"]) * 3, np.int64)
    mesh.calc_loop_triangles()
    mesh.loop_triangles.foreach_get("loops", loops)
    expected = np.array(custom)[loops]
    checks.check(np.allclose(m["corner_normals"], expected, atol=1e-3), "custom split normals exported per corner",
                 str(m["corner_normals"][:3].round(3).tolist()))
    checks.check(np.allclose(m["corner_uvs"][:, 0], 0.25 * loops) and np.allclose(m["corner_uvs"][:, 1], 0.5),
                 "UVs come from the active render UV map (not the active one)")


def test_million_triangles(checks):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=708, y_subdivisions=708, size=10)
    ob = bpy.context.active_object
    uv = ob.data.uv_layers
    checks.check(len(uv) >= 1, "grid has a UV map")
    depsgraph = bpy.context.evaluated_depsgraph_get()
    ob_eval = ob.evaluated_get(depsgraph)
    t0 = time.perf_counter()
    arrays = mesh_export.object_mesh_arrays(ob_eval)
    dt = time.perf_counter() - t0
    tris = arrays.triangle_count
    checks.check(tris >= 1_000_000, "benchmark mesh has >= 1M triangles", f"{tris}")
    # Time is a benchmark figure (tests/blender/bench_export.py), not a test: printed only.
    print(f"  1M-triangle mesh -> numpy arrays: {dt:.3f} s, {arrays.nbytes() / 1e6:.0f} MB")
    ob.data.use_auto_smooth = True
    depsgraph = bpy.context.evaluated_depsgraph_get()
    t0 = time.perf_counter()
    arrays = mesh_export.object_mesh_arrays(ob.evaluated_get(depsgraph))
    dt2 = time.perf_counter() - t0
    checks.check(arrays.triangle_count == tris, "same mesh with auto smooth exports every triangle",
                 f"{arrays.triangle_count}")
    print(f"  with auto smooth (split normals via to_mesh): {dt2:.3f} s")
    print(f"  BENCH export 1M triangles: smooth/flat {dt:.3f} s, auto smooth {dt2:.3f} s")


def main():
    checks = U.Checks("test_export")
    for name, func in (("analytic", test_analytic), ("showcase", test_showcase), ("instancing", test_instancing),
                       ("materials", test_materials), ("world", test_world), ("bad geometry", test_bad_geometry),
                       ("normals and uvs", test_normals_and_uvs),
                       ("1M triangles", test_million_triangles)):
        checks.run(name, func, checks)
    checks.finish()


main()
