"""Blender node tree -> the typed graph (IR) the native renderer compiles.

``build_material_graph`` walks back from the Material Output's Surface
input, emitting each node a spec exists for (``nodes/``) once per group
context, dependencies first (so the IR is in topological order), and
collecting the per-material constants, the images and the mesh attributes
the graph reads. The contract a spec programs against is the
``NodeBuilder`` API below (CONTRACT.md has the long form).

The IR (what ``Renderer.add_graph_material`` takes)::

    {"nodes": [{"func": "node_math", "args": [...], "outputs": ["float"]}, ...],
     "surface": (node index, output index) or None,
     "constants": [float, ...], "images": [native image id, ...],
     "attributes": ["uv:UVMap", "color:Col", ...]}

with args ``("int", v)``, ``("const", type, offset)``, ``("block", offset, length)``,
``("link", type, node, output, from_type)``, ``("shading", name)``,
``("image", slot)``. Values never enter the GLSL, so materials that differ
only in values share one program.
"""

import math

from . import graph as graph_walk
from .nodes import SPECS

# Blender's scene-linear luminance (default OCIO config: Rec.709 measured in Cycles 3.4.1), as the
# GLSL conversions (material_lib.glsl) and Cycles' ConvertNode use it.
LUMINANCE = (0.2126729950, 0.7151526453, 0.0721754596)

MAX_NODES = 4096
MAX_ATTRIBUTES = 8
MAX_IMAGES = 16
MAX_BUMP_DEPTH = 4  # NODE_BUMP_DEPTH in shaders/nodes/node_vector_lib.glsl


class SpecError(Exception):
    """A node spec asked for something the node does not have."""


class GraphCycle(Exception):
    pass


def _floats(value):
    try:
        return [float(v) for v in value]
    except TypeError:
        return [float(value)]


def _finite(x):
    return x if math.isfinite(x) else 0.0


def convert_value(value, from_kind, to_kind):
    """A constant converted as Blender converts a link (ConvertNode)."""
    v = _floats(value)
    if to_kind == "float":
        if len(v) == 1:
            return [_finite(v[0])]
        if from_kind == "color":
            return [_finite(sum(c * w for c, w in zip(v[:3], LUMINANCE)))]
        return [_finite(sum(v[:3]) / 3.0)]
    if len(v) == 1:
        return [_finite(v[0])] * 3
    return [_finite(c) for c in (v + [0.0, 0.0, 0.0])[:3]]


