"""Node specs of the procedural texture nodes: Noise, Voronoi, Musgrave, Wave, Checker,
Brick, Gradient, Magic, White Noise.

GLSL: shaders/nodes/node_texture_lib.glsl (node_tex_*), with Blender's hashes in
shaders/nodes/hash_lib.glsl. Semantics are Cycles 3.4.1's: the kernel sources Blender
3.4.1 ships in scripts/addons/cycles/source/kernel/svm/ (noisetex.h, voronoi.h, ...) and,
for how a Blender node reaches the kernel, intern/cycles/blender/shader.cpp and
intern/cycles/scene/shader_nodes.cpp of the 3.x series:

- Enum properties are cast straight across (``(NodeVoronoiFeature)b_node.feature()``...),
  so the tables below are Blender's RNA enum values, which are Cycles' enum values.
- An unlinked texture Vector is the Generated coordinates (SocketType::
  LINK_TEXTURE_GENERATED), except White Noise (a plain ShaderNode: its hidden Vector is
  its (0, 0, 0) default).
- Cycles ignores links into unavailable (disabled) sockets and reads the socket's own
  value (blender/shader.cpp add_nodes), so a disabled input here is its default value.
- Every texture node but White Noise carries a TextureMapping (``node.texture_mapping``:
  translation, rotation, scale, vector type, axis mapping; min/max is not passed on by
  Cycles). Blender 3.x has no UI for it, but files from 2.7x and scripts can set it; when
  it is not the identity (TextureMapping::skip()) Cycles puts NODE_TEXTURE_MAPPING in
  front of the texture, and so do we: its 3x4 transform (compute_transform() below) goes
  in a constant block, mode 2 (vector type NORMAL) normalises after.
- Noise computes its Color only when the output is used (stack_valid()); Fac is the
  same either way.
"""


import math

from . import register
from .texture_mapping import mapping_args as _mapping_args

# Blender RNA enum identifier -> Cycles / Blender enum value (kernel/svm/types.h).
# Keep in step with the table at the top of node_texture_lib.glsl.
DIMENSIONS = {"1D": 1, "2D": 2, "3D": 3, "4D": 4}
VORONOI_FEATURE = {"F1": 0, "F2": 1, "SMOOTH_F1": 2, "DISTANCE_TO_EDGE": 3, "N_SPHERE_RADIUS": 4}
VORONOI_METRIC = {"EUCLIDEAN": 0, "MANHATTAN": 1, "CHEBYCHEV": 2, "MINKOWSKI": 3}
MUSGRAVE_TYPE = {"MULTIFRACTAL": 0, "FBM": 1, "HYBRID_MULTIFRACTAL": 2,
                 "RIDGED_MULTIFRACTAL": 3, "HETERO_TERRAIN": 4}
WAVE_TYPE = {"BANDS": 0, "RINGS": 1}
WAVE_BANDS_DIRECTION = {"X": 0, "Y": 1, "Z": 2, "DIAGONAL": 3}
WAVE_RINGS_DIRECTION = {"X": 0, "Y": 1, "Z": 2, "SPHERICAL": 3}
WAVE_PROFILE = {"SIN": 0, "SAW": 1, "TRI": 2}
GRADIENT_TYPE = {"LINEAR": 0, "QUADRATIC": 1, "EASING": 2, "DIAGONAL": 3, "RADIAL": 4,
                 "QUADRATIC_SPHERE": 5, "SPHERICAL": 6}

# Texture mapping modes of node_texture_lib.glsl tex_mapping_apply().

# Voronoi features that use neither the metric nor the exponent.
_VORONOI_NO_METRIC = (VORONOI_FEATURE["DISTANCE_TO_EDGE"], VORONOI_FEATURE["N_SPHERE_RADIUS"])


# --------------------------------------------------------------------------------------
# Inputs
# --------------------------------------------------------------------------------------

def _socket(sockets, identifier):
    for s in sockets:
        if s.identifier == identifier:
            return s
    return None


