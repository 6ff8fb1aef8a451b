"""Light on bumped and bent normals as Cycles 3.4 gives it (max_bounces 0).

Spheres whose closures take another normal than the smooth one, under a sun
and an area light, against Cycles:
  * Voronoi -> Bump (strength 0.6) -> a diffuse-only Principled (Cycles
    darkens diffuse closures towards the smooth normal's terminator:
    bump_shadowing_term, Chiang et al. 2019): 2.1 % too bright without it;
  * the same into a metal (roughness 0.4): light samples below the smooth
    normal give a glossy lobe nothing (shader_bsdf_is_transmission);
  * a constant world-up normal (Combine XYZ (0, 0, 1)) into a diffuse and a
    metal Principled: closure normals are bent by ensure_valid_reflection
    (svm_node_closure_bsdf) before all that (without it: 45 % too dark,
    the metal black; with it 0.15 % and 4.7 %, see LIMITS);
  * the smooth normal (control).
Per sphere (object index, eroded), the mean of ours (64 samples) must be
within MEAN_LIMIT of Cycles' (256 samples).

    blender -b --factory-startup --addons deferred_render -E DEFERRED_RENDER \\
        --python-exit-code 1 --python tests/blender/test_bump_lighting.py
"""

import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

OUT = U.out_dir("bump_lighting")
MEAN_LIMIT = 0.01   # measured worst 0.15 %, except:
# the metal under a bent normal: 4.7 % dark. 1.8 % of it is the share
# Cycles' BSDF samples (MIS) keep below the smooth normal's horizon, where
# this engine's light samples give a glossy lobe nothing and it has no BSDF
# samples of its own. The rest came with the receiver-plane shadow
# comparison (shadow_lib.glsl): the highlight this normal puts on the
# sphere's lower edge, where the light meets the facets at grazing angles,
# is partly shadowed there. Comparing grazing planes (|cos| < 0.25) with the
# old slope bias instead gives 2.0 % here but loses the shadow terminator
# (Suzanne under a sun 0.005 -> 0.056 relMSE, blender_shadow_terminator).
LIMITS = {"world-up normal, metal": 0.06}


def principled(nodes, metallic, normal_from):
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.8, 0.8, 0.8, 1.0)
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Specular"].default_value = 0.0 if metallic == 0.0 else 0.5
    bsdf.inputs["Roughness"].default_value = 0.4
    return bsdf


def voronoi_bump(nodes, links, bsdf):
    voronoi = nodes.new("ShaderNodeTexVoronoi")
    voronoi.inputs["Scale"].default_value = 6.0
    bump = nodes.new("ShaderNodeBump")
    bump.inputs["Strength"].default_value = 0.6
    links.new(voronoi.outputs["Distance"], bump.inputs["Height"])
    links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])


def world_up(nodes, links, bsdf):
    up = nodes.new("ShaderNodeCombineXYZ")
    up.inputs["Z"].default_value = 1.0
    links.new(up.outputs["Vector"], bsdf.inputs["Normal"])


CASES = (("bump, diffuse", 0.0, voronoi_bump), ("bump, metal", 1.0, voronoi_bump),
         ("world-up normal, diffuse", 0.0, world_up), ("world-up normal, metal", 1.0, world_up),
         ("smooth normal", 0.0, None))


def build_scene():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 500, 120
    scene.render.resolution_percentage = 100
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    for k, (name, metallic, normal) in enumerate(CASES):
        bpy.ops.mesh.primitive_uv_sphere_add(location=(-4.0 + 2.0 * k, 0.0, 0.0), radius=0.9, segments=64,
                                             ring_count=32)
        bpy.ops.object.shade_smooth()
        ob = bpy.context.object
        ob.pass_index = k + 1
        mat = bpy.data.materials.new(name)
        mat.use_nodes = True
        bsdf = principled(mat.node_tree.nodes, metallic, normal)
        if normal is not None:
            normal(mat.node_tree.nodes, mat.node_tree.links, bsdf)
        ob.data.materials.append(mat)
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    cam.location = (0.0, -12.0, 0.0)
    cam.rotation_euler = (math.pi / 2, 0.0, 0.0)
    cam.data.type = 'ORTHO'
    cam.data.ortho_scale = 10.2
    scene.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 2.0
    sun.rotation_euler = (math.radians(50), 0.0, math.radians(-30))
    scene.collection.objects.link(sun)
    area = bpy.data.objects.new("Area", bpy.data.lights.new("Area", "AREA"))
    area.data.energy = 400.0
    area.data.size = 3.0
    area.location = (3.0, -4.0, 4.0)
    area.rotation_euler = (math.radians(50), 0.0, math.radians(35))
    scene.collection.objects.link(area)
    layer = scene.view_layers[0]
    U.set_all_passes(layer, False)
    layer.use_pass_object_index = True
    scene.cycles.samples = 256
    scene.cycles.max_bounces = 0
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.deferred_render.samples = 64
    return scene


def render(scene, engine):
    scene.render.engine = engine
    channels = U.read_exr(U.render_exr(os.path.join(OUT, engine.lower()), scene))
    return (U.exr_pass(channels, "ViewLayer", "Combined", "RGB").astype(np.float64),
            channels["ViewLayer.IndexOB.X"].astype(np.int64))


def main():
    checks = U.Checks("bump lighting")
    if not U.require_engine(checks):
        checks.finish()
    scene = build_scene()
    cycles, index = render(scene, "CYCLES")
    ours, _ = render(scene, "DEFERRED_RENDER")
    for k, (name, _, _) in enumerate(CASES):
        mask = (index == k + 1) & U.interior_mask(index, radius=2)
        c, o = cycles[mask].mean(), ours[mask].mean()
        print(f"  {name}: {mask.sum()} px, Cycles {c:.4f}, ours {o:.4f}, ratio {o / c:.4f}")
        limit = LIMITS.get(name, MEAN_LIMIT)
        checks.check(mask.sum() > 1000 and abs(o / c - 1.0) < limit, f"{name}: mean within {limit:.0%}",
                     f"ratio {o / c:.4f}")
    checks.finish()


main()
