"""The Sky Texture's Preetham and Hosek/Wilkie models against Cycles 3.4.

  * precompute (materials/sky_hosek_preetham.py) against values derived by
    hand from the formulas: the Hosek/Wilkie state where the quintic
    Bezier reduces to one control point (sun on the horizon: the first;
    sun at the zenith: the last) and at a fractional turbidity and albedo
    (the four-way blend), with table values typed from sky_model_data.h;
    Preetham's zenith values and Perez coefficients for a sun at the
    zenith, and the colour of the zenith itself (gamma = theta = 0, where
    the Perez functions cancel: xyY = the zenith values);
  * renders, for each model at two sun directions and two turbidities
    (and three ground albedos), by Cycles on the CPU (1 sample, filter
    width 0.01 px: each pixel is its centre's ray, noise-free for a smooth
    sky) and by this engine, of a camera looking towards the sun's azimuth
    (the sun, the horizon and below it in view):
      - the node at each pixel: a plane filling the view emits the Sky
        Texture along the camera ray (Vector = -Incoming);
      - the world's background (Sky Texture -> Background, no objects),
        which this engine's camera rays see through its baked 1024 x 512
        world map (bilinear), hence the looser bound;
    per pixel, relative error = max over channels of |ours - Cycles| /
    max(max over channels of Cycles, 1e-6); its mean and its maximum over
    each image within the bounds below. The numpy reference
    (sky_hosek_preetham.radiance) is compared with Cycles the same way: the
    precomputed constants are Cycles' if it matches.

    BLENDER_USER_SCRIPTS=build/blender_scripts \
    blender -b --factory-startup blend_samples/analytic.blend --addons deferred_render \
        -E DEFERRED_RENDER --python-exit-code 1 --python tests/blender/test_sky_models.py
"""

import importlib.util
import math
import os
import sys

import bpy
import numpy as np
from mathutils import Matrix, Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import blender_test_utils as U  # noqa: E402

REPO = os.path.dirname(os.path.dirname(HERE))
MATERIALS = os.path.join(REPO, "addon", "deferred_render", "materials")


def _load(name):
    """The add-on's module from the source tree (sky_hosek_preetham imports
    its data module relatively: both are loaded as a package's)."""
    import types
    pkg = sys.modules.get("_sky_src")
    if pkg is None:
        pkg = types.ModuleType("_sky_src")
        pkg.__path__ = [MATERIALS]
        sys.modules["_sky_src"] = pkg
    spec = importlib.util.spec_from_file_location(f"_sky_src.{name}", os.path.join(MATERIALS, name + ".py"))
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


sky = _load("sky_hosek_preetham")

# Bounds (measured on llvmpipe, see the printout and README):
# the node at each pixel (an emitting plane): GPU float32 maths, measured mean 1.2e-6, max 6.6e-6
NODE_MEAN_LIMIT = 5e-6
NODE_MAX_LIMIT = 5e-5
# the world's background, which camera rays see through this engine's baked 1024 x 512
# camera map (bilinear, 0.35 degree texels; world_lib.glsl): interpolation error where the
# sky curves fastest, just above the horizon. Measured per sky mean <= 6.0e-5, max 6.4e-3.
BACKGROUND_MEAN_LIMIT = 2e-4
BACKGROUND_MAX_LIMIT = 1.5e-2
# numpy reference (sky_hosek_preetham.radiance) vs Cycles: measured mean 5.7e-7, max 6.7e-6
REFERENCE_MEAN_LIMIT = 2e-6
REFERENCE_MAX_LIMIT = 5e-5
PRECOMPUTE_LIMIT = 1e-6      # precompute vs the hand-derived values (relative)

D = math.radians


def direction(elevation_deg, azimuth_deg):
    e, a = D(elevation_deg), D(azimuth_deg)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))


# name, sky type, sun direction (unnormalised on purpose for one), turbidity, ground albedo
SKIES = [
    ("preetham_high_clear", "PREETHAM", direction(50.0, 30.0), 2.2, 0.3),
    ("preetham_high_hazy", "PREETHAM", direction(50.0, 30.0), 6.0, 0.3),
    ("preetham_low_clear", "PREETHAM", tuple(2.0 * v for v in direction(8.0, -120.0)), 2.2, 0.3),
    ("preetham_low_hazy", "PREETHAM", direction(8.0, -120.0), 6.0, 0.3),
    ("hosek_high_clear", "HOSEK_WILKIE", direction(50.0, 30.0), 2.2, 0.3),
    ("hosek_high_hazy", "HOSEK_WILKIE", direction(50.0, 30.0), 6.0, 0.8),
    ("hosek_low_clear", "HOSEK_WILKIE", tuple(2.0 * v for v in direction(8.0, -120.0)), 2.2, 0.0),
    ("hosek_low_hazy", "HOSEK_WILKIE", direction(8.0, -120.0), 6.0, 0.3),
]
WIDTH, HEIGHT, FOV = 96, 64, 120.0


