"""Cycles 3.4's Nishita sky (Sky Texture node, sky type NISHITA) in numpy.

Pure numpy, no bpy: usable by a node spec (to build the table and the
constant block) and by tests (``radiance()`` is the per-direction reference).
Written from the maths of these Cycles / Blender 3.4 sources (Apache-2.0):

- intern/sky/source/sky_nishita.cpp: SKY_nishita_skymodel_precompute_texture
  (single scattering along a 32-segment primary ray, 21 wavelengths,
  optical depth towards the sun by 8-node Gauss-Laguerre quadrature, CIE
  1931 XYZ) and SKY_nishita_skymodel_precompute_sun (the sun's transmitted
  radiance at the bottom and the top of its disc, divided by its solid angle).
- intern/cycles/scene/image_sky.cpp: SkyLoader, a 512 x 128 FLOAT4 image
  (the sky writes 3 channels per texel, the image manager expands them to
  RGBA with alpha 1). The table holds CIE XYZ, NOT RGB: Cycles converts to
  RGB in the kernel, after the bilinear lookup (xyz_to_rgb_clamped).
- intern/cycles/scene/shader_nodes.cpp: sky_texture_precompute_nishita and
  SkyTextureNode::compile: the altitude is clamped to [1, 59999] m for both
  the table and the sun, the sun size is max(sun_size, 0.0005)
  (SkyTextureNode::get_sun_size, shader_nodes.h), the sun rotation is
  wrapped to [0, 2pi) and stored as 2pi - rotation; the table is LINEAR
  interpolated with EXTEND (clamp-to-edge) wrapping. The sun elevation (an
  unbounded property) is wrapped and folded into [-pi/2, pi/2], the sun
  turned half round when folded: see sun_position() (measured in 3.4.1).
- intern/cycles/kernel/svm/sky.h (as shipped with Blender 3.4.1 in
  scripts/addons/cycles/source): svm_node_tex_sky reads 10 floats,
  sky_radiance_nishita evaluates a direction; kernel/camera/projection.h
  direction_to_spherical, util/math.h precise_angle, kernel/device/cpu/
  image.h interp_linear (the CPU kernel's bilinear lookup), kernel/util/
  color.h xyz_to_rgb_clamped.
- scene/shader.cpp ShaderManager::init_xyz_transforms: XYZ -> scene linear
  RGB (kernel_data.film.xyz_to_r/g/b). With Blender 3.4's default OCIO
  config this is XYZ_TO_RGB below (Rec.709 to ~2e-7; measured in Cycles
  3.4.1, the same matrix as shaders/nodes/node_converter_lib.glsl's
  color_xyz_to_scene_linear).

The precomputation emulates Cycles' float32 arithmetic operation by
operation (numpy float32; exp/sin/cos/pow evaluated in float64 and rounded,
as glibc's correctly rounded float functions give), so the table agrees with
Cycles' to a few float32 ulps, not merely to the model's accuracy.

Public API
----------
precompute_texture(sun_elevation, altitude, air_density, dust_density,
                   ozone_density, width=512, height=128)
    -> (height, width, 4) float32: XYZ in channels 0..2, 1 in channel 3.
precompute_sun(sun_elevation, sun_size, altitude, air_density, dust_density)
    -> (pixel_bottom, pixel_top): two (3,) float32 XYZ arrays.
node_constants(sun_disc, sun_size, sun_intensity, sun_elevation, sun_rotation,
               altitude, air_density, dust_density, xyz_to_rgb=XYZ_TO_RGB)
    -> list of CONSTANT_COUNT floats (the GLSL block, layout below).
radiance(dirs, constants, texture) -> (..., 3) float32 scene linear RGB.

All parameters are the Blender node's property values (radians, metres);
the Cycles clamps are applied here.

Constant block (what node_tex_sky_nishita reads with mat_const):
   0..2  pixel_bottom (XYZ)      \\
   3..5  pixel_top (XYZ)          |  Cycles' nishita_data[0..9], in the
   6     sun_elevation (folded)   |  order svm_node_tex_sky reads them
   7     sun_rotation (2pi - wrapped rotation, + pi if folded: sun_position)
   8     sun angular diameter, or -1 when the sun disc is off
   9     sun_intensity           /
  10..18 xyz_to_rgb rows r, g, b (kernel_data.film.xyz_to_r/g/b)

Texture upload: RGBA32F, width 512, height 128, row 0 = ``pixels[0]`` = the
horizon (latitude 0), row 127 near the zenith; no flip. Column x holds
longitude 2pi*x/512 - pi, mirrored (column 511 - x = column x).
"""

