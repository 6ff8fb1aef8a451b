"""Isolation renders behind real_content.md's list of causes: each
experiment renders a row of spheres (or a small scene), one variant per
object, with Cycles and with this engine under the same sun + area light as
the materials-library scene, and prints per-object mean ratio and relMSE
(and Cycles' own noise at N against K*N samples).

    BLENDER_USER_SCRIPTS=$PWD/build/blender_scripts blender -b --factory-startup \\
        --addons deferred_render --python bench/materials/real_content_isolate.py -- \\
        [--out out/real_content/isolate] [--samples 64] [--ref-factor 4] [EXPERIMENT ...]

With no experiment named, all run (list: --list). Writes OUT/EXPERIMENT.png
(rows: Cycles, Deferred, signed difference x4 against the reference:
red = ours brighter, blue = ours darker) and OUT/isolate.md (one table per experiment).

Variants edit a material's node tree by path: "Group.003/Anisotropic BSDF"
is the node "Anisotropic BSDF" inside the tree of the group node
"Group.003" (groups on a path are copied first, so the edit touches this
variant only).
"""

import argparse
import importlib.util
import math
import os
import sys

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location("real_content", os.path.join(HERE, "real_content.py"))
rc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(rc)

_library_loaded = {}
_ARGS = None


# ---------------------------------------------------------------------------
# materials and edits
# ---------------------------------------------------------------------------

def library(name):
    """A fresh copy of a materials-library material (node groups copied
    when an edit goes into them)."""
    if name not in _library_loaded:
        with bpy.data.libraries.load(rc.LIBRARY) as (src, dst):
            dst.materials = [name]
        _library_loaded[name] = dst.materials[0]
    return _library_loaded[name].copy()


def resolve(mat, path):
    """(tree, node) for 'Group/Inner/Node'; groups on the way are copied."""
    tree = mat.node_tree
    parts = path.split("/")
    for part in parts[:-1]:
        group = tree.nodes[part]
        group.node_tree = group.node_tree.copy()
        tree = group.node_tree
    return tree, tree.nodes[parts[-1]]


def socket(sockets, key):
    for s in sockets:
        if s.identifier == key:
            return s
    return sockets[key]


def unlink(mat, path, inp):
    tree, node = resolve(mat, path)
    for link in list(socket(node.inputs, inp).links):
        tree.links.remove(link)
    return mat


def set_input(mat, path, inp, value):
    tree, node = resolve(mat, path)
    s = socket(node.inputs, inp)
    for link in list(s.links):
        tree.links.remove(link)
    s.default_value = value
    return mat


def set_prop(mat, path, prop, value):
    _, node = resolve(mat, path)
    setattr(node, prop, value)
    return mat


def link_new(mat, path_to, inp, node_type, out, **props):
    """Link a new node's output (e.g. Geometry 'Normal') into path_to.inp."""
    tree, node = resolve(mat, path_to)
    n = tree.nodes.new(node_type)
    for k, v in props.items():
        setattr(n, k, v)
    tree.links.new(socket(n.outputs, out), socket(node.inputs, inp))
    return mat


def bsdf_material(name, kind, **inputs):
    """Material Output <- one BSDF node of kind with the given inputs."""
    mat, nodes, links = rc.new_material(name)
    nodes.remove(rc.principled(mat))
    n = nodes.new(kind)
    for k, v in inputs.items():
        if k.startswith("prop_"):
            setattr(n, k[5:], v)
        else:
            n.inputs[k].default_value = v
    links.new(n.outputs[0], nodes["Material Output"].inputs["Surface"])
    return mat


def principled_material(name, **inputs):
    mat, nodes, links = rc.new_material(name)
    b = rc.principled(mat)
    for k, v in inputs.items():
        b.inputs[k].default_value = v
    return mat


