"""Walks ``depsgraph.object_instances`` and fills the native scene.

Every visible evaluated object instance is visited once: real objects,
collection instances, particle and geometry-nodes instances (modifiers are
already applied in the evaluated data). What is exported:

- one native mesh per mesh data-block, shared by all its instances. The key
  is the evaluated data (two objects sharing a mesh without modifiers share
  it; an object with modifiers has evaluated data of its own); non-mesh
  objects (curves, text, metaballs) are keyed by object;
- one native material per material data-block: a constant Principled
  parameter set when the node tree reduces to one exactly (``material.py``),
  else a node graph compiled to GLSL (``materials/``), whose images are
  uploaded once per render and whose mesh attributes are exported with the
  meshes that use it;
- instances grouped by (mesh, material-slot map): one ``add_instances`` call
  per group with an (N, 4, 4) float64 matrix array, so object- and
  data-linked materials both work;
- lights (``light.py``).

Objects that cannot be rendered (no faces, NaN/Inf vertices or matrix,
coordinates beyond 1e15 m) are skipped with one warning each; the render
goes on. The native scene validation is the last word: anything it still
refuses (a ValueError naming the array or parameter) skips that one object,
light or material with a warning instead of failing the frame. Not warned about: curves
without geometry (paths) and mesh objects whose modifiers leave no faces
(e.g. geometry nodes that output only instances), as Cycles does.
"""

import itertools
import math
import time

import numpy as np

from . import cryptomatte as crypto_export
from . import light as light_export
from . import material as material_export
from . import mesh as mesh_export
from . import motion as motion_export
from ..materials import builder as graph_builder

UNSUPPORTED_GEOMETRY = {"CURVES", "POINTCLOUD", "VOLUME", "GPENCIL"}
# The native input contract (native/src/scene_store.h, InputLimits): positions
# and matrix entries within 1e15 m keep squared camera-relative distances
# finite in float32 on the GPU.
MAX_MATRIX_VALUE = mesh_export.MAX_COORDINATE


class ExportStats:
    def __init__(self):
        self.meshes = 0
        self.meshes_reused = 0      # kept by the renderer from the last sync (MeshKeeper)
        self.triangles = 0          # unique (per native mesh)
        self.instances = 0
        self.instanced_triangles = 0
        self.materials = 0
        self.lights = 0
        self.skipped_objects = 0
        self.mesh_bytes = 0
        self.seconds = 0.0
        self.cryptomatte = None     # cryptomatte.Manifests of the export (export_scene sets it)

    def summary(self):
        reused = f" (+{self.meshes_reused} kept)" if self.meshes_reused else ""
        return (f"{self.instances} instances of {self.meshes} meshes{reused} "
                f"({self.triangles} unique / {self.instanced_triangles} rendered triangles), "
                f"{self.materials} materials, {self.lights} lights")


def _hash_string(text):
    """Cycles' hash_string (util/hash.h): i = i * 37 + c over the bytes, as C's
    (signed) char on x86."""
    i = 0
    for byte in text.encode("utf-8"):
        c = byte - 256 if byte > 127 else byte
        i = (i * 37 + c) & 0xFFFFFFFF
    return i


def _rot(x, k):
    return ((x << k) | (x >> (32 - k))) & 0xFFFFFFFF


def _hash_uint2(kx, ky):
    """Jenkins lookup3 hash of two uints (Cycles util/hash.h hash_uint2)."""
    m = 0xFFFFFFFF
    a = b = c = (0xDEADBEEF + (2 << 2) + 13) & m
    b = (b + ky) & m
    a = (a + kx) & m
    c ^= b; c = (c - _rot(b, 14)) & m
    a ^= c; a = (a - _rot(c, 11)) & m
    b ^= a; b = (b - _rot(a, 25)) & m
    c ^= b; c = (c - _rot(b, 16)) & m
    a ^= c; a = (a - _rot(c, 4)) & m
    b ^= a; b = (b - _rot(a, 14)) & m
    c ^= b; c = (c - _rot(b, 24)) & m
    return c


def holdout_collection_objects(view_layer):
    """Names of the objects in the view layer's collections marked Holdout
    (Outliner, per view layer; a child collection inherits it)."""
    names = set()
    if view_layer is None:
        return names

    def visit(layer_collection, inherited):
        holdout = inherited or bool(getattr(layer_collection, "holdout", False))
        if holdout:
            names.update(ob.name for ob in layer_collection.collection.objects)
        for child in layer_collection.children:
            visit(child, holdout)
    visit(view_layer.layer_collection, False)
    return names


