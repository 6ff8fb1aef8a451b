"""Shader-node probes: every supported node against Cycles 3.4, one tile each.

Each probe case is a material whose node output reaches an Emission shader
(strength 1) -> Material Output. All cases go into ONE scene: a grid of tiles
(a 1 m plane, or a UV sphere of diameter 1 m for normal/view-dependent
cases), each with its own material, under one orthographic camera that puts
every tile on exactly TILE x TILE pixels. The world is black and there are no
lights, so with max_bounces 0 Cycles shows exactly the emission colour; its
single sample sits at the pixel centre (filter width 0.01 px), where our
engine's sample 0 is. Inputs vary across a tile: they are affine functions of
the UV coordinates (Texture Coordinate UV -> Mapping -> Separate XYZ), so one
tile shows a whole range of arguments.

Used by tests/blender/test_node_probes.py (the CTest test, with tolerances)
and tools/node_probe_table.py (the README table and a side-by-side PNG).

Adding a case: add ``Case(name, node bl_idname, build)`` to one of the
``_*_cases`` functions (all_cases() collects them); ``build(t)`` gets a
``Tree`` and returns the output socket to show. Keep inputs where Cycles
itself is smooth: no pixel centre on a discontinuity (offsets that are not
round numbers help) and no steep slope (Cycles' own UV rounding is ~1e-7, and
an exact case must stay within 1e-4). ``python3 tools/node_probe_table.py
--sensitivity`` renders Cycles again with the camera moved by 1e-4 px and
names the cases that move by more than 10x their tolerance.

Changing this file changes the hash of the cached Cycles render (and so
renders it again on the next run).
"""

import hashlib
import math
import os
import sys
import time
from typing import Callable, NamedTuple, Optional

import bpy
import numpy as np
from mathutils import Matrix, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

TILE = 32        # pixels per tile side (= 1 m)
GAP = 4          # pixels of black between tiles
BORDER = 2       # pixels dropped at each tile edge before comparing
CAMERA_Z = 5.0
CLIP_START = 0.1

# Tolerance classes (the targets), per case.
EXACT = "exact"            # math, colour and converter nodes, inputs: max abs error
STATISTICAL = "texture"    # textures, procedurals, derivatives: mean and 99th percentile
LIMITS = {EXACT: {"max": 1e-4}, STATISTICAL: {"mean": 1e-3, "p99": 1e-2}}

# Cases our engine does not support yet: case name -> reason. Reported, not
# asserted; test_node_probes fails when one of them passes (remove it then).
# Example: "geometry_pointiness": "needs per-vertex curvature from the exporter".
KNOWN_UNSUPPORTED = {
    "attribute_object_property": "Attribute of type Object/Instancer is not read (warned, 0)",
    "geometry_parametric": "supported (corner weights, as Cycles' u, v); the probe plane's diagonal passes "
                           "through 30 pixel centres of the tile, where Cycles' 0.005 px jitter picks either "
                           "triangle (every other pixel of the tile is exact: 1.4e-8)",
}

# Nodes whose cases are statistical (everything else is EXACT).
_STATISTICAL_NODES = {
    "ShaderNodeTexNoise", "ShaderNodeTexVoronoi", "ShaderNodeTexMusgrave", "ShaderNodeTexWave",
    "ShaderNodeTexChecker", "ShaderNodeTexBrick", "ShaderNodeTexGradient", "ShaderNodeTexMagic",
    "ShaderNodeTexWhiteNoise", "ShaderNodeTexImage", "ShaderNodeNormalMap", "ShaderNodeBump",
    "ShaderNodeNewGeometry", "ShaderNodeLayerWeight", "ShaderNodeFresnel", "ShaderNodeTangent",
}


class Case(NamedTuple):
    name: str
    node: str                       # bl_idname of the node under test
    build: Callable                 # build(t: Tree) -> output socket shown by the emission
    shape: str = "plane"            # "plane", "sphere", "grid" (a 4x4 plane with attributes)
    #                                 "ngon" (the plane as one 12-gon, warped UVs) or
    #                                 "islands" (four separate quads)
    setup: Optional[Callable] = None  # setup(object) for object-level properties
    kind: Optional[str] = None      # EXACT / STATISTICAL; None: from the node

    @property
    def tolerance_class(self):
        return self.kind or (STATISTICAL if self.node in _STATISTICAL_NODES else EXACT)


# ---------------------------------------------------------------------------
# node tree builder
# ---------------------------------------------------------------------------

def socket(sockets, identifier):
    """A socket by its identifier ("Value_001", "A_Color", ...)."""
    for s in sockets:
        if s.identifier == identifier:
            return s
    raise KeyError(f"no socket {identifier!r} in {[s.identifier for s in sockets]}")


class Tree:
    """Builds one probe material's node tree (t.node, t.floats, t.field, ...)."""

    def __init__(self, probes, material):
        self.probes = probes          # ProbeScene (images)
        self.nodes = material.node_tree.nodes
        self.links = material.node_tree.links
        self._texco = None

    def node(self, idname, inputs=None, **props):
        """A new node; props are set first (they change which sockets exist),
        then inputs by identifier: a socket is linked, a value is the default."""
        n = self.nodes.new(idname)
        for key, value in props.items():
            setattr(n, key, value)
        for ident, value in (inputs or {}).items():
            self.set(socket(n.inputs, ident), value)
        return n

    def set(self, sock, value):
        if isinstance(value, bpy.types.NodeSocket):
            self.links.new(value, sock)
        elif sock.type == 'RGBA' and len(value) == 3:
            sock.default_value = (*value, 1.0)
        else:
            sock.default_value = value

    @staticmethod
    def out(node, identifier=None):
        """An output of ``node`` by identifier (default: the first enabled one)."""
        if identifier is None:
            return next(s for s in node.outputs if s.enabled)
        return socket(node.outputs, identifier)

    def texco(self, output="UV", from_object=None):
        """A Texture Coordinate output (one shared node; its own node with from_object)."""
        if from_object is not None:
            return self.out(self.node("ShaderNodeTexCoord", object=from_object), output)
        if self._texco is None:
            self._texco = self.node("ShaderNodeTexCoord")
        return self.out(self._texco, output)

    def field(self, c1, c2, offset=(0.0, 0.0, 0.0), source=None):
        """Vector socket = c1 * u + c2 * v + offset over the tile (u, v = UV in 0..1),
        through one Mapping node; c1 and c2 must be orthogonal (Mapping is
        rotation x scale)."""
        c1, c2 = Vector(c1), Vector(c2)
        if abs(c1.dot(c2)) > 1e-5 * max(1.0, c1.length * c2.length):  # mathutils is float32
            raise ValueError(f"field columns {c1} and {c2} are not orthogonal")
        if c1[1] == c1[2] == 0 and c2[0] == c2[2] == 0:     # axis-aligned: scale only
            rotation, scale = (0.0, 0.0, 0.0), (c1[0], c2[1], 1.0)
        else:
            e1 = c1.normalized() if c1.length > 0 else c2.orthogonal().normalized()
            e2 = c2.normalized() if c2.length > 0 else e1.cross(e1.orthogonal()).normalized()
            rotation = tuple(Matrix((e1, e2, e1.cross(e2))).transposed().to_euler('XYZ'))
            scale = (c1.length, c2.length, 1.0)
        return self.out(self.node("ShaderNodeMapping", {
            "Vector": source or self.texco("UV"), "Location": tuple(offset),
            "Rotation": rotation, "Scale": scale}, vector_type='POINT'))

    def split(self, vector):
        n = self.node("ShaderNodeSeparateXYZ", {"Vector": vector})
        return self.out(n, "X"), self.out(n, "Y"), self.out(n, "Z")

    def floats(self, x, y=(0.0, 0.0)):
        """Two float sockets: x[0] -> x[1] left to right, y[0] -> y[1] bottom to top."""
        fx, fy, _ = self.split(self.field((x[1] - x[0], 0, 0), (0, y[1] - y[0], 0), (x[0], y[0], 0)))
        return fx, fy

    def lin(self, au, av, c=0.0):
        """Float socket au * u + av * v + c."""
        return self.split(self.field((au, av, 0), (av, -au, 0), (c, 0, 0)))[0]

    def pack(self, x, y, z):
        """Combine XYZ of three floats (sockets or numbers)."""
        return self.out(self.node("ShaderNodeCombineXYZ", {"X": x, "Y": y, "Z": z}))

    def color_a(self, scale=1.0):
        """A colourful field in about [0.05, 0.95] (times scale)."""
        s = scale
        return self.field((0.8 * s, 0, 0.4 * s), (0.1 * s, 0.8 * s, -0.2 * s), (0.05 * s, 0.05 * s, 0.4 * s))

    def color_b(self):
        """A second colour field in [0.15, 0.95] (a divisor), not aligned with color_a."""
        return self.field((-0.15, 0.6, 0.3), (0.6, 0.15, 0.0), (0.3, 0.2, 0.55))

    def vec_a(self, scale=1.0):
        """A vector field in about [-2, 1.5] per component, crossing zero."""
        s = scale
        return self.field((3 * s, 0, 1 * s), (-0.5 * s, 3 * s, 1.5 * s), (-1.4871 * s, -1.5213 * s, -0.9687 * s))

    # Offsets are not round numbers: with round ones, some pixel centre has
    # a component of vec_a exactly a multiple of vec_pos's (a jump of modulo).
    def vec_b(self):
        return self.field((0.5, 2, 0), (2, -0.5, 1), (-1.0123, 0.2171, -0.6037))

    def vec_pos(self):
        """A vector field with every component in [0.2, 1.7] (divisors)."""
        return self.field((0.4, 1, 0), (1, -0.4, 0.8), (0.3137, 0.6071, 0.5123))

    def tex_coords(self, scale=1.0, angle=0.35, offset=(0.0, 0.0, 0.0), z=(0.0, 0.0)):
        """Rotated texture coordinates spanning about ``scale`` units across the
        tile (feature edges then never line up with pixel rows); z varies by
        z[0] * u + z[1] * v."""
        c, s = math.cos(angle) * scale, math.sin(angle) * scale
        c1, c2 = Vector((c, s, z[0])), Vector((-s, c, z[1]))
        c2 -= c1 * (c1.dot(c2) / c1.length_squared)        # keep orthogonal when z varies
        return self.field(c1, c2, offset)

    def image(self, key):
        return self.probes.image(key)


