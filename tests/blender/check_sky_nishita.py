"""The numpy Nishita sky (addon/deferred_render/materials/sky_nishita.py)
against Cycles 3.4's own Sky Texture (sky type NISHITA).

A world made of Sky Texture -> Background, rendered by Cycles on the CPU
(2 samples, filter width 0.01 px so each pixel is its centre's direction,
no denoising) from cameras looking along the horizon, up at the sky, at the
sun disc and below the horizon, for several skies (sun elevations and
rotations, altitudes, densities, sun sizes and intensities, sun disc on and
off, a sun half below the horizon). Each pixel is compared with
``sky_nishita.radiance()`` for its ray direction (blender_test_utils.
camera_rays), relative error = max over channels of |ours - Cycles| /
max(max over channels of Cycles, 1e-6):

  * away from the sun disc's edge (pixels within 2 pixel sizes of its rim,
    where a pixel may fall either side of the rim in float32, are left out):
    mean < MEAN_LIMIT, worst < MAX_LIMIT;
  * the disc's edge pixels are counted and reported separately.

    blender -b --factory-startup --python-exit-code 1 \
        --python tests/blender/check_sky_nishita.py
"""

import importlib.util
import math
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import blender_test_utils as U  # noqa: E402

REPO = os.path.dirname(os.path.dirname(HERE))
_spec = importlib.util.spec_from_file_location(
    "sky_nishita", os.path.join(REPO, "addon", "deferred_render", "materials", "sky_nishita.py"))
sky = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sky)

MEAN_LIMIT = 1e-3
MAX_LIMIT = 1e-2
EDGE_PIXELS = 2.0   # sun-rim band left out, in pixel sizes

D = math.radians

# name, node settings
SKIES = [
    ("default", dict()),
    ("high_sun_no_disc", dict(sun_elevation=D(40.0), sun_rotation=D(123.0), altitude=2500.0,
                              air_density=0.6, dust_density=3.5, ozone_density=2.0,
                              sun_disc=False, sun_intensity=0.5)),
    ("low_sun_big_disc", dict(sun_elevation=D(4.0), sun_rotation=D(-70.0), altitude=30000.0,
                              air_density=2.0, dust_density=0.3, ozone_density=0.0,
                              sun_size=D(6.0), sun_intensity=2.0)),
    ("sun_on_horizon", dict(sun_elevation=D(0.5), sun_rotation=D(400.0), altitude=0.0,
                            air_density=1.0, dust_density=5.0, ozone_density=1.0,
                            sun_size=D(3.0), sun_intensity=1.0)),
    ("sun_set", dict(sun_elevation=D(-3.0), sun_rotation=D(200.0), altitude=100.0,
                     air_density=1.0, dust_density=1.0, ozone_density=6.0, sun_size=D(2.0))),
    # Cycles' clamps: sun size 0 -> 0.0005 rad, altitude 60 km -> 59999 m.
    ("tiny_sun_space", dict(sun_elevation=D(60.0), sun_rotation=D(10.0), altitude=60000.0,
                            air_density=10.0, dust_density=0.0, ozone_density=10.0, sun_size=0.0)),
    # Elevation past the zenith (the property is unbounded; Cycles folds it back
    # with the sun half a turn round), rotation below -2pi.
    ("sun_past_zenith", dict(sun_elevation=D(100.0), sun_rotation=D(-400.0), altitude=500.0,
                             air_density=0.0, dust_density=10.0, ozone_density=3.0, sun_size=D(5.0),
                             sun_intensity=0.25)),
    # Elevation -200 deg: wrapped to 160, folded to 20 with the sun turned round.
    ("elevation_wrapped", dict(sun_elevation=D(-200.0), sun_rotation=D(50.0), sun_size=D(5.0))),
]

NODE_DEFAULTS = dict(sun_disc=True, sun_size=None, sun_intensity=1.0, sun_elevation=None,
                     sun_rotation=0.0, altitude=0.0, air_density=1.0, dust_density=1.0,
                     ozone_density=1.0)


def reset_scene():
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.cameras,
                       bpy.data.worlds, bpy.data.lights):
        for block in list(collection):
            collection.remove(block)
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.cycles.samples = 1
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.filter_width = 0.01
    U.bare_setup(scene, world=True)
    return scene


def sky_world(scene, settings):
    nt = scene.world.node_tree
    nt.nodes.clear()
    node = nt.nodes.new("ShaderNodeTexSky")
    node.sky_type = 'NISHITA'
    for key, value in settings.items():
        setattr(node, key, value)
    bg = nt.nodes.new("ShaderNodeBackground")
    out = nt.nodes.new("ShaderNodeOutputWorld")
    nt.links.new(node.outputs["Color"], bg.inputs["Color"])
    nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
    return node


def node_values(node):
    """The node's properties as bpy gives them (float32 values)."""
    return {k: getattr(node, k) for k in NODE_DEFAULTS}


def sun_direction(constants):
    """The sun's world direction as the kernel computes it (geographical_to_direction
    of elevation and the stored rotation + pi/2)."""
    e, r = constants[6], constants[7] + math.pi / 2
    return np.array([math.cos(e) * math.cos(r), math.cos(e) * math.sin(r), math.sin(e)])


def aim(cam, direction, fov_deg, width, height, scene):
    cam.rotation_mode = 'QUATERNION'
    cam.rotation_quaternion = Vector(direction).normalized().to_track_quat('-Z', 'Y')
    cam.location = (0.0, 0.0, 0.0)
    cam.data.type = 'PERSP'
    cam.data.lens_unit = 'FOV'
    cam.data.angle = math.radians(fov_deg)
    cam.data.clip_start = 0.01
    scene.render.resolution_x, scene.render.resolution_y = width, height
    bpy.context.view_layer.update()


