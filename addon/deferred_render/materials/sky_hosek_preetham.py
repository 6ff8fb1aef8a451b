"""Cycles 3.4's Preetham and Hosek/Wilkie skies (Sky Texture node, sky types
PREETHAM and HOSEK_WILKIE) in Python/numpy.

Pure Python + numpy, no bpy: used by the node spec (nodes/texture.py
sky_texture: the constant block) and by tests (``radiance()`` is the
per-direction reference). Written from the maths of these Cycles / Blender
3.4 sources (Apache-2.0; the Hosek/Wilkie data BSD-3-Clause):

- intern/cycles/blender/shader.cpp: the node's ``sun_direction`` reaches
  Cycles normalised (``normalize(get_float3(b_sky_node.sun_direction()))``),
  with ``turbidity`` and ``ground_albedo`` as they are (float32 properties;
  Blender clamps turbidity to [1, 10] and the albedo to [0, 1]).
- intern/cycles/scene/shader_nodes.cpp:
  * sky_spherical_coordinates(dir) = (acosf(dir.z), atan2f(dir.x, dir.y));
  * sky_perez_function(lam, theta, gamma) = (1 + lam0 e^(lam1 / cos theta))
    (1 + lam2 e^(lam3 gamma) + lam4 cos^2 gamma);
  * sky_texture_precompute_preetham: the sun's zenith angle and azimuth, the
    zenith Y (Preetham et al. 1999, eq. A.2, scaled by 0.06), x and y
    (A.3 cubics in theta and T), the Perez coefficients of Y, x, y (A.2,
    linear in T; 5 used, 4 zeros), each zenith value divided by the Perez
    function at (theta = 0, gamma = sun theta) - all in float32;
  * sky_texture_precompute_hosek: turbidity clamped to [0, 10], the sun's
    zenith angle clamped to [0, pi/2], elevation pi/2 - theta; the model
    state of SKY_arhosek_xyz_skymodelstate_alloc_init in double, stored as
    float.
  * SkyTextureNode::compile: svm_node_tex_sky's 29 floats: sun phi, sun
    theta, radiance x, y, z, config x[9], config y[9], config z[9].
- intern/sky/source/sky_model.cpp: ArHosekSkyModel_CookConfiguration and
  ArHosekSkyModel_CookRadianceConfiguration: quintic Bezier in
  (elevation / (pi/2))^(1/3) of the dataset's 6 control points, blended
  linearly between the two turbidities around T (none above T = 10) and
  between albedo 0 and 1 - in double, in the C source's order of
  operations. Tables: sky_hosek_data.py (sky_model_data.h's datasetXYZ*,
  checked bit for bit against Blender 3.4.1's by tools/hosek_xyz_tables.py).
- intern/cycles/kernel/svm/sky.h (shipped with Blender 3.4.1 in
  scripts/addons/cycles/source): sky_angle_between, sky_perez_function,
  sky_radiance_preetham (theta clamped to pi/2 - 0.001, xyY -> XYZ with
  util/color.h xyY_to_xyz), sky_radiance_internal and sky_radiance_hosek
  (the same clamp, XYZ times 2pi/683); kernel/util/color.h
  xyz_to_rgb_clamped; kernel/camera/projection.h direction_to_spherical
  (theta = safe_acosf(z), phi = atan2f(x, y)). Neither model has a sun disc
  in Cycles 3.4.

Float32 is emulated as in sky_nishita.py: numpy float32 arithmetic in the C
order, libm functions in float64 rounded to float32 (glibc's float
functions are correctly rounded for these arguments).

Public API
----------
preetham(sun_direction, turbidity) -> dict (Cycles' SunSky fields)
hosek(sun_direction, turbidity, ground_albedo) -> dict
node_constants(sky_type, sun_direction, turbidity, ground_albedo, xyz_to_rgb=XYZ_TO_RGB)
    -> list of CONSTANT_COUNT floats (the GLSL block, layout below).
radiance(sky_type, dirs, constants) -> (..., 3) float32 scene linear RGB.

Constant block (node_tex_sky_preetham / node_tex_sky_hosek, mat_const):
   0     sun phi                  \\
   1     sun theta                 |  svm_node_tex_sky's floats, in the
   2..4  radiance x, y, z          |  order it reads them (Preetham:
   5..13 config x[0..8]            |  zenith Y, x, y and the Perez
  14..22 config y[0..8]            |  coefficients of Y, x, y)
  23..31 config z[0..8]           /
  32, 33 sinf(sun theta), cosf(sun theta)   (the kernel's sinf/cosf of the
  34, 35 sinf(sun phi), cosf(sun phi)        sun angles, float32)
  36     cosf(pi/2 - 0.001): cos of the horizon-clamped zenith angle
  37..45 XYZ -> scene linear RGB, rows r, g, b (kernel_data.film.xyz_to_r/g/b)
"""

