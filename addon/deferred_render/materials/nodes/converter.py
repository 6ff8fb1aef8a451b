"""Node specs of the converter nodes: Math, Vector Math, Clamp, Map Range,
Separate/Combine RGB, XYZ, HSV and Color, RGB to BW, Blackbody, Wavelength.

GLSL: shaders/nodes/node_converter_lib.glsl. The enum tables below are the
ints the GLSL #defines use (NODE_MATH_*, NODE_VECTOR_MATH_*, NODE_CLAMP_*,
NODE_MAP_RANGE_*, NODE_COMBSEP_COLOR_*); change both sides together.
Socket identifiers are those of Blender 3.4.1.
"""

from . import register

# Math operation -> NODE_MATH_* (node_converter_lib.glsl).
MATH_OPS = {
    "ADD": 0,
    "SUBTRACT": 1,
    "MULTIPLY": 2,
    "DIVIDE": 3,
    "MULTIPLY_ADD": 4,
    "POWER": 5,
    "LOGARITHM": 6,
    "SQRT": 7,
    "INVERSE_SQRT": 8,
    "ABSOLUTE": 9,
    "EXPONENT": 10,
    "MINIMUM": 11,
    "MAXIMUM": 12,
    "LESS_THAN": 13,
    "GREATER_THAN": 14,
    "SIGN": 15,
    "COMPARE": 16,
    "SMOOTH_MIN": 17,
    "SMOOTH_MAX": 18,
    "ROUND": 19,
    "FLOOR": 20,
    "CEIL": 21,
    "TRUNC": 22,
    "FRACT": 23,
    "MODULO": 24,
    "WRAP": 25,
    "SNAP": 26,
    "PINGPONG": 27,
    "SINE": 28,
    "COSINE": 29,
    "TANGENT": 30,
    "ARCSINE": 31,
    "ARCCOSINE": 32,
    "ARCTANGENT": 33,
    "ARCTAN2": 34,
    "SINH": 35,
    "COSH": 36,
    "TANH": 37,
    "RADIANS": 38,
    "DEGREES": 39,
}

# Vector Math operation -> NODE_VECTOR_MATH_* (node_converter_lib.glsl).
VECTOR_MATH_OPS = {
    "ADD": 0,
    "SUBTRACT": 1,
    "MULTIPLY": 2,
    "DIVIDE": 3,
    "MULTIPLY_ADD": 4,
    "CROSS_PRODUCT": 5,
    "PROJECT": 6,
    "REFLECT": 7,
    "REFRACT": 8,
    "FACEFORWARD": 9,
    "DOT_PRODUCT": 10,
    "DISTANCE": 11,
    "LENGTH": 12,
    "SCALE": 13,
    "NORMALIZE": 14,
    "ABSOLUTE": 15,
    "MINIMUM": 16,
    "MAXIMUM": 17,
    "FLOOR": 18,
    "CEIL": 19,
    "FRACTION": 20,
    "MODULO": 21,
    "WRAP": 22,
    "SNAP": 23,
    "SINE": 24,
    "COSINE": 25,
    "TANGENT": 26,
}

# Clamp clamp_type -> NODE_CLAMP_*.
CLAMP_TYPES = {"MINMAX": 0, "RANGE": 1}

# Map Range interpolation_type -> NODE_MAP_RANGE_*.
MAP_RANGE_TYPES = {"LINEAR": 0, "STEPPED": 1, "SMOOTHSTEP": 2, "SMOOTHERSTEP": 3}

# Separate/Combine Color mode -> NODE_COMBSEP_COLOR_*.
COLOR_MODES = {"RGB": 0, "HSV": 1, "HSL": 2}


@register("ShaderNodeMath")
def math_node(b):
    op = MATH_OPS.get(b.node.operation)
    if op is None:
        return b.unsupported(f"operation {b.node.operation}")
    b.call("node_math",
           [b.int(op), b.int(int(b.node.use_clamp)),
            b.input("Value", "float"), b.input("Value_001", "float"),
            b.input("Value_002", "float")],
           [("Value", "float")])


@register("ShaderNodeVectorMath")
def vector_math_node(b):
    op = VECTOR_MATH_OPS.get(b.node.operation)
    if op is None:
        return b.unsupported(f"operation {b.node.operation}")
    # "Scale" is the Scale of SCALE and the IOR of REFRACT.
    b.call("node_vector_math",
           [b.int(op),
            b.input("Vector", "vector"), b.input("Vector_001", "vector"),
            b.input("Vector_002", "vector"), b.input("Scale", "float")],
           [("Vector", "vector"), ("Value", "float")])


