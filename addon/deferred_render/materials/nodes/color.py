"""Node specs of the colour nodes: Mix (3.4), MixRGB, Invert,
Hue/Saturation/Value, Gamma, Bright/Contrast, ColorRamp, RGB Curves,
Vector Curves, Float Curve.

GLSL: shaders/nodes/node_color_lib.glsl. BLEND_TYPES are the ints of the GLSL
NODE_MIX_* #defines (Blender's MA_RAMP_* values, which Cycles' NodeMix uses
too); change both sides together. Socket identifiers are those of Blender
3.4.1.

ColorRamp and the curve nodes are baked into tables exactly as Cycles 3.4
does (intern/cycles/blender/shader.cpp and util.h: colorramp_to_array,
curvemapping_color_to_array, curvemapping_float_to_array, curvemapping_minmax,
RAMP_TABLE_SIZE = 256), with Blender's own evaluate(); the GLSL reproduces the
kernel's table lookup (kernel/svm/ramp.h).
"""

import struct

from . import register

# blend_type -> NODE_MIX_* (node_color_lib.glsl).
BLEND_TYPES = {
    "MIX": 0,
    "ADD": 1,
    "MULTIPLY": 2,
    "SUBTRACT": 3,
    "SCREEN": 4,
    "DIVIDE": 5,
    "DIFFERENCE": 6,
    "DARKEN": 7,
    "LIGHTEN": 8,
    "OVERLAY": 9,
    "DODGE": 10,
    "BURN": 11,
    "HUE": 12,
    "SATURATION": 13,
    "VALUE": 14,
    "COLOR": 15,
    "SOFT_LIGHT": 16,
    "LINEAR_LIGHT": 17,
}

# Entries of a baked ramp or curve table (Cycles' RAMP_TABLE_SIZE; the GLSL
# COLOR_RAMP_TABLE_SIZE).
RAMP_TABLE_SIZE = 256


def _f32(x):
    """x rounded to a 32-bit float, as Cycles' float arithmetic rounds it."""
    return struct.unpack("f", struct.pack("f", x))[0]


@register("ShaderNodeMix")
def mix_node(b):
    node = b.node
    clamp_factor = b.int(int(node.clamp_factor))
    if node.data_type == "FLOAT":
        b.call("node_mix_float",
               [clamp_factor, b.input("Factor_Float", "float"),
                b.input("A_Float", "float"), b.input("B_Float", "float")],
               [("Result_Float", "float")])
    elif node.data_type == "VECTOR":
        if node.factor_mode == "NON_UNIFORM":
            b.call("node_mix_vector_non_uniform",
                   [clamp_factor, b.input("Factor_Vector", "vector"),
                    b.input("A_Vector", "vector"), b.input("B_Vector", "vector")],
                   [("Result_Vector", "vector")])
        else:
            b.call("node_mix_vector",
                   [clamp_factor, b.input("Factor_Float", "float"),
                    b.input("A_Vector", "vector"), b.input("B_Vector", "vector")],
                   [("Result_Vector", "vector")])
    elif node.data_type == "RGBA":
        blend = BLEND_TYPES.get(node.blend_type)
        if blend is None:
            return b.unsupported(f"blend type {node.blend_type}")
        b.call("node_mix_color",
               [b.int(blend), clamp_factor, b.int(int(node.clamp_result)),
                b.input("Factor_Float", "float"),
                b.input("A_Color", "color"), b.input("B_Color", "color")],
               [("Result_Color", "color")])
    else:
        return b.unsupported(f"data type {node.data_type}")


@register("ShaderNodeMixRGB")
def mix_rgb_node(b):
    # use_alpha is ignored, as in Cycles.
    blend = BLEND_TYPES.get(b.node.blend_type)
    if blend is None:
        return b.unsupported(f"blend type {b.node.blend_type}")
    b.call("node_mix_rgb",
           [b.int(blend), b.int(int(b.node.use_clamp)),
            b.input("Fac", "float"), b.input("Color1", "color"), b.input("Color2", "color")],
           [("Color", "color")])


@register("ShaderNodeInvert")
def invert_node(b):
    b.call("node_invert", [b.input("Fac", "float"), b.input("Color", "color")],
           [("Color", "color")])


@register("ShaderNodeHueSaturation")
def hue_saturation_node(b):
    b.call("node_hue_saturation",
           [b.input("Hue", "float"), b.input("Saturation", "float"),
            b.input("Value", "float"), b.input("Fac", "float"), b.input("Color", "color")],
           [("Color", "color")])