import math

import numpy as np

from .sky_hosek_data import DATASETS_XYZ, DATASETS_XYZ_RAD

__all__ = ["CONSTANT_COUNT", "XYZ_TO_RGB", "PREETHAM", "HOSEK_WILKIE", "sun_spherical", "preetham",
           "hosek", "hosek_state", "node_constants", "radiance"]

F = np.float32
CONSTANT_COUNT = 46
PREETHAM = "PREETHAM"
HOSEK_WILKIE = "HOSEK_WILKIE"

# XYZ (D65) -> Blender 3.4 scene linear (Rec.709), rows r, g, b: the matrix
# sky_nishita.py measured in Cycles 3.4.1 (ShaderManager::init_xyz_transforms
# with the default OCIO config).
XYZ_TO_RGB = ((3.2404549780, -1.5371401203, -0.4985321715),
              (-0.9692662720, 1.8760104222, 0.0415556675),
              (0.0556431964, -0.2040253449, 1.0572247801))

M_PI_F = F(math.pi)
M_PI_2_F = F(math.pi / 2.0)
M_2PI_F = F(2.0 * math.pi)
THETA_CLAMP = M_PI_2_F - F(0.001)            # sky.h: min(theta, M_PI_2_F - 0.001f)
HOSEK_SCALE = M_2PI_F / F(683.0)             # sky.h: (M_2PI_F / 683), folded in float
MATH_PI = 3.141592653589793                  # sky_model.cpp (double)


def _f(x):
    """A float64 libm result rounded to float32 (glibc's correctly rounded float functions)."""
    return F(x)


def _acosf(x):
    return _f(math.acos(float(x)))


def _atan2f(y, x):
    return _f(math.atan2(float(y), float(x)))


def _expf(x):
    return _f(math.exp(float(x)))


def _cosf(x):
    return _f(math.cos(float(x)))


def _sinf(x):
    return _f(math.sin(float(x)))


def _tanf(x):
    return _f(math.tan(float(x)))


def normalize_direction(sun_direction):
    """Cycles' normalize() of the node's float32 sun direction (a / len(a), float32)."""
    x, y, z = (F(v) for v in sun_direction)
    length = np.sqrt((x * x + y * y) + z * z)
    if not length > 0.0:
        # 0/0 in Cycles: NaN angles. Straight up instead (the node's default).
        return F(0.0), F(0.0), F(1.0)
    return x / length, y / length, z / length


def sun_spherical(sun_direction):
    """sky_spherical_coordinates of the normalised sun direction: (theta, phi), float32.
    acosf, not safe_acosf: normalize() keeps |z| <= 1."""
    x, y, z = normalize_direction(sun_direction)
    return _acosf(min(max(float(z), -1.0), 1.0)), _atan2f(x, y)


# ---------------------------------------------------------------------------
# Preetham (shader_nodes.cpp sky_texture_precompute_preetham), float32
# ---------------------------------------------------------------------------

