"""Vector nodes (shaders/nodes/node_vector_lib.glsl): Mapping, Normal Map,
Bump, Normal."""

from . import register

MAPPING_TYPES = {"POINT": 0, "TEXTURE": 1, "VECTOR": 2, "NORMAL": 3}
NORMAL_MAP_SPACES = {"TANGENT": 0, "OBJECT": 1, "WORLD": 2, "BLENDER_OBJECT": 3, "BLENDER_WORLD": 4}


@register("ShaderNodeMapping")
def mapping(b):
    b.call("node_mapping",
           [b.int(MAPPING_TYPES[b.node.vector_type]), b.input("Vector", "vector"), b.input("Location", "vector"),
            b.input("Rotation", "vector"), b.input("Scale", "vector")],
           [("Vector", "vector")])


@register("ShaderNodeNormalMap")
def normal_map(b):
    space = b.node.space
    if space == "TANGENT":
        tangent = b.attribute("tangent:" + b.node.uv_map)
        has_tangent = 1
    else:
        tangent = b.const((0.0, 0.0, 0.0), "vector")
        has_tangent = 0
    # The tangent slot is a vec4 (xyz, sign); node_normal_map takes it as is.
    # Smooth: the interpolated normal; meshes with flat faces still carry
    # their (flat) corner normals, which equal the true normal there.
    b.call("node_normal_map",
           [b.int(NORMAL_MAP_SPACES[space]), b.int(has_tangent), b.int(1), b.input("Strength", "float"),
            b.input("Color", "color"), tangent if has_tangent else ("shading", "attr_none")],
           [("Normal", "vector")])


@register("ShaderNodeBump")
def bump(b):
    # Cycles evaluates the height at P, P + dP.dx and P + dP.dy (svm bump_dx/dy
    # variants); an unlinked height is constant: no offset evaluation needed.
    h_c = b.input("Height", "float")
    if b.is_linked("Height"):
        h_x = b.at_bump_offset(0, lambda: b.input("Height", "float"))
        h_y = b.at_bump_offset(1, lambda: b.input("Height", "float"))
    else:
        h_x = h_y = h_c
    b.call("node_bump",
           [b.int(int(b.node.invert)), b.input("Strength", "float"), b.input("Distance", "float"),
            h_c, h_x, h_y, b.input("Normal", "vector", implicit="N")],
           [("Normal", "vector")])


@register("ShaderNodeNormal")
def normal(b):
    direction = tuple(b.node.outputs["Normal"].default_value)
    b.call("node_normal", [b.const(direction, "vector"), b.input("Normal", "vector")],
           [("Normal", "vector"), ("Dot", "float")])


VECTOR_ROTATE_TYPES = {"AXIS_ANGLE": 0, "X_AXIS": 1, "Y_AXIS": 2, "Z_AXIS": 3, "EULER_XYZ": 4}


@register("ShaderNodeVectorRotate")
def vector_rotate(b):
    b.call("node_vector_rotate",
           [b.int(VECTOR_ROTATE_TYPES[b.node.rotation_type]), b.int(int(b.node.invert)),
            b.input("Vector", "vector"), b.input("Center", "vector"), b.input("Axis", "vector"),
            b.input("Angle", "float"), b.input("Rotation", "vector")],
           [("Vector", "vector")])
