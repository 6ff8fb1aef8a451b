"""The scene world -> the background and world light, and the mist settings.

A world whose Background colour and strength are constants (unlinked, or an
RGB / Value node) is a constant colour: Color x Strength, with no map (the
lighting integrates it analytically). A world without nodes uses
World.color, as Cycles does; no world is black. Any other tree (Environment
Texture, Mapping, gradients, mixes of backgrounds, Light Path tricks) goes
through the material graph compiler (materials/builder.py) and is baked by
the native world module into an environment map the lighting importance
samples (native/src/world_module.h).
"""

import math

MIST_FALLOFFS = {"QUADRATIC", "LINEAR", "INVERSE_QUADRATIC"}
# The native input contract (native/src/scene_store.h, InputLimits::kMaxWorld).
MAX_WORLD = 1e12


def _color3(value):
    c = tuple(float(v) for v in tuple(value)[:3])
    return tuple(v if math.isfinite(v) else 0.0 for v in c)


def _linked(socket):
    if socket is None or not socket.is_linked:
        return None
    link = socket.links[0]
    if not link.is_valid or link.is_muted:
        return None
    node = link.from_node
    seen = set()
    while node.bl_idname == "NodeReroute" and node not in seen:
        seen.add(node)
        if not node.inputs[0].is_linked:
            return None
        node = node.inputs[0].links[0].from_node
    return None if node.mute else node


def export_world(world, renderer, image_registry, warn=None, light_group=0, orthographic=False):
    """Hand the world to ``renderer``: set_world(color=..., graph=IR or None).

    ``image_registry()`` gives the export's ImageRegistry (texture uploads).
    A graph the compiler cannot take falls back to the viewport colour with
    a warning naming why. ``light_group``: the world's light group (its sky
    sun lamps too), 0 none. ``orthographic``: the scene camera is (Window
    coordinates of the background then differ from Cycles')."""
    def note(message):
        if warn:
            warn(message)
    group = {"light_group": light_group} if light_group else {}

    if world is not None and _needs_graph(world) and hasattr(renderer, "set_world"):
        from ..materials import builder as graph_builder
        try:
            graph = graph_builder.build_world_graph(world, image_registry())
        except (graph_builder.GraphCycle, graph_builder.SpecError, RecursionError) as ex:
            note(f"World '{world.name}': {ex} (rendered with the viewport colour)")
        else:
            notes = list(graph.notes)
            if orthographic and getattr(graph, "world_window", False):
                # Cycles' orthographic camera rays take Window from their own
                # origin (the pixel); the baked map holds one value per direction.
                notes.append("Window coordinates seen by an orthographic camera are those of light "
                             "samples (the projection of the direction), not the pixel's")
            if notes:
                note(f"World '{world.name}': " + "; ".join(notes))
            try:
                # The colour is the fallback if the native bake fails (warned).
                renderer.set_world(color=_finite_color(world.color), graph=graph.ir, **group)
                for direction, irradiance, angle in graph.sun_lamps:
                    _add_sun_lamp(renderer, direction, irradiance, angle, note, group)
                return
            except ValueError as ex:  # refused by the native validation
                note(f"World '{world.name}': {ex} (rendered with the viewport colour)")
        renderer.set_world(color=_finite_color(world.color), **group)
        return
    color, warnings = world_color(world)
    for message in warnings:
        note(message)
    renderer.set_world(color=color, **group)


def _add_sun_lamp(renderer, direction, irradiance, angle, note, group=None):
    """A sky's sun disc as a sun lamp: light from ``direction`` (world, unit)
    with ``irradiance`` (RGB, W/m^2) over a disc of ``angle`` (radians)."""
    import numpy as np
    z = np.asarray(direction, dtype=np.float64)
    if not np.all(np.isfinite(z)) or not np.all(np.isfinite(irradiance)):
        note("Sky Texture: the sun disc's light is not finite (left out)")
        return
    z /= np.linalg.norm(z)
    helper = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1], matrix[:3, 2] = x, y, z  # a sun lamp shines along its -Z
    peak = max(irradiance)
    energy = min(peak, MAX_WORLD)
    renderer.add_light(type="SUN", matrix=matrix, color=tuple(c / peak for c in irradiance), energy=energy,
                       angle=float(angle), cast_shadow=True, **(group or {}))


