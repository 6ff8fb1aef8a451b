"""The RenderEngine "Deferred" (bl_idname DEFERRED_RENDER).

Thin: pass registration is in ``passes.py``, the final render (and the
material preview thumbnails) in ``final.py``, the Rendered viewport in
``viewport.py``; scene export in ``..export``.
"""

import bpy
from bpy.app.handlers import persistent

from .. import native
from . import final, passes, session, viewport


class DeferredRenderEngine(bpy.types.RenderEngine):
    bl_idname = "DEFERRED_RENDER"
    bl_label = "Deferred"
    # Material, world and light preview thumbnails are rendered by render().
    bl_use_preview = True
    # Principled BSDF and the other Cycles/EEVEE shader nodes stay visible.
    bl_use_shading_nodes_custom = False
    # The compositor runs on our result (Render Layers node, Composite, File Output).
    bl_use_postprocess = True
    # Viewport "Material Preview" uses EEVEE; "Rendered" is ours (view_update/view_draw).
    bl_use_eevee_viewport = True

    def update_render_passes(self, scene=None, renderlayer=None):
        """Register the passes the renderer produces whose checkbox is on."""
        mod = native.try_load()
        native_passes = mod.PASSES if mod is not None else passes.COMBINED_ONLY
        for spec in passes.enabled_passes(renderlayer, native_passes):
            self.register_pass(scene, renderlayer, spec.name, spec.channels, spec.chan_id, spec.type)

    def __init__(self):
        self._viewport = None

    def __del__(self):
        # Blender frees the engine: a viewport's renderer goes with it.
        session_ = getattr(self, "_viewport", None)
        if session_ is not None:
            session_.free()

    def render(self, depsgraph):
        final.render(self, depsgraph)

    def view_update(self, context, depsgraph):
        if self._viewport is None:
            self._viewport = viewport.ViewportSession(self)
        self._viewport.update(context, depsgraph)

    def view_draw(self, context, depsgraph):
        if self._viewport is None:
            self._viewport = viewport.ViewportSession(self)
            self._viewport.update(context, depsgraph)
        self._viewport.draw(context, depsgraph)


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
    for view in viewport.sessions():
        view.free()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