import math

import numpy as np

__all__ = ["TEXTURE_WIDTH", "TEXTURE_HEIGHT", "CONSTANT_COUNT", "XYZ_TO_RGB",
           "precompute_texture", "precompute_sun", "node_constants", "radiance",
           "clamp_altitude", "clamp_sun_size", "sun_position", "texture_key"]

F = np.float32

TEXTURE_WIDTH = 512   # SkyLoader::load_metadata
TEXTURE_HEIGHT = 128
CONSTANT_COUNT = 19

# XYZ (D65) -> Blender 3.4 scene linear (Rec.709), rows r, g, b. Cycles 3.4.1
# with the default OCIO config: inverse(scene_linear -> aces_interchange) x
# inverse(Cycles' ACES-AP0 -> XYZ-D65 matrix), measured in renders.
XYZ_TO_RGB = ((3.2404549780, -1.5371401203, -0.4985321715),
              (-0.9692662720, 1.8760104222, 0.0415556675),
              (0.0556431964, -0.2040253449, 1.0572247801))

# ---------------------------------------------------------------------------
# Model constants (sky_nishita.cpp), as float32
# ---------------------------------------------------------------------------

M_PI_F = F(math.pi)
M_PI_2_F = F(math.pi / 2.0)
M_2PI_F = F(2.0 * math.pi)

