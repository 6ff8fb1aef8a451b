"""The RenderEngine "Deferred" (bl_idname DEFERRED_RENDER).

Thin: pass registration is in ``passes.py``, the final render in
``final.py``; scene export in ``..export``.
"""

import bpy
from bpy.app.handlers import persistent

from .. import native
from . import final, passes, session


class DeferredRenderEngine(bpy.types.RenderEngine):
    bl_idname = "DEFERRED_RENDER"
    bl_label = "Deferred"
    bl_use_preview = False
    # Principled BSDF and the other Cycles/EEVEE shader nodes stay visible.
    bl_use_shading_nodes_custom = False
    # The compositor runs on our result (Render Layers node, Composite, File Output).
    bl_use_postprocess = True
    # Viewport "Material Preview" uses EEVEE; there is no interactive viewport render.
    bl_use_eevee_viewport = True

    def update_render_passes(self, scene=None, renderlayer=None):
        """Register the passes the renderer produces whose checkbox is on."""
        mod = native.try_load()
        native_passes = mod.PASSES if mod is not None else passes.COMBINED_ONLY
        for spec in passes.enabled_passes(renderlayer, native_passes):
            self.register_pass(scene, renderlayer, spec.name, spec.channels, spec.chan_id, spec.type)

    def render(self, depsgraph):
        final.render(self, depsgraph)


classes = (DeferredRenderEngine,)


@persistent
def _release_kept_renderer(*_args):
    """A new file: the renderer kept for Persistent Data holds the old one's images."""
    session.release()


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    if _release_kept_renderer not in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.append(_release_kept_renderer)


def unregister():
    if _release_kept_renderer in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_release_kept_renderer)
    session.release()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
