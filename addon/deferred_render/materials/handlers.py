"""Keeps the image pixel cache (images.py) true to Blender's buffers: an
image that a depsgraph update touches (Image > Reload, painting, a new
file path) is dropped, and a file load drops everything."""

import bpy
from bpy.app.handlers import persistent

from . import images


@persistent
def _on_depsgraph_update(scene, depsgraph):
    for update in depsgraph.updates:
        if isinstance(update.id, bpy.types.Image):
            images.forget(update.id.name_full)


@persistent
def _on_load(*_args):
    images.forget()


_HANDLERS = ((bpy.app.handlers.depsgraph_update_post, _on_depsgraph_update),
             (bpy.app.handlers.load_post, _on_load))


def register():
    for handlers, func in _HANDLERS:
        if func not in handlers:
            handlers.append(func)


def unregister():
    for handlers, func in _HANDLERS:
        if func in handlers:
            handlers.remove(func)
    images.forget()