def mix_material(name, fac_node, fac_out, a, b, fac_props=None):
    """Mix Shader(fac_node.fac_out, BSDF a, BSDF b); a, b: (kind, inputs)."""
    mat, nodes, links = rc.new_material(name)
    nodes.remove(rc.principled(mat))
    f = nodes.new(fac_node)
    for k, v in (fac_props or {}).items():
        f.inputs[k].default_value = v
    mix = nodes.new("ShaderNodeMixShader")
    links.new(f.outputs[fac_out], mix.inputs["Fac"])
    for slot, (kind, inputs) in ((1, a), (2, b)):
        n = nodes.new(kind)
        for k, v in inputs.items():
            n.inputs[k].default_value = v
        links.new(n.outputs[0], mix.inputs[slot])
    links.new(mix.outputs[0], nodes["Material Output"].inputs["Surface"])
    return mat


# ---------------------------------------------------------------------------
# experiments: name -> (doc, function returning [(label, material)])
# ---------------------------------------------------------------------------

def exp_group_normal():
    """Unlinked group-input vector feeding a Normal socket (library 'Fresnel':
    GL_Fresnel's Layer Weight Normal <- Group Input with default (0,0,0))."""
    a = library("Fresnel")
    b = link_new(library("Fresnel"), "Group/Layer Weight", "Normal", "ShaderNodeNewGeometry", "Normal")
    return [("Fresnel as is", a), ("Layer Weight Normal <- Geometry Normal", b),
            ("group: Noise Vector <- unlinked group input", _group_texture_vector())]


def _group_texture_vector():
    """Emission(Noise Texture) where the Noise's Vector comes from a group
    input left unlinked on the group node (default (0, 0, 0))."""
    group = bpy.data.node_groups.new("NoiseOfInput", "ShaderNodeTree")
    gin = group.nodes.new("NodeGroupInput")
    gout = group.nodes.new("NodeGroupOutput")
    group.inputs.new("NodeSocketVector", "Vector")
    group.outputs.new("NodeSocketColor", "Color")
    noise = group.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 3.0
    group.links.new(gin.outputs["Vector"], noise.inputs["Vector"])
    group.links.new(noise.outputs["Color"], gout.inputs["Color"])
    mat, nodes, links = rc.new_material("group texture vector")
    nodes.remove(rc.principled(mat))
    g = nodes.new("ShaderNodeGroup")
    g.node_tree = group
    em = nodes.new("ShaderNodeEmission")
    links.new(g.outputs["Color"], em.inputs["Color"])
    links.new(em.outputs[0], nodes["Material Output"].inputs["Surface"])
    return mat


def exp_velvet():
    """'Crushed Velvet Eevee' (black in Cycles)."""
    return [("as is", library("Crushed Velvet Eevee")),
            ("Displacement unlinked", unlink(library("Crushed Velvet Eevee"), "Material Output", "Displacement")),
            ("IOR 1.45", set_input(library("Crushed Velvet Eevee"), "Principled BSDF", "IOR", 1.45)),
            ("Transmission 0", set_input(library("Crushed Velvet Eevee"), "Principled BSDF", "Transmission", 0.0)),
            ("IOR 1.45 + Transmission 0", set_input(set_input(library("Crushed Velvet Eevee"), "Principled BSDF",
                                                              "IOR", 1.45), "Principled BSDF", "Transmission", 0.0)),
            ("IOR 1.45 + Transmission 0 + no Displacement",
             unlink(set_input(set_input(library("Crushed Velvet Eevee"), "Principled BSDF", "IOR", 1.45),
                              "Principled BSDF", "Transmission", 0.0), "Material Output", "Displacement"))]


def exp_building():
    """'Building': Mix(Mix(Glass Beckmann 0, Glossy Beckmann 0.14 by 0.73), Diffuse) by a Brick texture's Fac
    (the mortar: Diffuse), whose Fac x 0.05 is also its Displacement (a step: bump only where the offsets
    straddle the mortar's edges). Its Squash 0 (every 3rd row) makes a row of zero-width bricks, which Cycles
    renders as one brick (svm_brick's x is NaN there)."""
    b = "Building"

    def windows(glass_fac=None, displacement=True):
        m = set_input(library(b), "Mix Shader", "Fac", 0.0)
        if glass_fac is not None:
            set_input(m, "Mix Shader.001", "Fac", glass_fac)
        return m if displacement else unlink(m, "Material Output", "Displacement")

    return [("as is", library(b)),
            ("Displacement unlinked", unlink(library(b), "Material Output", "Displacement")),
            ("mortar: Diffuse only", set_input(library(b), "Mix Shader", "Fac", 1.0)),
            ("bricks: Glass and Glossy", windows()),
            ("bricks, no Displacement", windows(displacement=False)),
            ("bricks: Glass only", windows(0.0)),
            ("bricks: Glossy only", windows(1.0))]


