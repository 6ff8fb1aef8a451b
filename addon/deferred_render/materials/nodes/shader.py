"""Shader nodes -> closures (shaders/nodes/node_shader_lib.glsl).

What the G-buffer cannot hold is named in the material's warning: Principled
subsurface, anisotropy and a clearcoat normal; transmission, folded in as
Cycles shows a closed glass object at Max Bounces 0 (no refraction); a tinted
Transparent BSDF (rendered as its grey); Add Shader of
two reflecting BSDFs (drawn one at a time at twice the weight, exact for the
diffuse and metallic parts only). Shader nodes without a spec fall back to a
Diffuse BSDF of their Color input (builder.py, '#unsupported_shader').
"""

from . import register
from .. import graph as graph_walk

# An IOR this close to 0 with Transmission: Cycles 3.4 renders the surface
# black (measured: the materials library's 'Crushed Velvet Eevee', IOR 0,
# Transmission 0.059, Multiscatter GGX at roughness 1, is black at IOR 0 to
# 1e-4 under sun, area, point and spot lights and the world, lit at 1e-3:
# its glass closure is not finite there and Cycles' film drops the sample).
# This engine renders the IOR's limit (a white mirror lobe of weight
# Transmission) and says so.
NEAR_ZERO_IOR = 1e-3
NEAR_ZERO_IOR_NOTE = ("'{name}': 'IOR' = {ior:.3g} with Transmission: Cycles 3.4 renders this surface black "
                      "(its glass closure is not finite at an IOR near 0); rendered as the IOR's limit, a mirror")

# Multiscatter GGX (a Principled BSDF's distribution; the library materials
# use it, a new one in Blender 3.4 is GGX) is shaded as GGX: Cycles' random walk between microfacets returns the energy single scattering
# loses at high roughness, which this engine does not model. Measured by
# tools/cycles_probe/probe_multiscatter.py (multiscatter_table.py): a
# sphere under a uniform world is 0.2-1.9 % brighter in Cycles for a
# dielectric, 11 % for a metal at roughness 0.5 and 2.3x at 1. Named where
# the estimate passes MULTISCATTER_NOTE_ABOVE (a linked input: its worst
# value).
MULTISCATTER_NOTE_ABOVE = 1.02


def _interpolate(xs, ys, x):
    x = min(max(x, xs[0]), xs[-1])
    for k in range(len(xs) - 1):
        if x <= xs[k + 1]:
            t = (x - xs[k]) / (xs[k + 1] - xs[k])
            return ys[k] + t * (ys[k + 1] - ys[k])
    return ys[-1]


def multiscatter_ratio(metallic, roughness):
    """Cycles' Principled BSDF mean with Multiscatter GGX over GGX (the
    measured table, interpolated); a None input (linked) takes its worst
    value."""
    from .. import multiscatter_table as t
    def row(m):
        if roughness is None:
            return max(t.RATIO[t.METALLIC.index(m)])
        return _interpolate(t.ROUGHNESS, t.RATIO[t.METALLIC.index(m)], roughness)
    column = [row(m) for m in t.METALLIC]
    return max(column) if metallic is None else _interpolate(t.METALLIC, column, metallic)


def multiscatter_note(name, metallic, roughness):
    """The note for a Principled BSDF with Multiscatter GGX, or None where
    Cycles' is within MULTISCATTER_NOTE_ABOVE of GGX."""
    ratio = multiscatter_ratio(metallic, roughness)
    if ratio < MULTISCATTER_NOTE_ABOVE:
        return None
    linked = [label for label, v in (("Metallic", metallic), ("Roughness", roughness)) if v is None]
    how = "up to" if linked else "about"
    why = f"{' and '.join(linked)} linked; " if linked else ""
    return (f"'{name}': Multiscatter GGX shaded as GGX: Cycles renders it {how} {100.0 * (ratio - 1.0):.0f} % "
            f"brighter ({why}its multiple scattering, measured on a sphere under a uniform world)")


# Shader nodes without a reflecting lobe (for Add Shader's note).
_NOT_REFLECTING = {"ShaderNodeEmission", "ShaderNodeBackground", "ShaderNodeBsdfTransparent", "ShaderNodeHoldout"}


def _closure_normal(b):
    """The closure's Normal input; a normal other than the smooth one (Bump,
    Normal Map, any vector) marks the graph (the lighting then needs the
    smooth normal too: Cycles drops light samples below it)."""
    arg = b.input("Normal", "vector", implicit="N")
    if arg != ("shading", "N"):
        b._graph.closure_normal = True
    return arg


def _value(b, identifier):
    """The socket's constant value when unlinked (None if linked)."""
    if b.is_linked(identifier):
        return None
    for s in b.node.inputs:
        if s.identifier == identifier:
            v = s.default_value
            try:
                return float(v)
            except TypeError:
                return tuple(v)
    return None


