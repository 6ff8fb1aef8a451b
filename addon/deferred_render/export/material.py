"""Materials -> the Principled parameter set of ``Renderer.add_material``.

The native renderer shades one constant Principled BSDF (Blender 3.4 inputs)
per material. The node tree is reduced to that set:

- Principled BSDF: inputs read by *name* through PRINCIPLED_INPUTS (3.x names
  first, then the 4.x names), never by index. Inputs driven by an RGB or Value
  node are folded to their constant; any other link is not understood.
- Diffuse BSDF  -> base colour, metallic 0, specular 0 and its own diffuse
  model (``diffuse_roughness``: Oren-Nayar sigma, 0 = Lambert), as Cycles.
- Glossy BSDF   -> its own lobe (``glossy_model``: GGX or Beckmann, weight =
  colour, no Fresnel), metallic 1 so there is no diffuse lobe; Sharp is a
  mirror.
- Glass BSDF    -> its reflection as Cycles shows a closed glass object at
  Max Bounces 0 (_glass: a metallic lobe of colour x F0(IOR)); no refraction.
- Refraction BSDF -> black, as Cycles shows a closed object at Max Bounces 0.
- Emission      -> black, non-reflective surface with that emission.
- Add Shader    -> exact when at most one side reflects: that side's BSDF
  plus the emission of both.
- Mix Shader    -> with a constant factor. Sides that differ only in
  colours (and emission) are mixed as one parameter set, exactly; a side
  that only emits scales the other side's lobes. Otherwise (e.g. Diffuse +
  Glossy, two roughnesses) the material becomes a *stochastic mix*: up to
  MAX_COMPONENTS parameter sets with weights, one chosen per pixel and film
  sample (``Renderer.add_material(mix_with=, mix_probability=)``), so the
  accumulated image converges to Cycles' weighted closures. Factor 0 or 1
  picks one side.
- Reroute nodes are followed.

Transmission is folded into the set as Cycles shows a closed glass object at
Max Bounces 0 (fold_transmission: its reflection, no refraction), named in
the warning. Anything else (textures, groups, Subsurface, normal maps...)
is listed in *one* warning per material. If the surface shader itself
cannot be reduced, the material's viewport display settings are used
(Material > Viewport Display: colour, metallic, roughness), which is also what
a material without nodes renders with.
"""

import math

from ..materials.builder import material_output
from ..materials.nodes.shader import NEAR_ZERO_IOR, NEAR_ZERO_IOR_NOTE, multiscatter_note

# Native parameter -> (kind, Principled input names: Blender 3.x first, then 4.x).
# Every read of a Principled BSDF input goes through this table.
PRINCIPLED_INPUTS = (
    ("base_color", "color", ("Base Color",)),
    ("metallic", "float", ("Metallic",)),
    ("roughness", "float", ("Roughness",)),
    ("specular", "float", ("Specular", "Specular IOR Level")),
    ("specular_tint", "float", ("Specular Tint",)),
    ("sheen", "float", ("Sheen", "Sheen Weight")),
    ("sheen_tint", "float", ("Sheen Tint",)),
    ("clearcoat", "float", ("Clearcoat", "Coat Weight")),
    ("clearcoat_roughness", "float", ("Clearcoat Roughness", "Coat Roughness")),
    ("emission", "color", ("Emission", "Emission Color")),
    ("emission_strength", "float", ("Emission Strength",)),
    ("alpha", "float", ("Alpha",)),
)

# Principled inputs the renderer does not model: (names, neutral value). A
# linked input or a value away from neutral is reported as not understood.
PRINCIPLED_UNSUPPORTED = (
    (("Subsurface", "Subsurface Weight"), 0.0),
    (("Anisotropic",), 0.0),
    (("Normal",), None),            # only a link matters
    (("Clearcoat Normal", "Coat Normal"), None),
    (("Tangent",), None),
)

# Transmission (folded into the parameter set, fold_transmission) and the IOR it uses.
PRINCIPLED_TRANSMISSION = ("Transmission", "Transmission Weight")
PRINCIPLED_IOR = ("IOR",)