def exp_diffuse():
    """Diffuse BSDF (rendered as Principled's Burley diffuse at roughness 1)."""
    c = (0.8, 0.8, 0.8, 1)
    return [("Diffuse r0", bsdf_material("d0", "ShaderNodeBsdfDiffuse", Color=c, Roughness=0.0)),
            ("Diffuse r0.5", bsdf_material("d5", "ShaderNodeBsdfDiffuse", Color=c, Roughness=0.5)),
            ("Diffuse r1", bsdf_material("d1", "ShaderNodeBsdfDiffuse", Color=c, Roughness=1.0)),
            ("Principled spec0 r1", principled_material("p1", **{"Base Color": c, "Specular": 0.0,
                                                                 "Roughness": 1.0}))]


def exp_glossy():
    """Glossy BSDF (rendered as a Principled metal of its colour; Sharp as roughness 0)."""
    red = (0.8, 0.1, 0.05, 1)
    return [("Glossy red r0.3", bsdf_material("g1", "ShaderNodeBsdfGlossy", Color=red, Roughness=0.3)),
            ("Principled metal red r0.3", principled_material("g2", **{"Base Color": red, "Metallic": 1.0,
                                                                       "Roughness": 0.3})),
            ("Glossy white r0.3", bsdf_material("g3", "ShaderNodeBsdfGlossy", Color=(1, 1, 1, 1), Roughness=0.3)),
            ("Glossy red r0.05", bsdf_material("g4", "ShaderNodeBsdfGlossy", Color=red, Roughness=0.05)),
            ("Glossy red r0", bsdf_material("g5", "ShaderNodeBsdfGlossy", Color=red, Roughness=0.0)),
            ("Glossy Beckmann r0.3", bsdf_material("g6", "ShaderNodeBsdfGlossy", Color=red, Roughness=0.3,
                                                   prop_distribution='BECKMANN')),
            ("Glossy Ashikhmin r0.3", bsdf_material("g7", "ShaderNodeBsdfGlossy", Color=red, Roughness=0.3,
                                                    prop_distribution='ASHIKHMIN_SHIRLEY')),
            ("Glossy Sharp", bsdf_material("g8", "ShaderNodeBsdfGlossy", Color=red, Roughness=0.3,
                                           prop_distribution='SHARP'))]


def exp_beckmann():
    """Glossy BSDF distribution: Beckmann (rendered as GGX) against GGX at the same roughness."""
    c = (0.8, 0.8, 0.8, 1)
    out = []
    for r in (0.1, 0.3, 0.6):
        for dist in ('GGX', 'BECKMANN'):
            out.append((f"{dist} r{r}", bsdf_material(f"b{dist}{r}", "ShaderNodeBsdfGlossy", Color=c, Roughness=r,
                                                      prop_distribution=dist)))
    return out


def exp_anisotropic():
    """Anisotropic BSDF (shaded as the isotropic Glossy)."""
    c = (0.8, 0.8, 0.8, 1)
    return [("Anisotropic 0", bsdf_material("a0", "ShaderNodeBsdfAnisotropic", Color=c, Roughness=0.3, Anisotropy=0.0)),
            ("Anisotropic 0.9", bsdf_material("a9", "ShaderNodeBsdfAnisotropic", Color=c, Roughness=0.3,
                                              Anisotropy=0.9)),
            ("Brushed Metal", library("Brushed Metal"))]