@register("ShaderNodeBsdfPrincipled")
def principled(b):
    for identifier, neutral in (("Subsurface", 0.0), ("Anisotropic", 0.0)):
        v = _value(b, identifier)
        if v is None:
            b._graph.note(f"'{b.node.name}': '{identifier}' is linked (not rendered)")
        elif abs(v - neutral) > 1e-6:
            b._graph.note(f"'{b.node.name}': '{identifier}' = {v:.3g} (not rendered)")
    # Transmission is folded into the parameter set (principled_fold_transmission).
    transmission = _value(b, "Transmission")
    if transmission is None or transmission > 1e-6:
        value = "linked" if transmission is None else f"{transmission:.3g}"
        b._graph.note(f"'{b.node.name}': 'Transmission' {value}: rendered as Cycles at Max Bounces 0 shows a "
                      "closed glass object (its Fresnel reflection, less diffuse); light refracted through the "
                      "surface is not rendered")
        ior = _value(b, "IOR")
        if ior is not None and ior < NEAR_ZERO_IOR:
            b._graph.note(NEAR_ZERO_IOR_NOTE.format(name=b.node.name, ior=ior))
    if b.is_linked("Clearcoat Normal"):
        b._graph.note(f"'{b.node.name}': 'Clearcoat Normal' (the base normal is used)")
    if getattr(b.node, "distribution", "GGX") == "MULTI_GGX":
        note = multiscatter_note(b.node.name, _value(b, "Metallic"), _value(b, "Roughness"))
        if note:
            b._graph.note(note)
    alpha = _value(b, "Alpha")
    if alpha is None or alpha < 1.0:
        b._graph.uses_alpha = True  # stochastic transparency (the program discards)
    b.call("node_bsdf_principled",
           [b.input("Base Color", "color"), b.input("Metallic", "float"), b.input("Specular", "float"),
            b.input("Specular Tint", "float"), b.input("Roughness", "float"), b.input("Sheen", "float"),
            b.input("Sheen Tint", "float"), b.input("Clearcoat", "float"), b.input("Clearcoat Roughness", "float"),
            b.input("Transmission", "float"), b.input("IOR", "float"), b.input("Emission", "color"), b.input("Emission Strength", "float"), b.input("Alpha", "float"),
            _closure_normal(b)],
           [("BSDF", "closure")])


@register("ShaderNodeBsdfDiffuse")
def diffuse(b):
    b.call("node_bsdf_diffuse",
           [b.input("Color", "color"), b.input("Roughness", "float"), _closure_normal(b)],
           [("BSDF", "closure")])


# node_bsdf_glossy's model (the G-buffer's closure model, gbuffer_lib.glsl).
GLOSSY_MODEL_GGX = 1
GLOSSY_MODEL_BECKMANN = 2


@register("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic")
def glossy(b):
    distribution = getattr(b.node, "distribution", "GGX")
    if distribution == "SHARP":
        roughness = b.const(0.0, "float")  # Cycles: a perfect mirror, Roughness unused
    else:
        roughness = b.input("Roughness", "float")
        if distribution not in {"GGX", "BECKMANN"}:
            b._graph.note(f"'{b.node.name}': {distribution.replace('_', ' ').title()} distribution shaded as GGX")
    if b.node.bl_idname == "ShaderNodeBsdfAnisotropic":
        anisotropy = _value(b, "Anisotropy")
        if anisotropy is None or abs(anisotropy) > 1e-6:
            b._graph.note(f"'{b.node.name}': anisotropy is not rendered (isotropic)")
    model = GLOSSY_MODEL_BECKMANN if distribution == "BECKMANN" else GLOSSY_MODEL_GGX
    b.call("node_bsdf_glossy",
           [b.int(model), b.input("Color", "color"), roughness, _closure_normal(b)],
           [("BSDF", "closure")])


@register("ShaderNodeBsdfGlass")
def glass(b):
    distribution = getattr(b.node, "distribution", "GGX")
    if distribution == "SHARP":
        roughness = b.const(0.0, "float")  # Cycles: sharp glass, Roughness unused
    else:
        roughness = b.input("Roughness", "float")
        if distribution != "GGX":
            b._graph.note(f"'{b.node.name}': {distribution.replace('_', ' ').title()} distribution shaded as GGX")
    b._graph.note(f"'{b.node.name}': Glass BSDF rendered as Cycles at Max Bounces 0 shows a closed glass object "
                  "(its Fresnel reflection); light refracted through the surface is not rendered")
    b.call("node_bsdf_glass", [b.input("Color", "color"), roughness, b.input("IOR", "float"), _closure_normal(b)],
           [("BSDF", "closure")])