class NodeBuilder:
    """What a node spec sees: one Blender node in one group context."""

    def __init__(self, graph, node, ctx):
        self._graph = graph
        self.node = node
        self.ctx = ctx
        self.emitted = False
        self.outputs = None

    # -- arguments --------------------------------------------------------
    def _socket(self, identifier):
        for s in self.node.inputs:
            if s.identifier == identifier:
                return s
        raise SpecError(f"{self.node.bl_idname} has no input '{identifier}'")

    def input(self, identifier, type, implicit=None):
        socket = self._socket(identifier)
        source = graph_walk.resolve_input(socket, self.ctx)
        if isinstance(source, graph_walk.Output):
            arg = self._graph.output_arg(source, type)
            if arg is not None:
                return arg
            if type == "closure":
                return self._graph.closure_none()
            # An output we do not compute: its own default value (Blender's
            # output sockets carry one; 0 for those that do not).
            value = getattr(source.socket, "default_value", 0.0)
            return self.const(convert_value(value, graph_walk.socket_kind(source.socket), type), type)
        else:
            final = source.socket
        target = final if final is not None else socket
        if type == "closure":
            return self._graph.closure_none()
        if implicit is not None:
            # Cycles removes group inputs, reroutes and muted nodes (proxies)
            # before it links default inputs (Shader::set_graph ->
            # remove_proxy_nodes, then ShaderGraph::default_inputs): a
            # Normal or texture Vector reached only through them is
            # unlinked there and reads the geometry normal / texture
            # coordinates, whatever value the group socket shows.
            return ("shading", implicit)
        value = getattr(target, "default_value", None)
        if value is None:
            value = getattr(socket, "default_value", 0.0)
        return self.const(convert_value(value, graph_walk.socket_kind(target), type), type)

    def is_linked(self, identifier):
        """True if a real node output drives the input (after groups, reroutes, mutes)."""
        source = graph_walk.resolve_input(self._socket(identifier), self.ctx)
        return isinstance(source, graph_walk.Output)

    def const(self, value, type):
        v = _floats(value)
        v = v[:1] if type == "float" else (v + [0.0, 0.0, 0.0])[:3] if len(v) > 1 else v * 3
        offset = len(self._graph.constants)
        self._graph.constants.extend(_finite(x) for x in v)
        return ("const", type, offset)

    def block(self, floats):
        offset = len(self._graph.constants)
        values = [_finite(float(x)) for x in floats]
        self._graph.constants.extend(values)
        return ("block", offset, len(values))

    def int(self, value):
        return ("int", int(value))

    def shading(self, name):
        return ("shading", name)

    def attribute(self, key):
        """An attribute slot (mesh data by key: 'uv:NAME', 'tangent:NAME',
        'color:NAME', 'attr:NAME'; an empty NAME is the active render one);
        beyond the slot limit the value 0 ("attr_none")."""
        slot = self._graph.attribute_slot(key)
        return ("shading", "attr_none" if slot is None else f"attr{slot}")

    def image(self, image):
        return ("image", self._graph.image_slot(image))

    def computed_image(self, key, make_pixels):
        """A sampler2D of pixels the spec computes (make_pixels() -> (H, W, 4)
        float32, row 0 first), uploaded once per distinct ``key``."""
        return ("image", self._graph.pixels_slot(key, make_pixels))

    # -- the call ---------------------------------------------------------
    def call(self, func, args, outputs):
        if self.emitted:
            raise SpecError(f"{self.node.bl_idname}: one call per node")
        self.emitted = True
        self.outputs = list(outputs)
        self._graph.append_node(func, args, [t for _, t in outputs])

    def at_bump_offset(self, axis, evaluate):
        """``evaluate()`` (argument-building calls) with the shading point moved
        to P + dP.dx (axis 0) or P + dP.dy (axis 1), as Cycles evaluates a
        Bump node's height: every node upstream is emitted again there."""
        graph = self._graph
        if len(graph.variant) >= MAX_BUMP_DEPTH:
            graph.note(f"{_label(self.node)}: Bump nodes nested deeper than {MAX_BUMP_DEPTH} (flat)")
            return evaluate()
        return graph.in_variant(axis, axis, evaluate)

    def unsupported(self, reason):
        self._graph.note(f"{_label(self.node)}: {reason} (default output used)")


def _label(node):
    return f"'{node.name}' ({node.bl_label or node.bl_idname})"


class ImageRegistry:
    """Blender image -> native image id, once per export (missing: magenta).

    Images whose content has a key (images.native_key: file, time, settings,
    packed data) are uploaded with it; a renderer kept from the last render
    (Persistent Data) gives the id back from ``find_image`` and nothing is
    uploaded again."""

    def __init__(self, add_image, warn, find_image=None):
        self._add_image = add_image
        self._find_image = find_image
        self._warn = warn
        self._ids = {}
        self._magenta = None

    def image_id(self, image):
        key = image.as_pointer() if image is not None else None
        if key in self._ids:
            return self._ids[key]
        from . import images
        try:
            result = images.cached_image_pixels(image)
            for w in result.warnings:
                self._warn(f"Image '{image.name}': {w}")
            content_key = images.native_key(image)
            native_id = self._find_image(content_key) if (content_key and self._find_image) else None
            if native_id is None:
                native_id = (self._add_image(result.pixels, key=content_key) if content_key
                             else self._add_image(result.pixels))
            self._ids[key] = (native_id, result)
        except (images.ImageUnavailable, ValueError, RuntimeError, MemoryError) as ex:
            # Unreadable, refused by the native validation, or out of (GPU) memory.
            self._warn(f"Image '{getattr(image, 'name', '?')}': {ex} (rendered magenta, as Cycles does)")
            self._ids[key] = (self.magenta(), None)
        return self._ids[key]

    def pixels_id(self, key, make_pixels):
        """Native id of an image the add-on computes (a sky model's table):
        ``make_pixels()`` -> (H, W, 4) float32, called only when neither this
        export nor a kept renderer (find_image) has ``key`` already."""
        cache_key = ("pixels", key)
        if cache_key in self._ids:
            return self._ids[cache_key]
        native_id = self._find_image(key) if self._find_image else None
        if native_id is None:
            native_id = self._add_image(make_pixels(), key=key)
        self._ids[cache_key] = (native_id, None)
        return self._ids[cache_key]

    def magenta(self):
        if self._magenta is None:
            import numpy as np
            self._magenta = self._add_image(np.array([[[255, 0, 255, 255]]], dtype=np.uint8))
        return self._magenta


