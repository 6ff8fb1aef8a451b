"""Mesh data-blocks -> numpy arrays for ``Renderer.add_mesh``.

Everything goes through ``foreach_get`` into preallocated numpy buffers and
numpy fancy indexing: there is no Python loop over vertices, loops or
triangles (a 1M-triangle mesh takes well under a second, see
tests/blender/bench_export.py).

Per-corner data follows the native convention: corner c of triangle t is
element 3*t + c, in the order of the triangle's vertex indices, because
Blender keeps split normals and UVs on loops, not vertices.

Normals, as Cycles 3.4 computes them (intern/cycles/blender/mesh.cpp):
- without auto smooth and custom normals: smooth faces use the vertex normal,
  flat faces the polygon normal;
- with auto smooth or custom split normals: the split normals of a
  temporary copy (``to_mesh()`` + ``calc_normals_split()``), so the evaluated
  data the depsgraph owns is never modified.
"""

import numpy as np

from . import attributes as attribute_export

# Object types whose geometry becomes a mesh through Object.to_mesh().
MESHABLE_TYPES = {"MESH", "CURVE", "SURFACE", "FONT", "META"}

# Largest |coordinate| (and matrix entry) the native renderer accepts
# (native/src/scene_store.h, InputLimits::kMaxCoordinate).
MAX_COORDINATE = 1e15


class MeshArrays:
    """The arrays handed to ``Renderer.add_mesh`` (shapes and dtypes fixed)."""

    __slots__ = ("name", "positions", "indices", "corner_normals", "corner_uvs", "material_indices",
                 "attributes", "texspace_location", "texspace_size")

    def __init__(self, name, positions, indices, corner_normals, corner_uvs, material_indices,
                 attributes=(), texspace_location=(0.0, 0.0, 0.0), texspace_size=(1.0, 1.0, 1.0)):
        self.name = name
        self.positions = positions            # (V, 3) float32
        self.indices = indices                # (T, 3) uint32
        self.corner_normals = corner_normals  # (T*3, 3) float32
        self.corner_uvs = corner_uvs          # (T*3, 2) float32 or None
        self.material_indices = material_indices  # (T,) int32
        self.attributes = list(attributes)    # [(key, (T*3, C) float32)] node materials read
        self.texspace_location = texspace_location
        self.texspace_size = texspace_size

    @property
    def triangle_count(self):
        return len(self.indices)

    @property
    def vertex_count(self):
        return len(self.positions)

    def nbytes(self):
        # Each array once: the render UV map and its "uv:" attribute may be one array.
        arrays = {id(a): a for a in (self.positions, self.indices, self.corner_normals, self.corner_uvs,
                                     self.material_indices, *(a for _, a in self.attributes)) if a is not None}
        return sum(a.nbytes for a in arrays.values())


class MeshSkipped(Exception):
    """The mesh cannot be rendered (no triangles, non-finite coordinates).

    The message says why; ``empty`` tells a mesh without faces from a broken one."""

    def __init__(self, message, empty=False):
        super().__init__(message)
        self.empty = empty


def _get(collection, attr, count, dtype, width=1):
    buf = np.empty(count * width, dtype=dtype)
    if count:
        collection.foreach_get(attr, buf)
    return buf if width == 1 else buf.reshape(count, width)


def _normalized(vectors):
    """Unit vectors; zero-length or non-finite ones become +Z (degenerate faces).

    Blender's normals are unit already: only the rows that are not get fixed."""
    vectors = np.ascontiguousarray(vectors, dtype=np.float32)
    length2 = np.einsum("ij,ij->i", vectors, vectors)
    off = ~(np.abs(length2 - 1.0) < 1e-4)  # also catches NaN
    if off.any():
        fix = vectors[off]
        length = np.sqrt(length2[off])
        bad = ~np.isfinite(length) | (length < 1e-20)
        fix[bad] = (0.0, 0.0, 1.0)
        length[bad] = 1.0
        vectors[off] = fix / length[:, None]
    return vectors