# The renderer's defaults (= native add_material defaults = Blender's default surface).
DEFAULT_PARAMS = {
    "base_color": (0.8, 0.8, 0.8),
    "metallic": 0.0,
    "roughness": 0.5,
    "specular": 0.5,
    "specular_tint": 0.0,
    "sheen": 0.0,
    "sheen_tint": 0.5,
    "clearcoat": 0.0,
    "clearcoat_roughness": 0.03,
    "emission": (0.0, 0.0, 0.0),
    "emission_strength": 1.0,
    "alpha": 1.0,
    # < 0: the Principled BSDF's diffuse lobe (Burley); 0..1: a Diffuse BSDF,
    # Oren-Nayar with this sigma (0: Lambert), as Cycles shades it.
    "diffuse_roughness": -1.0,
    # 0: the Principled BSDF's specular; 1/2: a Glossy BSDF, GGX/Beckmann.
    "glossy_model": 0,
    "pass_index": 0,
}

_COLOR_PARAMS = ("base_color", "emission")


class _Unreduced(Exception):
    """A shader node that does not reduce to the parameter set."""


def _clamp01(x):
    return min(max(float(x), 0.0), 1.0)


def _finite(x, fallback):
    x = float(x)
    return x if math.isfinite(x) else fallback


def _color(value, fallback=(0.0, 0.0, 0.0)):
    try:
        rgb = tuple(float(v) for v in tuple(value)[:3])
    except TypeError:  # a float socket used where a colour is expected
        rgb = (float(value),) * 3
    return tuple(_finite(c, f) for c, f in zip(rgb, fallback))


def _scalar(value):
    try:
        seq = tuple(value)
    except TypeError:
        return float(value)
    # A colour socket where a float is expected (4.x colour tints): its mean.
    return sum(float(v) for v in seq[:3]) / 3.0


def _find_input(node, names):
    for name in names:
        socket = node.inputs.get(name)
        if socket is not None:
            return socket
    return None


def _from_socket(link_from_node, link_from_socket, seen):
    """Follow reroutes; return the node and output socket a link comes from."""
    node, socket = link_from_node, link_from_socket
    while node.bl_idname == "NodeReroute":
        if node in seen:
            break
        seen.add(node)
        if not node.inputs[0].is_linked:
            return None, None
        link = node.inputs[0].links[0]
        node, socket = link.from_node, link.from_socket
    return node, socket


def _input_value(socket, notes, label):
    """Constant value of an input socket: its default, or the RGB/Value node
    driving it. Anything else is noted and the socket's own value used."""
    if not socket.is_linked:
        return socket.default_value
    link = socket.links[0]
    if not link.is_valid or link.is_muted:
        return socket.default_value
    node, out = _from_socket(link.from_node, link.from_socket, set())
    if node is None:
        return socket.default_value
    if node.bl_idname in {"ShaderNodeRGB", "ShaderNodeValue"}:
        return out.default_value
    notes.append(f"{label} driven by {node.bl_label or node.bl_idname} (used its own value)")
    return socket.default_value


def _principled(node, notes):
    params = {}
    for param, kind, names in PRINCIPLED_INPUTS:
        socket = _find_input(node, names)
        if socket is None:
            continue
        value = _input_value(socket, notes, f"'{socket.name}'")
        if kind == "color":
            params[param] = _color(value, DEFAULT_PARAMS[param])
        else:
            params[param] = _finite(_scalar(value), DEFAULT_PARAMS[param])
    for names, neutral in PRINCIPLED_UNSUPPORTED:
        socket = _find_input(node, names)
        if socket is None:
            continue
        if socket.is_linked:
            notes.append(f"'{socket.name}' input (linked, ignored)")
        elif neutral is not None and abs(_scalar(socket.default_value) - neutral) > 1e-6:
            notes.append(f"'{socket.name}' = {_scalar(socket.default_value):.3g} (not rendered)")
    # 'MULTI_GGX' has no closed form: shaded as GGX (see shared/REFERENCE.md),
    # named where Cycles' is measurably brighter (materials/nodes/shader.py).
    if getattr(node, "distribution", "GGX") == "MULTI_GGX":
        note = multiscatter_note(node.name, float(params.get("metallic", 0.0)), float(params.get("roughness", 0.5)))
        if note:
            notes.append(note)
    socket = _find_input(node, PRINCIPLED_TRANSMISSION)
    transmission = 0.0 if socket is None else _finite(
        _scalar(_input_value(socket, notes, f"'{socket.name}'")), 0.0)
    if transmission > 1e-6:
        ior_socket = _find_input(node, PRINCIPLED_IOR)
        ior = 1.45 if ior_socket is None else _finite(
            _scalar(_input_value(ior_socket, notes, f"'{ior_socket.name}'")), 1.45)
        if ior < NEAR_ZERO_IOR:
            notes.append(NEAR_ZERO_IOR_NOTE.format(name=node.name, ior=ior))
        params = fold_transmission(_full(params), transmission, ior)
        params.pop("pass_index", None)
        notes.append(TRANSMISSION_NOTE.format(name=socket.name, value=transmission))
    return params