class GraphBuilder:
    def __init__(self, images=None):
        self.nodes = []          # IR node dicts
        self.constants = []
        self.images = []         # native image ids, by slot
        self.image_info = []     # ImagePixels (or None) by slot
        self.attributes = []     # attribute keys, by slot
        self.notes = []
        self._registry = images
        self._emitted = {}       # (bump variant, ctx key, node pointer) -> (IR index, outputs) or None
        self._in_progress = set()
        self.variant = ()        # bump offsets entered, innermost last (nodes re-emitted per variant)
        self.uses_alpha = False  # some closure's alpha can be below 1 (MATERIAL_ALPHA)
        self.closure_normal = False  # some closure's normal is not the smooth one
        self.world = False       # a world's tree (its shading point is a direction)
        self.sun_lamps = []      # (direction, irradiance RGB, angle) of sky sun discs (world trees)
        self._none = None

    def note(self, text):
        if text not in self.notes:
            self.notes.append(text)

    def append_node(self, func, args, output_types):
        if len(self.nodes) >= MAX_NODES:
            raise GraphCycle(f"more than {MAX_NODES} nodes")
        self.nodes.append({"func": func, "args": list(args), "outputs": list(output_types)})
        return len(self.nodes) - 1

    def in_variant(self, tag, axis, evaluate):
        """``evaluate()`` with its nodes emitted apart (bump variant ``tag``),
        the shading point moved to P + dP.dx / P + dP.dy for axis 0 / 1
        (node_bump_offset, then node_bump_restore); axis None: not moved."""
        if axis is not None:
            self.append_node("node_bump_offset", [("int", axis)], [])
        self.variant = self.variant + (tag,)
        try:
            return evaluate()
        finally:
            self.variant = self.variant[:-1]
            if axis is not None:
                self.append_node("node_bump_restore", [], [])

    def closure_none(self):
        if self._none is None:
            self._none = self.append_node("node_closure_none", [], ["closure"])
        return ("link", "closure", self._none, 0, "closure")

    def attribute_slot(self, key):
        if key not in self.attributes:
            if len(self.attributes) >= MAX_ATTRIBUTES:
                self.note(f"more than {MAX_ATTRIBUTES} attributes read (attribute '{key}' is 0)")
                return None
            self.attributes.append(key)
        return self.attributes.index(key)

    def image_slot(self, image):
        if self._registry is None:
            raise SpecError("no image registry")
        return self._slot(*self._registry.image_id(image))

    def pixels_slot(self, key, make_pixels):
        """Slot of an image the add-on computes (ImageRegistry.pixels_id)."""
        if self._registry is None:
            raise SpecError("no image registry")
        return self._slot(*self._registry.pixels_id(key, make_pixels))

    def _slot(self, native_id, info):
        if native_id in self.images:
            return self.images.index(native_id)
        if len(self.images) >= MAX_IMAGES:
            self.note(f"more than {MAX_IMAGES} images (the last one reused)")
            return MAX_IMAGES - 1
        self.images.append(native_id)
        self.image_info.append(info)
        return len(self.images) - 1

    def emit(self, node, ctx):
        """IR index and outputs of a node (emitting it first), or None."""
        key = (self.variant, tuple(g.as_pointer() for g in ctx), node.as_pointer())
        if key in self._emitted:
            return self._emitted[key]
        if key in self._in_progress:
            raise GraphCycle(f"the node tree has a cycle through {_label(node)}")
        self._in_progress.add(key)
        try:
            spec = SPECS.get(node.bl_idname)
            entry = None
            if spec is None:
                fallback = SPECS.get("#unsupported_shader") if any(o.type == "SHADER" for o in node.outputs) else None
                if fallback is not None:
                    self.note(f"{_label(node)} is not supported (rendered as a Diffuse BSDF of its colour)")
                    spec = fallback
                else:
                    self.note(f"{_label(node)} is not supported (its outputs take their default values)")
            if spec is not None:
                b = NodeBuilder(self, node, ctx)
                try:
                    spec(b)
                except (GraphCycle, graph_walk.GraphError):
                    raise
                except Exception as ex:  # a spec meeting a node it does not expect: its defaults
                    self.note(f"{_label(node)} could not be translated ({type(ex).__name__}: {ex}); "
                              "its outputs take their default values")
                    b.emitted = False
                if b.emitted:
                    entry = (len(self.nodes) - 1, b.outputs)
        finally:
            self._in_progress.discard(key)
        self._emitted[key] = entry
        return entry

    def output_arg(self, source, type):
        entry = self.emit(source.node, source.ctx)
        if entry is None:
            return None
        index, outputs = entry
        for pos, (identifier, kind) in enumerate(outputs):
            if identifier == source.socket.identifier:
                if (kind == "closure") != (type == "closure"):
                    self.note(f"{_label(source.node)}: a shader linked to a value input (ignored)")
                    return None
                return ("link", type, index, pos, kind)
        self.note(f"{_label(source.node)}: output '{source.socket.name}' is not supported (default used)")
        return None


