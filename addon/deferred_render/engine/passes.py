"""Render passes: which ones are registered for a view layer.

Names, channel ids and types are Cycles' (shared/REFERENCE.md section 1).
The channel ids and counts come from ``deferred_native.PASSES`` (what the
renderer produces); this table adds the Blender side: the pass type and the
view-layer checkbox that turns the pass on. A pass is registered only when
the renderer produces it *and* its checkbox is on, so the compositor's
Render Layers node shows exactly the passes that will hold pixels.
"""

from ..export import cryptomatte as crypto_export

# name -> (type for register_pass, ViewLayer flag; None = always registered)
PASS_TABLE = {
    "Combined": ("COLOR", None),
    "Depth": ("VALUE", "use_pass_z"),
    "Mist": ("VALUE", "use_pass_mist"),
    "Position": ("VECTOR", "use_pass_position"),
    "Normal": ("VECTOR", "use_pass_normal"),
    "Vector": ("VECTOR", "use_pass_vector"),
    "UV": ("VECTOR", "use_pass_uv"),
    "IndexOB": ("VALUE", "use_pass_object_index"),
    "IndexMA": ("VALUE", "use_pass_material_index"),
    "DiffDir": ("COLOR", "use_pass_diffuse_direct"),
    "DiffInd": ("COLOR", "use_pass_diffuse_indirect"),
    "DiffCol": ("COLOR", "use_pass_diffuse_color"),
    "GlossDir": ("COLOR", "use_pass_glossy_direct"),
    "GlossInd": ("COLOR", "use_pass_glossy_indirect"),
    "GlossCol": ("COLOR", "use_pass_glossy_color"),
    "Emit": ("COLOR", "use_pass_emit"),
    "Env": ("COLOR", "use_pass_environment"),
    "Shadow": ("COLOR", "use_pass_shadow"),
    "AO": ("COLOR", "use_pass_ambient_occlusion"),
    # Cycles' own view-layer setting (its add-on's property group).
    "Shadow Catcher": ("COLOR", "cycles.use_pass_shadow_catcher"),
}


def flag_owner(view_layer, flag):
    """(the data holding a pass flag, its property name): the view layer, or
    for a dotted flag its property group (``cycles.use_pass_shadow_catcher``);
    (None, name) when that group is not there (the Cycles add-on disabled)."""
    owner = view_layer
    *groups, name = flag.split(".")
    for group in groups:
        owner = getattr(owner, group, None) if owner is not None else None
    return owner, name


def flag_value(view_layer, flag):
    owner, name = flag_owner(view_layer, flag)
    return bool(getattr(owner, name, False)) if owner is not None else False

# What is registered when the native module cannot be imported: the render
# fails with a clear message anyway, and Blender needs a Combined pass.
COMBINED_ONLY = (("Combined", "RGBA", 4),)


class PassSpec:
    __slots__ = ("name", "chan_id", "channels", "type", "flag")

    def __init__(self, name, chan_id, channels, type, flag):
        self.name = name
        self.chan_id = chan_id
        self.channels = channels
        self.type = type
        self.flag = flag

    def __repr__(self):
        return f"PassSpec({self.name!r}, {self.chan_id!r}, {self.channels}, {self.type!r})"


def supported_passes(native_passes):
    """PassSpecs for every pass the renderer produces, in its order."""
    specs = []
    for entry in native_passes:
        name, chan_id, channels = entry[0], entry[1], int(entry[2])
        if name not in PASS_TABLE:
            continue  # a pass this add-on does not know how to present
        pass_type, flag = PASS_TABLE[name]
        specs.append(PassSpec(name, chan_id, channels, pass_type, flag))
    return specs


def cryptomatte_passes(view_layer):
    """PassSpecs of the Cryptomatte layers the view layer asks for:
    CryptoObject00, 01, ... (two ranks each, Levels of them), with Cycles'
    lowercase channel ids (cycles/engine.py), which the EXR keeps as the
    Cryptomatte convention wants."""
    layers, levels = crypto_export.enabled_layers(view_layer)
    flags = dict(crypto_export.KINDS)
    return [PassSpec(name, "rgba", 4, "COLOR", flags[layer])
            for layer in layers for name in crypto_export.pass_names(layer, levels)]


def aov_passes(view_layer):
    """PassSpecs of the view layer's shader AOVs, as Cycles registers them
    (cycles/engine.py: a Color AOV is RGBA, a Value AOV X)."""
    from ..export import requested_aovs
    return [PassSpec(name, "RGBA", 4, "COLOR", None) if kind == 'COLOR' else PassSpec(name, "X", 1, "VALUE", None)
            for name, kind in requested_aovs(view_layer)]


def light_group_passes(view_layer):
    """PassSpecs of the view layer's light groups: Combined_<name>, RGB (Cycles')."""
    from ..export import light_group_indices
    return [PassSpec(f"Combined_{name}", "RGB", 3, "COLOR", None) for name in light_group_indices(view_layer)]


def enabled_passes(view_layer, native_passes):
    """PassSpecs to register for ``view_layer`` (Combined always first)."""
    specs = []
    for spec in supported_passes(native_passes):
        if spec.flag is None or (view_layer is not None and flag_value(view_layer, spec.flag)):
            specs.append(spec)
    if native_passes is not COMBINED_ONLY:
        specs += cryptomatte_passes(view_layer)
        specs += aov_passes(view_layer)
        specs += light_group_passes(view_layer)
    if not specs or specs[0].name != "Combined":
        combined = [s for s in specs if s.name == "Combined"]
        others = [s for s in specs if s.name != "Combined"]
        if not combined:
            combined = [PassSpec("Combined", "RGBA", 4, "COLOR", None)]
        specs = combined + others
    return specs


def supported_flags(native_passes):
    """The ViewLayer flags this renderer honours (for the Passes panel)."""
    return [spec.flag for spec in supported_passes(native_passes) if spec.flag]