def _perez_host(lam, theta, gamma):
    """shader_nodes.cpp sky_perez_function (float32)."""
    one = F(1.0)
    cg = _cosf(gamma)
    return ((one + lam[0] * _expf(lam[1] / _cosf(theta))) *
            ((one + lam[2] * _expf(lam[3] * gamma)) + (lam[4] * cg) * cg))


def preetham(sun_direction, turbidity):
    """Cycles' SunSky for the Preetham model: theta, phi, radiance_x/y/z (the
    zenith Y, x, y over their Perez function at the zenith) and config_x/y/z
    (the Perez coefficients of Y, x, y, 9 floats each, 5..8 zero)."""
    theta, phi = sun_spherical(sun_direction)
    theta2 = theta * theta
    theta3 = theta2 * theta
    T = F(turbidity)
    T2 = T * T

    chi = (F(4.0 / 9.0) - T / F(120.0)) * (M_PI_F - F(2.0) * theta)
    radiance_x = ((F(4.0453) * T - F(4.9710)) * _tanf(chi) - F(0.2155) * T) + F(2.4192)
    radiance_x = radiance_x * F(0.06)

    radiance_y = ((((F(0.00166) * theta3 - F(0.00375) * theta2) + F(0.00209) * theta) * T2 +
                   (((F(-0.02903) * theta3 + F(0.06377) * theta2) - F(0.03202) * theta) + F(0.00394)) * T) +
                  (((F(0.11693) * theta3 - F(0.21196) * theta2) + F(0.06052) * theta) + F(0.25886)))
    radiance_z = ((((F(0.00275) * theta3 - F(0.00610) * theta2) + F(0.00317) * theta) * T2 +
                   (((F(-0.04214) * theta3 + F(0.08970) * theta2) - F(0.04153) * theta) + F(0.00516)) * T) +
                  (((F(0.15346) * theta3 - F(0.26756) * theta2) + F(0.06670) * theta) + F(0.26688)))

    def lin(a, b):
        return F(a) * T + F(b)

    config_x = [lin(0.1787, -1.4630), lin(-0.3554, 0.4275), lin(-0.0227, 5.3251),
                lin(0.1206, -2.5771), lin(-0.0670, 0.3703)] + [F(0.0)] * 4
    config_y = [lin(-0.0193, -0.2592), lin(-0.0665, 0.0008), lin(-0.0004, 0.2125),
                lin(-0.0641, -0.8989), lin(-0.0033, 0.0452)] + [F(0.0)] * 4
    config_z = [lin(-0.0167, -0.2608), lin(-0.0950, 0.0092), lin(-0.0079, 0.2102),
                lin(-0.0441, -1.6537), lin(-0.0109, 0.0529)] + [F(0.0)] * 4

    zero = F(0.0)
    radiance_x = radiance_x / _perez_host(config_x, zero, theta)
    radiance_y = radiance_y / _perez_host(config_y, zero, theta)
    radiance_z = radiance_z / _perez_host(config_z, zero, theta)
    return dict(theta=theta, phi=phi, radiance=(radiance_x, radiance_y, radiance_z),
                config=(config_x, config_y, config_z))


# ---------------------------------------------------------------------------
# Hosek / Wilkie (sky_model.cpp, double; shader_nodes.cpp stores float)
# ---------------------------------------------------------------------------

def _bezier(elev_matrix, offset, stride, s):
    """The quintic Bezier of sky_model.cpp's cooking functions, in its order:
    control point k at elev_matrix[offset + stride * k]."""
    e = [elev_matrix[offset + stride * k] for k in range(6)]
    return (math.pow(1.0 - s, 5.0) * e[0] +
            5.0 * math.pow(1.0 - s, 4.0) * s * e[1] +
            10.0 * math.pow(1.0 - s, 3.0) * math.pow(s, 2.0) * e[2] +
            10.0 * math.pow(1.0 - s, 2.0) * math.pow(s, 3.0) * e[3] +
            5.0 * (1.0 - s) * math.pow(s, 4.0) * e[4] +
            math.pow(s, 5.0) * e[5])