# What the fold leaves out, said in the material's warning.
TRANSMISSION_NOTE = ("'{name}' = {value:.3g}: rendered as Cycles at Max Bounces 0 shows a closed glass "
                     "object (its Fresnel reflection, less diffuse); light refracted through the surface "
                     "is not rendered")


def dielectric_f0(ior):
    """Cycles' fresnel_dielectric_cos(1, ior): the reflectance at normal
    incidence, the same for ior and 1 / ior."""
    ior = max(float(ior), 1e-5)
    return ((ior - 1.0) / (ior + 1.0)) ** 2


def fold_transmission(params, transmission, ior):
    """A Principled parameter set with Transmission folded into the
    parameters the renderer has (shaders/nodes/node_shader_lib.glsl
    principled_fold_transmission is the same formula).

    Cycles 3.4 (svm_node_closure_bsdf, CLOSURE_BSDF_PRINCIPLED_ID): with
    m = metallic, T = transmission, T' = T (1 - m), the diffuse and sheen
    lobes take wd = (1 - m)(1 - T), the specular lobe ws = 1 - T', and a
    glass closure of weight T' adds a reflection of weight
    fresnel_dielectric_cos(N.I, ior) (white at Specular Tint 0) and a
    refraction. At Max Bounces 0 the refraction of a closed object meets
    its own far side, so it shows nothing; the reflection is a GGX lobe of
    the same roughness. Here: base' = base (wd + m ws) and metallic' = m ws /
    (wd + m ws) give the diffuse base wd and the metallic colour base m ws
    exactly; sheen' = sheen wd / (1 - metallic'); the dielectric reflectance
    at normal incidence D = 0.08 specular (1 - m) ws + T' F0(ior) becomes
    0.08 specular' (1 - metallic'), one Principled specular lobe (its
    Fresnel curve from that F0; Cycles' glass reflection takes N.I's
    Fresnel where this takes L.H's). Where specular' would pass the
    G-buffer's 12 (metallic' near 1: Metallic above 0 at Transmission near
    1) the lobe turns wholly metallic, of colour base (wd + m ws) + D (the
    small diffuse part goes into it)."""
    m = _clamp01(params["metallic"])
    t = _clamp01(transmission)
    if t <= 0.0:
        return params
    glass = t * (1.0 - m)
    wd = (1.0 - m) * (1.0 - t)
    ws = 1.0 - glass
    k = wd + m * ws
    dielectric = 0.08 * float(params["specular"]) * (1.0 - m) * ws + glass * dielectric_f0(ior)
    out = dict(params)
    metallic = m * ws / k if k > 0.0 else m
    out["base_color"] = tuple(c * k for c in params["base_color"])
    if 1.0 - metallic > 1e-6 and dielectric <= 12.0 * 0.08 * (1.0 - metallic):
        out["metallic"] = metallic
        out["specular"] = dielectric / (0.08 * (1.0 - metallic))
        out["sheen"] = float(params["sheen"]) * wd / (1.0 - metallic)
    else:
        out["metallic"] = 1.0
        out["base_color"] = tuple(c + dielectric for c in out["base_color"])
        out["sheen"] = 0.0
    return out


def _diffuse(node, notes):
    return {
        "base_color": _color(_input_value(node.inputs["Color"], notes, "Diffuse 'Color'"), (0.8, 0.8, 0.8)),
        "metallic": 0.0,
        "specular": 0.0,
        "roughness": 1.0,
        # svm_node_closure_bsdf: Lambert at roughness 0, else Oren-Nayar (sigma saturated).
        "diffuse_roughness": min(max(_finite(_scalar(_input_value(node.inputs["Roughness"], notes,
                                                                   "Diffuse 'Roughness'")), 0.0), 0.0), 1.0),
    }