# ---------------------------------------------------------------------------
# cases
# ---------------------------------------------------------------------------

def _math_cases():
    # operation -> (x range, y range, third input); step functions keep every
    # pixel centre away from their jumps, singular ones away from the poles.
    r2, r2b = (-2.0, 2.0), (-1.7, 1.9)
    ops = {
        "ADD": (r2, (-3, 3), 0), "SUBTRACT": (r2, (-3, 3), 0), "MULTIPLY": (r2, (-3, 3), 0),
        "DIVIDE": (r2, (0.5, 2.5), 0), "MULTIPLY_ADD": (r2, r2b, 0.5),
        "POWER": ((-1.0, 2.0), (0.25, 2.5), 0), "LOGARITHM": ((0.3, 4.3), (1.8, 6.0), 0),
        "SQRT": ((-1.0, 4.0), r2, 0), "INVERSE_SQRT": ((0.2, 4.2), r2, 0),
        "ABSOLUTE": (r2, r2, 0), "EXPONENT": ((-2.0, 1.5), r2, 0),
        "MINIMUM": (r2, r2b, 0), "MAXIMUM": (r2, r2b, 0),
        "LESS_THAN": (r2, r2b, 0), "GREATER_THAN": (r2, r2b, 0), "SIGN": (r2, r2, 0),
        "COMPARE": (r2, r2b, 0.3), "SMOOTH_MIN": (r2, r2b, 0.5), "SMOOTH_MAX": (r2, r2b, 0.5),
        "ROUND": (r2, r2, 0), "FLOOR": (r2, r2, 0), "CEIL": (r2, r2, 0), "TRUNC": (r2, r2, 0),
        "FRACT": (r2, r2, 0), "MODULO": (r2, (0.3, 1.3), 0), "WRAP": (r2, (0.35, 1.45), -0.4),
        "SNAP": (r2, (0.3, 1.3), 0), "PINGPONG": (r2, (0.3, 1.3), 0),
        "SINE": ((-4, 4), r2, 0), "COSINE": ((-4, 4), r2, 0), "TANGENT": ((-1.2, 1.2), r2, 0),
        "ARCSINE": ((-1.2, 1.2), r2, 0), "ARCCOSINE": ((-1.2, 1.2), r2, 0),
        "ARCTANGENT": ((-4, 4), r2, 0), "ARCTAN2": (r2, (-2.0, -0.25), 0),   # across the branch cut
        "SINH": (r2, r2, 0), "COSH": (r2, r2, 0), "TANH": (r2, r2, 0),
        "RADIANS": ((-90, 90), r2, 0), "DEGREES": (r2, r2, 0),
    }
    assert set(ops) == {e.identifier for e in bpy.types.ShaderNodeMath.bl_rna.properties["operation"].enum_items}

    def build(op, x, y, c, clamp=False):
        def f(t):
            a, b = t.floats(x, y)
            return t.out(t.node("ShaderNodeMath", {"Value": a, "Value_001": b, "Value_002": c},
                                operation=op, use_clamp=clamp))
        return f

    cases = [Case(f"math_{op.lower()}", "ShaderNodeMath", build(op, *args)) for op, args in ops.items()]
    cases.append(Case("math_multiply_clamp", "ShaderNodeMath", build("MULTIPLY", r2, (-3, 3), 0, True)))
    return cases


def _vector_math_cases():
    a, b, pos = Tree.vec_a, Tree.vec_b, Tree.vec_pos
    half = lambda t: t.vec_a(0.6)  # noqa: E731  (tangent away from its poles)
    # operation -> (A, B, C or scale, output)
    ops = {
        "ADD": (a, b, None), "SUBTRACT": (a, b, None), "MULTIPLY": (a, b, None),
        "DIVIDE": (a, pos, None), "MULTIPLY_ADD": (a, b, (0.3, -0.2, 0.5)),
        "CROSS_PRODUCT": (a, b, None), "PROJECT": (a, pos, None), "REFLECT": (a, pos, None),
        "REFRACT": (a, pos, 0.7), "FACEFORWARD": (a, b, (0.2, 0.5, -0.3)),
        "DOT_PRODUCT": (a, b, None), "DISTANCE": (a, b, None), "LENGTH": (a, b, None),
        "SCALE": (a, b, -1.7), "NORMALIZE": (a, b, None), "ABSOLUTE": (a, b, None),
        "MINIMUM": (a, b, None), "MAXIMUM": (a, b, None), "FLOOR": (a, b, None), "CEIL": (a, b, None),
        "FRACTION": (a, b, None), "MODULO": (a, pos, None), "WRAP": (a, pos, (-0.4, -0.3, -0.2)),
        "SNAP": (a, pos, None), "SINE": (a, b, None), "COSINE": (a, b, None), "TANGENT": (half, b, None),
    }
    assert set(ops) == {e.identifier for e in bpy.types.ShaderNodeVectorMath.bl_rna.properties["operation"].enum_items}
    floats = {"DOT_PRODUCT", "DISTANCE", "LENGTH"}

    def build(op, fa, fb, c):
        def f(t):
            inputs = {"Vector": fa(t), "Vector_001": fb(t)}
            if isinstance(c, tuple):
                inputs["Vector_002"] = c
            elif c is not None:
                inputs["Scale"] = c
            n = t.node("ShaderNodeVectorMath", inputs, operation=op)
            return t.out(n, "Value" if op in floats else "Vector")
        return f

    return [Case(f"vector_math_{op.lower()}", "ShaderNodeVectorMath", build(op, *args)) for op, args in ops.items()]


def _clamp_map_range_cases():
    def clamp(kind):
        def f(t):
            x, y = t.floats((-2, 2), (-1.8, 1.8))
            return t.out(t.node("ShaderNodeClamp", {"Value": x, "Min": -1.0, "Max": y}, clamp_type=kind))
        return f

    def map_float(interp, clamp):
        def f(t):
            x, y = t.floats((-0.5, 1.5), (0.6, 1.4))
            return t.out(t.node("ShaderNodeMapRange", {
                "Value": x, "From Min": 0.1, "From Max": y, "To Min": -1.0, "To Max": 2.0, "Steps": 4.0},
                data_type='FLOAT', interpolation_type=interp, clamp=clamp), "Result")
        return f

    def map_vector(interp, clamp):
        def f(t):
            return t.out(t.node("ShaderNodeMapRange", {
                "Vector": t.vec_a(), "From_Min_FLOAT3": (-1.0, -0.5, -0.8), "From_Max_FLOAT3": t.vec_pos(),
                "To_Min_FLOAT3": (0.2, -1.0, 0.5), "To_Max_FLOAT3": (1.5, 2.0, -0.5),
                "Steps_FLOAT3": (3.0, 4.0, 5.0)},
                data_type='FLOAT_VECTOR', interpolation_type=interp, clamp=clamp), "Vector")
        return f

    cases = [Case(f"clamp_{k.lower()}", "ShaderNodeClamp", clamp(k)) for k in ("MINMAX", "RANGE")]
    for interp in ("LINEAR", "STEPPED", "SMOOTHSTEP", "SMOOTHERSTEP"):
        cases.append(Case(f"map_range_{interp.lower()}", "ShaderNodeMapRange", map_float(interp, False)))
    cases.append(Case("map_range_linear_clamp", "ShaderNodeMapRange", map_float("LINEAR", True)))
    for interp in ("LINEAR", "STEPPED", "SMOOTHSTEP", "SMOOTHERSTEP"):
        cases.append(Case(f"map_range_vector_{interp.lower()}", "ShaderNodeMapRange", map_vector(interp, False)))
    cases.append(Case("map_range_vector_linear_clamp", "ShaderNodeMapRange", map_vector("LINEAR", True)))
    return cases


BLEND_TYPES = ['MIX', 'DARKEN', 'MULTIPLY', 'BURN', 'LIGHTEN', 'SCREEN', 'DODGE', 'ADD', 'OVERLAY',
               'SOFT_LIGHT', 'LINEAR_LIGHT', 'DIFFERENCE', 'SUBTRACT', 'DIVIDE', 'HUE', 'SATURATION',
               'COLOR', 'VALUE']