def _cook(dataset, block, stride, count, turbidity, albedo, solar_elevation):
    """ArHosekSkyModel_CookConfiguration (block 54, stride 9, count 9) and
    ArHosekSkyModel_CookRadianceConfiguration (block 6, stride 1, count 1)."""
    int_turbidity = int(turbidity)
    turbidity_rem = turbidity - float(int_turbidity)
    s = math.pow(solar_elevation / (MATH_PI / 2.0), 1.0 / 3.0)
    # (albedo weight, turbidity weight, table offset) in the C source's order.
    terms = [((1.0 - albedo), (1.0 - turbidity_rem), block * (int_turbidity - 1)),
             (albedo, (1.0 - turbidity_rem), block * 10 + block * (int_turbidity - 1))]
    if int_turbidity != 10:
        terms += [((1.0 - albedo), turbidity_rem, block * int_turbidity),
                  (albedo, turbidity_rem, block * 10 + block * int_turbidity)]
    out = [0.0] * count
    for k, (wa, wt, offset) in enumerate(terms):
        for i in range(count):
            value = wa * wt * _bezier(dataset, offset + i, stride, s)
            out[i] = value if k == 0 else out[i] + value
    return out


def hosek_state(turbidity, albedo, elevation):
    """SKY_arhosek_xyz_skymodelstate_alloc_init: (configs[3][9], radiances[3]) in double."""
    configs = [_cook(DATASETS_XYZ[c], 54, 9, 9, turbidity, albedo, elevation) for c in range(3)]
    radiances = [_cook(DATASETS_XYZ_RAD[c], 6, 1, 1, turbidity, albedo, elevation)[0] for c in range(3)]
    return configs, radiances


def hosek(sun_direction, turbidity, ground_albedo):
    """Cycles' SunSky for the Hosek/Wilkie model (float32 values)."""
    theta, phi = sun_spherical(sun_direction)
    turbidity = min(max(F(turbidity), F(0.0)), F(10.0))
    theta = min(max(theta, F(0.0)), M_PI_2_F)
    solar_elevation = M_PI_2_F - theta
    configs, radiances = hosek_state(float(turbidity), float(F(ground_albedo)), float(solar_elevation))
    return dict(theta=theta, phi=phi, radiance=tuple(F(r) for r in radiances),
                config=tuple([F(v) for v in c] for c in configs))


# ---------------------------------------------------------------------------
# The constant block
# ---------------------------------------------------------------------------

def node_constants(sky_type, sun_direction, turbidity, ground_albedo, xyz_to_rgb=XYZ_TO_RGB):
    """The CONSTANT_COUNT floats node_tex_sky_preetham / node_tex_sky_hosek
    read (layout in the module docstring)."""
    if sky_type == PREETHAM:
        s = preetham(sun_direction, turbidity)
    elif sky_type == HOSEK_WILKIE:
        s = hosek(sun_direction, turbidity, ground_albedo)
    else:
        raise ValueError(f"sky type {sky_type!r}")
    data = [s["phi"], s["theta"]] + list(s["radiance"])
    for c in s["config"]:
        data += list(c)
    data += [_sinf(s["theta"]), _cosf(s["theta"]), _sinf(s["phi"]), _cosf(s["phi"]), _cosf(THETA_CLAMP)]
    m = np.asarray(xyz_to_rgb, dtype=np.float64).reshape(-1)
    data += [F(v) for v in m]
    data = [float(F(v)) for v in data]
    assert len(data) == CONSTANT_COUNT
    return data


# ---------------------------------------------------------------------------
# Kernel reference (kernel/svm/sky.h, Cycles 3.4.1), float32
# ---------------------------------------------------------------------------