def _glossy(node, notes):
    distribution = getattr(node, "distribution", "GGX")
    if distribution not in {"GGX", "BECKMANN", "SHARP"}:
        notes.append(f"'{node.name}': {distribution.replace('_', ' ').title()} distribution shaded as GGX")
    if node.bl_idname == "ShaderNodeBsdfAnisotropic":
        anisotropy = node.inputs["Anisotropy"]
        if anisotropy.is_linked or abs(_scalar(anisotropy.default_value)) > 1e-6:
            notes.append(f"'{node.name}': anisotropy is not rendered (isotropic)")
    roughness = (0.0 if distribution == "SHARP" else
                 _finite(_scalar(_input_value(node.inputs["Roughness"], notes, "Glossy 'Roughness'")), 0.5))
    return {
        "base_color": _color(_input_value(node.inputs["Color"], notes, "Glossy 'Color'"), (0.8, 0.8, 0.8)),
        "metallic": 1.0,
        "roughness": roughness,
        # A Glossy BSDF's own lobe: weight = colour, no Fresnel; GGX or Beckmann.
        "glossy_model": 2 if distribution == "BECKMANN" else 1,
    }


def _glass(node, notes):
    """Glass BSDF as Cycles shows a closed glass object at Max Bounces 0
    (node_bsdf_glass in shaders/nodes/node_shader_lib.glsl: the same
    parameters): its reflection, colour x fresnel_dielectric_cos(N.I, ior),
    as a metallic lobe of normal-incidence colour colour x F0(ior)."""
    distribution = getattr(node, "distribution", "GGX")
    if distribution not in {"GGX", "SHARP"}:
        notes.append(f"'{node.name}': {distribution.replace('_', ' ').title()} distribution shaded as GGX")
    notes.append(f"'{node.name}': Glass BSDF rendered as Cycles at Max Bounces 0 shows a closed glass object "
                 "(its Fresnel reflection); light refracted through the surface is not rendered")
    roughness = (0.0 if distribution == "SHARP" else
                 _finite(_scalar(_input_value(node.inputs["Roughness"], notes, "Glass 'Roughness'")), 0.0))
    f0 = dielectric_f0(_finite(_scalar(_input_value(node.inputs["IOR"], notes, "Glass 'IOR'")), 1.45))
    color = _color(_input_value(node.inputs["Color"], notes, "Glass 'Color'"), (1.0, 1.0, 1.0))
    return {
        "base_color": tuple(max(c, 0.0) * f0 for c in color),
        "metallic": 1.0,
        "specular": f0 / 0.08,
        "roughness": _clamp01(roughness),
    }


def _emission(node, notes):
    return {
        "base_color": (0.0, 0.0, 0.0),
        "metallic": 0.0,
        "specular": 0.0,
        "emission": _color(_input_value(node.inputs["Color"], notes, "Emission 'Color'"), (1.0, 1.0, 1.0)),
        "emission_strength": _finite(_scalar(_input_value(node.inputs["Strength"], notes, "Emission 'Strength'")), 1.0),
    }


def _full(params):
    out = dict(DEFAULT_PARAMS)
    out.update(params)
    out.pop("pass_index", None)
    return out


def _emitted(params):
    """Emitted radiance of a parameter set as one colour (emission x strength)."""
    s = params["emission_strength"]
    return tuple(c * s for c in params["emission"])


def _reflects(params):
    """True if the set reflects light at all (a pure Emission shader does not)."""
    base_black = max(params["base_color"]) <= 0.0
    no_specular = params["specular"] <= 0.0 and params["metallic"] <= 0.0
    return not (base_black and no_specular and params["sheen"] <= 0.0 and params["clearcoat"] <= 0.0)