RAYLEIGH_SCALE = F(8e3)      # scale heights (m)
MIE_SCALE = F(1.2e3)
MIE_COEFF = F(2e-5)          # Mie scattering coefficient (1/m)
MIE_G = F(0.76)              # aerosol anisotropy
SQR_G = MIE_G * MIE_G        # float product, as the static initialiser
EARTH_RADIUS = F(6360e3)
ATMOSPHERE_RADIUS = F(6420e3)
STEPS = 32                   # segments of the primary ray
NUM_WAVELENGTHS = 21         # 380..780 nm every 20 nm
STEP_LAMBDA = F((780 - 380) // (21 - 1))   # integer division in the C source: 20
MIE_EXTINCTION = F(1.11) * MIE_COEFF       # 1.11f * mie_coeff, folded in float

# Sun irradiance at the top of the atmosphere (W m^-2 nm^-1).
IRRADIANCE = np.array([
    1.45756829855592995315, 1.56596305559738380175, 1.65148449067670455293,
    1.71496242737209314555, 1.75797983805020541226, 1.78256407885924539336,
    1.79095108475838560302, 1.78541550133410664714, 1.76815554864306845317,
    1.74122069647250410362, 1.70647127164943679389, 1.66556087452739887134,
    1.61993437242451854274, 1.57083597368892080581, 1.51932335059305478886,
    1.46628494965214395407, 1.41245852740172450623, 1.35844961970384092709,
    1.30474913844739281998, 1.25174963272610817455, 1.19975998755420620867], dtype=F)
# Rayleigh scattering coefficient (1/m).
RAYLEIGH_COEFF = np.array([
    0.00005424820087636473, 0.00004418549866505454, 0.00003635151910165377,
    0.00003017929012024763, 0.00002526320226989157, 0.00002130859310621843,
    0.00001809838025320633, 0.00001547057129129042, 0.00001330284977336850,
    0.00001150184784075764, 0.00000999557429990163, 0.00000872799973630707,
    0.00000765513700977967, 0.00000674217203751443, 0.00000596134125832052,
    0.00000529034598065810, 0.00000471115687557433, 0.00000420910481110487,
    0.00000377218381260133, 0.00000339051255477280, 0.00000305591531679811], dtype=F)
# Ozone absorption coefficient (1/m).
OZONE_COEFF = np.array([
    0.00000000325126849861, 0.00000000585395365047, 0.00000001977191155085,
    0.00000007309568762914, 0.00000020084561514287, 0.00000040383958096161,
    0.00000063551335912363, 0.00000096707041180970, 0.00000154797400424410,
    0.00000209038647223331, 0.00000246128056164565, 0.00000273551299461512,
    0.00000215125863128643, 0.00000159051840791988, 0.00000112356197979857,
    0.00000073527551487574, 0.00000046450130357806, 0.00000033096079921048,
    0.00000022512612292678, 0.00000014879129266490, 0.00000016828623364192], dtype=F)
# CIE 1931 colour matching functions at the 21 wavelengths (x, y, z).
CMF_XYZ = np.array([
    (0.00136800000, 0.00003900000, 0.00645000100),
    (0.01431000000, 0.00039600000, 0.06785001000),
    (0.13438000000, 0.00400000000, 0.64560000000),
    (0.34828000000, 0.02300000000, 1.74706000000),
    (0.29080000000, 0.06000000000, 1.66920000000),
    (0.09564000000, 0.13902000000, 0.81295010000),
    (0.00490000000, 0.32300000000, 0.27200000000),
    (0.06327000000, 0.71000000000, 0.07824999000),
    (0.29040000000, 0.95400000000, 0.02030000000),
    (0.59450000000, 0.99500000000, 0.00390000000),
    (0.91630000000, 0.87000000000, 0.00165000100),
    (1.06220000000, 0.63100000000, 0.00080000000),
    (0.85444990000, 0.38100000000, 0.00019000000),
    (0.44790000000, 0.17500000000, 0.00002000000),
    (0.16490000000, 0.06100000000, 0.00000000000),
    (0.04677000000, 0.01700000000, 0.00000000000),
    (0.01135916000, 0.00410200000, 0.00000000000),
    (0.00289932700, 0.00104700000, 0.00000000000),
    (0.00069007860, 0.00024920000, 0.00000000000),
    (0.00016615050, 0.00006000000, 0.00000000000),
    (0.00004150994, 0.00001499000, 0.00000000000)], dtype=F)
# Gauss-Laguerre quadrature (8 nodes, parameter scaled so the last node is
# inside the atmosphere; exp(x) folded into the weights): ray_optical_depth.
QUADRATURE_NODES = np.array([0.006811185292, 0.03614807107, 0.09004346519, 0.1706680068,
                             0.2818362161, 0.4303406404, 0.6296271457, 0.9145252695], dtype=F)
QUADRATURE_WEIGHTS = np.array([0.01750893642, 0.04135477391, 0.06678839063, 0.09507698807,
                               0.1283416365, 0.1707430204, 0.2327233347, 0.3562490486], dtype=F)


# ---------------------------------------------------------------------------
# float32 helpers: vectors are (x, y, z) tuples of float32 arrays, combined
# in the C source's order (dot = (x*x' + y*y') + z*z', etc.)
# ---------------------------------------------------------------------------

def _a(x):
    return np.asarray(x, dtype=F)


def _expf(x):
    return np.exp(np.asarray(x, dtype=np.float64)).astype(F)


def _sinf(x):
    return np.sin(np.asarray(x, dtype=np.float64)).astype(F)


def _cosf(x):
    return np.cos(np.asarray(x, dtype=np.float64)).astype(F)


def _powf(x, y):
    return np.power(np.asarray(x, dtype=np.float64), float(y)).astype(F)


def _dot(a, b):
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]


def _len(a):
    return np.sqrt(_dot(a, a))


def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _scale(s, a):
    return (a[0] * s, a[1] * s, a[2] * s)


def _geographical_to_direction(lat, lon):
    """sky_nishita.cpp geographical_to_direction: (cos lat cos lon, cos lat sin lon, sin lat)."""
    c = _cosf(lat)
    return (c * _cosf(lon), c * _sinf(lon), _sinf(lat))


def _density_rayleigh(h):
    return _expf(-h / RAYLEIGH_SCALE)


def _density_mie(h):
    return _expf(-h / MIE_SCALE)