def _finite_color(value):
    return tuple(min(max(c, 0.0), MAX_WORLD) for c in _color3(value))


def _world_output(tree):
    """The World Output Cycles renders (the graph compiler's own choice)."""
    from ..materials.builder import material_output
    return material_output(tree, "ShaderNodeOutputWorld")


def _needs_graph(world):
    """True if the world's tree is more than a constant background."""
    if not world.use_nodes or world.node_tree is None:
        return False
    output = _world_output(world.node_tree)
    if output is None:
        return False
    node = _linked(output.inputs.get("Surface"))
    if node is None:
        return False
    if node.bl_idname != "ShaderNodeBackground":
        return True
    for name, constant in (("Color", "ShaderNodeRGB"), ("Strength", "ShaderNodeValue")):
        socket = node.inputs[name]
        if socket.is_linked:
            src = _linked(socket)
            if src is not None and src.bl_idname != constant:
                return True
    return False


def world_color(world):
    """Return ((r, g, b), warnings): finite, in [0, 1e12]."""
    color, warnings = _world_color(world)
    color = tuple(max(0.0, c) if math.isfinite(c) else 0.0 for c in color)
    if max(color) > MAX_WORLD:
        warnings = list(warnings) + [f"World '{world.name}': colour x strength {max(color):g} clamped to {MAX_WORLD:g}"]
        color = tuple(min(c, MAX_WORLD) for c in color)
    return color, warnings


def _world_color(world):
    if world is None:
        return (0.0, 0.0, 0.0), []
    if not world.use_nodes or world.node_tree is None:
        return _color3(world.color), []
    output = _world_output(world.node_tree)
    if output is None:
        return (0.0, 0.0, 0.0), []
    node = _linked(output.inputs.get("Surface"))
    if node is None:
        return (0.0, 0.0, 0.0), []
    if node.bl_idname == "ShaderNodeBackground":
        warnings = []
        color_socket, strength_socket = node.inputs["Color"], node.inputs["Strength"]
        color = color_socket.default_value
        if color_socket.is_linked:
            src = _linked(color_socket)
            if src is not None and src.bl_idname == "ShaderNodeRGB":
                color = src.outputs[0].default_value
            else:
                label = src.bl_label if src is not None else "a link"
                warnings.append(f"World '{world.name}': background colour driven by {label} "
                                "(not understood, used the viewport colour)")
                color = world.color
        strength = float(strength_socket.default_value)
        if strength_socket.is_linked:
            src = _linked(strength_socket)
            if src is not None and src.bl_idname == "ShaderNodeValue":
                strength = float(src.outputs[0].default_value)
            else:
                warnings.append(f"World '{world.name}': background strength driven by a node (used its own value)")
        if not math.isfinite(strength):
            strength = 0.0
        return tuple(max(0.0, c * strength) for c in _color3(color)), warnings
    return _color3(world.color), [
        f"World '{world.name}': {node.bl_label} shader is not understood (used the viewport colour)"]


def mist_params(world):
    """Keyword arguments of render() for the Mist pass (World > Mist Pass)."""
    if world is None:
        return {"mist_start": 5.0, "mist_depth": 25.0, "mist_falloff": "QUADRATIC"}
    mist = world.mist_settings
    falloff = mist.falloff if mist.falloff in MIST_FALLOFFS else "QUADRATIC"
    # NaN/Inf (possible through Python or drivers) would reach the Mist pass.
    start = float(mist.start) if math.isfinite(mist.start) else 5.0
    depth = float(mist.depth) if math.isfinite(mist.depth) and mist.depth > 0 else 25.0
    return {"mist_start": start, "mist_depth": depth, "mist_falloff": falloff}