def _mix_cases():
    blend_items = bpy.types.ShaderNodeMix.bl_rna.properties["blend_type"].enum_items
    assert set(BLEND_TYPES) == {e.identifier for e in blend_items}

    def mix_float(clamp_factor):
        def f(t):
            x, y = t.floats((-0.3, 1.3), (-1.0, 2.0))
            return t.out(t.node("ShaderNodeMix", {"Factor_Float": x, "A_Float": y, "B_Float": 0.5},
                                data_type='FLOAT', clamp_factor=clamp_factor), "Result_Float")
        return f

    def mix_vector(mode):
        def f(t):
            factor = (t.field((1.4, 0, 0.5), (0, 1.4, 0), (-0.2, -0.2, 0.1)) if mode == 'NON_UNIFORM'
                      else t.lin(1.4, 0.2, -0.2))
            return t.out(t.node("ShaderNodeMix", {
                "Factor_Vector" if mode == 'NON_UNIFORM' else "Factor_Float": factor,
                "A_Vector": t.vec_a(), "B_Vector": t.vec_b()},
                data_type='VECTOR', factor_mode=mode, clamp_factor=True), "Result_Vector")
        return f

    def mix_color(blend, factor=(0.0, 1.0), clamp_factor=True, clamp_result=False, scale=1.0):
        def f(t):
            fac = t.lin(factor[1] - factor[0], 0.15, factor[0])
            return t.out(t.node("ShaderNodeMix", {
                "Factor_Float": fac, "A_Color": t.color_a(scale), "B_Color": t.color_b()},
                data_type='RGBA', blend_type=blend, clamp_factor=clamp_factor,
                clamp_result=clamp_result), "Result_Color")
        return f

    cases = [Case("mix_float", "ShaderNodeMix", mix_float(True)),
             Case("mix_float_unclamped_factor", "ShaderNodeMix", mix_float(False)),
             Case("mix_vector_uniform", "ShaderNodeMix", mix_vector('UNIFORM')),
             Case("mix_vector_non_uniform", "ShaderNodeMix", mix_vector('NON_UNIFORM'))]
    cases += [Case(f"mix_color_{b.lower()}", "ShaderNodeMix", mix_color(b)) for b in BLEND_TYPES]
    cases.append(Case("mix_color_mix_unclamped_factor", "ShaderNodeMix", mix_color('MIX', (-0.3, 1.3), False)))
    cases.append(Case("mix_color_add_clamp_result", "ShaderNodeMix",
                      mix_color('ADD', clamp_result=True, scale=1.3)))
    return cases


def _mix_rgb_cases():
    def mix(blend, factor=(0.0, 1.0), clamp=False, scale=1.0):
        def f(t):
            fac = t.lin(factor[1] - factor[0], 0.15, factor[0])
            return t.out(t.node("ShaderNodeMixRGB", {"Fac": fac, "Color1": t.color_a(scale), "Color2": t.color_b()},
                                blend_type=blend, use_clamp=clamp))
        return f

    cases = [Case(f"mix_rgb_{b.lower()}", "ShaderNodeMixRGB", mix(b)) for b in BLEND_TYPES]
    cases.append(Case("mix_rgb_add_clamp", "ShaderNodeMixRGB", mix('ADD', clamp=True, scale=1.3)))
    cases.append(Case("mix_rgb_mix_factor_out_of_range", "ShaderNodeMixRGB", mix('MIX', (-0.3, 1.3))))
    return cases


def _color_cases():
    def invert(t):
        fac, _ = t.floats((0.0, 1.0))
        return t.out(t.node("ShaderNodeInvert", {"Fac": fac, "Color": t.color_a()}))

    def hsv(fac):
        def f(t):
            h, s = t.floats((0.0, 1.0), (0.0, 2.0))
            return t.out(t.node("ShaderNodeHueSaturation", {
                "Hue": h, "Saturation": s, "Value": 1.2, "Fac": fac, "Color": t.color_a()}))
        return f

    def gamma(t):
        g, _ = t.floats((0.3, 3.0))
        return t.out(t.node("ShaderNodeGamma", {"Color": t.color_a(1.3), "Gamma": g}))

    def bright_contrast(t):
        b, c = t.floats((-0.5, 0.5), (-0.5, 1.0))
        return t.out(t.node("ShaderNodeBrightContrast", {"Color": t.color_a(), "Bright": b, "Contrast": c}))

    def rgb_to_bw(t):
        return t.out(t.node("ShaderNodeRGBToBW", {"Color": t.color_a(1.5)}))

    return [Case("invert", "ShaderNodeInvert", invert),
            Case("hue_saturation", "ShaderNodeHueSaturation", hsv(1.0)),
            Case("hue_saturation_fac", "ShaderNodeHueSaturation", hsv(0.6)),
            Case("gamma", "ShaderNodeGamma", gamma),
            Case("bright_contrast", "ShaderNodeBrightContrast", bright_contrast),
            Case("rgb_to_bw", "ShaderNodeRGBToBW", rgb_to_bw)]


def _separate_combine_cases():
    def separate(name, idname, outs, mode=None, scale=1.0):
        def f(t):
            n = t.node(idname, **({"mode": mode} if mode else {}))
            t.set(n.inputs[0], t.color_a(scale))
            a, b, c = (t.out(n, o) for o in outs)
            return t.pack(c, a, b)   # permuted: a swapped output shows
        return Case(name, idname, f)

    def combine(name, idname, ins, mode=None, ranges=((0, 1), (0, 1), 0.6)):
        def f(t):
            x, y = t.floats(ranges[0], ranges[1])
            return t.out(t.node(idname, {ins[0]: x, ins[1]: y, ins[2]: ranges[2]},
                                **({"mode": mode} if mode else {})))
        return Case(name, idname, f)

    rgb, xyz, hsv, col = ("R", "G", "B"), ("X", "Y", "Z"), ("H", "S", "V"), ("Red", "Green", "Blue")
    wide = ((-0.5, 1.5), (0, 2), 0.3)
    return [separate("separate_rgb", "ShaderNodeSeparateRGB", rgb, scale=1.2),
            combine("combine_rgb", "ShaderNodeCombineRGB", rgb, ranges=wide),
            separate("separate_xyz", "ShaderNodeSeparateXYZ", xyz),
            combine("combine_xyz", "ShaderNodeCombineXYZ", xyz, ranges=((-2, 2), (-1, 3), -0.7)),
            separate("separate_hsv", "ShaderNodeSeparateHSV", hsv),
            combine("combine_hsv", "ShaderNodeCombineHSV", hsv),
            separate("separate_color_rgb", "ShaderNodeSeparateColor", col, 'RGB', 1.2),
            separate("separate_color_hsv", "ShaderNodeSeparateColor", col, 'HSV'),
            separate("separate_color_hsl", "ShaderNodeSeparateColor", col, 'HSL'),
            combine("combine_color_rgb", "ShaderNodeCombineColor", col, 'RGB', wide),
            combine("combine_color_hsv", "ShaderNodeCombineColor", col, 'HSV'),
            combine("combine_color_hsl", "ShaderNodeCombineColor", col, 'HSL')]


def _ramp_curve_cases():
    def ramp(interp, mode='RGB', hue='NEAR', output="Color"):
        def f(t):
            fac, _ = t.floats((-0.1, 1.1))
            n = t.node("ShaderNodeValToRGB", {"Fac": fac})
            r = n.color_ramp
            r.color_mode, r.hue_interpolation, r.interpolation = mode, hue, interp
            stops = [(0.1, (0.9, 0.1, 0.2, 1.0)), (0.35, (0.2, 0.9, 0.3, 0.8)),
                     (0.6, (1.0, 0.8, 0.1, 0.6)), (0.9, (0.1, 0.3, 0.9, 0.3))]
            r.elements[0].position, r.elements[0].color = stops[0]
            r.elements[1].position, r.elements[1].color = stops[-1]
            for pos, color in stops[1:-1]:
                r.elements.new(pos).color = color
            return t.out(n, output)
        return f

    def rgb_curves(fac, levels):
        def f(t):
            n = t.node("ShaderNodeRGBCurve", {"Fac": fac, "Color": t.color_a(1.2)})
            m = n.mapping
            m.extend = 'EXTRAPOLATED'
            m.curves[3].points.new(0.3, 0.5)
            m.curves[0].points.new(0.5, 0.3)
            m.curves[1].points[1].location = (1.0, 0.8)
            m.curves[2].points.new(0.7, 0.9)
            m.curves[2].points.new(0.2, 0.05)
            if levels:
                m.black_level, m.white_level = (0.05, 0.1, 0.0), (0.9, 1.1, 1.0)
            m.update()
            return t.out(n)
        return f

    def vector_curves(t):
        n = t.node("ShaderNodeVectorCurve", {"Fac": 1.0, "Vector": t.vec_a(0.6)})
        m = n.mapping
        m.extend = 'EXTRAPOLATED'
        m.curves[0].points.new(-0.3, 0.4)
        m.curves[1].points.new(0.2, -0.5)
        m.curves[2].points.new(0.5, 0.6)
        m.curves[2].points.new(-0.6, -0.1)
        m.update()
        return t.out(n)

    def float_curve(t):
        x, _ = t.floats((-0.2, 1.2))
        n = t.node("ShaderNodeFloatCurve", {"Factor": 1.0, "Value": x})
        m = n.mapping
        m.extend = 'EXTRAPOLATED'
        m.curves[0].points.new(0.4, 0.7)
        m.curves[0].points.new(0.75, 0.35)
        m.update()
        return t.out(n)

    cases = [Case(f"color_ramp_{i.lower()}", "ShaderNodeValToRGB", ramp(i))
             for i in ('LINEAR', 'EASE', 'CARDINAL', 'B_SPLINE', 'CONSTANT')]
    cases += [Case(f"color_ramp_hsv_{h.lower()}", "ShaderNodeValToRGB", ramp('LINEAR', 'HSV', h))
              for h in ('NEAR', 'FAR', 'CW', 'CCW')]
    cases += [Case("color_ramp_hsl_near", "ShaderNodeValToRGB", ramp('LINEAR', 'HSL', 'NEAR')),
              Case("color_ramp_alpha", "ShaderNodeValToRGB", ramp('LINEAR', output="Alpha")),
              Case("rgb_curves", "ShaderNodeRGBCurve", rgb_curves(1.0, False)),
              Case("rgb_curves_fac_levels", "ShaderNodeRGBCurve", rgb_curves(0.6, True)),
              Case("vector_curves", "ShaderNodeVectorCurve", vector_curves),
              Case("float_curve", "ShaderNodeFloatCurve", float_curve)]
    return cases