def rel_close(a, b):
    """Largest |a - b| relative to |b|."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-30)))


def scaled_close(a, b):
    """Largest |a - b| relative to the largest |b| of the vector."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


# ---------------------------------------------------------------------------
# precompute against hand-derived values
# ---------------------------------------------------------------------------

# sky_model_data.h, typed from the source: datasetXYZ1 (X), albedo 0,
# turbidity 1, control points 0 and 5; datasetXYZ2 (Y) albedo 1, turbidity 2,
# control point 0; datasetXYZRad1..3 albedo 0 turbidity 1 (all 6 points).
XYZ1_A0_T1_P0 = [-1.117001e+000, -1.867262e-001, -1.113505e+001, 1.259865e+001, -3.937339e-002,
                 1.167571e+000, 7.100686e-003, 3.592678e+000, 6.083296e-001]
XYZ1_A0_T1_P5 = [-1.070108e+000, -1.600465e-001, 1.593886e+000, -4.479251e-005, -3.306541e+000,
                 9.390193e-001, 9.513168e-002, 2.343583e+000, 5.335404e-001]
XYZ2_A1_T2_P0 = [-1.125833e+000, -1.870849e-001, -9.555833e+000, 1.059713e+001, -4.225402e-002,
                 9.164663e-001, 4.338796e-002, 4.400980e+000, 6.056119e-001]
RAD_A0_T1 = [[1.560219e+000, 1.417388e+000, 1.206927e+000, 1.091949e+001, 5.931416e+000, 7.304788e+000],
             [1.632341e+000, 1.395230e+000, 1.375634e+000, 1.238193e+001, 5.921102e+000, 7.766508e+000],
             [1.168084e+000, 2.156455e+000, -3.980314e+000, 1.989302e+001, 1.328335e+001, 1.435621e+001]]


def precompute_hosek(checks):
    tables = sys.modules["_sky_src.sky_hosek_data"]   # the data module sky_hosek_preetham uses
    xyz, rad = tables.DATASETS_XYZ, tables.DATASETS_XYZ_RAD

    # The typed values are the module's (a transcription check independent of the generator).
    checks.check(list(xyz[0][0:9]) == XYZ1_A0_T1_P0 and list(xyz[0][45:54]) == XYZ1_A0_T1_P5 and
                 list(xyz[1][540 + 54:540 + 63]) == XYZ2_A1_T2_P0 and
                 all(list(rad[c][0:6]) == RAD_A0_T1[c] for c in range(3)) and
                 all(len(t) == 1080 for t in xyz) and all(len(t) == 120 for t in rad),
                 "Hosek/Wilkie tables: lengths and values typed from sky_model_data.h")

    # Sun on the horizon: elevation 0, Bezier parameter 0 -> control point 0.
    # Turbidity 1, albedo 0: config = the point, radiance = Rad[0].
    s = sky.hosek((1.0, 0.0, 0.0), 1.0, 0.0)
    err = max(rel_close(s["config"][0], XYZ1_A0_T1_P0),
              rel_close(s["radiance"], [RAD_A0_T1[c][0] for c in range(3)]))
    checks.check(err < PRECOMPUTE_LIMIT, "Hosek, sun on the horizon, T = 1, albedo 0: control point 0",
                 f"max relative error {err:.1e}")

    # Sun at the zenith: parameter ((pi/2 as float) / (pi/2))^(1/3) = 1 + 9e-9 -> control
    # point 5 (and -5e-8 of point 4: compared relative to the largest coefficient).
    s = sky.hosek((0.0, 0.0, 1.0), 1.0, 0.0)
    err = max(scaled_close(s["config"][0], XYZ1_A0_T1_P5),
              rel_close(s["radiance"], [RAD_A0_T1[c][5] for c in range(3)]))
    checks.check(err < PRECOMPUTE_LIMIT and abs(float(s["theta"])) == 0.0,
                 "Hosek, sun at the zenith, T = 1, albedo 0: control point 5",
                 f"max relative error {err:.1e}")

    # T = 2.5, albedo 0.25, sun on the horizon: (1-a)(1-r) P(T2, a0) + a(1-r) P(T2, a1)
    # + (1-a) r P(T3, a0) + a r P(T3, a1), r = 0.5, P = control point 0 of each block.
    a, r = 0.25, 0.5
    for c, name in enumerate("XYZ"):
        table = xyz[c]
        p = lambda alb, t: np.array(table[540 * alb + 54 * (t - 1):540 * alb + 54 * (t - 1) + 9])  # noqa: E731
        want = (1 - a) * (1 - r) * p(0, 2) + a * (1 - r) * p(1, 2) + (1 - a) * r * p(0, 3) + a * r * p(1, 3)
        q = lambda alb, t: rad[c][60 * alb + 6 * (t - 1)]  # noqa: E731
        want_rad = (1 - a) * (1 - r) * q(0, 2) + a * (1 - r) * q(1, 2) + (1 - a) * r * q(0, 3) + a * r * q(1, 3)
        s = sky.hosek((0.0, -1.0, 0.0), 2.5, 0.25)
        err = max(rel_close(s["config"][c], want), rel_close(s["radiance"][c], want_rad))
        checks.check(err < PRECOMPUTE_LIMIT, f"Hosek {name}, T = 2.5, albedo 0.25: the four-way blend",
                     f"max relative error {err:.1e}")
    # T = 10 uses only the T = 10 blocks (no T = 11): control point 0 of albedo 0 / 1.
    s = sky.hosek((1.0, 0.0, 0.0), 10.0, 1.0)
    err = rel_close(s["config"][2], xyz[2][540 + 486:540 + 495])
    checks.check(err < PRECOMPUTE_LIMIT, "Hosek Z, T = 10, albedo 1: the last block alone",
                 f"max relative error {err:.1e}")