def object_random(inst, ob):
    """Object Info > Random as Cycles computes it (blender/object.cpp: the
    instance's random_id, or hash_uint2(hash_string(name), 0) for an object
    itself; scene/object.cpp: random_id / 0xFFFFFFFF)."""
    if inst is not None and inst.is_instance:
        random_id = int(inst.random_id) & 0xFFFFFFFF
    else:
        random_id = _hash_uint2(_hash_string(ob.name), 0)
    return random_id * (1.0 / 0xFFFFFFFF)


def terminator_offset(ob):
    """Cycles' Object > Shading > Shadow Terminator > Geometry Offset (0..1,
    default 0.1): how far shadow rays from smooth-shaded triangles near the
    terminator start above them (shadow_lib.glsl shadow_ray_origin). Read
    from the original object: reading the add-on's property group on an
    instancer's temporary object creates ID properties Blender never frees."""
    cycles = getattr(getattr(ob, "original", None) or ob, "cycles", None)
    value = getattr(cycles, "shadow_terminator_geometry_offset", 0.1) if cycles is not None else 0.1
    try:
        value = float(value)
    except (TypeError, ValueError):
        return 0.1
    return min(max(value, 0.0), 1.0) if math.isfinite(value) else 0.1


class _Group:
    __slots__ = ("mesh_id", "material_ids", "cast_shadow", "holdout", "shadow_catcher", "light_group", "matrices",
                 "object_indices", "names", "colors", "randoms", "crypto", "terminator_offsets", "motion")

    def __init__(self, mesh_id, material_ids, cast_shadow, holdout=False, shadow_catcher=False):
        self.mesh_id = mesh_id
        self.material_ids = material_ids
        self.cast_shadow = cast_shadow
        self.holdout = holdout
        self.shadow_catcher = shadow_catcher
        self.light_group = 0
        self.matrices = []
        self.object_indices = []
        self.names = []
        self.colors = []
        self.randoms = []
        self.crypto = []    # (object hash, asset hash) per instance, when Cryptomatte is asked for
        self.terminator_offsets = []  # Object > Shading > Shadow Terminator > Geometry Offset
        self.motion = []    # (2, 4, 4) previous and next world matrices (Vector pass, motion blur)


class MeshKeeper:
    """Names for the meshes a renderer keeps between syncs (``add_mesh(...,
    key=)``, ``find_mesh``): the viewport re-syncs the whole scene after any
    edit, and a mesh whose geometry did not change is found again instead of
    exported. A key changes when the object's geometry does
    (``geometry_changed``, from ``depsgraph.updates``), and with what the
    export of the mesh depends on besides its data: the object's material
    slot count (indices are clamped to it) and the attributes its materials
    read."""

    def __init__(self):
        self._generation = {}   # object name -> geometry edits seen
        self.triangles = {}     # key -> triangle count of the mesh uploaded under it
        self._used = None       # keys the sync in progress asked for

    def begin_sync(self):
        self._used = set()

    def end_sync(self):
        """Forget the keys the sync did not use (the renderer drops their
        meshes at its next clear): edits would otherwise grow it forever."""
        if self._used is not None:
            self.triangles = {k: v for k, v in self.triangles.items() if k in self._used}
        self._used = None

    @staticmethod
    def object_name(ob):
        original = getattr(ob, "original", None) or ob
        return original.name_full

    def key(self, ob, attribute_keys=frozenset()):
        name = self.object_name(ob)
        attributes = ",".join(sorted(repr(k) for k in attribute_keys))
        # Also the original data-block's address: an undo reloads a changed
        # mesh at a new address (unchanged ones keep theirs), whether or not
        # the depsgraph reports it as a geometry update; and the evaluated
        # mesh's sizes, a cheap guard against any edit the updates miss.
        original = getattr(ob, "original", None) or ob
        data = getattr(original, "data", None)
        address = data.as_pointer() if data is not None else 0
        mesh = ob.data if ob.type == "MESH" else None
        sizes = (len(mesh.vertices), len(mesh.polygons)) if mesh is not None else ()
        key = (f"{name}|{self._generation.get(name, 0)}|{address:x}|{sizes}|{len(ob.material_slots)}|"
               f"{attributes}")
        if self._used is not None:
            self._used.add(key)
        return key

    def geometry_changed(self, name):
        self._generation[name] = self._generation.get(name, 0) + 1