def _converter_cases():
    def blackbody(t):
        return t.out(t.node("ShaderNodeBlackbody", {"Temperature": t.floats((800, 12000))[0]}))

    def wavelength(t):
        return t.out(t.node("ShaderNodeWavelength", {"Wavelength": t.floats((380, 780))[0]}))

    return [Case("blackbody", "ShaderNodeBlackbody", blackbody),
            Case("wavelength", "ShaderNodeWavelength", wavelength)]


def _brick(fancy, squash=0.7):
    def f(t):
        inputs = {"Vector": t.tex_coords(1.0), "Color1": (0.8, 0.3, 0.1), "Color2": (0.2, 0.5, 0.7),
                  "Mortar": (0.9, 0.9, 0.8), "Scale": 2.0, "Mortar Size": 0.08}   # mortar ~2 px wide
        props = {}
        if fancy:
            inputs.update({"Mortar Size": 0.1, "Mortar Smooth": 0.4, "Bias": 0.3,
                           "Brick Width": 0.6, "Row Height": 0.3})
            # Squash 0 (the materials library's 'Building'): a row of
            # zero-width bricks, one brick between horizontal mortar
            # lines in Cycles (svm_brick's x is NaN there).
            props = {"offset": 0.3, "offset_frequency": 3, "squash": squash, "squash_frequency": 2}
        n = t.node("ShaderNodeTexBrick", inputs, **props)
        color = t.split(t.out(n, "Color"))
        return t.pack(color[0], color[2], t.out(n, "Fac"))
    return f


def _late_cases():
    """Cases added after the grid was laid out, appended last so that no
    other tile moves (a tile's place shifts where its inputs' steep parts
    land against the pixel grid)."""
    return [Case("brick_squash_0", "ShaderNodeTexBrick", _brick(True, 0.0))]


def _texture_cases():
    def w_input(t):
        return t.lin(1.3, 0.7, 0.25)

    def vector_input(t, dims, span=1.5):
        return t.tex_coords(span, z=(0.4, 0.3) if dims in ('3D', '4D') else (0.0, 0.0))

    def noise(dims, detail=2.0, roughness=0.5, distortion=0.0, implicit=False):
        def f(t):
            inputs = {"Scale": 3.0, "Detail": detail, "Roughness": roughness, "Distortion": distortion}
            if dims in ('1D', '4D'):
                inputs["W"] = w_input(t)
            if dims != '1D' and not implicit:
                inputs["Vector"] = vector_input(t, dims)
            return t.out(t.node("ShaderNodeTexNoise", inputs, noise_dimensions=dims), "Color")
        return f

    def voronoi(dims, feature, metric='EUCLIDEAN'):
        def f(t):
            inputs = {"Scale": 4.0, "Smoothness": 0.6, "Exponent": 1.5, "Randomness": 0.9}
            if dims in ('1D', '4D'):
                inputs["W"] = w_input(t)
            if dims != '1D':
                inputs["Vector"] = vector_input(t, dims, 1.2)
            n = t.node("ShaderNodeTexVoronoi", inputs, voronoi_dimensions=dims, feature=feature, distance=metric)
            if feature == 'DISTANCE_TO_EDGE':
                return t.out(n, "Distance")
            if feature == 'N_SPHERE_RADIUS':
                return t.out(n, "Radius")
            third = t.out(n, "W") if dims in ('1D', '4D') else t.split(t.out(n, "Position"))[0]
            return t.pack(t.out(n, "Distance"), t.split(t.out(n, "Color"))[1], third)
        return f

    def musgrave(kind, dims='3D'):
        def f(t):
            inputs = {"Scale": 2.5, "Detail": 4.0, "Dimension": 1.5, "Lacunarity": 2.1, "Offset": 0.8, "Gain": 1.2}
            if dims in ('1D', '4D'):
                inputs["W"] = w_input(t)
            if dims != '1D':
                inputs["Vector"] = vector_input(t, dims)
            return t.out(t.node("ShaderNodeTexMusgrave", inputs, musgrave_dimensions=dims, musgrave_type=kind))
        return f

    def wave(kind, direction, profile, distortion=0.0, detail=0.0):
        def f(t):
            props = {"wave_type": kind, "wave_profile": profile,
                     ("bands_direction" if kind == 'BANDS' else "rings_direction"): direction}
            return t.out(t.node("ShaderNodeTexWave", {
                "Vector": t.tex_coords(1.0, z=(0.6, 0.4)), "Scale": 3.0, "Distortion": distortion,
                "Detail": detail, "Detail Scale": 1.5, "Detail Roughness": 0.6, "Phase Offset": 0.4},
                **props), "Fac")
        return f

    def checker(t):
        return t.out(t.node("ShaderNodeTexChecker", {
            "Vector": t.tex_coords(1.0, z=(0.3, 0.2)), "Color1": (0.8, 0.2, 0.1), "Color2": (0.1, 0.3, 0.7),
            "Scale": 3.0}), "Color")

    brick = _brick

    def gradient(kind):
        def f(t):
            vec = t.field((2.4, 0, 0.5), (0, 2.4, 0), (-1.2, -1.2, -0.2))
            return t.out(t.node("ShaderNodeTexGradient", {"Vector": vec}, gradient_type=kind), "Fac")
        return f

    def magic(depth, distortion):
        def f(t):
            return t.out(t.node("ShaderNodeTexMagic", {
                "Vector": t.tex_coords(1.0, z=(0.3, 0.5)), "Scale": 3.0, "Distortion": distortion},
                turbulence_depth=depth), "Color")
        return f

    def white_noise(dims):
        # Hashes of the float bits: inputs are whole numbers (floor of a field),
        # so both renderers hash exactly the same values.
        def f(t):
            inputs = {}
            if dims in ('1D', '4D'):
                inputs["W"] = t.out(t.node("ShaderNodeMath", {"Value": t.lin(6.0, 2.3, 0.1)}, operation='FLOOR'))
            if dims != '1D':
                inputs["Vector"] = t.out(t.node("ShaderNodeVectorMath", {
                    "Vector": t.field((6, 0, 0), (0, 6, 0), (-2.9, -3.1, 1.5))}, operation='FLOOR'))
            n = t.node("ShaderNodeTexWhiteNoise", inputs, noise_dimensions=dims)
            color = t.split(t.out(n, "Color"))
            return t.pack(t.out(n, "Value"), color[1], color[2])
        return f

    cases = [Case(f"noise_{d.lower()}", "ShaderNodeTexNoise", noise(d)) for d in ('1D', '2D', '3D', '4D')]
    cases += [Case("noise_3d_detail_distortion", "ShaderNodeTexNoise", noise('3D', 6.0, 0.55, 1.5)),
              Case("noise_3d_no_detail", "ShaderNodeTexNoise", noise('3D', 0.0)),
              Case("noise_2d_fractional_detail", "ShaderNodeTexNoise", noise('2D', 2.5, 0.7)),
              Case("noise_3d_implicit_generated", "ShaderNodeTexNoise", noise('3D', implicit=True))]
    voronoi_set = [('1D', 'F1', 'EUCLIDEAN'), ('1D', 'SMOOTH_F1', 'EUCLIDEAN'), ('1D', 'DISTANCE_TO_EDGE', 'EUCLIDEAN'),
                   ('2D', 'F1', 'EUCLIDEAN'), ('2D', 'F2', 'MANHATTAN'), ('2D', 'SMOOTH_F1', 'CHEBYCHEV'),
                   ('2D', 'DISTANCE_TO_EDGE', 'EUCLIDEAN'), ('2D', 'N_SPHERE_RADIUS', 'EUCLIDEAN'),
                   ('2D', 'F1', 'MINKOWSKI'),
                   ('3D', 'F1', 'EUCLIDEAN'), ('3D', 'F1', 'MANHATTAN'), ('3D', 'F1', 'CHEBYCHEV'),
                   ('3D', 'F1', 'MINKOWSKI'), ('3D', 'F2', 'EUCLIDEAN'), ('3D', 'SMOOTH_F1', 'EUCLIDEAN'),
                   ('3D', 'DISTANCE_TO_EDGE', 'EUCLIDEAN'), ('3D', 'N_SPHERE_RADIUS', 'EUCLIDEAN'),
                   ('4D', 'F1', 'EUCLIDEAN'), ('4D', 'F2', 'MINKOWSKI'), ('4D', 'SMOOTH_F1', 'MANHATTAN'),
                   ('4D', 'DISTANCE_TO_EDGE', 'EUCLIDEAN'), ('4D', 'N_SPHERE_RADIUS', 'EUCLIDEAN')]
    for d, feat, metric in voronoi_set:
        name = f"voronoi_{d.lower()}_{feat.lower()}" + ("" if metric == 'EUCLIDEAN' else f"_{metric.lower()}")
        cases.append(Case(name, "ShaderNodeTexVoronoi", voronoi(d, feat, metric)))
    cases += [Case(f"musgrave_{k.lower()}", "ShaderNodeTexMusgrave", musgrave(k))
              for k in ('FBM', 'MULTIFRACTAL', 'RIDGED_MULTIFRACTAL', 'HYBRID_MULTIFRACTAL', 'HETERO_TERRAIN')]
    cases += [Case("musgrave_fbm_2d", "ShaderNodeTexMusgrave", musgrave('FBM', '2D')),
              Case("musgrave_multifractal_4d", "ShaderNodeTexMusgrave", musgrave('MULTIFRACTAL', '4D'))]
    for kind, direction, profile in [('BANDS', 'X', 'SIN'), ('BANDS', 'Y', 'SAW'), ('BANDS', 'Z', 'TRI'),
                                     ('BANDS', 'DIAGONAL', 'SIN'), ('RINGS', 'X', 'TRI'), ('RINGS', 'Y', 'SIN'),
                                     ('RINGS', 'Z', 'SAW'), ('RINGS', 'SPHERICAL', 'SIN')]:
        cases.append(Case(f"wave_{kind.lower()}_{direction.lower()}_{profile.lower()}", "ShaderNodeTexWave",
                          wave(kind, direction, profile)))
    cases.append(Case("wave_bands_x_sin_distorted", "ShaderNodeTexWave", wave('BANDS', 'X', 'SIN', 4.0, 3.0)))
    cases += [Case("checker", "ShaderNodeTexChecker", checker),
              Case("brick", "ShaderNodeTexBrick", brick(False)),
              Case("brick_offset_squash", "ShaderNodeTexBrick", brick(True))]
    cases += [Case(f"gradient_{k.lower()}", "ShaderNodeTexGradient", gradient(k))
              for k in ('LINEAR', 'QUADRATIC', 'EASING', 'DIAGONAL', 'SPHERICAL', 'QUADRATIC_SPHERE', 'RADIAL')]
    cases += [Case("magic_depth2", "ShaderNodeTexMagic", magic(2, 1.0)),
              Case("magic_depth5", "ShaderNodeTexMagic", magic(5, 1.2))]
    cases += [Case(f"white_noise_{d.lower()}", "ShaderNodeTexWhiteNoise", white_noise(d))
              for d in ('1D', '2D', '3D', '4D')]
    return cases


