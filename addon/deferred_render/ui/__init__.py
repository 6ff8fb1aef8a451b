"""Panels: ours (``panels.py``) and Blender's own that apply to this engine.

Blender 3.4's built-in property panels show themselves when
``context.engine in cls.COMPAT_ENGINES`` (a set on each panel class;
"external engines can add themselves here", bl_ui/properties_*.py). On
register we add DEFERRED_RENDER to:

- every built-in panel meant for all engines, i.e. whose set contains
  'BLENDER_RENDER' (Format = resolution/percentage/border/crop, Frame Range,
  Output, Color Management, View Layer, Object visibility, camera, mesh
  data, ...), except those listed in EXCLUDED_PANELS;
- the EEVEE panels in EXTRA_PANELS that draw settings we read (material and
  world surface node trees, World > Mist Pass).

Film > Transparent, the pass checkboxes, the light settings and the material
pass index have panels of our own, because Blender's carry EEVEE-only
settings. unregister() removes the engine from every set it was added to.
"""

import bpy

from . import panels

ENGINE = panels.ENGINE

# Built-in 'BLENDER_RENDER' panels that would show settings we do not honour
# or duplicate one of ours.
EXCLUDED_PANELS = {
    "DATA_PT_light",                        # ours: DEFERRED_RENDER_PT_light
    "NODE_DATA_PT_light",                   # node-editor copy, shares DATA_PT_light's set
    "DATA_PT_area",                         # ours: DEFERRED_RENDER_PT_light
    "DATA_PT_falloff_curve",                # custom falloff is not rendered
    "EEVEE_MATERIAL_PT_viewport_settings",  # EEVEE blend/shadow modes
    "VIEWLAYER_PT_filter",
    "VIEWLAYER_PT_layer_passes",
    "RENDER_PT_stereoscopy",                # one view only
    "DATA_PT_camera_stereoscopy",
}

# EEVEE panels whose settings this engine reads.
EXTRA_PANELS = (
    "EEVEE_MATERIAL_PT_context_material",   # material slots
    "EEVEE_MATERIAL_PT_surface",            # the surface node tree
    "EEVEE_WORLD_PT_surface",               # world Background colour x strength
    "EEVEE_WORLD_PT_mist",                  # Mist pass start/depth/falloff
    "DATA_PT_spot",                         # spot size/blend (3.4 also has BLENDER_RENDER)
    "MATERIAL_PT_preview",                  # the preview render (bl_use_preview); lights' has BLENDER_RENDER
)

_patched = []


def compatible_panels():
    """Built-in panel classes that get DEFERRED_RENDER in COMPAT_ENGINES."""
    found = []
    seen = set()
    # Node-editor copies of a panel share its COMPAT_ENGINES set object:
    # excluding a panel must exclude every panel holding the same set.
    excluded_sets = {id(getattr(bpy.types, name).COMPAT_ENGINES) for name in EXCLUDED_PANELS
                     if isinstance(getattr(getattr(bpy.types, name, None), "COMPAT_ENGINES", None), set)}
    for panel in bpy.types.Panel.__subclasses__():
        engines = getattr(panel, "COMPAT_ENGINES", None)
        name = panel.__name__
        if not isinstance(engines, set) or name.startswith(ENGINE) or name in EXCLUDED_PANELS:
            continue
        if id(engines) in excluded_sets:
            continue
        if "BLENDER_RENDER" in engines and name not in seen:
            found.append(panel)
            seen.add(name)
    for name in EXTRA_PANELS:
        panel = getattr(bpy.types, name, None)
        if panel is not None and name not in seen and isinstance(getattr(panel, "COMPAT_ENGINES", None), set):
            found.append(panel)
            seen.add(name)
    return found


def register():
    for cls in panels.classes:
        bpy.utils.register_class(cls)
    for panel in compatible_panels():
        if ENGINE not in panel.COMPAT_ENGINES:
            panel.COMPAT_ENGINES.add(ENGINE)
            _patched.append(panel)


def unregister():
    while _patched:
        panel = _patched.pop()
        panel.COMPAT_ENGINES.discard(ENGINE)
    for cls in reversed(panels.classes):
        bpy.utils.unregister_class(cls)