def _density_ozone(h):
    """Tent profile, 0 at 10 km, 1 at 25 km, 0 at 40 km (density_ozone)."""
    k = F(1.0) / F(15000.0)
    up = k * h - F(2.0) / F(3.0)
    down = -(k * h - F(8.0) / F(3.0))
    return np.where((h >= F(10000.0)) & (h < F(25000.0)), up,
                    np.where((h >= F(25000.0)) & (h < F(40000.0)), down, F(0.0))).astype(F)


def _phase_rayleigh(mu):
    return F(3.0) / (F(16.0) * M_PI_F) * (F(1.0) + mu * mu)


def _phase_mie(mu):
    num = F(3.0) * (F(1.0) - SQR_G) * (F(1.0) + mu * mu)
    base = (F(1.0) + SQR_G) - (F(2.0) * MIE_G) * mu
    den = F(8.0) * M_PI_F * (F(2.0) + SQR_G) * _powf(base, 1.5)
    return num / den


def _surface_intersection(pos, d):
    """True where the ray from pos along d hits the Earth (surface_intersection)."""
    if np.all(d[2] >= F(0.0)):
        return np.zeros(np.shape(pos[0]), dtype=bool)
    neg = (-pos[0], -pos[1], -pos[2])
    b = F(-2.0) * _dot(d, neg)
    c = _dot(pos, pos) - EARTH_RADIUS * EARTH_RADIUS
    t = b * b - F(4.0) * c
    return (d[2] < F(0.0)) & (t >= F(0.0))


def _atmosphere_intersection(pos, d):
    """Exit point of the ray from pos along d through the atmosphere's top sphere."""
    neg = (-pos[0], -pos[1], -pos[2])
    b = F(-2.0) * _dot(d, neg)
    c = _dot(pos, pos) - ATMOSPHERE_RADIUS * ATMOSPHERE_RADIUS
    with np.errstate(invalid="ignore"):
        t = (-b + np.sqrt(b * b - F(4.0) * c)) / F(2.0)
    return (pos[0] + d[0] * t, pos[1] + d[1] * t, pos[2] + d[2] * t)


def _distance(a, b):
    return _len((a[0] - b[0], a[1] - b[1], a[2] - b[2]))


def _ray_optical_depth(origin, d):
    """(Rayleigh, Mie, ozone) density integrals from origin to the atmosphere's
    top along d: Gauss-Laguerre quadrature (ray_optical_depth)."""
    end = _atmosphere_intersection(origin, d)
    ray_length = _distance(origin, end)
    segment = _scale(ray_length, d)
    od = [F(0.0), F(0.0), F(0.0)]
    for i in range(len(QUADRATURE_NODES)):
        p = _add(origin, _scale(QUADRATURE_NODES[i], segment))
        h = _len(p) - EARTH_RADIUS
        w = QUADRATURE_WEIGHTS[i]
        od[0] = od[0] + _density_rayleigh(h) * w
        od[1] = od[1] + _density_mie(h) * w
        od[2] = od[2] + _density_ozone(h) * w
    return (od[0] * ray_length, od[1] * ray_length, od[2] * ray_length)


def _single_scattering(d, sun_dir, origin, air, dust, ozone):
    """Spectral in-scattered radiance along the rays d (single_scattering):
    (N, 21) float32 for N directions."""
    n = d[0].shape[0]
    end = _atmosphere_intersection(origin, d)
    ray_length = _distance(origin, end)
    segment_length = ray_length / F(STEPS)
    segment = _scale(segment_length, d)

    mu = _dot(d, sun_dir)
    phase_r = _phase_rayleigh(mu)
    phase_m = _phase_mie(mu)

    od = [np.zeros(n, F), np.zeros(n, F), np.zeros(n, F)]
    spectrum = np.zeros((n, NUM_WAVELENGTHS), F)
    p = _add(origin, _scale(F(0.5), segment))   # each segment is evaluated at its middle
    ray_c = RAYLEIGH_COEFF[None, :]
    oz_c = OZONE_COEFF[None, :]
    irr = IRRADIANCE[None, :]
    for _ in range(STEPS):
        h = _len(p) - EARTH_RADIUS
        dens = (air * _density_rayleigh(h), dust * _density_mie(h), ozone * _density_ozone(h))
        od = [od[k] + segment_length * dens[k] for k in range(3)]
        lit = ~_surface_intersection(p, sun_dir)
        if np.any(lit):
            lod = _ray_optical_depth(p, sun_dir)
            tod = (od[0] + air * lod[0], od[1] + dust * lod[1], od[2] + ozone * lod[2])
            ext = ((tod[0][:, None] * ray_c + (tod[1] * MIE_EXTINCTION)[:, None])
                   + tod[2][:, None] * oz_c)
            attenuation = _expf(-ext)
            # reduce_add(phase * scattering density); the ozone term is 0 * 0.
            scat = phase_r[:, None] * (dens[0][:, None] * ray_c) + (phase_m * (dens[1] * MIE_COEFF))[:, None]
            term = attenuation * scat * irr * segment_length[:, None]
            spectrum = np.where(lit[:, None], spectrum + term, spectrum)
        p = _add(p, segment)
    return spectrum