def exp_layer_weight():
    """everyday_nodes' Layer Weight (Fresnel, blend 0.3) mixing Diffuse and Glossy r0.2."""
    dif = ("ShaderNodeBsdfDiffuse", {"Color": (0.7, 0.1, 0.1, 1)})
    glo = ("ShaderNodeBsdfGlossy", {"Roughness": 0.2})
    return [("LW mix as in the scene", mix_material("lw", "ShaderNodeLayerWeight", "Fresnel", dif, glo,
                                                     {"Blend": 0.3})),
            ("Diffuse alone", bsdf_material("lwd", "ShaderNodeBsdfDiffuse", Color=(0.7, 0.1, 0.1, 1))),
            ("Glossy alone", bsdf_material("lwg", "ShaderNodeBsdfGlossy", Roughness=0.2)),
            ("Emission of LW Fresnel", _emission_of("ShaderNodeLayerWeight", "Fresnel", {"Blend": 0.3}))]


def _emission_of(kind, out, inputs):
    mat, nodes, links = rc.new_material("em_" + kind)
    nodes.remove(rc.principled(mat))
    n = nodes.new(kind)
    for k, v in inputs.items():
        n.inputs[k].default_value = v
    em = nodes.new("ShaderNodeEmission")
    links.new(n.outputs[out], em.inputs["Color"])
    links.new(em.outputs[0], nodes["Material Output"].inputs["Surface"])
    return mat


def exp_bump():
    """Voronoi / Noise -> Bump -> Principled Normal (everyday_nodes)."""
    out = []
    for label, strength, tex in (("Voronoi bump 0.6", 0.6, "ShaderNodeTexVoronoi"),
                                 ("Voronoi bump 0", 0.0, "ShaderNodeTexVoronoi"),
                                 ("Noise bump 0.6", 0.6, "ShaderNodeTexNoise"),
                                 ("Voronoi bump 0.1", 0.1, "ShaderNodeTexVoronoi")):
        mat, nodes, links = rc.new_material(label)
        t = nodes.new(tex)
        t.inputs["Scale"].default_value = 6.0
        bump = nodes.new("ShaderNodeBump")
        bump.inputs["Strength"].default_value = strength
        bump.inputs["Distance"].default_value = 0.1
        links.new(t.outputs[0] if tex.endswith("Voronoi") else t.outputs["Fac"], bump.inputs["Height"])
        links.new(bump.outputs["Normal"], rc.principled(mat).inputs["Normal"])
        rc.principled(mat).inputs["Base Color"].default_value = (0.7, 0.5, 0.3, 1)
        rc.principled(mat).inputs["Roughness"].default_value = 0.4
        out.append((label, mat))
    plain = principled_material("plain", **{"Base Color": (0.7, 0.5, 0.3, 1), "Roughness": 0.4})
    out.append(("no bump", plain))
    return out


def exp_bump_lobes():
    """Voronoi -> Bump (strength 0.6) under the diffuse lobe alone (Principled
    specular 0) and under a metal lobe alone: Cycles' microfacet eval returns 0
    for a light below the smooth normal's horizon (sd->N), its diffuse eval
    only clamps against the bumped normal. Run with --no-shadows."""
    out = []
    for label, extra in (("diffuse only (spec 0)", {"Specular": 0.0}),
                         ("metal r0.4", {"Metallic": 1.0}),
                         ("Principled (both)", {})):
        mat, nodes, links = rc.new_material(label)
        t = nodes.new("ShaderNodeTexVoronoi")
        t.inputs["Scale"].default_value = 6.0
        bump = nodes.new("ShaderNodeBump")
        bump.inputs["Strength"].default_value = 0.6
        bump.inputs["Distance"].default_value = 0.1
        links.new(t.outputs["Distance"], bump.inputs["Height"])
        b = rc.principled(mat)
        links.new(bump.outputs["Normal"], b.inputs["Normal"])
        b.inputs["Base Color"].default_value = (0.7, 0.5, 0.3, 1)
        b.inputs["Roughness"].default_value = 0.4
        for k, v in extra.items():
            b.inputs[k].default_value = v
        out.append((label, mat))
    return out