def material_output(tree, kind="ShaderNodeOutputMaterial"):
    """The output Cycles renders: get_output_node('CYCLES'), else any output
    node of ``kind`` (Material Output, or World Output for a world)."""
    output = None
    try:
        output = tree.get_output_node("CYCLES")
    except (AttributeError, TypeError):
        pass
    if output is None:
        output = next((n for n in tree.nodes if n.bl_idname == kind), None)
    return output


class MaterialGraph:
    """The IR of one material and what it needs from meshes (and, for a
    world, the sun lamps its sky discs light with)."""

    def __init__(self, ir, notes, attributes, sun_lamps=()):
        self.ir = ir
        self.notes = notes
        self.attributes = attributes
        self.sun_lamps = list(sun_lamps)


def build_material_graph(material, images=None):
    """MaterialGraph for a node material, or raise GraphCycle/SpecError.

    ``images``: an ImageRegistry (texture nodes upload through it)."""
    try:
        return _build(material, images)
    except graph_walk.GraphError as ex:  # groups too deep or containing themselves, link loops
        raise GraphCycle(str(ex)) from ex


def _graph_emits(g):
    """True if some Emission node of the graph, or a Principled BSDF's
    Emission, can emit (a link, or a constant colour and strength not 0)."""
    def nonzero(arg):
        if arg[0] != "const":
            return True  # linked: varies
        kind, offset = arg[1], arg[2]
        n = 1 if kind == "float" else 3
        return any(v != 0.0 for v in g.constants[offset:offset + n])
    for node in g.nodes:
        if node["func"] == "node_emission":
            color, strength = node["args"][0], node["args"][1]
        elif node["func"] == "node_bsdf_principled":
            color, strength = node["args"][-4], node["args"][-3]
        else:
            continue
        if nonzero(color) and nonzero(strength):
            return True
    return False


# Node functions whose value depends on the incoming direction, and their
# Blender names (for the emission bake's warning).
_VIEW_NAMES = {"node_fresnel": "Fresnel", "node_layer_weight": "Layer Weight", "node_camera_data": "Camera Data"}
_VIEW_DEPENDENT = set(_VIEW_NAMES)


def _constant_emission(g, surface):
    """The radiance the surface closure emits when the graph makes it a
    constant: an Emission shader or a Principled BSDF (emission x strength x
    its constant alpha) straight at the output; else None."""
    if surface is None:
        return None
    node = g.nodes[surface[0]]
    def const(arg):
        if arg[0] != "const":
            return None
        n = 1 if arg[1] == "float" else 3
        return g.constants[arg[2]:arg[2] + n]
    if node["func"] == "node_emission":
        color, strength, alpha = const(node["args"][0]), const(node["args"][1]), [1.0]
    elif node["func"] == "node_bsdf_principled":
        color, strength, alpha = const(node["args"][-4]), const(node["args"][-3]), const(node["args"][-2])
    else:
        return None
    if color is None or strength is None or alpha is None:
        return None
    a = min(max(alpha[0], 0.0), 1.0)
    # Bounded for float32 (the native side lights with at most 1e12 anyway).
    return tuple(min(max(0.0, c * strength[0] * a), 1e30) for c in color)