@register("ShaderNodeClamp")
def clamp_node(b):
    clamp_type = CLAMP_TYPES.get(b.node.clamp_type)
    if clamp_type is None:
        return b.unsupported(f"clamp type {b.node.clamp_type}")
    b.call("node_clamp",
           [b.int(clamp_type),
            b.input("Value", "float"), b.input("Min", "float"), b.input("Max", "float")],
           [("Result", "float")])


@register("ShaderNodeMapRange")
def map_range_node(b):
    range_type = MAP_RANGE_TYPES.get(b.node.interpolation_type)
    if range_type is None:
        return b.unsupported(f"interpolation {b.node.interpolation_type}")
    use_clamp = b.int(int(b.node.clamp))
    if b.node.data_type == "FLOAT_VECTOR":
        b.call("node_vector_map_range",
               [b.int(range_type), use_clamp,
                b.input("Vector", "vector"),
                b.input("From_Min_FLOAT3", "vector"), b.input("From_Max_FLOAT3", "vector"),
                b.input("To_Min_FLOAT3", "vector"), b.input("To_Max_FLOAT3", "vector"),
                b.input("Steps_FLOAT3", "vector")],
               [("Vector", "vector")])
    elif b.node.data_type == "FLOAT":
        b.call("node_map_range",
               [b.int(range_type), use_clamp,
                b.input("Value", "float"),
                b.input("From Min", "float"), b.input("From Max", "float"),
                b.input("To Min", "float"), b.input("To Max", "float"),
                b.input("Steps", "float")],
               [("Result", "float")])
    else:
        return b.unsupported(f"data type {b.node.data_type}")


@register("ShaderNodeSeparateRGB")
def separate_rgb_node(b):
    b.call("node_separate_rgb", [b.input("Image", "color")],
           [("R", "float"), ("G", "float"), ("B", "float")])


@register("ShaderNodeCombineRGB")
def combine_rgb_node(b):
    b.call("node_combine_rgb",
           [b.input("R", "float"), b.input("G", "float"), b.input("B", "float")],
           [("Image", "color")])


@register("ShaderNodeSeparateXYZ")
def separate_xyz_node(b):
    b.call("node_separate_xyz", [b.input("Vector", "vector")],
           [("X", "float"), ("Y", "float"), ("Z", "float")])


@register("ShaderNodeCombineXYZ")
def combine_xyz_node(b):
    b.call("node_combine_xyz",
           [b.input("X", "float"), b.input("Y", "float"), b.input("Z", "float")],
           [("Vector", "vector")])


@register("ShaderNodeSeparateHSV")
def separate_hsv_node(b):
    b.call("node_separate_hsv", [b.input("Color", "color")],
           [("H", "float"), ("S", "float"), ("V", "float")])


@register("ShaderNodeCombineHSV")
def combine_hsv_node(b):
    b.call("node_combine_hsv",
           [b.input("H", "float"), b.input("S", "float"), b.input("V", "float")],
           [("Color", "color")])


@register("ShaderNodeSeparateColor")
def separate_color_node(b):
    mode = COLOR_MODES.get(b.node.mode)
    if mode is None:
        return b.unsupported(f"mode {b.node.mode}")
    b.call("node_separate_color", [b.int(mode), b.input("Color", "color")],
           [("Red", "float"), ("Green", "float"), ("Blue", "float")])


@register("ShaderNodeCombineColor")
def combine_color_node(b):
    mode = COLOR_MODES.get(b.node.mode)
    if mode is None:
        return b.unsupported(f"mode {b.node.mode}")
    b.call("node_combine_color",
           [b.int(mode),
            b.input("Red", "float"), b.input("Green", "float"), b.input("Blue", "float")],
           [("Color", "color")])


@register("ShaderNodeRGBToBW")
def rgb_to_bw_node(b):
    b.call("node_rgb_to_bw", [b.input("Color", "color")], [("Val", "float")])


@register("ShaderNodeBlackbody")
def blackbody_node(b):
    b.call("node_blackbody", [b.input("Temperature", "float")], [("Color", "color")])


@register("ShaderNodeWavelength")
def wavelength_node(b):
    b.call("node_wavelength", [b.input("Wavelength", "float")], [("Color", "color")])