def mesh_arrays(mesh, name=None, split_normals=None, attribute_keys=(), warn=None):
    """Arrays of a bpy.types.Mesh (triangulated through its loop triangles).

    ``split_normals``: use the loop split normals (the mesh must have had
    ``calc_normals_split()``); None decides like Cycles (auto smooth or custom
    normals). ``attribute_keys``: the per-corner attributes node materials
    read (export/attributes.py). Raises MeshSkipped for meshes that cannot be
    rendered.
    """
    name = name or mesh.name
    mesh.calc_loop_triangles()
    tris = mesh.loop_triangles
    nt = len(tris)
    nv = len(mesh.vertices)
    if nt == 0 or nv == 0:
        raise MeshSkipped(f"mesh '{name}' has no faces", empty=True)

    positions = _get(mesh.vertices, "co", nv, np.float32, 3)
    if not np.isfinite(positions).all():
        bad = int((~np.isfinite(positions)).any(axis=1).sum())
        raise MeshSkipped(f"mesh '{name}' has {bad} vertices with NaN/Inf coordinates")
    if positions.size and np.abs(positions).max() > MAX_COORDINATE:
        bad = int((np.abs(positions) > MAX_COORDINATE).any(axis=1).sum())
        raise MeshSkipped(f"mesh '{name}' has {bad} vertices beyond {MAX_COORDINATE:g} m (float32 rendering limit)")

    # uint32 buffers match Blender's MLoopTri storage, so foreach_get takes
    # its raw-copy fast path (int32 buffers are ~8x slower on 3.4).
    tri_verts = _get(tris, "vertices", nt, np.uint32, 3)
    tri_loops = _get(tris, "loops", nt, np.uint32, 3).reshape(-1)
    material_indices = _get(tris, "material_index", nt, np.uint32).view(np.int32)

    poly_index = None  # read when something needs it
    flat_triangles = None  # (T,) bool where Cycles shades a triangle flat (no split normals)
    if split_normals is None:
        split_normals = bool(mesh.use_auto_smooth or mesh.has_custom_normals)
    if split_normals:
        corner_normals = _get(tris, "split_normals", nt, np.float32, 9).reshape(nt * 3, 3)
    else:
        poly_index = _get(tris, "polygon_index", nt, np.uint32)
        npoly = len(mesh.polygons)
        smooth = _get(mesh.polygons, "use_smooth", npoly, bool)
        vertex_normals = _get(mesh.vertex_normals, "vector", nv, np.float32, 3)
        polygon_normals = _get(mesh.polygon_normals, "vector", npoly, np.float32, 3)
        tri_poly = poly_index.astype(np.intp)  # np.take with intp indices: no conversion per gather
        corner_normals = np.repeat(np.take(polygon_normals, tri_poly, axis=0), 3, axis=0)
        smooth_triangles = np.take(smooth, tri_poly)
        flat_triangles = ~smooth_triangles
        smooth_corners = np.repeat(smooth_triangles, 3)
        if smooth_corners.any():
            flat_verts = tri_verts.reshape(-1)
            corner_normals[smooth_corners] = vertex_normals[flat_verts[smooth_corners]]
    corner_normals = _normalized(corner_normals)

    gather = None  # per-point/corner/face data -> triangle corners, made on first use
    uv_layer = attribute_export.render_uv_layer(mesh)
    if uv_layer is not None or attribute_keys:
        if poly_index is None and attribute_keys:
            poly_index = _get(tris, "polygon_index", nt, np.uint32)
        gather = attribute_export.CornerGather(tri_verts, tri_loops, poly_index)
    corner_uvs = None
    if uv_layer is not None:
        corner_uvs = gather.uv_map(uv_layer, len(mesh.loops))

    corner_normals = np.ascontiguousarray(corner_normals, dtype=np.float32)
    positions = np.ascontiguousarray(positions)
    tri_verts = np.ascontiguousarray(tri_verts)
    corner_attributes = []
    if attribute_keys:
        corner_attributes = attribute_export.corner_attributes(
            mesh, attribute_keys, gather, warn or (lambda message: None),
            attribute_export.ExportedGeometry(positions, tri_verts, corner_normals, flat_triangles))
    texspace_location = tuple(getattr(mesh, "texspace_location", (0.0, 0.0, 0.0)))
    texspace_size = tuple(getattr(mesh, "texspace_size", (1.0, 1.0, 1.0)))

    return MeshArrays(
        name,
        positions,
        tri_verts,
        corner_normals,
        corner_uvs,
        material_indices,
        corner_attributes,
        texspace_location,
        texspace_size,
    )


def object_mesh_arrays(ob, attribute_keys=(), warn=None):
    """Arrays of an evaluated object's final geometry (modifiers applied).

    Meshes without auto smooth are read directly from the evaluated data;
    everything else (auto smooth / custom normals, curves, text, metaballs)
    goes through a temporary ``to_mesh()`` copy that is freed again.
    """
    data = ob.data
    is_mesh = ob.type == "MESH" and data is not None and hasattr(data, "loop_triangles")
    if is_mesh and not (data.use_auto_smooth or data.has_custom_normals):
        return mesh_arrays(data, name=data.name, split_normals=False, attribute_keys=attribute_keys, warn=warn)

    try:
        temp = ob.to_mesh()
    except RuntimeError:
        temp = None
    if temp is None:
        if is_mesh:
            # Geometry-nodes instance data that to_mesh() cannot copy: use
            # the evaluated mesh as is (smooth/flat normals, like Cycles'
            # "non-real object data" path).
            return mesh_arrays(data, name=data.name, split_normals=False, attribute_keys=attribute_keys, warn=warn)
        raise MeshSkipped(f"object '{ob.name}' has no mesh geometry", empty=True)
    try:
        split = bool(temp.use_auto_smooth or temp.has_custom_normals)
        if split:
            temp.calc_normals_split()
        return mesh_arrays(temp, name=(data.name if data is not None else ob.name), split_normals=split,
                           attribute_keys=attribute_keys, warn=warn)
    finally:
        ob.to_mesh_clear()


def clamp_material_indices(arrays, slot_count):
    """Blender clamps a face's material index to the last slot; so do we."""
    mi = arrays.material_indices
    if slot_count <= 1:
        if mi.any():
            arrays.material_indices = np.zeros_like(mi)
    elif mi.size and (mi.max() >= slot_count or mi.min() < 0):
        arrays.material_indices = np.clip(mi, 0, slot_count - 1).astype(np.int32)
    return arrays