def _mix(a, b, t):
    out = {}
    for key in a:
        if key in _COLOR_PARAMS:
            continue
        out[key] = (1.0 - t) * a[key] + t * b[key]
    out["base_color"] = tuple((1.0 - t) * x + t * y for x, y in zip(a["base_color"], b["base_color"]))
    # Emission mixes as radiance, not as colour and strength separately.
    ea, eb = _emitted(a), _emitted(b)
    out["emission"] = tuple((1.0 - t) * x + t * y for x, y in zip(ea, eb))
    out["emission_strength"] = 1.0
    if not _reflects(a):      # mixing with pure emission scales the BSDF only by its colours
        for key in ("metallic", "roughness", "specular", "specular_tint", "sheen", "sheen_tint",
                    "clearcoat", "clearcoat_roughness", "alpha", "diffuse_roughness", "glossy_model"):
            out[key] = b[key]
        out["specular"] = t * b["specular"]
        if _summed_diffuse_glossy(b):
            out["specular_tint"] = t * b["specular_tint"]  # its glossy weight
    elif not _reflects(b):
        for key in ("metallic", "roughness", "specular", "specular_tint", "sheen", "sheen_tint",
                    "clearcoat", "clearcoat_roughness", "alpha", "diffuse_roughness", "glossy_model"):
            out[key] = a[key]
        out["specular"] = (1.0 - t) * a["specular"]
        if _summed_diffuse_glossy(a):
            out["specular_tint"] = (1.0 - t) * a["specular_tint"]
    return out


def _summed_diffuse_glossy(p):
    """A set made by _diffuse_glossy: its glossy weight is specular_tint."""
    return p["glossy_model"] > 0 and p["metallic"] < 0.5


# A stochastic mix: a list of (parameter set, weight), weights summing to 1.
MAX_COMPONENTS = 8

# Parameters that must be equal for two sets to mix exactly as one set
# (radiance is linear in the colours and emission only).
_SHAPE_PARAMS = ("metallic", "roughness", "specular", "specular_tint", "sheen", "sheen_tint",
                 "clearcoat", "clearcoat_roughness", "alpha", "diffuse_roughness", "glossy_model")


def _components(x):
    return x if isinstance(x, list) else [(x, 1.0)]


def _exactly_mixable(a, b):
    """True if (1-t) a + t b is the parameter set with interpolated colours:
    same lobe shapes, and the base colour entering only linearly (no
    specular or sheen tint, which divide by its luminance)."""
    if any(a[k] != b[k] for k in _SHAPE_PARAMS):
        return False
    return a["specular_tint"] == 0.0 and (a["sheen"] == 0.0 or a["sheen_tint"] == 0.0)


def _lambert_diffuse(p):
    """A Diffuse BSDF of roughness 0 alone (Lambert)."""
    return (p["glossy_model"] == 0 and p["diffuse_roughness"] == 0.0 and p["metallic"] == 0.0 and
            p["specular"] == 0.0 and p["sheen"] == 0.0 and p["clearcoat"] == 0.0)


def _grey_glossy(p):
    """A Glossy BSDF alone (metallic 1: no diffuse lobe) of a grey colour."""
    c = p["base_color"]
    return (p["glossy_model"] > 0 and p["metallic"] == 1.0 and p["sheen"] == 0.0 and p["clearcoat"] == 0.0 and
            c[0] == c[1] == c[2])


def _diffuse_glossy(a, b, wa, wb):
    """wa a + wb b as one set where a is a Lambert diffuse and b a grey glossy
    (or the other way round) of one coverage: the glossy model with metallic
    0, the diffuse weight in base_color and the glossy weight in
    specular_tint (native Material, scene.h; shaders/nodes/node_shader_lib.glsl
    merge_diffuse_glossy, the graphs' same rule). Cycles sums the two
    closures; a stochastic mix would draw one of them per sample. None where
    the sets are not those, or the glossy weight is above 1 (a native
    Material's specular_tint is at most 1; the graphs' G-buffer holds more)."""
    for d, g, wd, wg in ((a, b, wa, wb), (b, a, wb, wa)):
        if not (_lambert_diffuse(d) and _grey_glossy(g) and d["alpha"] == g["alpha"]):
            continue
        k = wg * g["base_color"][0]
        if not 0.0 <= k <= 1.0:
            continue
        out = dict(g)
        out["base_color"] = tuple(wd * x for x in d["base_color"])
        out["metallic"] = 0.0
        out["specular_tint"] = k
        out["diffuse_roughness"] = 0.0  # Lambert (the native packing keeps the glossy model)
        ed, eg = _emitted(d), _emitted(g)
        out["emission"] = tuple(wd * x + wg * y for x, y in zip(ed, eg))
        out["emission_strength"] = 1.0
        return out
    return None


