"""Input nodes (shaders/nodes/node_input_lib.glsl): values of the shading
point as Cycles' camera ray sees them, and mesh attributes by name."""

from . import register


@register("ShaderNodeValue")
def value(b):
    b.call("node_value", [b.const(b.node.outputs[0].default_value, "float")], [("Value", "float")])


@register("ShaderNodeRGB")
def rgb(b):
    b.call("node_rgb", [b.const(tuple(b.node.outputs[0].default_value)[:3], "color")], [("Color", "color")])


def _inverse_rows(obj):
    """3x4 rows of the inverse world matrix of ``obj`` (Texture Coordinate > Object)."""
    m = obj.matrix_world.inverted_safe()
    return [m[r][c] for r in range(3) for c in range(4)]


@register("ShaderNodeTexCoord")
def tex_coord(b):
    obj = b.node.object
    if obj is not None:
        args = [b.int(1), b.block(_inverse_rows(obj))]
    else:
        args = [b.int(0), b.int(0)]
    if b.node.from_instancer:
        b.unsupported("'From Instancer' (the instance's own coordinates are used)")
    if b._graph.world and b.node.outputs["Window"].is_linked:
        # The baked world map holds Window per direction: exact for a
        # perspective camera; export_world warns for an orthographic one.
        b._graph.world_window = True
    b.call("node_tex_coord", args,
           [("Generated", "vector"), ("Normal", "vector"), ("UV", "vector"), ("Object", "vector"),
            ("Camera", "vector"), ("Window", "vector"), ("Reflection", "vector")])


@register("ShaderNodeUVMap")
def uv_map(b):
    if b.node.from_instancer:
        b._graph.note(f"'{b.node.name}': 'From Instancer' UV (the mesh's own UV map is used)")
    b.call("node_uvmap", [b.attribute("uv:" + b.node.uv_map)], [("UV", "vector")])


@register("ShaderNodeAttribute")
def attribute(b):
    if b.node.attribute_type != "GEOMETRY":
        b._graph.note(f"'{b.node.name}': {b.node.attribute_type.title()} attributes are not read (0 used)")
        value = b.shading("attr_none")
    else:
        value = b.attribute("attr:" + b.node.attribute_name)
    b.call("node_attribute", [value],
           [("Color", "color"), ("Vector", "vector"), ("Fac", "float"), ("Alpha", "float")])


@register("ShaderNodeVertexColor")
def vertex_color(b):
    b.call("node_vertex_color", [b.attribute("color:" + b.node.layer_name)],
           [("Color", "color"), ("Alpha", "float")])


@register("ShaderNodeObjectInfo")
def object_info(b):
    b.call("node_object_info", [],
           [("Location", "vector"), ("Color", "color"), ("Alpha", "float"), ("Object Index", "float"),
            ("Material Index", "float"), ("Random", "float")])


@register("ShaderNodeNewGeometry")
def geometry(b):
    # Pointiness and Random Per Island are mesh data the export computes as
    # Cycles does (export/attributes.py), read only where they are used.
    def mesh_value(output, key):
        return b.attribute(key) if b.node.outputs[output].is_linked else b.shading("attr_none")
    b.call("node_geometry", [mesh_value("Pointiness", "pointiness:"), mesh_value("Random Per Island", "island:")],
           [("Position", "vector"), ("Normal", "vector"), ("Tangent", "vector"), ("True Normal", "vector"),
            ("Incoming", "vector"), ("Parametric", "vector"), ("Backfacing", "float"), ("Pointiness", "float"),
            ("Random Per Island", "float")])


@register("ShaderNodeLayerWeight")
def layer_weight(b):
    b.call("node_layer_weight", [b.input("Blend", "float"), b.input("Normal", "vector", implicit="N")],
           [("Fresnel", "float"), ("Facing", "float")])


@register("ShaderNodeFresnel")
def fresnel(b):
    b.call("node_fresnel", [b.input("IOR", "float"), b.input("Normal", "vector", implicit="N")], [("Fac", "float")])


@register("ShaderNodeLightPath")
def light_path(b):
    b.call("node_light_path", [],
           [(name, "float") for name in ("Is Camera Ray", "Is Shadow Ray", "Is Diffuse Ray", "Is Glossy Ray",
                                         "Is Singular Ray", "Is Reflection Ray", "Is Transmission Ray",
                                         "Ray Length", "Ray Depth", "Diffuse Depth", "Glossy Depth",
                                         "Transparent Depth", "Transmission Depth")])


@register("ShaderNodeCameraData")
def camera_data(b):
    b.call("node_camera_data", [], [("View Vector", "vector"), ("View Z Depth", "float"), ("View Distance", "float")])


TANGENT_DIRECTIONS = {"RADIAL": 0, "UV_MAP": 1}
TANGENT_AXES = {"X": 0, "Y": 1, "Z": 2}


@register("ShaderNodeTangent")
def tangent(b):
    uv = b.node.direction_type == "UV_MAP"
    b.call("node_tangent",
           [b.int(TANGENT_DIRECTIONS[b.node.direction_type]), b.int(TANGENT_AXES[b.node.axis]),
            b.attribute("tangent:" + b.node.uv_map) if uv else b.shading("attr_none")],
           [("Tangent", "vector")])


@register("ShaderNodeLightFalloff")
def light_falloff(b):
    b.call("node_light_falloff", [b.input("Strength", "float"), b.input("Smooth", "float")],
           [("Quadratic", "float"), ("Linear", "float"), ("Constant", "float")])


VECTOR_TRANSFORM_TYPES = {"VECTOR": 0, "POINT": 1, "NORMAL": 2}
VECTOR_TRANSFORM_SPACES = {"WORLD": 0, "OBJECT": 1, "CAMERA": 2}


@register("ShaderNodeVectorTransform")
def vector_transform(b):
    b.call("node_vector_transform",
           [b.int(VECTOR_TRANSFORM_TYPES[b.node.vector_type]), b.int(VECTOR_TRANSFORM_SPACES[b.node.convert_from]),
            b.int(VECTOR_TRANSFORM_SPACES[b.node.convert_to]), b.input("Vector", "vector")],
           [("Vector", "vector")])


@register("ShaderNodeDisplacement")
def displacement(b):
    # node_displacement's space: 0 object (the object's scale scales the
    # offset), 1 world (svm_node_displacement).
    b.call("node_displacement",
           [b.int(0 if b.node.space == "OBJECT" else 1), b.input("Height", "float"), b.input("Midlevel", "float"),
            b.input("Scale", "float"), b.input("Normal", "vector", implicit="N")],
           [("Displacement", "vector")])