def _bump_emission(label, height, distance=1.0, strength=1.0, space_object=None):
    """Emission of the Bump node's Normal * 0.5 + 0.5 (no light involved):
    height is 'object_x' (Separate XYZ of Object coordinates: a linear
    field), 'noise' or 'voronoi', or None (Geometry Normal for comparison)."""
    mat, nodes, links = rc.new_material(label)
    nodes.remove(rc.principled(mat))
    em = nodes.new("ShaderNodeEmission")
    links.new(em.outputs[0], nodes["Material Output"].inputs["Surface"])
    vm = nodes.new("ShaderNodeVectorMath")
    vm.operation = 'MULTIPLY_ADD'
    vm.inputs[1].default_value = (0.5, 0.5, 0.5)
    vm.inputs[2].default_value = (0.5, 0.5, 0.5)
    links.new(vm.outputs["Vector"], em.inputs["Color"])
    if height is None:
        geo = nodes.new("ShaderNodeNewGeometry")
        links.new(geo.outputs["Normal"], vm.inputs[0])
        return mat
    bump = nodes.new("ShaderNodeBump")
    bump.inputs["Strength"].default_value = strength
    bump.inputs["Distance"].default_value = distance
    if height == "object_x":
        tc = nodes.new("ShaderNodeTexCoord")
        sep = nodes.new("ShaderNodeSeparateXYZ")
        links.new(tc.outputs["Object"], sep.inputs[0])
        links.new(sep.outputs["X"], bump.inputs["Height"])
    elif height == "noise":
        t = nodes.new("ShaderNodeTexNoise")
        t.inputs["Scale"].default_value = 3.0
        links.new(t.outputs["Fac"], bump.inputs["Height"])
    elif height == "voronoi":
        t = nodes.new("ShaderNodeTexVoronoi")
        t.inputs["Scale"].default_value = 6.0
        links.new(t.outputs["Distance"], bump.inputs["Height"])
    links.new(bump.outputs["Normal"], vm.inputs[0])
    return mat


def exp_bump_normal():
    """Bump node's output normal shown as emission (N * 0.5 + 0.5), no light."""
    return [("Geometry Normal", _bump_emission("geo", None)),
            ("Bump of Object X, d1 s1", _bump_emission("bx", "object_x")),
            ("Bump of Object X, d0.1 s1", _bump_emission("bx01", "object_x", 0.1)),
            ("Bump of Object X, d1 s0.5", _bump_emission("bxs", "object_x", 1.0, 0.5)),
            ("Bump of Noise, d0.1", _bump_emission("bn", "noise", 0.1)),
            ("Bump of Voronoi, d0.1", _bump_emission("bv", "voronoi", 0.1))]


def exp_normal_horizon():
    """A closure normal far from the smooth normal: Principled Normal <- the
    constant world vector (0, 0, 1) (Combine XYZ). Cycles 3.4 (a) bends every
    closure's normal input with ensure_valid_reflection(Ng, I, N)
    (svm/closure.h) and (b) gives a microfacet lobe nothing from a light below
    the smooth normal's horizon (bsdf_microfacet_ggx_eval gets sd->N as "Ng"),
    while the diffuse lobe only clamps against its own normal. Diffuse only
    (specular 0) shows (a) alone. Run with --no-shadows so that
    self-shadowing does not hide the back half."""
    def up(name, **inputs):
        m = principled_material(name, **inputs)
        cxyz = m.node_tree.nodes.new("ShaderNodeCombineXYZ")
        cxyz.inputs["Z"].default_value = 1.0
        m.node_tree.links.new(cxyz.outputs[0], rc.principled(m).inputs["Normal"])
        return m
    grey = (0.8, 0.8, 0.8, 1)
    return [("N=(0,0,1) Principled", up("up", **{"Base Color": grey, "Roughness": 0.5})),
            ("N=(0,0,1) diffuse only (spec 0)", up("upd", **{"Base Color": grey, "Roughness": 0.5,
                                                              "Specular": 0.0})),
            ("N=(0,0,1) metal r0.5", up("upm", **{"Base Color": grey, "Roughness": 0.5, "Metallic": 1.0})),
            ("smooth normal", principled_material("plain", **{"Base Color": grey, "Roughness": 0.5}))]