def _spec_to_xyz(spectrum):
    """(N, 21) spectra -> (N, 3) CIE XYZ (spec_to_xyz), summed wavelength by wavelength."""
    xyz = np.zeros((spectrum.shape[0], 3), F)
    for i in range(NUM_WAVELENGTHS):
        xyz = xyz + CMF_XYZ[i][None, :] * spectrum[:, i:i + 1]
    return xyz * STEP_LAMBDA


# ---------------------------------------------------------------------------
# Cycles' parameter handling (shader_nodes.cpp / shader_nodes.h)
# ---------------------------------------------------------------------------

def clamp_altitude(altitude):
    """SkyTextureNode::compile: clamp(altitude, 1, 59999) (below 1 m is
    numerically unstable, above 60 km is space)."""
    return F(min(max(F(altitude), F(1.0)), F(59999.0)))


def clamp_sun_size(sun_size):
    """SkyTextureNode::get_sun_size: fmaxf(sun_size, 0.0005)."""
    return F(max(F(sun_size), F(0.0005)))


def texture_key(sun_elevation, altitude, air_density, dust_density, ozone_density):
    """What the table depends on (after Cycles' clamps), e.g. for an image cache key."""
    return ("sky_nishita", float(sun_position(sun_elevation)[0]), float(clamp_altitude(altitude)),
            float(F(air_density)), float(F(dust_density)), float(F(ozone_density)))


# ---------------------------------------------------------------------------
# Precomputation
# ---------------------------------------------------------------------------

def precompute_texture(sun_elevation, altitude, air_density, dust_density, ozone_density,
                       width=TEXTURE_WIDTH, height=TEXTURE_HEIGHT):
    """The image Cycles builds for the sky (SkyLoader -> SKY_nishita_skymodel_
    precompute_texture), from the node's properties.

    Returns (height, width, 4) float32: channels 0..2 CIE XYZ (not RGB:
    Cycles converts after the lookup), channel 3 = 1. Row y is latitude
    (pi/2 + pi/(4 height)) (y/height)^2 (rows crowd toward the horizon,
    row 0 = horizon); column x is longitude 2pi x/width - pi relative to the
    sun, and the sky is mirrored: column width-1-x = column x.
    Altitude is clamped and the elevation folded as Cycles does."""
    alt = clamp_altitude(altitude)
    air, dust, ozone = F(air_density), F(dust_density), F(ozone_density)
    elevation = sun_position(sun_elevation)[0]
    half_width = width // 2
    origin = (F(0.0), F(0.0), EARTH_RADIUS + alt)
    sun_dir = _geographical_to_direction(elevation, F(0.0))
    sun_dir = tuple(_a(c) for c in sun_dir)

    latitude_step = M_PI_2_F / F(height)
    longitude_step = M_2PI_F / F(width)
    half_lat_step = latitude_step / F(2.0)
    ys = np.arange(height, dtype=F) / F(height)
    latitude = (M_PI_2_F + half_lat_step) * (ys * ys)                 # (H,)
    longitude = longitude_step * np.arange(half_width, dtype=F) - M_PI_F   # (W/2,)
    lat = np.repeat(latitude, half_width)
    lon = np.tile(longitude, height)
    d = _geographical_to_direction(lat, lon)

    xyz = _spec_to_xyz(_single_scattering(d, sun_dir, origin, air, dust, ozone))
    xyz = xyz.reshape(height, half_width, 3)
    pixels = np.ones((height, width, 4), F)
    pixels[:, :half_width, :3] = xyz
    pixels[:, width - 1:width - 1 - half_width:-1, :3] = xyz     # mirror sky
    # ImageManager: a texel with a non-finite channel becomes 0.
    bad = ~np.all(np.isfinite(pixels), axis=-1)
    pixels[bad] = 0.0
    return pixels