def _mixture(a, b, t, notes):
    """(1 - t) a + t b for parameter sets or mixtures."""
    if not isinstance(a, list) and not isinstance(b, list):
        summed = _diffuse_glossy(a, b, 1.0 - t, t)
        if summed is not None:
            return summed
    if not isinstance(a, list) and not isinstance(b, list) and \
            (not _reflects(a) or not _reflects(b) or _exactly_mixable(a, b)):
        return _mix(a, b, t)
    if not isinstance(a, list) and not _reflects(a):   # emission mixed into each component
        return [(_mix(a, p, t), w) for p, w in _components(b)]
    if not isinstance(b, list) and not _reflects(b):
        return [(_mix(p, b, t), w) for p, w in _components(a)]
    out = [(p, (1.0 - t) * w) for p, w in _components(a)] + [(p, t * w) for p, w in _components(b)]
    merged = []
    for p, w in out:
        for i, (q, v) in enumerate(merged):
            if _exactly_mixable(p, q):
                merged[i] = (_mix(q, p, w / (v + w)), v + w)
                break
        else:
            merged.append((p, w))
    if len(merged) > MAX_COMPONENTS:
        notes.append(f"more than {MAX_COMPONENTS} different shaders mixed (the smallest merged as parameters)")
        merged.sort(key=lambda c: -c[1])
        while len(merged) > MAX_COMPONENTS:
            p, w = merged.pop()
            q, v = merged[-1]
            merged[-1] = (_mix(q, p, w / (v + w)), v + w)
    return merged[0][0] if len(merged) == 1 else merged


def _add(a, b, notes):
    if isinstance(a, list) or isinstance(b, list):
        # Emission added to a mixture: added to each component.
        emitter, mixture = (b, a) if isinstance(a, list) else (a, b)
        if isinstance(emitter, list) or _reflects(emitter):
            raise _Unreduced("Add Shader of two reflecting BSDFs")
        return [(_add(p, emitter, notes), w) for p, w in mixture]
    if _reflects(a) and _reflects(b):
        summed = _diffuse_glossy(a, b, 1.0, 1.0)
        if summed is not None:
            return summed
        raise _Unreduced("Add Shader of two reflecting BSDFs")
    base = a if _reflects(a) else b
    out = dict(base)
    ea, eb = _emitted(a), _emitted(b)
    out["emission"] = tuple(x + y for x, y in zip(ea, eb))
    out["emission_strength"] = 1.0
    return out


def _reduce(node, notes, depth=0):
    """Parameter set of a shader node (full dict) or a stochastic mix (a list
    of (dict, weight)), or raise _Unreduced."""
    if depth > 32:
        raise _Unreduced("shader tree too deep")
    kind = node.bl_idname
    if kind == "ShaderNodeBsdfPrincipled":
        return _full(_principled(node, notes))
    if kind == "ShaderNodeBsdfDiffuse":
        return _full(_diffuse(node, notes))
    if kind == "ShaderNodeBsdfGlossy" or kind == "ShaderNodeBsdfAnisotropic":
        return _full(_glossy(node, notes))
    if kind == "ShaderNodeEmission":
        return _full(_emission(node, notes))
    if kind == "ShaderNodeBsdfGlass":
        return _full(_glass(node, notes))
    if kind == "ShaderNodeBsdfRefraction":
        # At Max Bounces 0 Cycles shows a closed object of it black (node_shader.py refraction).
        notes.append(f"'{node.name}': Refraction BSDF rendered as Cycles at Max Bounces 0 shows a closed object "
                     "(black); light refracted through the surface is not rendered")
        return _full({"base_color": (0.0, 0.0, 0.0), "specular": 0.0, "metallic": 0.0})
    if kind in {"ShaderNodeMixShader", "ShaderNodeAddShader"}:
        shader_inputs = [s for s in node.inputs if s.type == "SHADER"]
        sides = []
        for socket in shader_inputs[:2]:
            linked = _linked_node(socket)
            if linked is None:
                # An unlinked shader socket is "no closure": black, non-emitting.
                sides.append(_full({"base_color": (0.0, 0.0, 0.0), "specular": 0.0, "metallic": 0.0}))
            else:
                sides.append(_reduce(linked, notes, depth + 1))
        if kind == "ShaderNodeAddShader":
            return _add(sides[0], sides[1], notes)
        fac_socket = node.inputs[0]
        fac = _clamp01(_scalar(_input_value(fac_socket, notes, "Mix Shader 'Fac'")))
        if fac <= 0.0:
            return sides[0]
        if fac >= 1.0:
            return sides[1]
        return _mixture(sides[0], sides[1], fac, notes)
    raise _Unreduced(f"{node.bl_label or kind} shader")