def _image_cases():
    def image(key, interp='Linear', ext='REPEAT', projection='FLAT', vector="field", output="color"):
        def f(t):
            n = t.node("ShaderNodeTexImage", image=t.image(key), interpolation=interp, extension=ext,
                       projection=projection, projection_blend=0.3)
            if vector == "field":     # about [-0.45, 1.45]: texels of 4-5 px, every extension visible
                t.set(n.inputs["Vector"], t.tex_coords(1.6, angle=0.2, offset=(-0.15, -0.45, 0.0)))
            elif vector is not None:
                t.set(n.inputs["Vector"], t.texco(vector))
            if output == "alpha":
                color = t.split(t.out(n, "Color"))
                return t.pack(color[0], color[1], t.out(n, "Alpha"))
            return t.out(n, "Color")
        return f

    cases = []
    for interp in ('Linear', 'Closest', 'Cubic'):
        for ext in ('REPEAT', 'EXTEND', 'CLIP'):
            cases.append(Case(f"image_{interp.lower()}_{ext.lower()}", "ShaderNodeTexImage",
                              image("srgb", interp, ext)))
    cases += [Case("image_smart_repeat", "ShaderNodeTexImage", image("srgb", 'Smart')),
              Case("image_png_non_color", "ShaderNodeTexImage", image("non_color")),
              Case("image_exr_float", "ShaderNodeTexImage", image("exr")),
              Case("image_exr_float_cubic_extend", "ShaderNodeTexImage", image("exr", 'Cubic', 'EXTEND')),
              Case("image_png_rgba_color", "ShaderNodeTexImage", image("rgba")),
              Case("image_png_rgba_alpha", "ShaderNodeTexImage", image("rgba", output="alpha")),
              Case("image_implicit_uv", "ShaderNodeTexImage", image("srgb", 'Closest', vector=None)),
              Case("image_projection_box", "ShaderNodeTexImage", image("srgb", projection='BOX', vector="Object"),
                   shape="sphere"),
              Case("image_projection_sphere", "ShaderNodeTexImage",
                   image("srgb", projection='SPHERE', vector="Object")),
              Case("image_projection_tube", "ShaderNodeTexImage", image("srgb", projection='TUBE', vector="Object"))]
    return cases


def _rotate_z_90(ob):
    ob.rotation_euler[2] = math.pi / 2


def _turn_and_squash(ob):
    ob.rotation_euler = (0.0, 0.0, 0.6)
    ob.scale = (1.0, 1.0, 0.7)


def _input_cases():
    def texco(output, with_object=False):
        return lambda t: t.texco(output, t.probes.reference_object if with_object else None)

    def uv_map(name):
        return lambda t: t.out(t.node("ShaderNodeUVMap", uv_map=name))

    def mapping(kind):
        def f(t):
            return t.out(t.node("ShaderNodeMapping", {
                "Vector": t.vec_a(), "Location": (0.3, -0.2, 0.5), "Rotation": (0.4, -0.3, 0.9),
                "Scale": (1.5, 0.7, -1.2)}, vector_type=kind))
        return f

    def output_of(idname, output, **props):
        return lambda t: t.out(t.node(idname, **props), output)

    def light_path(*outputs):
        def f(t):
            n = t.node("ShaderNodeLightPath")
            return t.pack(*(t.out(n, o) for o in outputs))
        return f

    def set_object_info(ob):
        ob.color = (0.3, 0.6, 0.9, 0.45)
        ob.pass_index = 7
        ob.active_material.pass_index = 3

    def value(v):
        def f(t):
            n = t.node("ShaderNodeValue")
            n.outputs[0].default_value = v
            return t.out(n)
        return f

    def rgb(t):
        n = t.node("ShaderNodeRGB")
        n.outputs[0].default_value = (*RGB_SANITY, 1.0)
        return t.out(n)

    geometry = "ShaderNodeNewGeometry"
    info = "ShaderNodeObjectInfo"
    return [
        Case("tex_coord_generated", "ShaderNodeTexCoord", texco("Generated"), setup=_rotate_z_90),
        Case("tex_coord_normal", "ShaderNodeTexCoord", texco("Normal"), shape="sphere", setup=_turn_and_squash),
        Case("tex_coord_uv", "ShaderNodeTexCoord", texco("UV")),
        Case("tex_coord_object", "ShaderNodeTexCoord", texco("Object"), setup=_rotate_z_90),
        Case("tex_coord_object_from_empty", "ShaderNodeTexCoord", texco("Object", True)),
        Case("tex_coord_camera", "ShaderNodeTexCoord", texco("Camera")),
        Case("tex_coord_window", "ShaderNodeTexCoord", texco("Window")),
        Case("tex_coord_reflection", "ShaderNodeTexCoord", texco("Reflection"), shape="sphere"),
        Case("uv_map_default", "ShaderNodeUVMap", uv_map("")),
        Case("uv_map_named", "ShaderNodeUVMap", uv_map("UVAlt")),
        *(Case(f"mapping_{k.lower()}", "ShaderNodeMapping", mapping(k))
          for k in ('POINT', 'TEXTURE', 'VECTOR', 'NORMAL')),
        Case("geometry_position", geometry, output_of(geometry, "Position")),
        Case("geometry_normal", geometry, output_of(geometry, "Normal"), shape="sphere", setup=_turn_and_squash),
        Case("geometry_tangent", geometry, output_of(geometry, "Tangent"), shape="sphere"),
        # Exact per facet; ~1 % of the sphere's pixel centres lie within Cycles'
        # 0.005 px jitter of a facet edge and see the neighbour, where Cycles'
        # per-pixel seed decides: its mean error sits near the limit (8.2e-4 in
        # the 323-case layout, 1.1e-3 in the 321-case one).
        Case("geometry_true_normal", geometry, output_of(geometry, "True Normal"), shape="sphere"),
        Case("geometry_incoming", geometry, output_of(geometry, "Incoming")),
        Case("geometry_parametric", geometry, output_of(geometry, "Parametric")),
        Case("geometry_backfacing", geometry, output_of(geometry, "Backfacing"),
             setup=lambda ob: setattr(ob, "rotation_euler", (math.pi, 0.0, 0.0))),
        Case("geometry_pointiness", geometry, output_of(geometry, "Pointiness"), shape="sphere"),
        Case("geometry_random_per_island", geometry, output_of(geometry, "Random Per Island")),
        Case("geometry_random_per_island_islands", geometry, output_of(geometry, "Random Per Island"),
             shape="islands"),
        Case("geometry_pointiness_grid", geometry, output_of(geometry, "Pointiness"), shape="grid"),
        *(Case(f"object_info_{o.lower().replace(' ', '_')}", info, output_of(info, o), setup=set_object_info)
          for o in ("Location", "Color", "Alpha", "Object Index", "Material Index", "Random")),
        Case("layer_weight_fresnel", "ShaderNodeLayerWeight",
             output_of("ShaderNodeLayerWeight", "Fresnel"), shape="sphere"),
        Case("layer_weight_facing", "ShaderNodeLayerWeight",
             output_of("ShaderNodeLayerWeight", "Facing"), shape="sphere"),
        Case("layer_weight_blend_varying", "ShaderNodeLayerWeight",
             lambda t: t.out(t.node("ShaderNodeLayerWeight", {"Blend": t.floats((0.05, 0.95))[0]}), "Fresnel"),
             shape="sphere"),
        Case("fresnel", "ShaderNodeFresnel", output_of("ShaderNodeFresnel", "Fac"), shape="sphere"),
        Case("fresnel_ior_varying", "ShaderNodeFresnel",
             lambda t: t.out(t.node("ShaderNodeFresnel", {"IOR": t.floats((1.05, 2.5))[0]})), shape="sphere"),
        Case("light_path_camera_shadow_diffuse", "ShaderNodeLightPath",
             light_path("Is Camera Ray", "Is Shadow Ray", "Is Diffuse Ray")),
        Case("light_path_glossy_singular_reflection", "ShaderNodeLightPath",
             light_path("Is Glossy Ray", "Is Singular Ray", "Is Reflection Ray")),
        Case("light_path_transmission_depths", "ShaderNodeLightPath",
             light_path("Is Transmission Ray", "Ray Depth", "Diffuse Depth")),
        Case("light_path_more_depths", "ShaderNodeLightPath",
             light_path("Glossy Depth", "Transparent Depth", "Transmission Depth")),
        Case("light_path_ray_length", "ShaderNodeLightPath", output_of("ShaderNodeLightPath", "Ray Length")),
        Case("value", "ShaderNodeValue", value(0.37)),
        Case("value_negative", "ShaderNodeValue", value(-0.5)),
        Case(RGB_SANITY_CASE, "ShaderNodeRGB", rgb),
    ]