def precompute_preetham(checks):
    for T in (2.2, 6.0):
        Tf = float(np.float32(T))
        s = sky.preetham((0.0, 0.0, 1.0), T)
        # Perez coefficients (Preetham et al. 1999, A.2), linear in T.
        want_cfg = [
            [0.1787 * Tf - 1.4630, -0.3554 * Tf + 0.4275, -0.0227 * Tf + 5.3251, 0.1206 * Tf - 2.5771,
             -0.0670 * Tf + 0.3703],
            [-0.0193 * Tf - 0.2592, -0.0665 * Tf + 0.0008, -0.0004 * Tf + 0.2125, -0.0641 * Tf - 0.8989,
             -0.0033 * Tf + 0.0452],
            [-0.0167 * Tf - 0.2608, -0.0950 * Tf + 0.0092, -0.0079 * Tf + 0.2102, -0.0441 * Tf - 1.6537,
             -0.0109 * Tf + 0.0529]]
        cfg_err = max(rel_close(s["config"][k][:5], want_cfg[k]) for k in range(3))
        zeros = all(float(v) == 0.0 for k in range(3) for v in s["config"][k][5:])
        # Zenith values for a sun at the zenith (theta = 0): chi = (4/9 - T/120) pi.
        chi = (4.0 / 9.0 - Tf / 120.0) * math.pi
        Yz = ((4.0453 * Tf - 4.9710) * math.tan(chi) - 0.2155 * Tf + 2.4192) * 0.06
        xz = 0.00394 * Tf + 0.25886
        yz = 0.00516 * Tf + 0.26688

        def perez(lam, theta, gamma):
            return ((1 + lam[0] * math.exp(lam[1] / math.cos(theta))) *
                    (1 + lam[2] * math.exp(lam[3] * gamma) + lam[4] * math.cos(gamma) ** 2))
        want_rad = [Yz / perez(want_cfg[0], 0, 0), xz / perez(want_cfg[1], 0, 0), yz / perez(want_cfg[2], 0, 0)]
        rad_err = rel_close(s["radiance"], want_rad)
        checks.check(cfg_err < 1e-5 and rad_err < 1e-5 and zeros,
                     f"Preetham T = {T}, sun at the zenith: Perez coefficients and zenith values",
                     f"coefficients {cfg_err:.1e}, zenith values {rad_err:.1e} (relative; float32 "
                     "arithmetic on 4-digit coefficients)")
        # The zenith's colour: the Perez functions cancel, xyY = (xz, yz, Yz).
        constants = sky.node_constants("PREETHAM", (0.0, 0.0, 1.0), T, 0.3)
        X, Y, Z = xz / yz * Yz, Yz, (1 - xz - yz) / yz * Yz
        want_rgb = np.maximum(np.array(sky.XYZ_TO_RGB) @ np.array([X, Y, Z]), 0.0)
        got = sky.radiance("PREETHAM", np.array([[0.0, 0.0, 1.0]]), constants)[0]
        err = rel_close(got, want_rgb)
        checks.check(err < 1e-5, f"Preetham T = {T}: the zenith's colour is the zenith xyY",
                     f"{got.round(5).tolist()} vs {want_rgb.round(5).tolist()}, relative {err:.1e}")