# float32 cos/sin/exp of arrays, as Cycles' cosf/sinf/expf: sky_nishita's.
from .sky_nishita import _cosf as _cosf_a, _expf as _expf_a, _sinf as _sinf_a  # noqa: E402


def _perez_kernel(lam, theta, gamma):
    """sky.h sky_perez_function."""
    one = F(1.0)
    ct = _cosf_a(theta)
    cg = _cosf_a(gamma)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return ((one + lam[0] * _expf_a(lam[1] / ct)) *
                ((one + lam[2] * _expf_a(lam[3] * gamma)) + (lam[4] * cg) * cg)).astype(F)


def _radiance_internal(c, theta, gamma):
    """sky.h sky_radiance_internal (Hosek/Wilkie)."""
    one = F(1.0)
    ct = _cosf_a(theta)
    cg = _cosf_a(gamma)
    exp_m = _expf_a(c[4] * gamma)
    ray_m = cg * cg
    base = (one + c[8] * c[8]) - (F(2.0) * c[8]) * cg
    mie_m = ((one + ray_m) / np.power(base.astype(np.float64), 1.5).astype(F)).astype(F)
    zenith = np.sqrt(ct)
    with np.errstate(over="ignore", invalid="ignore"):
        return ((one + c[0] * _expf_a(c[1] / (ct + F(0.01)))) *
                ((((c[2] + c[3] * exp_m) + c[5] * ray_m) + c[6] * mie_m) + c[7] * zenith)).astype(F)


def radiance(sky_type, dirs, constants):
    """Cycles' Sky Texture colour (scene linear RGB, float32) of the Preetham
    or Hosek/Wilkie sky for directions ``dirs`` (..., 3), ``constants`` from
    node_constants(); the kernel's float32 evaluation."""
    dirs = np.asarray(dirs, dtype=F)
    shape = dirs.shape[:-1]
    d = dirs.reshape(-1, 3)
    c = [F(v) for v in constants]
    sunphi, suntheta = c[0], c[1]
    rad = c[2:5]
    configs = (c[5:14], c[14:23], c[23:32])
    m = np.array(c[37:46], dtype=F).reshape(3, 3)

    # direction_to_spherical
    theta = np.arccos(np.clip(d[:, 2].astype(np.float64), -1.0, 1.0)).astype(F)
    phi = np.arctan2(d[:, 0].astype(np.float64), d[:, 1].astype(np.float64)).astype(F)
    # sky_angle_between(theta, phi, suntheta, sunphi)
    cospsi = (_sinf_a(theta) * _sinf(suntheta) * _cosf_a(sunphi - phi) + _cosf_a(theta) * _cosf(suntheta))
    gamma = np.arccos(np.clip(cospsi.astype(np.float64), -1.0, 1.0)).astype(F)
    theta = np.minimum(theta, THETA_CLAMP)

    if sky_type == PREETHAM:
        x = rad[1] * _perez_kernel(configs[1], theta, gamma)
        y = rad[2] * _perez_kernel(configs[2], theta, gamma)
        Y = rad[0] * _perez_kernel(configs[0], theta, gamma)
        # util/color.h xyY_to_xyz
        with np.errstate(divide="ignore", invalid="ignore"):
            X = np.where(y != 0.0, (x / y) * Y, F(0.0))
            Z = np.where((y != 0.0) & (Y != 0.0), ((F(1.0) - x - y) / y) * Y, F(0.0))
        xyz = np.stack([X, Y, Z], axis=-1).astype(F)
        scale = F(1.0)
    elif sky_type == HOSEK_WILKIE:
        xyz = np.stack([_radiance_internal(configs[k], theta, gamma) * rad[k] for k in range(3)],
                       axis=-1).astype(F)
        scale = HOSEK_SCALE
    else:
        raise ValueError(f"sky type {sky_type!r}")
    rgb = np.maximum(xyz @ m.T, F(0.0)).astype(F) * scale
    return rgb.reshape(shape + (3,)).astype(F)