def _attribute_cases():
    def attribute(name, output, kind='GEOMETRY'):
        return lambda t: t.out(t.node("ShaderNodeAttribute", attribute_name=name, attribute_type=kind), output)

    def color_attribute(name, with_alpha):
        def f(t):
            n = t.node("ShaderNodeVertexColor", layer_name=name)
            if not with_alpha:
                return t.out(n, "Color")
            color = t.split(t.out(n, "Color"))
            return t.pack(color[0], color[1], t.out(n, "Alpha"))
        return f

    def tint(ob):
        ob["probe_tint"] = (0.2, 0.5, 0.8)

    a, c = "ShaderNodeAttribute", "ShaderNodeVertexColor"
    return [Case("attribute_point_color", a, attribute("probe_point", "Color"), shape="grid"),
            Case("attribute_point_alpha", a, attribute("probe_point", "Alpha"), shape="grid"),
            Case("attribute_corner_byte_color", a, attribute("probe_corner", "Color"), shape="grid"),
            Case("attribute_float", a, attribute("probe_float", "Fac"), shape="grid"),
            Case("attribute_vector", a, attribute("probe_vector", "Vector"), shape="grid"),
            Case("attribute_uv_by_name", a, attribute("UVAlt", "Vector"), shape="grid"),
            Case("attribute_object_property", a, attribute("probe_tint", "Color", 'OBJECT'), setup=tint),
            Case("color_attribute_default", c, color_attribute("", False), shape="grid"),
            Case("color_attribute_corner_alpha", c, color_attribute("probe_corner", True), shape="grid")]


def _vector_cases():
    def rotate(kind, invert=False):
        def f(t):
            angle, _ = t.floats((-1.5, 2.0))
            return t.out(t.node("ShaderNodeVectorRotate", {
                "Vector": t.vec_a(), "Center": (0.2, -0.1, 0.3), "Axis": (0.3, 0.5, 0.8), "Angle": angle,
                "Rotation": (0.3, -0.5, 0.9)}, rotation_type=kind, invert=invert))
        return f

    def transform(kind, src, dst):
        return lambda t: t.out(t.node("ShaderNodeVectorTransform", {"Vector": t.vec_a()},
                                      vector_type=kind, convert_from=src, convert_to=dst))

    def camera_data(t):
        n = t.node("ShaderNodeCameraData")
        return t.pack(t.out(n, "View Z Depth"), t.out(n, "View Distance"), t.split(t.out(n, "View Vector"))[2])

    def normal_dot(t):
        n = t.node("ShaderNodeNormal", {"Normal": t.out(t.node("ShaderNodeNewGeometry"), "Normal")})
        n.outputs["Normal"].default_value = Vector((0.3, 0.5, 0.81)).normalized()
        return t.out(n, "Dot")

    def tangent(kind):
        return lambda t: t.out(t.node("ShaderNodeTangent", direction_type=kind, axis='Z'))

    rot = "ShaderNodeVectorRotate"
    vt = "ShaderNodeVectorTransform"
    return [*(Case(f"vector_rotate_{k.lower()}", rot, rotate(k))
              for k in ('AXIS_ANGLE', 'X_AXIS', 'Y_AXIS', 'Z_AXIS', 'EULER_XYZ')),
            Case("vector_rotate_axis_angle_invert", rot, rotate('AXIS_ANGLE', True)),
            Case("vector_transform_point_object_world", vt, transform('POINT', 'OBJECT', 'WORLD'),
                 shape="sphere", setup=_turn_and_squash),
            Case("vector_transform_vector_world_camera", vt, transform('VECTOR', 'WORLD', 'CAMERA')),
            Case("vector_transform_normal_object_camera", vt, transform('NORMAL', 'OBJECT', 'CAMERA'),
                 shape="sphere", setup=_turn_and_squash),
            Case("camera_data", "ShaderNodeCameraData", camera_data),
            Case("normal_dot", "ShaderNodeNormal", normal_dot, shape="sphere"),
            Case("tangent_radial_z", "ShaderNodeTangent", tangent('RADIAL'), shape="sphere"),
            Case("tangent_uv_map", "ShaderNodeTangent", tangent('UV_MAP'), shape="sphere"),
            Case("tangent_uv_map_turned", "ShaderNodeTangent", tangent('UV_MAP'), shape="sphere",
                 setup=_turn_and_squash),
            Case("tangent_uv_map_ngon", "ShaderNodeTangent", tangent('UV_MAP'), shape="ngon")]


def _normal_cases():
    def normal_map(space, strength=0.8):
        def f(t):
            color = t.field((0.5, 0, 0), (0, 0.5, 0), (0.25, 0.25, 0.85))
            return t.out(t.node("ShaderNodeNormalMap", {"Strength": strength, "Color": color}, space=space))
        return f

    def bump(height, invert=False, strength=1.0, distance=0.1):
        def f(t):
            if height == "noise":
                h = t.out(t.node("ShaderNodeTexNoise", {"Vector": t.texco("Object"), "Scale": 3.0, "Detail": 1.0}),
                          "Fac")
            elif height == "wave":
                h = t.out(t.node("ShaderNodeTexWave", {"Vector": t.texco("Object"), "Scale": 2.0}), "Fac")
            else:   # from the UV coordinates: sin(12 u) * 0.5
                h = t.out(t.node("ShaderNodeMath", {"Value": t.lin(12.0, 3.0), "Value_001": 0.5},
                                 operation='SINE'))
            return t.out(t.node("ShaderNodeBump", {"Strength": strength, "Distance": distance, "Height": h},
                                invert=invert))
        return f

    nm = "ShaderNodeNormalMap"
    return [Case("normal_map_tangent", nm, normal_map('TANGENT'), shape="sphere"),
            Case("normal_map_tangent_turned", nm, normal_map('TANGENT'), shape="sphere", setup=_turn_and_squash),
            Case("normal_map_tangent_strength_2", nm, normal_map('TANGENT', 2.0), shape="sphere"),
            Case("normal_map_tangent_ngon", nm, normal_map('TANGENT'), shape="ngon"),
            Case("normal_map_object", nm, normal_map('OBJECT'), shape="sphere", setup=_turn_and_squash),
            Case("normal_map_world", nm, normal_map('WORLD'), shape="sphere"),
            Case("normal_map_blender_object", nm, normal_map('BLENDER_OBJECT'), shape="sphere",
                 setup=_turn_and_squash),
            Case("normal_map_blender_world", nm, normal_map('BLENDER_WORLD'), shape="sphere"),
            Case("bump_noise_sphere", "ShaderNodeBump", bump("noise"), shape="sphere"),
            Case("bump_wave_plane_invert", "ShaderNodeBump", bump("wave", True, 0.7, 0.3)),
            Case("bump_uv_sine_plane", "ShaderNodeBump", bump("uv", False, 1.0, 0.05))]


RGB_SANITY = (0.2, 0.5, 0.8)
def _proxy_cases():
    """Inputs with a default link (Normal, texture Vector) reached only
    through a group input left unlinked on the group node, or through an
    unconnected reroute: Cycles removes such proxies before it links default
    inputs, so they read the geometry normal / texture coordinates, not the
    value the group socket shows (library material 'Fresnel')."""
    def group_of(kind, inner):
        """A group whose input socket of ``kind`` feeds ``inner(group_tree,
        socket) -> output socket``; the group node's input keeps its default."""
        def f(t):
            tree = bpy.data.node_groups.new(f"probe group {kind}", "ShaderNodeTree")
            gin = tree.nodes.new("NodeGroupInput")
            gout = tree.nodes.new("NodeGroupOutput")
            tree.inputs.new(kind, "In")
            tree.outputs.new("NodeSocketColor", "Out")
            result = inner(tree, gin.outputs[0])
            tree.links.new(result, gout.inputs[0])
            node = t.node("ShaderNodeGroup", node_tree=tree)
            node.inputs[0].default_value = (0.0, 0.0, 0.0) if kind == "NodeSocketVector" else 0.25
            return t.out(node)
        return f

    def layer_weight(tree, sock):
        n = tree.nodes.new("ShaderNodeLayerWeight")
        tree.links.new(sock, n.inputs["Normal"])
        return n.outputs["Fresnel"]

    def noise(tree, sock):
        n = tree.nodes.new("ShaderNodeTexNoise")
        n.inputs["Scale"].default_value = 3.3
        tree.links.new(sock, n.inputs["Vector"])
        return n.outputs["Fac"]

    def reroute_normal(t):
        r = t.node("NodeReroute")
        n = t.node("ShaderNodeFresnel")
        t.links.new(r.outputs[0], n.inputs["Normal"])
        return t.out(n)

    return [
        Case("group_input_to_layer_weight_normal", "ShaderNodeLayerWeight",
             group_of("NodeSocketVector", layer_weight), shape="sphere"),
        Case("group_float_input_to_layer_weight_normal", "ShaderNodeLayerWeight",
             group_of("NodeSocketFloat", layer_weight), shape="sphere"),
        Case("group_input_to_noise_vector", "ShaderNodeTexNoise", group_of("NodeSocketVector", noise)),
        Case("reroute_to_fresnel_normal", "ShaderNodeFresnel", reroute_normal, shape="sphere"),
    ]