class SceneExporter:
    """Streams one depsgraph into anything with the ``Renderer`` scene API
    (add_mesh, add_material, add_instances, add_light): the native renderer,
    or a recorder in the tests."""

    def __init__(self, renderer, warn=None, test_break=None, cryptomatte=None, aovs_requested=False,
                 light_groups=None, mesh_keeper=None, motion=None):
        self.renderer = renderer
        # Meshes the renderer keeps between syncs (the viewport; None: each
        # sync uploads every mesh, as a final render does).
        self.mesh_keeper = mesh_keeper if hasattr(renderer, "find_mesh") else None
        # The scene at other times (motion.Motion): the Vector pass's
        # neighbouring frames or motion blur's shutter open and close; None:
        # nothing moves.
        self.motion = motion
        # The view layer's light groups, name -> index from 1 (none: {}).
        self.light_groups = light_groups or {}
        # The view layer asks for shader AOVs: materials with AOV Output
        # nodes take the node path (only programs write AOVs).
        self.aovs_requested = aovs_requested
        # Cryptomatte names and hashes (cryptomatte.Manifests); none asked: no hashing.
        self.cryptomatte = cryptomatte if cryptomatte is not None else crypto_export.Manifests(())
        self.warn = warn or (lambda message: None)
        self.test_break = test_break or (lambda: False)
        self.stats = ExportStats()
        self._mesh_ids = {}         # mesh key -> (native id, triangle count) or None if skipped
        self._material_ids = {}     # material key -> native id
        self._groups = {}           # (mesh id, material ids) -> _Group
        self._material_attributes = {}  # native material id -> attribute keys its graph reads
        self._images = None         # materials.builder.ImageRegistry, made on first use
        self.graph_materials = 0
        self._warned = set()
        self.cancelled = False
        self._holdout_objects = set()  # names of objects in the view layer's holdout collections

    # -- warnings ---------------------------------------------------------
    def _warn_once(self, key, message):
        if key not in self._warned:
            self._warned.add(key)
            self.warn(message)

    # -- materials --------------------------------------------------------
    def material_id(self, material):
        if material is not None:
            original = getattr(material, "original", None) or material
            key = original.as_pointer()
        else:
            key = None
        mat_id = self._material_ids.get(key)
        crypto = self._material_crypto(material) if mat_id is None else 0
        if mat_id is None and material is not None:
            mat_id = self._graph_material_id(material, key, crypto)
            if mat_id is not None:
                self._material_ids[key] = mat_id
                self.stats.materials += 1
        if mat_id is None:
            params, notes = material_export.material_params(material)
            if notes:
                self._warn_once(("material", key), material_export.warning_text(material, notes))
            params = material_export.apply_blend_mode(params, material)
            if crypto:
                params = material_export.with_param(params, "crypto", crypto)
            try:
                mat_id = material_export.add_materials(self.renderer.add_material, params)
            except ValueError as ex:  # refused by the native validation: default surface
                name = material.name if material is not None else "<default>"
                self._warn_once(("material-refused", key), f"Material '{name}': {ex} (rendered with the default surface)")
                mat_id = self.renderer.add_material(**material_export.DEFAULT_SURFACE,
                                                    **({"crypto": crypto} if crypto else {}))
            self._material_ids[key] = mat_id
            self.stats.materials += 1
        return mat_id

    def _material_crypto(self, material):
        """The material's Cryptomatte hash (Cycles names a missing material
        'default_surface'); 0 when no Cryptomatte is asked for."""
        if not self.cryptomatte.wants("CryptoMaterial"):
            return 0
        return self.cryptomatte.hash("CryptoMaterial", material.name if material is not None else "default_surface")

    def light_group_of(self, datablock):
        """The light-group index of an object or world (its Light Group
        field), 0 when it has none or the view layer has no such group."""
        if not self.light_groups or datablock is None:
            return 0
        return self.light_groups.get(getattr(datablock, "lightgroup", ""), 0)

    def image_registry(self):
        """The export's ImageRegistry (one upload per image for materials and world)."""
        if self._images is None:
            self._images = graph_builder.ImageRegistry(self.renderer.add_image, self.warn,
                                                     getattr(self.renderer, "find_image", None))
        return self._images

    def _graph_material_id(self, material, key, crypto=0):
        """A node material when the tree does not reduce to one constant
        parameter set (material.py); None to take the constant path."""
        if not material.use_nodes or material.node_tree is None:
            return None
        if not hasattr(self.renderer, "add_graph_material"):
            return None
        _, notes = material_export.material_params(material)
        writes_aovs = self.aovs_requested and graph_builder.aov_output_nodes(material.node_tree)
        if all(material_export.is_clamp_note(n) for n in notes) and not writes_aovs:
            return None  # the constant parameter set represents it: no program needed
        try:
            graph = graph_builder.build_material_graph(material, self.image_registry())
        except (graph_builder.GraphCycle, graph_builder.SpecError, RecursionError) as ex:
            self._warn_once(("material-graph", key), f"Material '{material.name}': {ex} "
                                                     "(rendered with its viewport display colour)")
            return None
        if graph.notes:
            self._warn_once(("material", key), f"Material '{material.name}': " + "; ".join(graph.notes))
        mode, threshold = material_export.blend_mode(material)
        if mode == "clip":
            graph_builder.apply_alpha_clip(graph, threshold)
        try:
            kwargs = {"pass_index": int(material.pass_index), "blend": mode == "blend"}
            if crypto:
                kwargs["crypto"] = crypto
            if getattr(graph, "light_emission", None) is not None:
                kwargs["light_emission"] = graph.light_emission  # its meshes light other surfaces
            if getattr(graph, "emission_varies", False):
                kwargs["emission_varies"] = True  # baked by the renderer to light other surfaces
            if not getattr(graph, "emits", True):
                kwargs["emits"] = False  # the emission samples need not resolve its surfaces
            mat_id = self.renderer.add_graph_material(graph.ir, **kwargs)
        except ValueError as ex:  # refused by the native validation
            self._warn_once(("material-graph", key), f"Material '{material.name}': {ex} "
                                                     "(rendered with its viewport display colour)")
            return None
        self._material_attributes[mat_id] = graph.attributes
        self.graph_materials += 1
        return mat_id

    def _slot_material_ids(self, ob):
        slots = ob.material_slots
        if len(slots) == 0:
            return (self.material_id(None),)
        return tuple(self.material_id(slot.material) for slot in slots)

    # -- meshes -----------------------------------------------------------
    @staticmethod
    def _mesh_key(ob):
        if ob.type == "MESH" and ob.data is not None:
            return ("data", ob.data.as_pointer())
        return ("object", ob.as_pointer())

    def _kept_mesh_key(self, inst, ob, attribute_keys):
        if self.mesh_keeper is None or inst.is_instance:
            # Instances (collection instances, geometry nodes) come from
            # evaluated objects whose names do not identify their geometry.
            return None
        return self.mesh_keeper.key(ob, attribute_keys)

    def _mesh_id(self, ob, attribute_keys=frozenset(), kept_key=None, motion_key=None):
        # Objects sharing a mesh but reading other attributes get their own copy.
        key = (self._mesh_key(ob), attribute_keys)
        if key in self._mesh_ids:
            return self._mesh_ids[key]
        if kept_key is not None:
            kept_id = self.renderer.find_mesh(kept_key)
            triangles = self.mesh_keeper.triangles.get(kept_key)
            if kept_id is not None and triangles is not None:
                self.stats.meshes_reused += 1
                self.stats.triangles += triangles
                self._mesh_ids[key] = (kept_id, triangles)
                return self._mesh_ids[key]
        entry = None
        try:
            arrays = mesh_export.object_mesh_arrays(
                ob, attribute_keys, warn=lambda message: self._warn_once(("attribute", message), message))
        except mesh_export.MeshSkipped as ex:
            self.stats.skipped_objects += 1
            # Silent, as in Cycles: curves without bevel (paths) and meshes
            # emptied by modifiers (geometry nodes that output only
            # instances). A mesh object without faces and without modifiers,
            # or with NaN/Inf vertices, gets a warning.
            expected_empty = ex.empty and (ob.type != "MESH" or len(ob.modifiers) > 0)
            if not expected_empty:
                self._warn_once(("mesh", key), f"Object '{ob.name}' skipped: {ex}")
        else:
            mesh_export.clamp_material_indices(arrays, max(1, len(ob.material_slots)))
            try:
                extras = self._mesh_extras(arrays)
                if kept_key is not None:
                    extras["key"] = kept_key
                if motion_key is not None:
                    motion_positions = self.motion.vertex_positions(motion_key, arrays.vertex_count)
                    if motion_positions is False:
                        self._warn_once(("motion-topology", ob.name),
                                        f"Object '{ob.name}': its vertex count changes between frames, so its "
                                        "deformation has no motion (Vector pass, motion blur), as in Cycles")
                    elif motion_positions is not None:
                        extras["motion_positions"] = motion_positions
                mesh_id = self.renderer.add_mesh(
                    arrays.positions, arrays.indices,
                    corner_normals=arrays.corner_normals,
                    corner_uvs=arrays.corner_uvs,
                    material_indices=arrays.material_indices,
                    **extras)
            except ValueError as ex:  # refused by the native validation
                self.stats.skipped_objects += 1
                self._warn_once(("mesh", key), f"Object '{ob.name}' skipped: {ex}")
            else:
                entry = (mesh_id, arrays.triangle_count)
                if kept_key is not None:
                    self.mesh_keeper.triangles[kept_key] = arrays.triangle_count
                self.stats.meshes += 1
                self.stats.triangles += arrays.triangle_count
                self.stats.mesh_bytes += arrays.nbytes()
        self._mesh_ids[key] = entry
        return entry

    def _mesh_extras(self, arrays):
        """Keyword arguments only node materials need (recorders without them work)."""
        if not hasattr(self.renderer, "add_graph_material"):
            return {}
        # Texture space always: a mesh exported first for a constant material
        # may be shared with a node material reading Generated coordinates.
        return {"attributes": list(arrays.attributes),
                "texspace_location": arrays.texspace_location, "texspace_size": arrays.texspace_size}

    # -- the walk ---------------------------------------------------------
    def sync(self, depsgraph):
        """Visit every object instance; returns False if cancelled."""
        start = time.perf_counter()
        self._holdout_objects = holdout_collection_objects(getattr(depsgraph, "view_layer", None))
        for count, inst in enumerate(depsgraph.object_instances):
            if count % 256 == 0 and self.test_break():
                self.cancelled = True
                return False
            ob = inst.object
            kind = ob.type
            if kind == "LIGHT":
                self._sync_light(inst, ob)
            elif kind in mesh_export.MESHABLE_TYPES:
                if inst.show_self:
                    self._sync_geometry(inst, ob)
            elif kind in UNSUPPORTED_GEOMETRY:
                self._warn_once(("type", kind), f"{kind.title()} objects are not rendered (e.g. '{ob.name}')")
        self.flush_instances()
        self.stats.seconds += time.perf_counter() - start
        return True

    def _sync_geometry(self, inst, ob):
        # The 16 values row by row, as a tuple (np.array(Matrix) per instance
        # goes through the sequence protocol, several times slower; the whole
        # export: bench/warm/bench_export.py); flush_instances makes one array.
        matrix = tuple(itertools.chain.from_iterable(inst.matrix_world))
        # Blender clamps an infinite scale to FLT_MAX; that overflows as well.
        # (A NaN or an infinity makes the sum one too.)
        if not math.isfinite(sum(matrix)):
            self._warn_once(("matrix", ob.name), f"Object '{ob.name}' skipped: NaN/Inf transform")
            self.stats.skipped_objects += 1
            return
        if max(matrix) > MAX_MATRIX_VALUE or min(matrix) < -MAX_MATRIX_VALUE:
            self._warn_once(("matrix", ob.name), f"Object '{ob.name}' skipped: transform beyond "
                                                 f"{MAX_MATRIX_VALUE:g} (float32 rendering limit)")
            self.stats.skipped_objects += 1
            return
        material_ids = self._slot_material_ids(ob)
        keys = frozenset(k for m in material_ids for k in self._material_attributes.get(m, ()))
        motion_key = motion_export.instance_key(inst, ob) if self.motion is not None else None
        entry = self._mesh_id(ob, keys, kept_key=self._kept_mesh_key(inst, ob, keys), motion_key=motion_key)
        if entry is None:
            return
        mesh_id, triangles = entry
        # Object > Visibility > Ray Visibility > Shadow: off, the object
        # blocks no light (Cycles' shadow rays pass it) and no world light.
        cast_shadow = bool(getattr(ob, "visible_shadow", True))
        original = getattr(ob, "original", None) or ob
        shading_offset = getattr(getattr(original, "cycles", None), "shadow_terminator_offset", 0.0)
        if isinstance(shading_offset, (int, float)) and shading_offset > 0.0:
            self._warn_once(("terminator-shading", ob.name),
                            f"Object '{ob.name}': Shadow Terminator Shading Offset is not rendered "
                            "(the Geometry Offset is)")
        # Object > Visibility > Holdout, or a holdout collection of the view
        # layer: a hole in the image (Cycles' SD_OBJECT_HOLDOUT_MASK).
        holdout = bool(getattr(ob, "is_holdout", False)) or ob.original.name in self._holdout_objects
        light_group = self.light_group_of(ob)
        # Object > Visibility > Mask > Shadow Catcher (Cycles: the object's or
        # its instancer's flag).
        parent = getattr(inst, "parent", None) if inst.is_instance else None
        shadow_catcher = bool(getattr(ob, "is_shadow_catcher", False)) or \
            bool(getattr(parent, "is_shadow_catcher", False))
        group_key = (mesh_id, material_ids, cast_shadow, holdout, light_group, shadow_catcher)
        group = self._groups.get(group_key)
        if group is None:
            group = self._groups[group_key] = _Group(mesh_id, material_ids, cast_shadow, holdout, shadow_catcher)
            group.light_group = light_group
        group.matrices.append(matrix)
        group.object_indices.append(ob.pass_index)
        group.names.append(ob.name)
        group.colors.append(tuple(ob.color))
        group.randoms.append(object_random(inst, ob))
        group.terminator_offsets.append(terminator_offset(ob))
        if motion_key is not None:
            group.motion.append(self.motion.matrices(motion_key, np.array(matrix, dtype=np.float64).reshape(4, 4)))
        if self.cryptomatte.layers:
            group.crypto.append((self.cryptomatte.hash("CryptoObject", ob.name),
                                 self.cryptomatte.hash("CryptoAsset", crypto_export.asset_object(inst, ob).name)))
        self.stats.instances += 1
        self.stats.instanced_triangles += triangles

    def _sync_light(self, inst, ob):
        try:
            params = light_export.light_params(ob.data, inst.matrix_world, name=ob.name)
        except light_export.LightSkipped as ex:
            self._warn_once(("light", ob.name), f"Light skipped: {ex}")
            return
        if params is None:
            return
        light_group = self.light_group_of(ob)
        if light_group:
            params["light_group"] = light_group
        try:
            self.renderer.add_light(**params)
        except ValueError as ex:  # refused by the native validation
            self._warn_once(("light", ob.name), f"Light '{ob.name}' skipped: {ex}")
            return
        self.stats.lights += 1

    def flush_instances(self):
        for group in self._groups.values():
            matrices = np.array(group.matrices, dtype=np.float64).reshape(-1, 4, 4)
            object_indices = np.asarray(group.object_indices, dtype=np.uint32)
            extras = {}
            if self._material_attributes:  # Object Info for node materials
                extras = {"colors": np.ascontiguousarray(group.colors, dtype=np.float32).reshape(-1, 4),
                          "randoms": np.ascontiguousarray(group.randoms, dtype=np.float32)}
            if group.crypto:
                extras["crypto"] = np.ascontiguousarray(group.crypto, dtype=np.uint32).reshape(-1, 2)
            if group.holdout:
                extras["holdout"] = True
            if group.shadow_catcher:
                extras["shadow_catcher"] = True
            if group.light_group:
                extras["light_group"] = group.light_group
            if group.motion:
                extras["motion"] = np.ascontiguousarray(np.stack(group.motion), dtype=np.float64)
            if any(group.terminator_offsets):
                extras["terminator_offsets"] = np.ascontiguousarray(group.terminator_offsets, dtype=np.float32)
            try:
                self.renderer.add_instances(group.mesh_id, matrices,
                                            object_indices=object_indices,
                                            material_slots=list(group.material_ids),
                                            cast_shadow=group.cast_shadow, **extras)
            except ValueError as ex:  # refused by the native validation
                names = ", ".join(f"'{n}'" for n in group.names[:3]) + (" ..." if len(group.names) > 3 else "")
                self.warn(f"{len(group.names)} object(s) skipped ({names}): {ex}")
                self.stats.skipped_objects += len(group.names)
        self._groups.clear()
