"""Shared helpers for the Cycles 3.4.1 probe scripts.

Run any probe with:
  blender -b --factory-startup --python-exit-code 1 --python tools/cycles_probe/<probe>.py
Each probe builds its scene from scratch, renders with Cycles CPU, saves a
single-layer float EXR to a temp dir, loads it back with bpy.data.images.load
and compares the pixels with candidate formulas (numpy).
"""
import bpy
import math
import os
import tempfile
import time

import numpy as np
from mathutils import Vector

TMP = tempfile.mkdtemp(prefix="cycles_probe_")


def reset(res_x=32, res_y=32, samples=1024, seed=0):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    c = sc.cycles
    c.device = "CPU"
    c.samples = samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = 0
    c.diffuse_bounces = 0
    c.glossy_bounces = 0
    c.transmission_bounces = 0
    c.volume_bounces = 0
    c.transparent_max_bounces = 0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.seed = seed
    c.pixel_filter_type = "GAUSSIAN"  # BOX forces width 1 px in Cycles sync
    c.filter_width = 0.01
    c.light_sampling_threshold = 0.0  # no probabilistic light termination
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    w = bpy.data.worlds.new("World")
    w.use_nodes = True
    bg = w.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0, 0, 0, 1)
    bg.inputs["Strength"].default_value = 0.0
    sc.world = w
    vs = sc.view_settings
    vs.view_transform = "Standard"
    vs.look = "None"
    vs.exposure = 0.0
    vs.gamma = 1.0
    r = sc.render
    r.resolution_x = res_x
    r.resolution_y = res_y
    r.resolution_percentage = 100
    r.pixel_aspect_x = 1
    r.pixel_aspect_y = 1
    r.film_transparent = False
    r.use_border = False
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
    r.image_settings.color_mode = "RGBA"
    return sc


def add_plane(size=200.0, mat=None, z=0.0):
    h = size / 2
    me = bpy.data.meshes.new("Plane")
    me.from_pydata([(-h, -h, z), (h, -h, z), (h, h, z), (-h, h, z)], [], [(0, 1, 2, 3)])
    me.update()
    ob = bpy.data.objects.new("Plane", me)
    bpy.context.scene.collection.objects.link(ob)
    if mat is not None:
        me.materials.append(mat)
    return ob


def _mat(name):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    return m, nt, out


def diffuse_mat(color=1.0, roughness=0.0):
    m, nt, out = _mat("Diffuse")
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (color, color, color, 1)
    d.inputs["Roughness"].default_value = roughness
    nt.links.new(d.outputs[0], out.inputs["Surface"])
    return m


def emission_mat(color=(1, 1, 1), strength=1.0, position=False):
    m, nt, out = _mat("Emission")
    e = nt.nodes.new("ShaderNodeEmission")
    e.inputs["Color"].default_value = (*color, 1)
    e.inputs["Strength"].default_value = strength
    if position:
        g = nt.nodes.new("ShaderNodeNewGeometry")
        nt.links.new(g.outputs["Position"], e.inputs["Color"])
    nt.links.new(e.outputs[0], out.inputs["Surface"])
    return m


def principled_mat(base=1.0, metallic=0.0, specular=0.5, roughness=0.5,
                   distribution="GGX", **extra):
    m, nt, out = _mat("Principled")
    p = nt.nodes.new("ShaderNodeBsdfPrincipled")
    p.distribution = distribution
    p.inputs["Base Color"].default_value = (base, base, base, 1)
    p.inputs["Metallic"].default_value = metallic
    p.inputs["Specular"].default_value = specular
    p.inputs["Roughness"].default_value = roughness
    for k, v in extra.items():
        p.inputs[k].default_value = v
    nt.links.new(p.outputs[0], out.inputs["Surface"])
    return m


def add_light(kind, energy, loc=(0, 0, 1), rot=(0, 0, 0), **props):
    ld = bpy.data.lights.new(kind, kind)
    ld.energy = energy
    ld.color = (1, 1, 1)
    for k, v in props.items():
        setattr(ld, k, v)
    ob = bpy.data.objects.new(kind, ld)
    ob.location = loc
    ob.rotation_euler = rot
    ob.visible_camera = False
    bpy.context.scene.collection.objects.link(ob)
    return ob


def add_ortho_camera(center=(0, 0), scale=4.0, view_dir=(0, 0, 1), dist=20.0):
    """Ortho camera looking at (center, z=0). view_dir = unit vector from the
    surface towards the camera (V)."""
    cd = bpy.data.cameras.new("Cam")
    cd.type = "ORTHO"
    cd.ortho_scale = scale
    cd.clip_start = 0.01
    cd.clip_end = 1000.0
    cd.sensor_fit = "AUTO"
    ob = bpy.data.objects.new("Cam", cd)
    v = Vector(view_dir).normalized()
    ob.location = Vector((center[0], center[1], 0.0)) + v * dist
    if (v - Vector((0, 0, 1))).length < 1e-9:
        ob.rotation_euler = (0, 0, 0)
    else:
        ob.rotation_mode = "QUATERNION"
        ob.rotation_quaternion = v.to_track_quat("Z", "Y")
    bpy.context.scene.collection.objects.link(ob)
    bpy.context.scene.camera = ob
    return ob


def pixel_world_xy(cam_ob):
    """World (x, y) where each pixel centre's ray hits z=0, shape (H, W, 2),
    row 0 = bottom row (as Blender stores pixels)."""
    sc = bpy.context.scene
    W, H = sc.render.resolution_x, sc.render.resolution_y
    cd = cam_ob.data
    s = cd.ortho_scale
    if W >= H:
        sx, sy = s, s * H / W
    else:
        sx, sy = s * W / H, s
    bpy.context.view_layer.update()
    M = cam_ob.matrix_world
    right = np.array(M.col[0][:3])
    up = np.array(M.col[1][:3])
    back = np.array(M.col[2][:3])
    o = np.array(M.translation)
    u = ((np.arange(W) + 0.5) / W - 0.5) * sx
    v = ((np.arange(H) + 0.5) / H - 0.5) * sy
    U, Vv = np.meshgrid(u, v)
    P = o[None, None] + U[..., None] * right + Vv[..., None] * up
    d = -back
    t = -P[..., 2] / d[2]
    X = P + t[..., None] * d
    return X[..., :2]


def render(name):
    sc = bpy.context.scene
    path = os.path.join(TMP, name + ".exr")
    sc.render.filepath = path
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    dt = time.time() - t0
    img = bpy.data.images.load(path)
    W, H = img.size
    buf = np.empty(W * H * 4, dtype=np.float32)
    img.pixels.foreach_get(buf)
    bpy.data.images.remove(img)
    print("[probe] rendered %s %dx%d %d spp in %.1fs" % (name, W, H, sc.cycles.samples, dt))
    return buf.reshape(H, W, 4)[..., :3].astype(np.float64), dt


def stats(ratio):
    ratio = np.asarray(ratio, dtype=np.float64).ravel()
    n = ratio.size
    m = ratio.mean()
    sd = ratio.std(ddof=1) if n > 1 else 0.0
    return m, sd, sd / math.sqrt(n) if n > 1 else 0.0


def fmt(x):
    return "%.6g" % x