def _linked_node(socket):
    if not socket.is_linked:
        return None
    link = socket.links[0]
    if not link.is_valid or link.is_muted:
        return None
    node, _ = _from_socket(link.from_node, link.from_socket, set())
    if node is not None and node.mute:
        return None
    return node


# Cycles' default surface (scene.cpp Scene::default_surface: a Diffuse BSDF
# of colour 0.8, roughness 0 = Lambert) for objects without a material.
DEFAULT_SURFACE = dict(DEFAULT_PARAMS, specular=0.0, diffuse_roughness=0.0)


def viewport_params(material):
    """A material without nodes as Cycles renders it (blender/shader.cpp:
    a Diffuse BSDF of the viewport colour), or the default surface."""
    if material is None:
        return dict(DEFAULT_SURFACE)
    params = _full({
        "base_color": _color(material.diffuse_color, (0.8, 0.8, 0.8)),
        "specular": 0.0,
        "diffuse_roughness": 0.0,
    })
    params["pass_index"] = int(material.pass_index)
    return params


# The native input contract (native/src/scene_store.h, InputLimits): specular
# up to 12 (F0 0.96; 12.5 is an infinite IOR), base colour up to 65504 (the
# half-float G-buffer).
MAX_SPECULAR = 12.0
MAX_BASE_COLOR = 65504.0


def _sanitize(params, notes=None):
    """Clamp to the ranges the renderer accepts; NaN becomes the default.
    Values beyond the native limits (reachable through linked Value/RGB
    nodes) are noted."""
    out = dict(params)
    for key in ("metallic", "roughness", "specular_tint", "sheen", "sheen_tint", "clearcoat",
                "clearcoat_roughness", "alpha"):
        out[key] = _clamp01(_finite(out[key], DEFAULT_PARAMS[key]))
    specular = _finite(out["specular"], DEFAULT_PARAMS["specular"])
    if specular > MAX_SPECULAR and notes is not None:
        notes.append(f"Specular {specular:g} clamped to {MAX_SPECULAR:g}")
    out["specular"] = min(max(0.0, specular), MAX_SPECULAR)
    strength = _finite(out["emission_strength"], 0.0)
    if strength < 0.0 and notes is not None:
        notes.append("negative Emission Strength")
    out["emission_strength"] = max(0.0, strength)
    base = tuple(max(0.0, _finite(c, 0.0)) for c in out["base_color"])
    if max(base) > MAX_BASE_COLOR and notes is not None:
        notes.append(f"Base Color above {MAX_BASE_COLOR:g} clamped")
    out["base_color"] = tuple(min(c, MAX_BASE_COLOR) for c in base)
    emission = tuple(_finite(c, 0.0) for c in out["emission"])
    if min(emission) < 0.0 and notes is not None:
        # Cycles emits negative light; the constant path cannot (node path does).
        notes.append("negative Emission")
    out["emission"] = tuple(max(0.0, c) for c in emission)
    return out