def _in(b, identifier, type, implicit=None):
    """An input as Cycles reads it: a disabled socket's links are ignored (its value is
    the socket's own default); otherwise b.input()."""
    socket = _socket(b.node.inputs, identifier)
    if socket is not None and not socket.enabled:
        value = getattr(socket, "default_value", 0.0)
        try:
            value = tuple(value)
        except TypeError:
            pass
        return b.const(value, type)
    return b.input(identifier, type, implicit=implicit)


def _vector(b):
    return _in(b, "Vector", "vector", implicit="generated")


def _output_used(b, identifier):
    socket = _socket(b.node.outputs, identifier)
    return bool(socket is not None and socket.is_linked)


def _enum(b, table, prop):
    value = getattr(b.node, prop)
    if value not in table:
        b.unsupported(f"{prop} {value}")
        return None
    return table[value]


# --------------------------------------------------------------------------------------
# Specs
# --------------------------------------------------------------------------------------

@register("ShaderNodeTexNoise")
def tex_noise(b):
    """noisetex.h svm_node_tex_noise()."""
    dims = _enum(b, DIMENSIONS, "noise_dimensions")
    if dims is None:
        return
    color_needed = 1 if _output_used(b, "Color") else 0
    b.call("node_tex_noise",
           [b.int(dims), b.int(color_needed)] + _mapping_args(b) +
           [_vector(b),
            _in(b, "W", "float"),
            _in(b, "Scale", "float"),
            _in(b, "Detail", "float"),
            _in(b, "Roughness", "float"),
            _in(b, "Distortion", "float")],
           [("Fac", "float"), ("Color", "color")])


@register("ShaderNodeTexVoronoi")
def tex_voronoi(b):
    """voronoi.h svm_node_tex_voronoi()."""
    dims = _enum(b, DIMENSIONS, "voronoi_dimensions")
    feature = _enum(b, VORONOI_FEATURE, "feature")
    metric = _enum(b, VORONOI_METRIC, "distance")
    if dims is None or feature is None or metric is None:
        return
    if dims == 1 or feature in _VORONOI_NO_METRIC:
        metric = 0  # unused by the kernel: one program for all metrics
    b.call("node_tex_voronoi",
           [b.int(dims), b.int(feature), b.int(metric)] + _mapping_args(b) +
           [_vector(b),
            _in(b, "W", "float"),
            _in(b, "Scale", "float"),
            _in(b, "Smoothness", "float"),
            _in(b, "Exponent", "float"),
            _in(b, "Randomness", "float")],
           [("Distance", "float"), ("Color", "color"), ("Position", "vector"),
            ("W", "float"), ("Radius", "float")])


@register("ShaderNodeTexMusgrave")
def tex_musgrave(b):
    """musgrave.h svm_node_tex_musgrave()."""
    dims = _enum(b, DIMENSIONS, "musgrave_dimensions")
    mtype = _enum(b, MUSGRAVE_TYPE, "musgrave_type")
    if dims is None or mtype is None:
        return
    b.call("node_tex_musgrave",
           [b.int(dims), b.int(mtype)] + _mapping_args(b) +
           [_vector(b),
            _in(b, "W", "float"),
            _in(b, "Scale", "float"),
            _in(b, "Detail", "float"),
            _in(b, "Dimension", "float"),
            _in(b, "Lacunarity", "float"),
            _in(b, "Offset", "float"),
            _in(b, "Gain", "float")],
           [("Fac", "float")])