def views(constants):
    """(name, direction, fov in degrees, width, height) of the cameras for one sky."""
    s = sun_direction(constants)
    az = math.atan2(s[1], s[0])
    horiz = np.array([math.cos(az), math.sin(az), 0.0])
    side = np.array([math.cos(az + 1.9), math.sin(az + 1.9), 0.0])
    out = [
        ("horizon_sun_side", horiz + np.array([0, 0, 0.15]), 100.0, 120, 80),
        ("horizon_away", side + np.array([0, 0, 0.05]), 100.0, 120, 80),
        ("zenith", np.array([0.02, 0.01, 1.0]), 120.0, 96, 96),
        ("below_horizon", side + np.array([0, 0, -0.45]), 90.0, 96, 72),
    ]
    size = constants[8]
    if size > 0.0:
        out.append(("sun_disc", s, max(math.degrees(size) * 1.6, 0.5), 80, 80))
    return out


def compare(checks, sky_name, view_name, rgb, dirs, constants, texture, pixel_angle):
    ours = sky.radiance(dirs, constants, texture).astype(np.float64)
    ref = rgb.astype(np.float64)
    scale = np.maximum(np.abs(ref).max(axis=-1), 1e-6)
    rel = np.abs(ours - ref).max(axis=-1) / scale

    edge = np.zeros(rel.shape, bool)
    if constants[8] >= 0.0:
        s = sun_direction(constants)
        ang = np.arccos(np.clip(dirs @ s, -1.0, 1.0))
        half = 0.5 * constants[8]
        edge = np.abs(ang - half) < EDGE_PIXELS * pixel_angle
        # The part of the disc cut by the horizon: the cut is an edge too.
        edge |= (ang < half + EDGE_PIXELS * pixel_angle) & (np.abs(dirs[..., 2]) < EDGE_PIXELS * pixel_angle)
    keep = ~edge
    r = rel[keep]
    worst = np.unravel_index(np.argmax(np.where(keep, rel, -1.0)), rel.shape)
    detail = (f"mean {r.mean():.2e} max {r.max():.2e} at {worst} (Cycles {ref[worst]}, ours {ours[worst]}), "
              f"{keep.sum()} px, {edge.sum()} edge px"
              + (f" (edge max {rel[edge].max():.2e})" if edge.any() else ""))
    checks.check(r.mean() < MEAN_LIMIT and r.max() < MAX_LIMIT, f"{sky_name} / {view_name}", detail)
    return r


def run_sky(checks, scene, sky_name, settings, out):
    node = sky_world(scene, settings)
    v = node_values(node)
    texture = sky.precompute_texture(v["sun_elevation"], v["altitude"], v["air_density"],
                                     v["dust_density"], v["ozone_density"])
    constants = sky.node_constants(v["sun_disc"], v["sun_size"], v["sun_intensity"], v["sun_elevation"],
                                   v["sun_rotation"], v["altitude"], v["air_density"], v["dust_density"])
    all_rel = []
    for view_name, direction, fov, width, height in views(constants):
        aim(scene.camera, direction, fov, width, height, scene)
        path = U.render_exr(os.path.join(out, f"{sky_name}_{view_name}"), scene)
        channels = U.read_exr(path)
        layer = scene.view_layers[0].name
        rgb = U.exr_pass(channels, layer, "Combined", "RGB")
        _origins, dirs, _m = U.camera_rays(scene, scene.camera, width, height)
        pixel_angle = math.radians(fov) / max(width, height)
        all_rel.append(compare(checks, sky_name, view_name, rgb, dirs, constants, texture, pixel_angle))
    return np.concatenate(all_rel)


def pixel_centres(checks, scene, out):
    """The premise: with 1 sample and filter width 0.01 each pixel is its
    centre's ray. A world whose colour is its direction (Generated = D)
    rendered like the skies gives each pixel's ray, compared with camera_rays.
    (With 2 samples Cycles' second sample lands up to 0.25 px away.)"""
    nt = scene.world.node_tree
    nt.nodes.clear()
    coords = nt.nodes.new("ShaderNodeTexCoord")
    bg = nt.nodes.new("ShaderNodeBackground")
    wo = nt.nodes.new("ShaderNodeOutputWorld")
    nt.links.new(coords.outputs["Generated"], bg.inputs["Color"])
    nt.links.new(bg.outputs["Background"], wo.inputs["Surface"])
    fov, width, height = 120.0, 96, 96
    aim(scene.camera, np.array([0.3, 0.2, 1.0]), fov, width, height, scene)
    path = U.render_exr(os.path.join(out, "directions"), scene)
    seen = U.exr_pass(U.read_exr(path), scene.view_layers[0].name, "Combined", "RGB").astype(np.float64)
    _origins, dirs, _m = U.camera_rays(scene, scene.camera, width, height)
    offset = np.linalg.norm(seen - dirs, axis=-1) / (math.radians(fov) / width)
    checks.check(offset.max() < 0.01, "1 sample, filter width 0.01: pixels are their centre's ray",
                 f"max offset {offset.max():.2e} px")


def main():
    checks = U.Checks("Nishita sky: numpy reference vs Cycles")
    out = U.out_dir("check_sky_nishita")
    scene = reset_scene()
    checks.run("pixel centres", pixel_centres, checks, scene, out)
    everything = []
    for sky_name, settings in SKIES:
        r = checks.run(sky_name, run_sky, checks, scene, sky_name, settings, out)
        if r is not None:
            everything.append(r)
    if everything:
        r = np.concatenate(everything)
        print(f"  all skies, away from the sun's rim: mean relative error {r.mean():.3e}, "
              f"max {r.max():.3e}, {r.size} px")
    checks.finish()


main()