def apply_alpha_clip(graph, threshold):
    """Material > Blend Mode: Alpha Clip on a built graph: its surface closure
    goes through node_alpha_clip (opaque where alpha > threshold, absent
    elsewhere). Nothing to do when the graph's alpha is always 1."""
    ir = graph.ir
    if not ir.get("alpha") or ir.get("surface") is None:
        return graph
    offset = len(ir["constants"])
    ir["constants"].append(_finite(float(threshold)))
    node, output = ir["surface"]
    ir["nodes"].append({"func": "node_alpha_clip",
                        "args": [("link", "closure", node, output, "closure"), ("const", "float", offset)],
                        "outputs": ["closure"]})
    ir["surface"] = (len(ir["nodes"]) - 1, 0)
    return graph


MAX_AOVS = 8  # kMaxGraphAovs


def _aov_outputs_in(tree, ctx=()):
    """(node, group context) of the AOV Output nodes that write an AOV
    (named, not muted) in ``tree`` and, as Cycles flattens node groups, in
    every group it uses (each group node a context of its own)."""
    found = [(n, ctx) for n in tree.nodes if n.bl_idname == "ShaderNodeOutputAOV" and n.name and not n.mute]
    for group in tree.nodes:
        if group.bl_idname != "ShaderNodeGroup" or group.node_tree is None or group.mute:
            continue
        if len(ctx) >= graph_walk.MAX_GROUP_DEPTH or any(g.node_tree == group.node_tree for g in ctx) \
                or group.node_tree == tree:
            continue  # a cycle or runaway nesting: the surface's walk reports it
        found.extend(_aov_outputs_in(group.node_tree, ctx + (group,)))
    return found


def aov_output_nodes(tree):
    """The AOV Output nodes that write an AOV, in the tree and its groups."""
    return [n for n, _ in _aov_outputs_in(tree)]


def _emit_aov_outputs(g, tree):
    """node_aov_output calls for the AOV Output nodes of the tree and of the
    groups it uses (Cycles' svm_node_aov_color/value: the Color and Value
    inputs at the shading point); returns the AOV name of each slot."""
    names = []
    for node, ctx in _aov_outputs_in(tree):
        if node.name in names:
            continue  # Cycles writes one value per AOV and sample: the first
        if len(names) >= MAX_AOVS:
            g.note(f"more than {MAX_AOVS} AOV outputs (AOV '{node.name}' stays 0)")
            continue
        b = NodeBuilder(g, node, ctx)
        color, value = b.input("Color", "color"), b.input("Value", "float")
        g.append_node("node_aov_output", [("int", len(names)), color, value], [])
        names.append(node.name)
    return names


def displacement_method(material):
    """Cycles' Displacement Method of the material: 'BUMP' (Bump Only, the
    default), 'DISPLACEMENT' or 'BOTH' (3.4: material.cycles, 4.x: the
    material itself)."""
    method = getattr(material, "displacement_method", None)
    if method is None:
        method = getattr(getattr(material, "cycles", None), "displacement_method", "BUMP")
    return method