def material_params(material):
    """Return (params, not_understood) for a material (None: default surface).

    ``params`` are keyword arguments of ``Renderer.add_material``; for a
    stochastic mix they also hold ``components``, a list of (keyword
    arguments, weight) that add_materials() turns into a chain;
    ``not_understood`` lists what the reduction could not represent (empty if
    the material is rendered as Blender describes it).
    """
    if material is None:
        return dict(DEFAULT_SURFACE), []
    notes = []
    if not material.use_nodes or material.node_tree is None:
        return viewport_params(material), notes

    output = material_output(material.node_tree)
    if output is None:
        # Not a parameter set: the node path renders it black, as Cycles does.
        notes.append("no Material Output node")
        return viewport_params(material), notes
    surface = output.inputs.get("Surface")
    shader = _linked_node(surface) if surface is not None else None
    if shader is None:
        notes.append("nothing linked to the Surface output")
        return viewport_params(material), notes
    if output.inputs.get("Volume") is not None and output.inputs["Volume"].is_linked:
        notes.append("Volume (not rendered)")
    if output.inputs.get("Displacement") is not None and output.inputs["Displacement"].is_linked:
        notes.append("Displacement (not rendered)")
    if shader.bl_idname == "ShaderNodeHoldout":
        # The whole surface a holdout (Cycles' holdout closure at full
        # weight): a hole in the image. A Holdout mixed with other shaders
        # is not reduced here (the node path warns about it).
        return dict(DEFAULT_SURFACE, holdout=True, pass_index=int(material.pass_index)), notes

    try:
        params = _reduce(shader, notes)
    except _Unreduced as ex:
        notes.insert(0, f"{ex} (used the viewport display colour)")
        return viewport_params(material), notes
    if isinstance(params, list):
        components = [(_sanitize(p, notes), w) for p, w in params]
        for p, _ in components:
            p["pass_index"] = int(material.pass_index)
        params = dict(components[0][0])
        params["components"] = components
        return params, notes
    params = _sanitize(params, notes)
    params["pass_index"] = int(material.pass_index)
    return params, notes


def blend_mode(material):
    """(mode, threshold) from Material > Settings > Blend Mode (EEVEE's
    setting, which Cycles ignores): "blend" (the forward pass), "clip"
    (opaque above the threshold, absent below) or "stochastic" (Opaque and
    Alpha Hashed: alpha as Cycles renders it)."""
    method = getattr(material, "blend_method", "OPAQUE") if material is not None else "OPAQUE"
    if method == 'BLEND':
        return "blend", 0.0
    if method == 'CLIP':
        t = float(getattr(material, "alpha_threshold", 0.5))
        return "clip", (t if math.isfinite(t) else 0.5)
    return "stochastic", 0.0


def with_param(params, key, value):
    """add_material keyword arguments (and a chain's components) with key=value."""
    out = dict(params, **{key: value})
    if params.get("components"):
        out["components"] = [(dict(p, **{key: value}), w) for p, w in params["components"]]
    return out


def apply_blend_mode(params, material):
    """add_material keyword arguments (and a chain's components) with the
    material's Blend Mode: Clip turns each constant alpha into 0 or 1, Blend
    sends the material to the forward pass."""
    mode, threshold = blend_mode(material)
    if mode == "stochastic":
        return params

    def one(p):
        p = dict(p)
        if mode == "clip":
            p["alpha"] = 1.0 if p.get("alpha", 1.0) > threshold else 0.0
        else:
            p["blend"] = True
        return p
    out = one(params)
    if params.get("components"):
        out["components"] = [(one(p), w) for p, w in params["components"]]
    return out


def is_clamp_note(note):
    """A note of _sanitize (a value clamped to the renderer's limits): the
    parameter set still represents the material, only clamped."""
    return "clamped" in note


def warning_text(material, notes):
    name = material.name if material is not None else "<default>"
    return f"Material '{name}': not understood: " + "; ".join(notes)


def add_materials(add_material, params):
    """Create the material (a chain for a stochastic mix) with
    ``add_material(**kwargs) -> id``; returns the id instances refer to."""
    def native(p):
        p = dict(p)
        if "glossy_model" in p:  # an enum: mixing sets of one model keeps it, as an int
            p["glossy_model"] = int(round(p["glossy_model"]))
        return p

    components = params.get("components")
    if not components:
        return add_material(**native(params))
    # Last component first; each earlier one points at the rest of the chain
    # and takes it with the rest's share of the weight.
    next_id, rest = -1, 0.0
    for p, w in reversed(components):
        total = rest + w
        probability = rest / total if next_id >= 0 and total > 0.0 else 0.0
        next_id = add_material(**native(p), mix_with=next_id, mix_probability=probability)
        rest = total
    return next_id