@register("ShaderNodeTexWave")
def tex_wave(b):
    """wave.h svm_node_tex_wave()."""
    wtype = _enum(b, WAVE_TYPE, "wave_type")
    bands = _enum(b, WAVE_BANDS_DIRECTION, "bands_direction")
    rings = _enum(b, WAVE_RINGS_DIRECTION, "rings_direction")
    profile = _enum(b, WAVE_PROFILE, "wave_profile")
    if None in (wtype, bands, rings, profile):
        return
    # The direction of the other wave type is unused: one program for all of them.
    if wtype == WAVE_TYPE["BANDS"]:
        rings = 0
    else:
        bands = 0
    b.call("node_tex_wave",
           [b.int(wtype), b.int(bands), b.int(rings), b.int(profile)] + _mapping_args(b) +
           [_vector(b),
            _in(b, "Scale", "float"),
            _in(b, "Distortion", "float"),
            _in(b, "Detail", "float"),
            _in(b, "Detail Scale", "float"),
            _in(b, "Detail Roughness", "float"),
            _in(b, "Phase Offset", "float")],
           [("Color", "color"), ("Fac", "float")])


@register("ShaderNodeTexChecker")
def tex_checker(b):
    """checker.h svm_node_tex_checker()."""
    b.call("node_tex_checker",
           _mapping_args(b) +
           [_vector(b),
            _in(b, "Color1", "color"),
            _in(b, "Color2", "color"),
            _in(b, "Scale", "float")],
           [("Color", "color"), ("Fac", "float")])


@register("ShaderNodeTexBrick")
def tex_brick(b):
    """brick.h svm_node_tex_brick(). The node's offset / squash (floats) and
    offset_frequency / squash_frequency (ints 1..99, Cycles packs them as uchar) are
    per-material constants, so editing them does not recompile."""
    node = b.node
    b.call("node_tex_brick",
           _mapping_args(b) +
           [_vector(b),
            _in(b, "Color1", "color"),
            _in(b, "Color2", "color"),
            _in(b, "Mortar", "color"),
            _in(b, "Scale", "float"),
            _in(b, "Mortar Size", "float"),
            _in(b, "Mortar Smooth", "float"),
            _in(b, "Bias", "float"),
            _in(b, "Brick Width", "float"),
            _in(b, "Row Height", "float"),
            b.const(float(node.offset), "float"),
            b.const(float(int(node.offset_frequency) & 0xFF), "float"),
            b.const(float(node.squash), "float"),
            b.const(float(int(node.squash_frequency) & 0xFF), "float")],
           [("Color", "color"), ("Fac", "float")])


@register("ShaderNodeTexGradient")
def tex_gradient(b):
    """gradient.h svm_node_tex_gradient()."""
    gtype = _enum(b, GRADIENT_TYPE, "gradient_type")
    if gtype is None:
        return
    b.call("node_tex_gradient",
           [b.int(gtype)] + _mapping_args(b) + [_vector(b)],
           [("Color", "color"), ("Fac", "float")])


@register("ShaderNodeTexMagic")
def tex_magic(b):
    """magic.h svm_node_tex_magic(); turbulence_depth (0..10) is the kernel's depth."""
    depth = int(b.node.turbulence_depth)
    b.call("node_tex_magic",
           [b.int(depth)] + _mapping_args(b) +
           [_vector(b),
            _in(b, "Scale", "float"),
            _in(b, "Distortion", "float")],
           [("Color", "color"), ("Fac", "float")])


@register("ShaderNodeTexWhiteNoise")
def tex_white_noise(b):
    """white_noise.h svm_node_tex_white_noise(): no texture mapping, and an unlinked
    Vector is its (0, 0, 0) default (WhiteNoiseTextureNode's Vector has no
    LINK_TEXTURE_GENERATED)."""
    dims = _enum(b, DIMENSIONS, "noise_dimensions")
    if dims is None:
        return
    b.call("node_tex_white_noise",
           [b.int(dims),
            _in(b, "Vector", "vector"),
            _in(b, "W", "float")],
           [("Value", "float"), ("Color", "color")])