def precompute_sun(sun_elevation, sun_size, altitude, air_density, dust_density):
    """SKY_nishita_skymodel_precompute_sun with the node's values (sun size and
    altitude clamped, elevation folded as Cycles does): the sun's radiance (CIE XYZ, W m^-2 sr^-1
    nm-weighted as the table) seen at the bottom and the top of its disc, the
    elevations clamped to >= 0. Returns (pixel_bottom, pixel_top), (3,) float32."""
    elevation = sun_position(sun_elevation)[0]
    angular = clamp_sun_size(sun_size)
    alt = clamp_altitude(altitude)
    air, dust = F(air_density), F(dust_density)
    half_angular = angular / F(2.0)
    solid_angle = M_2PI_F * (F(1.0) - _cosf(half_angular))
    bottom = elevation - half_angular
    top = elevation + half_angular
    el = _a([bottom if bottom > 0.0 else F(0.0), top if top > 0.0 else F(0.0)])
    d = _geographical_to_direction(el, _a([0.0, 0.0]))
    origin = (F(0.0), F(0.0), EARTH_RADIUS + alt)
    od = _ray_optical_depth(origin, d)
    # sun_radiation: transmittance through the atmosphere (no ozone term).
    tr = ((RAYLEIGH_COEFF[None, :] * od[0][:, None]) * air
          + (MIE_EXTINCTION * od[1])[:, None] * dust)
    spectrum = IRRADIANCE[None, :] * _expf(-tr) / solid_angle
    xyz = _spec_to_xyz(spectrum)
    return xyz[0].copy(), xyz[1].copy()


def sun_position(sun_elevation, sun_rotation=0.0):
    """The sun position Cycles 3.4.1 renders for the node's elevation and
    rotation: (elevation, rotation as stored for the kernel), float32.

    The elevation is wrapped to [-pi, pi] and folded into [-pi/2, pi/2] with
    the sun moved half a turn (the same direction: the daylight cycle can be
    animated past the zenith), then the rotation is wrapped to [0, 2pi) and
    stored as 2pi - rotation (sky_texture_precompute_nishita). The folding
    was measured in Blender 3.4.1 (elevations of 100, 170, 200, 400, -100 and
    -200 degrees match Cycles' renders only folded; check_sky_nishita.py keeps
    100 and -200); it is the arithmetic of SkyTextureNode::simplify_settings
    in later Cycles sources. The folded elevation is also the one the table
    and the sun pixels are computed for."""
    e = F(sun_elevation)
    r = F(sun_rotation)
    e = F(math.fmod(float(e), float(M_2PI_F)))             # fmodf is exact
    if abs(e) >= M_PI_F:
        e = F(e - F(math.copysign(2.0, e)) * M_PI_F)
    if e >= M_PI_2_F or e <= -M_PI_2_F:
        e = F(F(math.copysign(float(M_PI_F), e)) - e)
        r = F(r + M_PI_F)
    r = F(math.fmod(float(r), float(M_2PI_F)))
    if r < 0.0:
        r = F(r + M_2PI_F)
    return e, F(M_2PI_F - r)


def node_constants(sun_disc, sun_size, sun_intensity, sun_elevation, sun_rotation,
                   altitude, air_density, dust_density, xyz_to_rgb=XYZ_TO_RGB):
    """The CONSTANT_COUNT floats node_tex_sky_nishita reads (layout in the
    module docstring): Cycles' nishita_data as SkyTextureNode::compile passes
    them to svm_node_tex_sky, then the scene's XYZ -> RGB rows."""
    bottom, top = precompute_sun(sun_elevation, sun_size, altitude, air_density, dust_density)
    data = [float(v) for v in bottom] + [float(v) for v in top]
    elevation, rotation = sun_position(sun_elevation, sun_rotation)
    data += [float(elevation), float(rotation),
             float(clamp_sun_size(sun_size)) if sun_disc else -1.0, float(F(sun_intensity))]
    m = np.asarray(xyz_to_rgb, dtype=np.float64).reshape(3, 3)
    data += [float(F(v)) for v in m.reshape(-1)]
    assert len(data) == CONSTANT_COUNT
    return data


