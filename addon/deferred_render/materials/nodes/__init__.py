"""Node specs: bl_idname -> function(NodeBuilder). One module per family;
each registers its nodes with ``@register``. See ../CONTRACT.md."""

import importlib

SPECS = {}


def register(*idnames):
    def decorate(func):
        for idname in idnames:
            SPECS[idname] = func
        return func
    return decorate


for _family in ("shader", "input", "vector", "converter", "color", "texture", "image"):
    try:
        importlib.import_module(f".{_family}", __name__)
    except ModuleNotFoundError as _ex:  # a family not written yet
        if _ex.name != f"{__name__}.{_family}":
            raise