def exp_color_attribute():
    """Colour attribute on a UV sphere: byte/float, corner/point."""
    out = []
    for dtype in ('BYTE_COLOR', 'FLOAT_COLOR'):
        for domain in ('CORNER', 'POINT'):
            mat, nodes, links = rc.new_material(f"col {dtype} {domain}")
            va = nodes.new("ShaderNodeVertexColor")
            va.layer_name = "Col"
            links.new(va.outputs["Color"], rc.principled(mat).inputs["Base Color"])
            mat["color_attribute"] = (dtype, domain)
            out.append((f"{dtype} {domain}", mat))
    return out


def exp_library_glossy():
    """Library materials made of Glossy BSDFs (Beckmann) and mixes: as is."""
    names = ["Anodized", "Flaky Tangelo", "Galvanized Steel", "Jewelry", "Metalic Paint",
             "Metallic Paint Clean", "Polished Walnut", "Ceramic Polished"]
    return [(n, library(n)) for n in names]


def _suzanne_material(label, image=True, roughness=True, normal_map=True, assets=None):
    """textured_model's Suzanne material with parts replaced by constants."""
    mat, nodes, links = rc.new_material(label)
    bsdf = rc.principled(mat)
    if image:
        tex = rc.image_node(nodes, links, _asset("model_base_color", rc.colour_checker, 'sRGB'), uv_scale=(2, 2, 1))
        links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    else:
        bsdf.inputs["Base Color"].default_value = (0.3, 0.3, 0.3, 1)
    if roughness:
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
    else:
        bsdf.inputs["Roughness"].default_value = 0.4
    if normal_map:
        ntex = rc.image_node(nodes, links, _asset("model_normal", rc.bump_normal_map, 'Non-Color'), uv_scale=(2, 2, 1))
        nmap = nodes.new("ShaderNodeNormalMap")
        links.new(ntex.outputs["Color"], nmap.inputs["Color"])
        links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])
    mat["mesh"] = "suzanne"
    return mat


_assets = {}


def _asset(name, make, colorspace):
    if name not in _assets:
        folder = os.path.join(_ARGS.out, "assets")
        os.makedirs(folder, exist_ok=True)
        _assets[name] = rc.save_png(name, make(), folder, colorspace)
    return _assets[name]


def exp_suzanne():
    """textured_model's Suzanne (subdivided, smart UV): its material with parts replaced by constants."""
    return [("full", _suzanne_material("full")),
            ("no normal map", _suzanne_material("nonormal", normal_map=False)),
            ("roughness 0.4", _suzanne_material("norough", roughness=False)),
            ("grey base", _suzanne_material("nocolor", image=False)),
            ("grey, r0.4, normal map only", _suzanne_material("nmonly", image=False, roughness=False)),
            ("grey, r0.4, no normal map", _suzanne_material("plain", image=False, roughness=False,
                                                              normal_map=False))]


EXPERIMENTS = {
    "suzanne": exp_suzanne,
    "group_normal": exp_group_normal,
    "velvet": exp_velvet,
    "building": exp_building,
    "diffuse": exp_diffuse,
    "glossy": exp_glossy,
    "beckmann": exp_beckmann,
    "anisotropic": exp_anisotropic,
    "layer_weight": exp_layer_weight,
    "bump": exp_bump,
    "bump_normal": exp_bump_normal,
    "bump_lobes": exp_bump_lobes,
    "color_attribute": exp_color_attribute,
    "normal_horizon": exp_normal_horizon,
    "library_glossy": exp_library_glossy,
}


# ---------------------------------------------------------------------------
# scene, render, table
# ---------------------------------------------------------------------------