# ---------------------------------------------------------------------------
# Kernel reference (kernel/svm/sky.h sky_radiance_nishita, Cycles 3.4.1)
# ---------------------------------------------------------------------------

def _texture_lookup(texture, x, y):
    """kernel/device/cpu/image.h interp_linear, EXTEND: bilinear with the -0.5
    texel-centre offset, indices clamped to the edge (no horizontal wrap)."""
    h, w = texture.shape[:2]
    fx = x * F(w) - F(0.5)
    fy = y * F(h) - F(0.5)
    # frac(): float_to_int truncates, minus 1 below zero.
    ix = np.trunc(fx).astype(np.int64) - (fx < 0)
    iy = np.trunc(fy).astype(np.int64) - (fy < 0)
    tx = (fx - ix.astype(F)).astype(F)[..., None]
    ty = (fy - iy.astype(F)).astype(F)[..., None]
    nix = np.clip(ix + 1, 0, w - 1)
    ix = np.clip(ix, 0, w - 1)
    niy = np.clip(iy + 1, 0, h - 1)
    iy = np.clip(iy, 0, h - 1)
    one = F(1.0)
    t = texture.astype(F, copy=False)
    return ((one - ty) * (one - tx) * t[iy, ix] + (one - ty) * tx * t[iy, nix]
            + ty * (one - tx) * t[niy, ix] + ty * tx * t[niy, nix])