@register("ShaderNodeGamma")
def gamma_node(b):
    b.call("node_gamma", [b.input("Color", "color"), b.input("Gamma", "float")],
           [("Color", "color")])


@register("ShaderNodeBrightContrast")
def bright_contrast_node(b):
    b.call("node_bright_contrast",
           [b.input("Color", "color"), b.input("Bright", "float"),
            b.input("Contrast", "float")],
           [("Color", "color")])


def color_ramp_table(ramp):
    """Cycles' colorramp_to_array: RAMP_TABLE_SIZE (r, g, b, a) samples of
    ColorRamp.evaluate at i / (RAMP_TABLE_SIZE - 1). Blender's evaluate does
    every interpolation and colour mode (RGB/HSV/HSL, hue_interpolation)."""
    table = []
    for i in range(RAMP_TABLE_SIZE):
        table.extend(ramp.evaluate(_f32(i / (RAMP_TABLE_SIZE - 1))))
    return table


@register("ShaderNodeValToRGB")
def color_ramp_node(b):
    ramp = b.node.color_ramp
    interpolate = int(ramp.interpolation != "CONSTANT")
    b.call("node_color_ramp",
           [b.int(interpolate), b.block(color_ramp_table(ramp)), b.input("Fac", "float")],
           [("Color", "color"), ("Alpha", "float")])


def curve_mapping_range(mapping, num_curves):
    """Cycles' curvemapping_minmax: the x range spanned by the first and last
    points of the first num_curves curves."""
    min_x = min(mapping.curves[i].points[0].location[0] for i in range(num_curves))
    max_x = max(mapping.curves[i].points[-1].location[0] for i in range(num_curves))
    return min_x, max_x


def curve_sample_positions(min_x, max_x):
    """t_i = min_x + i / (size - 1) * (max_x - min_x), in float arithmetic."""
    range_x = _f32(max_x - min_x)
    last = RAMP_TABLE_SIZE - 1
    return [_f32(min_x + _f32(_f32(i / last) * range_x)) for i in range(RAMP_TABLE_SIZE)]


def curve_color_table(mapping, rgb_curve):
    """Cycles' curvemapping_color_to_array: (r, g, b) per sample; for RGB
    Curves the combined curve (curves[3]) is applied first."""
    min_x, max_x = curve_mapping_range(mapping, 4 if rgb_curve else 3)
    mapping.update()
    curve_r, curve_g, curve_b = mapping.curves[0], mapping.curves[1], mapping.curves[2]
    table = []
    for t in curve_sample_positions(min_x, max_x):
        if rgb_curve:
            t_r = t_g = t_b = mapping.evaluate(mapping.curves[3], t)
        else:
            t_r = t_g = t_b = t
        table.extend((mapping.evaluate(curve_r, t_r), mapping.evaluate(curve_g, t_g),
                      mapping.evaluate(curve_b, t_b)))
    return table


def curve_float_table(mapping):
    """Cycles' curvemapping_float_to_array."""
    min_x, max_x = curve_mapping_range(mapping, 1)
    mapping.update()
    curve = mapping.curves[0]
    return [mapping.evaluate(curve, t) for t in curve_sample_positions(min_x, max_x)]


def _curves_call(b, func, table, num_curves, inputs, outputs):
    mapping = b.node.mapping
    table_arg = b.block(table)
    # min/max after the table: mapping.update() may have sorted the points.
    min_x, max_x = curve_mapping_range(mapping, num_curves)
    extrapolate = int(mapping.extend == "EXTRAPOLATED")
    b.call(func,
           [b.int(extrapolate), table_arg,
            b.const(min_x, "float"), b.const(max_x, "float")] + inputs,
           outputs)


@register("ShaderNodeRGBCurve")
def rgb_curves_node(b):
    table = curve_color_table(b.node.mapping, rgb_curve=True)
    _curves_call(b, "node_rgb_curves", table, 4,
                 [b.input("Fac", "float"), b.input("Color", "color")],
                 [("Color", "color")])


@register("ShaderNodeVectorCurve")
def vector_curves_node(b):
    table = curve_color_table(b.node.mapping, rgb_curve=False)
    _curves_call(b, "node_vector_curves", table, 3,
                 [b.input("Fac", "float"), b.input("Vector", "vector")],
                 [("Vector", "vector")])


@register("ShaderNodeFloatCurve")
def float_curve_node(b):
    table = curve_float_table(b.node.mapping)
    _curves_call(b, "node_float_curve", table, 1,
                 [b.input("Factor", "float"), b.input("Value", "float")],
                 [("Value", "float")])