def fill_color_attribute(ob, dtype, domain):
    me = ob.data
    attr = me.color_attributes.new("Col", dtype, domain)
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    if domain == 'CORNER':
        vi = np.empty(len(me.loops), np.int32)
        me.loops.foreach_get("vertex_index", vi)
        co = co[vi]
    p = co / 0.9
    col = np.stack([0.5 + 0.5 * p[:, 0], 0.5 + 0.5 * p[:, 1], 0.5 + 0.5 * p[:, 2], np.ones(len(p))], -1)
    attr.data.foreach_set("color", col.astype(np.float32).ravel())


def build_row(scene, variants, px):
    n = len(variants)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=0.9)
    base = bpy.context.object
    rc.shade_smooth(base)
    mesh = base.data
    bpy.data.objects.remove(base)
    for i, (label, mat) in enumerate(variants):
        location = ((i - (n - 1) / 2) * 2.0, 0, 0)
        if mat.get("mesh") == "suzanne":
            ob = rc.primitive(bpy.ops.mesh.primitive_monkey_add, size=1.6, location=location, calc_uvs=True)
            ob.name = f"V{i:02d} {label}"
            ob.rotation_euler = (0, 0, math.radians(20))
            rc.smart_uv(ob)
            mod = ob.modifiers.new("Subdivision", 'SUBSURF')
            mod.levels = mod.render_levels = 1
            rc.shade_smooth(ob)
            ob.data.materials.append(mat)
            continue
        me = mesh.copy()
        ob = rc.link_object(scene, f"V{i:02d} {label}", me, location, mat)
        ob.rotation_euler = (0, 0, math.radians(-30))
        if "color_attribute" in mat.keys():
            fill_color_attribute(ob, *mat["color_attribute"])
    if _ARGS is not None and _ARGS.perspective:
        rc.add_camera(scene, (0, -10, 0), (0, 0, 0), lens=180.0 / n)   # 2n m wide at the spheres
    else:
        rc.add_camera(scene, (0, -30, 0), (0, 0, 0), ortho_scale=2.0 * n)
    rc.add_light(scene, 'SUN', "Sun", (-4, -6, 6), (0, 0, 0), energy=3.0)
    rc.add_light(scene, 'AREA', "Area", (8, -8, 4), (0, 0, 0), energy=1500.0, size=4.0)
    rc.set_world(scene, 0.0)
    return px * n, px


def signed_png(path, panels_lin, diff):
    """Cycles / ours / signed diff x4 (red: ours brighter, blue: darker), stacked."""
    d = diff.mean(-1) * 4.0
    signed = np.stack([np.clip(d, 0, 1), np.zeros_like(d), np.clip(-d, 0, 1)], -1)
    import OpenImageIO as oiio
    rows = [rc.srgb8(p) for p in panels_lin] + [(signed * 255 + 0.5).astype(np.uint8)]
    gap = np.full((4, rows[0].shape[1], 3), 255, np.uint8)
    img = np.concatenate([rows[0], gap, rows[1], gap, rows[2]], 0)
    img = np.ascontiguousarray(img)
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.UINT8))
    out.write_image(img)
    out.close()