RGB_SANITY_CASE = "rgb"   # Cycles must show exactly RGB_SANITY on this tile


def all_cases():
    cases = (_math_cases() + _vector_math_cases() + _clamp_map_range_cases() + _mix_cases() + _mix_rgb_cases()
             + _color_cases() + _separate_combine_cases() + _ramp_curve_cases() + _converter_cases()
             + _texture_cases() + _image_cases() + _input_cases() + _attribute_cases() + _vector_cases()
             + _normal_cases() + _proxy_cases() + _late_cases())
    names = [c.name for c in cases]
    dup = {n for n in names if names.count(n) > 1}
    assert not dup, f"duplicate case names: {dup}"
    return cases


# ---------------------------------------------------------------------------
# the scene: meshes, images, materials, camera
# ---------------------------------------------------------------------------

IMAGE_SIZE = (5, 4)   # texels (width, height); not square, so a swapped axis shows


def _texel_grid(channels):
    w, h = IMAGE_SIZE
    i, j, c = np.meshgrid(np.arange(w), np.arange(h), np.arange(channels), indexing="xy")
    return i, j, c


def _write_images(directory):
    """{key: path} of the image files the image cases read (row 0 = top)."""
    oiio = U._oiio()
    i, j, c = _texel_grid(3)
    srgb = ((53 * i + 97 * j + 71 * c + 17) % 256).astype(np.uint8)
    i4, j4, c4 = _texel_grid(4)
    rgba = ((41 * i4 + 89 * j4 + 67 * c4 + 29) % 256).astype(np.uint8)
    rgba[..., 3] = 60 + 45 * ((i4[..., 3] + 2 * j4[..., 3]) % 5)
    exr = (((0.37 * i + 0.61 * j + 0.23 * c) % 1.0) * 2.5 - 0.2).astype(np.float32)
    paths = {}
    for key, pixels, ext, fmt in (("srgb", srgb, "png", oiio.UINT8), ("rgba", rgba, "png", oiio.UINT8),
                                  ("exr", exr, "exr", oiio.FLOAT)):
        path = os.path.join(directory, f"probe_{key}.{ext}")
        out = oiio.ImageOutput.create(path)
        h, w, ch = pixels.shape
        if not out or not out.open(path, oiio.ImageSpec(w, h, ch, fmt)) or not out.write_image(pixels):
            raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
        out.close()
        paths[key] = path
    return paths


def _plane_mesh():
    """A 1 m square at the origin facing +Z, UV maps "UVMap" (0..1) and "UVAlt"."""
    me = bpy.data.meshes.new("probe_plane")
    me.from_pydata([(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.5, 0.5, 0), (-0.5, 0.5, 0)], [], [(0, 1, 2, 3)])
    _add_uv_maps(me)
    return me


def _islands_mesh():
    """Four separate quads (four mesh islands) in the 1 m square, 4 px apart,
    their edges on pixel boundaries; vertex and face orders differ per island
    so that Cycles' disjoint-set roots (what Random Per Island hashes) do too."""
    verts, faces = [], []
    for k, (x0, y0) in enumerate(((-0.5, -0.5), (0.0625, -0.5), (-0.5, 0.0625), (0.0625, 0.0625))):
        x1, y1 = x0 + 0.4375, y0 + 0.4375
        quad = [(x0, y0, 0.0), (x1, y0, 0.0), (x1, y1, 0.0), (x0, y1, 0.0)]
        base = len(verts)
        if k % 2:
            verts += quad[::-1]
            faces.append((base + 3, base + 2, base + 1, base))
        else:
            verts += quad
            faces.append((base, base + 1, base + 2, base + 3))
    me = bpy.data.meshes.new("probe_islands")
    me.from_pydata(verts, [], faces)
    _add_uv_maps(me)
    return me


def _ngon_mesh():
    """The 1 m square as ONE 12-gon (three vertices a side), its UV map warped
    so the triangles Blender splits it into (its loop triangles, which both
    engines render) have different UV gradients: tangents on an n-gon, which
    Blender's Mesh.calc_tangents refuses."""
    s = (-0.5, -1 / 6, 1 / 6)
    ring = [(x, -0.5) for x in s] + [(0.5, y) for y in s] + [(-x, 0.5) for x in s] + [(-0.5, -y) for y in s]
    me = bpy.data.meshes.new("probe_ngon")
    me.from_pydata([(x, y, 0.0) for x, y in ring], [], [tuple(range(len(ring)))])
    _add_uv_maps(me)
    co = np.array([me.vertices[loop.vertex_index].co[:2] for loop in me.loops]) + 0.5
    warped = np.stack([co[:, 0] + 0.12 * np.sin(3.0 * co[:, 1]), co[:, 1] + 0.15 * co[:, 0] ** 2], -1)
    me.uv_layers["UVMap"].data.foreach_set("uv", warped.ravel())
    return me


def _add_uv_maps(me):
    co = np.array([me.vertices[loop.vertex_index].co[:2] for loop in me.loops]) + 0.5
    main, alt = me.uv_layers.new(name="UVMap"), me.uv_layers.new(name="UVAlt")
    main.data.foreach_set("uv", co.ravel())
    alt.data.foreach_set("uv", np.stack([1.2 * (1 - co[:, 1]) + 0.2, 0.9 * co[:, 0] - 0.1], -1).ravel())
    me.uv_layers.active = main
    main.active_render = True


def _sphere_mesh():
    import bmesh
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")
    bmesh.ops.create_uvsphere(bm, u_segments=32, v_segments=16, radius=0.5, calc_uvs=True)
    me = bpy.data.meshes.new("probe_sphere")
    bm.to_mesh(me)
    bm.free()
    me.polygons.foreach_set("use_smooth", [True] * len(me.polygons))
    return me