@register("ShaderNodeBsdfRefraction")
def refraction(b):
    # Refraction alone: at Max Bounces 0 Cycles shows a closed object of it
    # black (its ray and its light samples meet the far side).
    b._graph.note(f"'{b.node.name}': Refraction BSDF rendered as Cycles at Max Bounces 0 shows a closed object "
                  "(black); light refracted through the surface is not rendered")
    b.call("node_closure_none", [], [("BSDF", "closure")])


@register("ShaderNodeEmission")
def emission(b):
    b.call("node_emission", [b.input("Color", "color"), b.input("Strength", "float")], [("Emission", "closure")])


@register("ShaderNodeBackground")
def background(b):
    # A world's shader: the radiance along the ray, colour x strength
    # (svm_node_emission_weight, then closure_background_setup). In a
    # material's surface it adds nothing a surface shows.
    if not b._graph.world:
        b._graph.note(f"'{b.node.name}': a Background shader in a material (black)")
        b.call("node_closure_none", [], [("Background", "closure")])
        return
    b.call("node_emission", [b.input("Color", "color"), b.input("Strength", "float")], [("Background", "closure")])


@register("ShaderNodeBsdfTransparent")
def transparent(b):
    b._graph.uses_alpha = True
    color = _value(b, "Color")
    if color is None:
        b._graph.note(f"'{b.node.name}': Transparent BSDF of a linked colour: the light it passes is "
                      f"its colour's grey (a tint is not rendered)")
    elif max(color[:3]) - min(color[:3]) > 1e-6:
        b._graph.note(f"'{b.node.name}': Transparent BSDF tint rendered as its grey "
                      f"({sum(color[:3]) / 3:.3g})")
    b.call("node_bsdf_transparent", [b.input("Color", "color")], [("BSDF", "closure")])


@register("ShaderNodeHoldout")
def holdout(b):
    # Cycles' holdout closure (node_holdout): mixed with other shaders, a
    # partial hole.
    b.call("node_holdout", [], [("Holdout", "closure")])


@register("ShaderNodeMixShader")
def mix_shader(b):
    b.call("node_mix_shader",
           [b.input("Fac", "float"), b.input("Shader", "closure"), b.input("Shader_001", "closure")],
           [("Shader", "closure")])


@register("ShaderNodeAddShader")
def add_shader(b):
    reflecting = 0
    kinds = set()
    for identifier in ("Shader", "Shader_001"):
        socket = next(s for s in b.node.inputs if s.identifier == identifier)
        source = graph_walk.resolve_input(socket, b.ctx)  # through reroutes, groups, mutes
        if isinstance(source, graph_walk.Output) and source.node.bl_idname not in _NOT_REFLECTING:
            reflecting += 1
            kinds.add(source.node.bl_idname)
        if isinstance(source, graph_walk.Output) and source.node.bl_idname == "ShaderNodeBsdfTransparent":
            # A white Transparent BSDF added to a closure passes all the light
            # behind *and* shows the other side (Cycles): coverage 0 cannot
            # (node_add_shader); a grey one is exact in expectation.
            color = source.node.inputs["Color"]
            if color.is_linked or min(color.default_value[:3]) >= 1.0:
                b._graph.note(f"'{b.node.name}': Add Shader with a white (or linked) Transparent BSDF: the other "
                              "side's light is dropped where the surface passes all the light behind it")
    # A Diffuse with a Glossy BSDF: summed where the glossy colour is grey
    # (node_shader_lib.glsl merge_diffuse_glossy), else one drawn at twice
    # its weight, exact for these two lobes (both linear in their colour).
    if reflecting == 2 and not kinds <= {"ShaderNodeBsdfDiffuse", "ShaderNodeBsdfGlossy"}:
        b._graph.note(f"'{b.node.name}': Add Shader of two BSDFs is drawn one at a time at twice the weight "
                      "(exact for diffuse and metallic lobes only)")
    b.call("node_add_shader", [b.input("Shader", "closure"), b.input("Shader_001", "closure")],
           [("Shader", "closure")])


@register("#unsupported_shader")
def unsupported_shader(b):
    """Fallback for shader nodes without a spec: a Diffuse BSDF of the node's colour."""
    has_color = any(s.identifier == "Color" for s in b.node.inputs)
    color = b.input("Color", "color") if has_color else b.const((0.8, 0.8, 0.8), "color")
    has_normal = any(s.identifier == "Normal" for s in b.node.inputs)
    normal = _closure_normal(b) if has_normal else b.shading("N")
    out = next(o for o in b.node.outputs if o.type == "SHADER")
    b.call("node_bsdf_diffuse", [color, b.const(1.0, "float"), normal], [(out.identifier, "closure")])
