"""Deferred: a Blender render engine backed by a native C++ deferred renderer.

Layout (BlendLuxCore style, see shared/STYLE.md):

- ``engine/``      the RenderEngine (final render); thin, delegates to export/
- ``export/``      depsgraph -> numpy arrays -> native scene, one module per
                   data-block kind (mesh, material, light, camera, world) and
                   ``instances`` which walks ``depsgraph.object_instances``
- ``properties/``  the ``scene.deferred_render`` settings group
- ``ui/``          Render Properties panels, and which of Blender's own
                   panels are shown for this engine
- ``materials/``   node trees -> the native renderer's graph IR (and images)
- ``native.py``    the lazy, guarded import of the compiled ``deferred_native``

The compiled module is optional at registration time: without it the engine
still registers (so .blend files that use it open normally) and render()
reports how to build it.
"""

bl_info = {
    "name": "Deferred Render Engine",
    "author": "deferred-render project",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Render Properties > Render Engine > Deferred",
    "description": "Rasterising deferred renderer (native C++/OpenGL, headless EGL) with Cycles-compatible passes",
    "category": "Render",
}

from . import native, properties, engine, ui  # noqa: E402,F401
from .materials import handlers as material_handlers  # noqa: E402


def register():
    properties.register()
    engine.register()
    ui.register()
    material_handlers.register()


def unregister():
    material_handlers.unregister()
    ui.unregister()
    engine.unregister()
    properties.unregister()