def _emit_displacement(g, material, output):
    """The Material Output's Displacement as Cycles renders it at Displacement
    Method "Bump Only" (ShaderGraph::bump_from_displacement): the displacement
    graph is evaluated at P, P + dP.dx and P + dP.dy (three copies, each its
    own bump variant here, so that the surface's nodes are emitted apart from
    them as Cycles copies them), each vector's height along the unbumped
    normal feeds a Bump of strength 1 and distance 1, and its normal becomes
    the shading normal of everything after it (node_displacement_bump).
    Moving the surface (Displacement Only / and Bump) is not rendered."""
    socket = output.inputs.get("Displacement")
    if socket is None or not socket.is_linked:
        return
    method = displacement_method(material)
    if method == "DISPLACEMENT":
        g.note("Displacement (Displacement Method 'Displacement Only': the surface is not moved)")
        return
    if method == "BOTH":
        g.note("Displacement (Displacement Method 'Displacement and Bump': its bump is rendered, "
               "the surface is not moved)")
    try:
        source = graph_walk.resolve_input(socket, ())
    except graph_walk.GraphError as ex:
        raise GraphCycle(str(ex))
    if not isinstance(source, graph_walk.Output):
        return  # a constant displacement: no bump

    def height():
        vector = g.output_arg(source, "vector")
        if vector is None:
            return None
        index = g.append_node("node_displacement_height", [vector], ["float"])
        return ("link", "float", index, 0, "float")

    def height_at(axis):
        return g.in_variant(("displacement", axis), axis, height)

    h_c = height_at(None)
    if h_c is None:
        return
    g.append_node("node_displacement_bump", [h_c, height_at(0), height_at(1)], [])


def build_world_graph(world, images=None):
    """MaterialGraph of a world's node tree: its surface closure's emission is
    the background radiance along each direction (the world module bakes it,
    native/src/world_module.h). Raises GraphCycle/SpecError like materials."""
    try:
        return _build(world, images, world=True)
    except graph_walk.GraphError as ex:
        raise GraphCycle(str(ex)) from ex


# Nodes a world graph cannot evaluate: they need a surface (screen
# derivatives, mesh attributes); Cycles gives them nothing useful there either.
WORLD_UNSUPPORTED = {"node_bump_offset"}


def _build(material, images, world=False):
    tree = material.node_tree
    g = GraphBuilder(images)
    g.world = world
    output = material_output(tree, "ShaderNodeOutputWorld" if world else "ShaderNodeOutputMaterial")
    surface = None
    if output is None:
        g.note(f"no {'World' if world else 'Material'} Output node (rendered black, as Cycles does)")
    else:
        if not world:
            # Before the surface: the bump it makes is the surface's normal.
            _emit_displacement(g, material, output)
        socket = output.inputs.get("Surface")
        try:
            source = graph_walk.resolve_input(socket, ()) if socket is not None else None
        except graph_walk.GraphError as ex:
            raise GraphCycle(str(ex))
        if isinstance(source, graph_walk.Output):
            arg = g.output_arg(source, "closure")
            if arg is not None:
                surface = (arg[2], arg[3])
        s = output.inputs.get("Volume")
        if s is not None and s.is_linked:
            g.note("Volume (not rendered)")
    aovs = [] if world else _emit_aov_outputs(g, tree)
    light_emission = None
    emission_varies = False
    emits = not world and _graph_emits(g)
    if emits:
        light_emission = _constant_emission(g, surface)
        # Not a constant: the renderer bakes the graph's emission over the
        # emitting triangles (native emitter_module.h) to light other surfaces.
        emission_varies = light_emission is None
        viewed = sorted({n["func"] for n in g.nodes} & _VIEW_DEPENDENT)
        if emission_varies and viewed:
            # Cycles evaluates them towards each shading point it lights; the
            # bake sees the surface along its normal, once.
            g.note("its light on other surfaces takes the view-dependent nodes (" +
                   ", ".join(_VIEW_NAMES[f] for f in viewed) + ") as seen along the surface normal")
    if world:
        used = {n["func"] for n in g.nodes} & WORLD_UNSUPPORTED
        if used:
            raise SpecError("Bump in a world node tree is not supported")
        if g.attributes:
            g.note("mesh attributes read in the world (" + ", ".join(g.attributes) + ") are 0")
    ir = {"name": material.name, "nodes": g.nodes, "surface": surface, "constants": g.constants,
          "images": g.images, "attributes": g.attributes, "alpha": g.uses_alpha,
          "closure_normal": g.closure_normal, "aovs": aovs}
    graph = MaterialGraph(ir, g.notes, list(g.attributes), g.sun_lamps)
    graph.light_emission = light_emission
    graph.emission_varies = emission_varies
    graph.emits = emits
    graph.world_window = getattr(g, "world_window", False)
    return graph