@register("ShaderNodeTexSky")
def sky_texture(b):
    """The Sky Texture as Cycles 3.4.1 evaluates it, all three models:

    - Nishita (Blender 3.4's default): materials/sky_nishita.py builds the
      512x128 XYZ table and the sun disc's constants;
      shaders/nodes/node_sky_lib.glsl node_tex_sky_nishita looks it up.
    - Preetham and Hosek/Wilkie: materials/sky_hosek_preetham.py computes
      Cycles' 29 sky constants (sun angles, zenith values / radiances, Perez
      / Hosek coefficients; the Hosek/Wilkie tables in sky_hosek_data.py)
      from the node's Sun Direction, Turbidity and Ground Albedo;
      node_tex_sky_preetham / node_tex_sky_hosek evaluate each direction as
      kernel/svm/sky.h does. Neither has a sun disc (nor has Cycles')."""
    node = b.node
    from .texture_mapping import MAP_NONE, texture_mapping
    if texture_mapping(getattr(node, "texture_mapping", None))[0] != MAP_NONE:
        b._graph.note(f"'{node.name}': the node's texture mapping is not applied (link a Mapping node instead)")
    if node.sky_type in ("PREETHAM", "HOSEK_WILKIE"):
        from .. import sky_hosek_preetham
        constants = sky_hosek_preetham.node_constants(node.sky_type, tuple(node.sun_direction),
                                                      node.turbidity, node.ground_albedo)
        b.call("node_tex_sky_preetham" if node.sky_type == "PREETHAM" else "node_tex_sky_hosek",
               [b.block(constants), b.input("Vector", "vector", implicit="P")],
               [("Color", "color")])
        return
    if node.sky_type != "NISHITA":
        return b.unsupported(f"{node.sky_type.replace('_', ' ').title()} sky model")
    from .. import sky_nishita
    params = (node.sun_elevation, node.altitude, node.air_density, node.dust_density, node.ozone_density)
    key = "computed:" + repr(sky_nishita.texture_key(*params))
    table = b.computed_image(key, lambda: sky_nishita.precompute_texture(*params))
    constants = sky_nishita.node_constants(node.sun_disc, node.sun_size, node.sun_intensity, node.sun_elevation,
                                           node.sun_rotation, node.altitude, node.air_density, node.dust_density)
    # The sun disc lights as a sun lamp (sky_nishita.sun_lamp) where its
    # strength is known: the sky straight into a world's Background. The
    # lighting bake then leaves the disc out (constant 19, WORLD_LIGHTING).
    strength = _background_strength(b) if (b._graph.world and node.sun_disc) else None
    lamp = sky_nishita.sun_lamp(constants) if strength is not None else None
    if lamp is not None:
        direction, irradiance, angle = lamp
        b._graph.sun_lamps.append((tuple(direction), tuple(float(v) * strength for v in irradiance), angle))
    elif b._graph.world and node.sun_disc:
        b._graph.note(f"'{node.name}': the sun disc lights only through the baked map (where the Sky Texture "
                      "feeds a Background directly, with its Vector unlinked, it is a sun lamp)")
    b.call("node_tex_sky_nishita",
           [b.block(list(constants) + [1.0 if lamp is not None else 0.0]), table,
            b.input("Vector", "vector", implicit="P")],
           [("Color", "color")])


def _background_strength(b):
    """The Strength of the Background the Sky Texture's Color feeds directly,
    when that Background is the world's surface; else None."""
    node = b.node
    if b.is_linked("Vector") or b.ctx:
        return None
    for link in node.outputs["Color"].links:
        target = link.to_node
        if (link.is_muted or target.bl_idname != "ShaderNodeBackground" or target.mute or
                link.to_socket.identifier != "Color" or target.inputs["Strength"].is_linked):
            continue
        for out_link in target.outputs[0].links:
            output = out_link.to_node
            if (not out_link.is_muted and output.bl_idname == "ShaderNodeOutputWorld" and
                    getattr(output, "is_active_output", True) and out_link.to_socket.name == "Surface"):
                strength = float(target.inputs["Strength"].default_value)
                return strength if math.isfinite(strength) and strength > 0.0 else None
    return None
