"""Node specs of the Image Texture and Environment Texture nodes.

GLSL: shaders/nodes/node_image_lib.glsl (node_tex_image, node_tex_image_box,
node_tex_environment and their *_missing variants for a node without an
image). Pixels and flags: materials/images.py. The ints are Blender's enum
values, which are Cycles' (util/texture.h InterpolationType, ExtensionType;
kernel/svm/types.h NodeImageProjection, NodeEnvironmentProjection; Cycles'
blender/shader.cpp casts them straight across).

Cycles 3.4 semantics reproduced here (scene/shader_nodes.cpp
ImageTextureNode/EnvironmentTextureNode, blender/shader.cpp):
- Vector unlinked: Image Texture uses the UV map (SocketType::LINK_TEXTURE_UV),
  Environment Texture the position (LINK_POSITION), which in a world is the
  ray direction.
- The colour is divided by alpha (NODE_IMAGE_ALPHA_UNASSOCIATE) only when the
  Alpha output is used, i.e. its links survive Cycles' graph clean-up (reach an
  output), and the image's alpha is not data. Environment Texture never does.
- A node without an image: Cycles tries to load an empty file name and binds
  its 1x1 magenta missing texture (colour space raw).
- The node's hidden texture mapping (``node.texture_mapping``) is applied when it
  is not the identity (TextureMapping::compute_transform, as a 3x4 block).
"""


from . import register
from .. import images
from .texture_mapping import mapping_args as _mapping_args

INTERPOLATION = {"Linear": 0, "Closest": 1, "Cubic": 2, "Smart": 3}
EXTENSION = {"REPEAT": 0, "EXTEND": 1, "CLIP": 2}
PROJECTION = {"FLAT": 0, "BOX": 1, "SPHERE": 2, "TUBE": 3}
ENV_PROJECTION = {"EQUIRECTANGULAR": 0, "MIRROR_BALL": 1}

# Texture mapping modes of node_image_lib.glsl img_mapping_apply().

OUTPUTS = [("Color", "color"), ("Alpha", "float")]
ENV_OUTPUTS = [("Color", "color")]  # Blender's Environment Texture has no Alpha output

_OUTPUT_NODES = ("ShaderNodeOutputMaterial", "ShaderNodeOutputWorld", "ShaderNodeOutputLight")


# --------------------------------------------------------------------------------------
# Is the Alpha output used? (Cycles: !alpha_out->links.empty() after ShaderGraph::clean,
# which removes the nodes the outputs do not depend on, with their links.)
# --------------------------------------------------------------------------------------

def _live_links(socket):
    if not socket.is_linked:
        return []
    return [l for l in socket.links if l.is_valid and not l.is_muted]


def _active_output(tree, bl_idname):
    """The output node Cycles evaluates in a material/world/light tree."""
    try:
        node = tree.get_output_node("CYCLES")
    except Exception:
        node = None
    if node is not None:
        return node
    outs = [n for n in tree.nodes if n.bl_idname == bl_idname]
    for n in outs:
        if getattr(n, "is_active_output", False):
            return n
    return outs[0] if outs else None


def output_used(socket, max_steps=4096):
    """Whether an output socket's value reaches an output Cycles evaluates: the
    active material/world/light output, a Shader AOV output, or (inside a node
    group) the group's output, counted as used. Follows reroutes, muted nodes'
    internal links and node groups (into and back out of them)."""
    # Work items: (output socket, stack of group nodes entered).
    stack = [(socket, ())]
    seen = set()
    steps = 0
    while stack:
        sock, ctx = stack.pop()
        for link in _live_links(sock):
            steps += 1
            if steps > max_steps:
                return True  # give up: assume used
            node, to_sock = link.to_node, link.to_socket
            key = (node.as_pointer(), to_sock.as_pointer(), tuple(g.as_pointer() for g in ctx))
            if key in seen:
                continue
            seen.add(key)
            idname = node.bl_idname
            if node.mute:
                for il in node.internal_links:
                    if il.from_socket == to_sock:
                        stack.append((il.to_socket, ctx))
                continue
            if idname == "ShaderNodeOutputAOV":
                return True
            if idname in _OUTPUT_NODES:
                if node == _active_output(node.id_data, idname):
                    return True
                continue
            if idname == "NodeGroupOutput":
                if not ctx:
                    return True  # a group's output: assume the group is used
                group = ctx[-1]
                active = _group_output(node.id_data)
                if node != active:
                    continue
                for out in group.outputs:
                    if out.identifier == to_sock.identifier:
                        stack.append((out, ctx[:-1]))
                continue
            if idname == "ShaderNodeGroup" and node.node_tree is not None:
                for gin in node.node_tree.nodes:
                    if gin.bl_idname == "NodeGroupInput":
                        for out in gin.outputs:
                            if out.identifier == to_sock.identifier:
                                stack.append((out, ctx + (node,)))
                continue
            for out in node.outputs:
                stack.append((out, ctx))
    return False


def _group_output(tree):
    outs = [n for n in tree.nodes if n.bl_idname == "NodeGroupOutput"]
    for n in outs:
        if getattr(n, "is_active_output", False):
            return n
    return outs[0] if outs else None


# --------------------------------------------------------------------------------------
# Specs
# --------------------------------------------------------------------------------------

@register("ShaderNodeTexImage")
def image_texture(b):
    node = b.node
    interpolation = INTERPOLATION.get(node.interpolation, 0)
    extension = EXTENSION.get(node.extension, 0)
    projection = PROJECTION.get(node.projection, 0)
    alpha_used = output_used(node.outputs["Alpha"])
    image = node.image
    flags = images.image_flags(image, alpha_used)
    if projection == PROJECTION["BOX"]:
        flags &= ~images.FLAG_UDIM_1001  # Cycles culls box-projected UDIMs to tile 1001
    mapping = _mapping_args(b)
    vector = b.input("Vector", "vector", implicit="uv")
    if projection == PROJECTION["BOX"]:
        tail = [vector, b.shading("N_object"), b.const(float(node.projection_blend), "float")]
        if image is None:
            b.call("node_tex_image_box_missing",
                   [b.int(interpolation), b.int(extension), b.int(flags)] + mapping + tail,
                   OUTPUTS)
        else:
            b.call("node_tex_image_box",
                   [b.int(interpolation), b.int(extension), b.int(flags)] + mapping +
                   [b.image(image)] + tail,
                   OUTPUTS)
        return
    head = [b.int(interpolation), b.int(extension), b.int(projection), b.int(flags)] + mapping
    if image is None:
        b.call("node_tex_image_missing", head + [vector], OUTPUTS)
    else:
        b.call("node_tex_image", head + [b.image(image), vector], OUTPUTS)


@register("ShaderNodeTexEnvironment")
def environment_texture(b):
    node = b.node
    interpolation = INTERPOLATION.get(node.interpolation, 0)
    projection = ENV_PROJECTION.get(node.projection, 0)
    image = node.image
    # Only NODE_IMAGE_COMPRESS_AS_SRGB applies (EnvironmentTextureNode::compile), and
    # the single-channel alpha of the kernel's texture read.
    flags = images.image_flags(image, False) & (images.FLAG_SRGB | images.FLAG_ALPHA_ONE)
    mapping = _mapping_args(b)
    vector = b.input("Vector", "vector", implicit="P")
    head = [b.int(interpolation), b.int(projection), b.int(flags)] + mapping
    if image is None:
        b.call("node_tex_environment_missing", head + [vector], ENV_OUTPUTS)
    else:
        b.call("node_tex_environment", head + [b.image(image), vector], ENV_OUTPUTS)