def radiance(dirs, constants, texture):
    """Cycles' Sky Texture colour (scene linear RGB, float32) for directions
    ``dirs`` (..., 3) (unit vectors: Cycles takes acos(z) as the zenith
    angle), with ``constants`` from node_constants() and ``texture`` from
    precompute_texture(). Evaluated in float32 as the kernel is."""
    dirs = np.asarray(dirs, dtype=F)
    shape = dirs.shape[:-1]
    d = dirs.reshape(-1, 3)
    dx, dy, dz = d[:, 0], d[:, 1], d[:, 2]
    c = [F(v) for v in constants]
    pixel_bottom = _a(c[0:3])
    pixel_top = _a(c[3:6])
    sun_elevation, sun_rotation, angular_diameter, sun_intensity = c[6], c[7], c[8], c[9]
    m = _a(c[10:19]).reshape(3, 3)
    sun_disc = angular_diameter >= 0.0

    # direction_to_spherical: theta = acos(z), phi = atan2(x, y)
    theta = np.arccos(np.clip(dz.astype(np.float64), -1.0, 1.0)).astype(F)
    phi = np.arctan2(dx.astype(np.float64), dy.astype(np.float64)).astype(F)

    # Table coordinates (shared by the sky and the ground).
    x = (phi + M_PI_F + sun_rotation) / M_2PI_F
    x = np.where(x > F(1.0), x - F(1.0), x).astype(F)

    # Above the horizon.
    sun_dir = _geographical_to_direction(sun_elevation, F(sun_rotation + M_PI_2_F))
    dm = np.sqrt((dx - sun_dir[0]) ** 2 + (dy - sun_dir[1]) ** 2 + (dz - sun_dir[2]) ** 2)
    dp = np.sqrt((dx + sun_dir[0]) ** 2 + (dy + sun_dir[1]) ** 2 + (dz + sun_dir[2]) ** 2)
    sun_dir_angle = (F(2.0) * np.arctan2(dm.astype(np.float64), dp.astype(np.float64))).astype(F)
    half_angular = angular_diameter / F(2.0)
    dir_elevation = M_PI_2_F - theta
    in_sun = (dz >= F(0.0)) & bool(sun_disc) & (sun_dir_angle < half_angular)

    sky_y = np.sqrt(np.maximum(dir_elevation / M_PI_2_F, F(0.0)))
    xyz_sky = _texture_lookup(texture, x, sky_y)[:, :3]

    # Sun disc: interpolate the two precomputed sun pixels along elevation.
    if sun_elevation - half_angular > 0.0:
        sy = (dir_elevation - sun_elevation) / angular_diameter + F(0.5)
        sun_valid = np.ones_like(in_sun)
    else:
        den = F(sun_elevation + half_angular)
        sun_valid = np.full_like(in_sun, bool(den > 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            sy = dir_elevation / den
    xyz_sun = (pixel_bottom[None, :] + sy[:, None] * (pixel_top - pixel_bottom)[None, :]) * sun_intensity
    # Uninitialised in Cycles when the whole disc is below the horizon (a
    # direction above it cannot be inside the disc then): 0 here.
    xyz_sun = np.where(sun_valid[:, None], xyz_sun, F(0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        r = sun_dir_angle / half_angular
        limb = F(1.0) - F(0.6) * (F(1.0) - np.sqrt(np.maximum(F(1.0) - r * r, F(0.0))))
    xyz_sun = xyz_sun * limb[:, None]

    # Below the horizon: the horizon row faded to black by z = -0.4.
    fade = F(1.0) + dz * F(2.5)
    fade = (fade * fade) * fade
    xyz_ground = _texture_lookup(texture, x, np.full_like(x, F(-0.5)))[:, :3] * fade[:, None]
    xyz_ground = np.where((dz < F(-0.4))[:, None], F(0.0), xyz_ground)

    xyz = np.where((dz >= F(0.0))[:, None], np.where(in_sun[:, None], xyz_sun, xyz_sky), xyz_ground)
    xyz = np.nan_to_num(xyz.astype(F), nan=0.0, posinf=0.0, neginf=0.0)
    rgb = np.maximum(xyz @ m.T, F(0.0)).astype(F)
    return rgb.reshape(shape + (3,))


# ---------------------------------------------------------------------------
# The sun disc as a lamp (this engine's addition, not Cycles')
# ---------------------------------------------------------------------------

def sun_lamp(constants, samples=48):
    """The sun disc as a sun lamp: (direction towards the sun (3,), irradiance
    RGB (3,) at normal incidence, angular diameter) or None (no disc, or a
    disc wholly below the horizon).

    Cycles samples the disc of a Nishita sky as its own light strategy
    (background_sun_sample); a baked environment map cannot hold a 0.5
    degree disc, so this engine lights with it as a sun lamp of the same
    irradiance: the disc's radiance (limb darkening, the part above the
    horizon) integrated over its cone, sampled on a polar grid."""
    c = [float(v) for v in constants]
    angular_diameter = c[8]
    if angular_diameter < 0.0:
        return None
    half = 0.5 * angular_diameter
    axis = np.array(_geographical_to_direction(F(c[6]), F(c[7] + M_PI_2_F)), dtype=np.float64)
    axis /= np.linalg.norm(axis)
    helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    t = np.cross(helper, axis)
    t /= np.linalg.norm(t)
    b = np.cross(axis, t)
    # Uniform in solid angle over the cone: cos from 1 to cos(half), stratified.
    i = (np.arange(samples) + 0.5) / samples
    cos_t = 1.0 - i * (1.0 - math.cos(half))
    phi = 2.0 * math.pi * (np.arange(samples) + 0.5) / samples
    cos_t, phi = np.meshgrid(cos_t, phi, indexing="ij")
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    dirs = (axis[None, None, :] * cos_t[..., None] + t[None, None, :] * (sin_t * np.cos(phi))[..., None] +
            b[None, None, :] * (sin_t * np.sin(phi))[..., None])
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    # Only the disc's own radiance: directions inside it and above the horizon.
    empty = np.zeros((TEXTURE_HEIGHT, TEXTURE_WIDTH, 4), dtype=F)
    rgb = radiance(dirs, constants, empty).astype(np.float64)
    inside = dirs[..., 2] >= 0.0
    solid_angle = 2.0 * math.pi * (1.0 - math.cos(half))
    irradiance = (rgb * (inside * cos_t)[..., None]).reshape(-1, 3).mean(axis=0) * solid_angle
    if not np.all(np.isfinite(irradiance)) or irradiance.max() <= 0.0:
        return None
    return axis, irradiance, angular_diameter
