"""Per-corner attributes node materials read, by key (materials/builder.py):

- ``uv:NAME``      UV map (2 floats); empty NAME: the active render UV map
- ``tangent:NAME`` MikkTSpace tangent of that UV map (xyz, bitangent sign),
                   as Blender's ``calc_tangents`` gives it (Cycles' normal map)
- ``color:NAME``   colour attribute (RGBA, scene linear); empty NAME: the
                   active render one
- ``attr:NAME``    any of the above by name, or a generic attribute (float,
                   int, bool, vector, 2D vector, colour) on points, corners or faces

Only keys some material of the object reads are exported, with numpy
``foreach_get`` (no Python loop over elements). A key the mesh cannot
provide is left out (the material reads 0, as Cycles does for a missing
attribute) and reported.
"""

import numpy as np


def _get(collection, attr, count, width):
    buf = np.empty(count * width, dtype=np.float32)
    if count:
        collection.foreach_get(attr, buf)
    return buf.reshape(count, width)


def render_uv_layer(mesh):
    """The UV map Cycles renders with (active for rendering, else the active one)."""
    for layer in mesh.uv_layers:
        if layer.active_render:
            return layer
    return mesh.uv_layers.active if len(mesh.uv_layers) else None


def _render_color(mesh):
    attrs = mesh.color_attributes
    if len(attrs) == 0:
        return None
    index = getattr(attrs, "render_color_index", -1)
    if 0 <= index < len(attrs):
        return attrs[index]
    return attrs.active_color or attrs[0]


class CornerGather:
    """Maps per-point / per-corner / per-face data to triangle corners.

    np.take with native-size (intp) indices: on 2M corners of a 2-float UV
    map it gathers in ~6 ms, where fancy indexing with Blender's uint32
    indices takes ~30-50 ms (each call converts the indices again).
    """

    def __init__(self, tri_verts, tri_loops, poly_index):
        self.verts = np.asarray(tri_verts).reshape(-1).astype(np.intp)
        self.loops = np.asarray(tri_loops).reshape(-1).astype(np.intp)
        self._poly_index = poly_index
        self._faces = None  # made on first use: most attributes live on corners or points

    def __call__(self, data, domain):
        if domain == "POINT":
            return np.take(data, self.verts, axis=0)
        if domain == "CORNER":
            return np.take(data, self.loops, axis=0)
        if domain == "FACE":
            if self._faces is None:
                self._faces = np.repeat(self._poly_index.astype(np.intp), 3)
            return np.take(data, self._faces, axis=0)
        return None


def _uv(mesh, name, gather):
    layer = render_uv_layer(mesh) if name == "" else mesh.uv_layers.get(name)
    if layer is None:
        return None
    return gather(_get(layer.data, "uv", len(mesh.loops), 2), "CORNER")


def _color(mesh, attr, gather):
    n = len(attr.data)
    return gather(_get(attr.data, "color", n, 4), attr.domain)


_GENERIC = {  # data_type -> (foreach_get property, components)
    "FLOAT": ("value", 1), "INT": ("value", 1), "BOOLEAN": ("value", 1), "INT8": ("value", 1),
    "FLOAT_VECTOR": ("vector", 3), "FLOAT2": ("vector", 2),
    "FLOAT_COLOR": ("color", 4), "BYTE_COLOR": ("color", 4),
}


def _generic(mesh, name, gather):
    if mesh.uv_layers.get(name) is not None:
        return _uv(mesh, name, gather)
    attr = mesh.attributes.get(name)
    if attr is None or attr.data_type not in _GENERIC or attr.domain not in {"POINT", "CORNER", "FACE"}:
        return None
    prop, width = _GENERIC[attr.data_type]
    n = len(attr.data)
    if attr.data_type in {"INT", "BOOLEAN", "INT8"}:
        raw = np.empty(n, dtype=np.int32 if attr.data_type != "BOOLEAN" else bool)
        if n:
            attr.data.foreach_get("value", raw)
        data = raw.astype(np.float32).reshape(n, 1)
    else:
        data = _get(attr.data, prop, n, width)
    return gather(data, attr.domain)


def _tangents(mesh, name, gather):
    layer = render_uv_layer(mesh) if name == "" else mesh.uv_layers.get(name)
    if layer is None:
        return None
    mesh.calc_tangents(uvmap=layer.name)  # RuntimeError on n-gons
    n = len(mesh.loops)
    tangent = np.empty((n, 4), dtype=np.float32)  # xyz, bitangent sign
    tangent[:, :3] = _get(mesh.loops, "tangent", n, 3)
    tangent[:, 3] = _get(mesh.loops, "bitangent_sign", n, 1)[:, 0]
    return gather(tangent, "CORNER")


def corner_attributes(mesh, keys, gather, warn):
    """[(key, (3T, C) float32)] for the keys the mesh has (object space)."""
    out = []
    for key in sorted(keys):
        kind, _, name = key.partition(":")
        data = None
        try:
            if kind == "uv":
                data = _uv(mesh, name, gather)
            elif kind == "color":
                attr = _render_color(mesh) if name == "" else mesh.color_attributes.get(name)
                data = _color(mesh, attr, gather) if attr is not None else None
            elif kind == "tangent":
                data = _tangents(mesh, name, gather)
            elif kind == "attr":
                attr = mesh.color_attributes.get(name)
                data = _color(mesh, attr, gather) if attr is not None else _generic(mesh, name, gather)
        except RuntimeError as ex:
            warn(f"mesh '{mesh.name}': {kind} '{name}' unavailable ({ex}); the material reads 0")
            continue
        if data is None:
            warn(f"mesh '{mesh.name}' has no {kind.replace('attr', 'attribute')} '{name or '(active)'}'; "
                 "the material reads 0")
            continue
        data = np.ascontiguousarray(data, dtype=np.float32)
        if not np.isfinite(data).all():  # the common case skips nan_to_num's three passes
            data = np.nan_to_num(data, nan=0.0, posinf=0.0, neginf=0.0)
        out.append((key, data))
    return out