def run(name, args):
    scene = rc.clear_data()
    variants = EXPERIMENTS[name]()
    w, h = build_row(scene, variants, args.px)
    scene = bpy.context.scene
    ns = argparse.Namespace(width=w, height=h)
    rc.common_settings(scene, ns)
    if args.no_shadows:
        rc.disable_shadows()
    base = os.path.join(args.out, name + ("_noshadow" if args.no_shadows else "") +
                        ("_persp" if args.perspective else ""))
    d_path, d_s, messages, _ = rc.render_deferred(scene, args.samples, base + "_deferred")
    c_path, _ = rc.render_cycles(scene, args.samples, 1, base + "_cycles", False)
    ref = None
    if args.ref_factor > 0:
        r_path, _ = rc.render_cycles(scene, args.samples * args.ref_factor, 2, base + "_cycles_ref", False)
        ref = rc.combined(rc.read_exr(r_path))
    cyc = rc.combined(rc.read_exr(c_path))
    ours_ch = rc.read_exr(d_path)
    ours = rc.combined(ours_ch)
    rows = rc.per_object(scene, rc.object_index(ours_ch), ours, cyc, ref)
    signed_png(base + ".png", [cyc, ours], ours - (ref if ref is not None else cyc))
    title = name + (" (no shadows)" if args.no_shadows else "") + (" (perspective)" if args.perspective else "")
    png = os.path.basename(base) + ".png"
    lines = [f"## {title}", "", EXPERIMENTS[name].__doc__.strip(), "", f"![{title}]({png})", ""]
    warns = [m for lvl, m in messages if lvl in ('WARNING', 'ERROR')]
    for m in warns:
        lines.append(f"- {m}")
    if warns:
        lines.append("")
    head = "| variant | Cycles mean | ours mean | ours/Cycles | relMSE vs Cycles N |"
    sep = "| --- | ---: | ---: | ---: | ---: |"
    if ref is not None:
        head += " ours/ref | relMSE ours vs ref | relMSE Cycles N vs ref |"
        sep += " ---: | ---: | ---: |"
    lines += [head, sep]
    for o in rows:
        line = (f"| {o['object'][4:]} | {rc.fmt(o['cycles_mean'])} | {rc.fmt(o['ours_mean'])} "
                f"| {o['ratio']:.3f} | {rc.fmt(o['relmse'])} |")
        if ref is not None:
            line += f" {o['ratio_ref']:.3f} | {rc.fmt(o['relmse_ours_ref'])} | {rc.fmt(o['relmse_cycles_ref'])} |"
        lines.append(line)
    lines.append("")
    print("\n".join(lines))
    return lines


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="real_content_isolate.py")
    p.add_argument("experiments", nargs="*")
    p.add_argument("--out", default=os.path.join(rc.REPO, "out", "real_content", "isolate"))
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--ref-factor", type=int, default=4)
    p.add_argument("--px", type=int, default=160, help="pixels per sphere")
    p.add_argument("--list", action="store_true")
    p.add_argument("--snapshot", default=None, help="also copy the Markdown and PNGs into this folder")
    p.add_argument("--no-shadows", action="store_true", help="nothing occludes (real_content.disable_shadows)")
    p.add_argument("--perspective", action="store_true", help="perspective camera 10 m away (default orthographic)")
    args = p.parse_args(argv)
    if args.list:
        for k, f in EXPERIMENTS.items():
            print(f"{k}: {f.__doc__.strip()}")
        return
    args.out = os.path.abspath(args.out)
    os.makedirs(args.out, exist_ok=True)
    global _ARGS
    _ARGS = args
    names = args.experiments or list(EXPERIMENTS)
    build = rc.build_info()  # at start: what this process loaded
    flags = (" --no-shadows" if args.no_shadows else "") + (" --perspective" if args.perspective else "")
    lines = ["# Isolation renders (real_content_isolate.py)", "",
             f"`... --python bench/materials/real_content_isolate.py -- --px {args.px}{flags} "
             f"{' '.join(names)}`; engine: {build}.", "",
             f"{args.samples} samples, Cycles reference at {args.ref_factor}x that (another seed); sun + area "
             "light as in materials_library, black world; one object per variant, figures over its pixels "
             "(eroded by one pixel). Images: rows Cycles, Deferred, signed difference x4 against the "
             "reference (red: ours brighter, blue: ours darker).", ""]
    for name in names:
        lines += run(name, args)
    md = "isolate" + ("_noshadow" if args.no_shadows else "") + ("_persp" if args.perspective else "") + ".md"
    with open(os.path.join(args.out, md), "w") as f:
        f.write("\n".join(lines) + "\n")
    if args.snapshot:
        import shutil
        snap = os.path.abspath(args.snapshot)
        os.makedirs(snap, exist_ok=True)
        shutil.copy(os.path.join(args.out, md), snap)
        for line in lines:
            if line.startswith("!["):
                png = line[line.index("(") + 1:-1]
                shutil.copy(os.path.join(args.out, png), snap)


if __name__ == "__main__":
    main()