# ---------------------------------------------------------------------------
# renders
# ---------------------------------------------------------------------------

def reset_scene():
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.cameras,
                       bpy.data.worlds, bpy.data.lights):
        for block in list(collection):
            collection.remove(block)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.filter_width = 0.01
    U.bare_setup(scene, world=True)
    return scene


def sky_world(scene, sky_type, sun_direction, turbidity, albedo):
    nt = scene.world.node_tree
    nt.nodes.clear()
    node = nt.nodes.new("ShaderNodeTexSky")
    node.sky_type = sky_type
    node.sun_direction = sun_direction
    node.turbidity = turbidity
    node.ground_albedo = albedo
    bg = nt.nodes.new("ShaderNodeBackground")
    out = nt.nodes.new("ShaderNodeOutputWorld")
    nt.links.new(node.outputs["Color"], bg.inputs["Color"])
    nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
    return node


def aim(scene, sun):
    """Towards the sun's azimuth, pitched so the sun and the horizon (and some
    ground) are in view."""
    cam = scene.camera
    s = np.array(sun, np.float64)
    s /= np.linalg.norm(s)
    az = math.atan2(s[1], s[0])
    pitch = min(math.asin(s[2]) * 0.5, D(25.0))
    view = (math.cos(pitch) * math.cos(az + 0.3), math.cos(pitch) * math.sin(az + 0.3), math.sin(pitch))
    cam.rotation_mode = 'QUATERNION'
    cam.rotation_quaternion = Vector(view).to_track_quat('-Z', 'Y')
    cam.location = (0.0, 0.0, 0.0)
    cam.data.type = 'PERSP'
    cam.data.lens_unit = 'FOV'
    cam.data.angle = D(FOV)
    cam.data.clip_start = 0.01
    bpy.context.view_layer.update()


def rel_error(a, ref):
    a, ref = a.astype(np.float64), ref.astype(np.float64)
    return np.abs(a - ref).max(axis=-1) / np.maximum(np.abs(ref).max(axis=-1), 1e-6)


def sky_plane(scene, sky_type, sun_direction, turbidity, albedo):
    """A plane filling the camera's view whose material emits the sky along
    the camera ray: Sky Texture (Vector = -Incoming) -> Emission. Cycles and
    this engine then evaluate the node at each pixel (no baked map)."""
    mesh = bpy.data.meshes.new("EmitPlane")
    mesh.from_pydata([(-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0)], [], [(0, 1, 2, 3)])
    plane = bpy.data.objects.new("EmitPlane", mesh)
    scene.collection.objects.link(plane)
    plane.matrix_world = scene.camera.matrix_world @ Matrix.Translation((0.0, 0.0, -2.0))
    mat = bpy.data.materials.new("EmitPlane")
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    geometry = nt.nodes.new("ShaderNodeNewGeometry")
    negate = nt.nodes.new("ShaderNodeVectorMath")
    negate.operation = 'SCALE'
    negate.inputs["Scale"].default_value = -1.0
    node = nt.nodes.new("ShaderNodeTexSky")
    node.sky_type = sky_type
    node.sun_direction = sun_direction
    node.turbidity = turbidity
    node.ground_albedo = albedo
    emission = nt.nodes.new("ShaderNodeEmission")
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(geometry.outputs["Incoming"], negate.inputs[0])
    nt.links.new(negate.outputs["Vector"], node.inputs["Vector"])
    nt.links.new(node.outputs["Color"], emission.inputs["Color"])
    nt.links.new(emission.outputs["Emission"], out.inputs["Surface"])
    mesh.materials.append(mat)
    bpy.context.view_layer.update()
    return plane


