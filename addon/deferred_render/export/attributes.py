"""Per-corner attributes node materials read, by key (materials/builder.py):

- ``uv:NAME``      UV map (2 floats); empty NAME: the active render UV map
- ``tangent:NAME`` MikkTSpace tangent of that UV map (xyz, bitangent sign)
                   over the loop triangles, as Cycles 3.4 computes it for its
                   normal map (native ``compute_tangents``: no mesh copy, and
                   n-gons work, where Blender's ``calc_tangents`` refuses them)
- ``color:NAME``   colour attribute (RGBA, scene linear); empty NAME: the
                   active render one
- ``attr:NAME``    any of the above by name, or a generic attribute (float,
                   int, bool, vector, 2D vector, colour) on points, corners or faces
- ``pointiness:``  the Geometry node's Pointiness, per vertex, and
- ``island:``      its Random Per Island, per triangle, both as Cycles 3.4
                   computes them (native ``compute_pointiness`` /
                   ``compute_random_per_island``)

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
        self._uv_maps = {}  # layer name -> gathered corners: the render UV map, its
        # "uv:" key and its tangents read one gather (~60 ms a map at 1M triangles)

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

    def uv_map(self, layer, loop_count):
        """A UV map's (3T, 2) corners, NaN/Inf read as 0; gathered once per mesh."""
        uvs = self._uv_maps.get(layer.name)
        if uvs is None:
            uvs = self(_get(layer.data, "uv", loop_count, 2), "CORNER")
            if not np.isfinite(uvs).all():
                uvs = np.nan_to_num(uvs, nan=0.0, posinf=0.0, neginf=0.0)
            self._uv_maps[layer.name] = uvs
        return uvs


def _uv(mesh, name, gather):
    layer = render_uv_layer(mesh) if name == "" else mesh.uv_layers.get(name)
    if layer is None:
        return None
    return gather.uv_map(layer, len(mesh.loops))


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


class ExportedGeometry:
    """The exported triangles, which the native computations read (MikkTSpace
    besides the UV map, Random Per Island)."""

    __slots__ = ("positions", "indices", "corner_normals", "flat_triangles", "_edges")

    def __init__(self, positions, indices, corner_normals, flat_triangles=None):
        self._edges = None  # the mesh's (E, 2) edges, read once for Pointiness and Random Per Island
        self.positions = positions            # (V, 3) float32
        self.indices = indices                # (T, 3) uint32
        self.corner_normals = corner_normals  # (3T, 3) float32, unit
        # (T,) bool or None: flat-shaded triangles, whose own normal Cycles
        # hands MikkTSpace (native/include/deferred/tangent_space.h)
        self.flat_triangles = flat_triangles

    def edges(self, mesh):
        if self._edges is None:
            n = len(mesh.edges)
            edges = np.empty(n * 2, dtype=np.uint32)
            if n:
                mesh.edges.foreach_get("vertices", edges)
            self._edges = edges.reshape(n, 2)
        return self._edges


def _pointiness(mesh, gather, inputs, warn):
    from .. import native  # the compiled module; NativeUnavailable is a RuntimeError
    _warn_split(mesh, "Pointiness", warn)
    nv = len(mesh.vertices)
    normals = _get(mesh.vertex_normals, "vector", nv, 3)
    values = native.load().compute_pointiness(inputs.positions, np.ascontiguousarray(normals), inputs.edges(mesh))
    return gather(values.reshape(nv, 1), "POINT")


def _random_per_island(mesh, inputs, warn):
    from .. import native
    _warn_split(mesh, "Random Per Island", warn)
    first = np.ascontiguousarray(inputs.indices[:, 0])
    values = native.load().compute_random_per_island(len(mesh.vertices), inputs.edges(mesh), first)
    return np.repeat(values, 3).reshape(-1, 1)


def _warn_split(mesh, what, warn):
    # Cycles 3.4 splits an auto-smooth mesh at its sharp edges before it
    # computes these (blender/util.h object_to_mesh: split_faces): islands
    # end at sharp edges and Pointiness reads the split fans' normals.
    if mesh.use_auto_smooth:
        warn(f"mesh '{mesh.name}': Geometry {what} is computed on the mesh as modelled; Cycles first splits "
             "an Auto Smooth mesh at its sharp edges, so it may differ there")


def _tangents(mesh, name, gather, inputs):
    uvs = _uv(mesh, name, gather)
    if uvs is None:
        return None
    from .. import native  # the compiled module; NativeUnavailable is a RuntimeError
    return native.load().compute_tangents(inputs.positions, inputs.indices, inputs.corner_normals,
                                          np.ascontiguousarray(uvs, dtype=np.float32), inputs.flat_triangles)


def corner_attributes(mesh, keys, gather, warn, geometry=None):
    """[(key, (3T, C) float32)] for the keys the mesh has (object space).

    ``geometry`` (ExportedGeometry) is needed for ``tangent:``, ``pointiness:``
    and ``island:`` keys."""
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
                data = _tangents(mesh, name, gather, geometry)
            elif kind == "pointiness":
                data = _pointiness(mesh, gather, geometry, warn)
            elif kind == "island":
                data = _random_per_island(mesh, geometry, warn)
            elif kind == "attr":
                attr = mesh.color_attributes.get(name)
                data = _color(mesh, attr, gather) if attr is not None else _generic(mesh, name, gather)
        except (RuntimeError, ValueError) as ex:  # ValueError: the native computations' bad input
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