def _grid_mesh(n=4):
    """A 1 m square of n x n quads with point, corner, float and vector attributes."""
    s = np.linspace(-0.5, 0.5, n + 1)
    verts = [(x, y, 0.0) for y in s for x in s]
    faces = [(r * (n + 1) + c, r * (n + 1) + c + 1, (r + 1) * (n + 1) + c + 1, (r + 1) * (n + 1) + c)
             for r in range(n) for c in range(n)]
    me = bpy.data.meshes.new("probe_grid")
    me.from_pydata(verts, [], faces)
    _add_uv_maps(me)
    x, y = np.array(verts)[:, 0], np.array(verts)[:, 1]
    point = me.color_attributes.new("probe_point", 'FLOAT_COLOR', 'POINT')
    point.data.foreach_set("color", np.stack([x + 0.5, y + 0.5, 0.5 + 0.4 * np.sin(3 * x + 2 * y),
                                              0.3 + 0.7 * (x + 0.5)], -1).ravel())
    corner = me.color_attributes.new("probe_corner", 'BYTE_COLOR', 'CORNER')
    k = np.arange(len(me.loops))[:, None] * 4 + np.arange(4)
    corner.data.foreach_set("color_srgb", (((37 * k + 61 * (k // 4) + 11) % 256) / 255.0).ravel())
    me.attributes.new("probe_float", 'FLOAT', 'POINT').data.foreach_set(
        "value", 2 * (x + 0.5) * (y + 0.5) - 0.3 + 0.2 * np.sin(5 * x))
    me.attributes.new("probe_vector", 'FLOAT_VECTOR', 'POINT').data.foreach_set(
        "vector", np.stack([2 * x, 3 * y - 0.5, 4 * x * y], -1).ravel())
    colors = me.color_attributes
    colors.active_color = colors["probe_point"]
    colors.render_color_index = list(colors).index(colors["probe_point"])
    return me


class Metrics(NamedTuple):
    max: float
    mean: float
    p99: float


class ProbeScene:
    """All cases in one new scene (made the window's scene), one tile each."""

    def __init__(self, cases, image_dir):
        self.cases = list(cases)
        n = len(self.cases)
        self.cols = math.ceil(math.sqrt(n))
        self.rows = math.ceil(n / self.cols)
        pitch = TILE + GAP
        self.width, self.height = self.cols * pitch, self.rows * pitch
        self.image_paths = _write_images(image_dir)
        self._images = {}
        self.build_errors = {}      # case name -> exception text
        self.scene = bpy.data.scenes.new("NodeProbes")
        self.activate()
        self._configure()
        self.reference_object = bpy.data.objects.new("probe_reference_space", None)
        self.reference_object.location = (0.7, -0.4, 0.3)
        self.reference_object.rotation_euler = (0.2, -0.3, 0.8)
        self.reference_object.scale = (1.5, 0.8, 1.2)
        self.scene.collection.objects.link(self.reference_object)
        meshes = {"plane": _plane_mesh(), "sphere": _sphere_mesh(), "grid": _grid_mesh(), "ngon": _ngon_mesh(),
                  "islands": _islands_mesh()}
        self.tiles = []             # (x0, y0): the tile's bottom-left pixel, rows from the bottom
        self.masks = {}
        for index, case in enumerate(self.cases):
            col, row = index % self.cols, index // self.cols
            x0 = col * pitch + GAP // 2
            y0 = self.height - (row * pitch + GAP // 2) - TILE
            self.tiles.append((x0, y0))
            ob = bpy.data.objects.new(f"probe_{case.name}", meshes[case.shape].copy())
            ob.location = ((x0 + TILE / 2 - self.width / 2) / TILE, (y0 + TILE / 2 - self.height / 2) / TILE, 0.0)
            ob.data.materials.append(self._material(case))
            self.scene.collection.objects.link(ob)
            if case.setup:
                case.setup(ob)
        for me in meshes.values():
            bpy.data.meshes.remove(me)

    def activate(self):
        bpy.context.window.scene = self.scene

    def _configure(self):
        scene = self.scene
        world = bpy.data.worlds.new("probe_world")
        world.use_nodes = False
        world.color = (0.0, 0.0, 0.0)
        scene.world = world
        cam = bpy.data.cameras.new("probe_camera")
        cam.type = 'ORTHO'
        cam.ortho_scale = max(self.width, self.height) / TILE
        cam.clip_start, cam.clip_end = CLIP_START, 100.0
        self.camera = bpy.data.objects.new("probe_camera", cam)
        self.camera.location = (0.0, 0.0, CAMERA_Z)
        scene.collection.objects.link(self.camera)
        scene.camera = self.camera
        r = scene.render
        r.resolution_x, r.resolution_y, r.resolution_percentage = self.width, self.height, 100
        r.pixel_aspect_x = r.pixel_aspect_y = 1.0
        r.film_transparent = False
        r.use_border = False
        scene.view_settings.view_transform = 'Standard'
        layer = scene.view_layers[0]
        U.set_all_passes(layer, False)
        layer.use_pass_combined = True
        cy = scene.cycles
        cy.device = 'CPU'
        cy.samples = 1
        cy.use_adaptive_sampling = False
        cy.max_bounces = 0
        cy.pixel_filter_type = 'BLACKMAN_HARRIS'
        cy.filter_width = 0.01        # the one sample at the pixel centre
        cy.use_denoising = False
        cy.seed = 0
        if hasattr(scene, "deferred_render"):
            scene.deferred_render.samples = 1   # sample 0: unjittered, at the pixel centre

    def image(self, key):
        """The bpy image for an image case ("srgb", "non_color", "rgba", "exr")."""
        if key not in self._images:
            img = bpy.data.images.load(self.image_paths["srgb" if key == "non_color" else key], check_existing=False)
            if key == "non_color":
                img.colorspace_settings.name = 'Non-Color'
            self._images[key] = img
        return self._images[key]

    def _material(self, case):
        mat = bpy.data.materials.new(f"probe_{case.name}")
        mat.use_nodes = True
        mat.cycles.sample_as_light = False
        nodes, links = mat.node_tree.nodes, mat.node_tree.links
        nodes.clear()
        output = nodes.new("ShaderNodeOutputMaterial")
        emission = nodes.new("ShaderNodeEmission")
        emission.inputs["Strength"].default_value = 1.0
        links.new(emission.outputs["Emission"], output.inputs["Surface"])
        try:
            links.new(case.build(Tree(self, mat)), emission.inputs["Color"])
        except Exception as ex:     # one broken case must not stop the others
            import traceback
            traceback.print_exc()
            self.build_errors[case.name] = f"{type(ex).__name__}: {ex}"
            emission.inputs["Color"].default_value = (1.0, 0.0, 1.0, 1.0)
        return mat

    def tile_mask(self, case):
        if case.shape not in self.masks:
            c = np.arange(TILE) + 0.5
            x, y = np.meshgrid(c, c)
            if case.shape == "sphere":   # the 32-gon's silhouette stays outside this circle
                mask = np.hypot(x - TILE / 2, y - TILE / 2) <= TILE / 2 - BORDER - 1
            else:
                mask = ((x > BORDER) & (x < TILE - BORDER) & (y > BORDER) & (y < TILE - BORDER))
            self.masks[case.shape] = mask
        return self.masks[case.shape]

    def tile(self, image, index):
        """(TILE, TILE, C) pixels of case ``index`` (rows from the bottom)."""
        x0, y0 = self.tiles[index]
        return image[y0:y0 + TILE, x0:x0 + TILE]

    def render(self, engine, path_without_ext):
        """Combined RGB (H, W, 3) float64, rows from the bottom."""
        self.activate()
        self.scene.render.engine = engine
        channels = U.read_exr(U.render_exr(path_without_ext, self.scene))
        return U.exr_pass(channels, self.scene.view_layers[0].name, "Combined", "RGB").astype(np.float64)

    def cache_key(self):
        """Hash of the case definitions (this file) and the Blender build."""
        with open(os.path.abspath(__file__), "rb") as f:
            source = f.read()
        return hashlib.sha256(source + bpy.app.version_string.encode() + bpy.app.build_hash).hexdigest()[:16]

    def reference(self, out, use_cache=True):
        """Cycles' Combined, cached as cycles_<key>.npy in ``out``; (image, came from the cache)."""
        path = os.path.join(out, f"cycles_{self.cache_key()}.npy")
        if use_cache and os.path.exists(path):
            return np.load(path).astype(np.float64), True
        image = self.render("CYCLES", os.path.join(out, "cycles"))
        for old in os.listdir(out):
            if old.startswith("cycles_") and old.endswith(".npy"):
                os.remove(os.path.join(out, old))
        np.save(path + ".tmp.npy", image.astype(np.float32))    # what the EXR held
        os.replace(path + ".tmp.npy", path)
        return image, False

    def measure(self, reference, ours):
        """Metrics per case over the tile's interior, all three channels."""
        result = []
        for index, case in enumerate(self.cases):
            mask = self.tile_mask(case)
            a, b = self.tile(reference, index)[mask], self.tile(ours, index)[mask]
            d = np.abs(a - b)
            d[np.isnan(a) & np.isnan(b)] = 0.0
            d[np.isnan(d)] = np.inf
            values = (d.max(), d.mean(), np.percentile(d, 99))
            result.append(Metrics(*(float(v) if np.isfinite(v) else math.inf for v in values)))
        return result

    def moved_camera_reference(self, out, shift_px):
        """Cycles again with every pixel centre moved by shift_px (x and y)."""
        cam = self.camera.data
        saved = cam.shift_x, cam.shift_y
        cam.shift_x += shift_px / max(self.width, self.height)
        cam.shift_y += shift_px / max(self.width, self.height)
        try:
            return self.render("CYCLES", os.path.join(out, "cycles_moved"))
        finally:
            cam.shift_x, cam.shift_y = saved


# ---------------------------------------------------------------------------
# verdicts and the whole run
# ---------------------------------------------------------------------------

def within_limits(case, metrics):
    return all(getattr(metrics, key) <= limit for key, limit in LIMITS[case.tolerance_class].items())


def verdict(case, metrics, build_error=None):
    """"pass", "FAIL", "unsupported" (known, still failing) or "UNEXPECTED PASS"."""
    ok = build_error is None and within_limits(case, metrics)
    if case.name in KNOWN_UNSUPPORTED:
        return "UNEXPECTED PASS" if ok else "unsupported"
    return "pass" if ok else "FAIL"


class ProbeRun(NamedTuple):
    probes: ProbeScene
    reference: np.ndarray
    ours: np.ndarray
    metrics: list
    reference_cached: bool
    seconds: dict            # build, cycles, ours, total


def run(out, use_cache=True, cases=None, engine=U.ENGINE, moved_reference=0.0):
    """Build the scene, get Cycles' image (cached) and ours, measure every case.
    With moved_reference (pixels), "ours" is Cycles with the camera moved by
    that much: how much each case changes under tiny input changes."""
    import tempfile
    os.makedirs(out, exist_ok=True)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="node_probes_") as image_dir:
        probes = ProbeScene(cases or all_cases(), image_dir)
        t1 = time.perf_counter()
        reference, cached = probes.reference(out, use_cache)
        t2 = time.perf_counter()
        if moved_reference:
            ours = probes.moved_camera_reference(out, moved_reference)
        else:
            ours = probes.render(engine, os.path.join(out, "ours"))
        t3 = time.perf_counter()
    metrics = probes.measure(reference, ours)
    seconds = {"build": t1 - t0, "cycles": t2 - t1, "ours": t3 - t2, "total": time.perf_counter() - t0}
    return ProbeRun(probes, reference, ours, metrics, cached, seconds)


def table_rows(result):
    """(case, node, class, max, mean, p99, verdict) per case."""
    probes = result.probes
    return [(case.name, case.node, case.tolerance_class, m.max, m.mean, m.p99,
             verdict(case, m, probes.build_errors.get(case.name)))
            for case, m in zip(probes.cases, result.metrics)]


def failing_only_below_zero(result):
    """Failing cases that would pass if Cycles' negative values were 0: what
    an output path that clamps at zero costs (value_negative shows it)."""
    rows = table_rows(result)
    clamped = result.probes.measure(np.maximum(result.reference, 0.0), result.ours)
    return [row[0] for row, case, m in zip(rows, result.probes.cases, clamped)
            if row[6] == "FAIL" and within_limits(case, m)]


def print_table(result):
    print(f"  {'case':<44} {'node':<26} {'class':<7} {'max abs':>9} {'mean abs':>9} {'p99':>9}  result")
    for name, node, kind, mx, mean, p99, v in table_rows(result):
        print(f"  {name:<44} {node:<26} {kind:<7} {mx:9.2e} {mean:9.2e} {p99:9.2e}  {v}")
    for name, error in result.probes.build_errors.items():
        print(f"  build error in {name}: {error}")
    sys.stdout.flush()


def case_counts(cases):
    """{node bl_idname: number of cases}, in case order."""
    counts = {}
    for case in cases:
        counts[case.node] = counts.get(case.node, 0) + 1
    return counts