def sky_warnings():
    """The last render's warnings, less the emitting plane's note that its
    (varying) emission lights nothing."""
    return " ".join(m for _, m in U.last_messages() if "EmitPlane" not in m)


def compare(checks, label, ours, cyc, ref, warned, mean_limit, max_limit, totals):
    e_ours = rel_error(ours[..., :3], cyc[..., :3])
    e_ref = rel_error(ref, cyc[..., :3])
    totals[0].append(e_ours.ravel())
    totals[1].append(e_ref.ravel())
    worst = np.unravel_index(np.argmax(e_ours), e_ours.shape)
    checks.check(e_ours.mean() < mean_limit and e_ours.max() < max_limit and "sky model" not in warned,
                 f"{label}: ours vs Cycles (mean < {mean_limit:g}, max < {max_limit:g})",
                 f"mean {e_ours.mean():.2e}, max {e_ours.max():.2e} at {worst} "
                 f"(Cycles {cyc[worst][:3].round(5).tolist()}, ours {ours[worst][:3].round(5).tolist()}), "
                 f"Cycles' mean {cyc[..., :3].mean():.4f}" + (f"; warned: {warned[:120]}" if warned else ""))
    checks.check(e_ref.mean() < REFERENCE_MEAN_LIMIT and e_ref.max() < REFERENCE_MAX_LIMIT,
                 f"{label}: numpy reference vs Cycles (mean < {REFERENCE_MEAN_LIMIT:g}, "
                 f"max < {REFERENCE_MAX_LIMIT:g})", f"mean {e_ref.mean():.2e}, max {e_ref.max():.2e}")


def renders(checks):
    scene = reset_scene()
    out = U.out_dir("test_sky_models")
    totals = {(k, v): [[], []] for k in ("PREETHAM", "HOSEK_WILKIE") for v in ("node", "background")}
    for name, sky_type, sun, turbidity, albedo in SKIES:
        node = sky_world(scene, sky_type, sun, turbidity, albedo)
        aim(scene, sun)
        _, dirs, _ = U.camera_rays(scene, scene.camera, WIDTH, HEIGHT)
        constants = sky.node_constants(sky_type, tuple(node.sun_direction), node.turbidity, node.ground_albedo)
        ref = sky.radiance(sky_type, dirs, constants)
        # The node at each pixel: the emitting plane.
        plane = sky_plane(scene, sky_type, sun, turbidity, albedo)
        cyc, _ = U.render_combined(scene, "CYCLES", 1, os.path.join(out, name + "_node_cycles"))
        ours, _ = U.render_combined(scene, U.ENGINE, 1, os.path.join(out, name + "_node_ours"))
        warned = sky_warnings()
        compare(checks, f"{name}, node per pixel", ours, cyc, ref, warned, NODE_MEAN_LIMIT, NODE_MAX_LIMIT,
                totals[(sky_type, "node")])
        mesh = plane.data
        material = mesh.materials[0]
        bpy.data.objects.remove(plane)
        bpy.data.meshes.remove(mesh)
        bpy.data.materials.remove(material)
        # The world's background, through this engine's baked camera map.
        cyc, _ = U.render_combined(scene, "CYCLES", 1, os.path.join(out, name + "_cycles"))
        ours, _ = U.render_combined(scene, U.ENGINE, 1, os.path.join(out, name + "_ours"))
        warned = sky_warnings()
        compare(checks, f"{name}, world background", ours, cyc, ref, warned, BACKGROUND_MEAN_LIMIT,
                BACKGROUND_MAX_LIMIT, totals[(sky_type, "background")])
    for (sky_type, what), (e_ours, e_ref) in totals.items():
        if e_ours:
            a, b = np.concatenate(e_ours), np.concatenate(e_ref)
            print(f"  {sky_type}, {what}: ours vs Cycles mean relative error {a.mean():.3e} (max {a.max():.3e}), "
                  f"numpy reference vs Cycles {b.mean():.3e} (max {b.max():.3e}), {a.size} px")


def main():
    checks = U.Checks("test_sky_models")
    if not U.require_engine(checks):
        checks.finish()
    checks.run("precompute_hosek", precompute_hosek, checks)
    checks.run("precompute_preetham", precompute_preetham, checks)
    checks.run("renders", renders, checks)
    checks.finish()


if __name__ == "__main__":
    main()
