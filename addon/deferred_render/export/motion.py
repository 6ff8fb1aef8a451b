"""The scene at the neighbouring frames, for the Vector pass.

Cycles fills its motion pass from the depsgraph evaluated at frame - 1 and
frame + 1 (blender/sync.cpp ``sync_motion``; ``Scene::motion_shutter_time()``
is 2 frames for the motion pass, so the relative times -1 and +1 land on the
neighbouring frames), with the render's subframe. For each object instance it
keeps the world matrix there; for a deforming mesh, the vertex positions,
when their count is the same as at this frame (otherwise the deformation is
left out: Cycles disables it and only logs "Topology differs"; here it is a
warning). The camera's matrices come with this frame's lens (Cycles 3.4's
motion pass projects with this frame's ``cameratoraster``).

Instances are matched across frames as Cycles' ``ObjectKey`` does: the
object itself, or for an instance its instancer and ``persistent_id``. An
instance missing at a neighbouring frame does not move.
"""

import numpy as np

from .camera import CameraError, _normalized_matrix


def instance_key(inst, ob):
    """What identifies an object instance across frames."""
    original = getattr(ob, "original", None) or ob
    name = getattr(original, "name_full", ob.name)
    if inst is not None and inst.is_instance:
        parent = inst.parent
        parent_name = getattr(getattr(parent, "original", None) or parent, "name_full", "") if parent else ""
        return ("instance", parent_name, tuple(inst.persistent_id), name)
    return ("object", name)


def deforms(ob):
    """Whether a mesh object's vertices can move within it between frames:
    modifiers (armatures, simulations, geometry nodes, ...) or shape keys,
    as Blender's ``BKE_object_is_deform_modified`` asks."""
    if ob.type != "MESH":
        return False
    original = getattr(ob, "original", None) or ob
    data = getattr(original, "data", None)
    return len(original.modifiers) > 0 or getattr(data, "shape_keys", None) is not None


def _vertex_positions(ob):
    mesh = ob.data
    if mesh is None or not hasattr(mesh, "vertices"):
        return None
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


class _Step:
    """One neighbouring frame: matrices and deforming vertices by instance key, the camera."""

    def __init__(self):
        self.matrices = {}
        self.positions = {}
        self.camera = None


def _snapshot(depsgraph, camera_object, engine, geometry_types):
    step = _Step()
    for inst in depsgraph.object_instances:
        ob = inst.object
        if ob.type not in geometry_types or not inst.show_self:
            continue
        key = instance_key(inst, ob)
        step.matrices[key] = np.array(inst.matrix_world, dtype=np.float64)
        if deforms(ob):
            positions = _vertex_positions(ob)
            if positions is not None:
                step.positions[key] = positions
    if camera_object is not None:
        evaluated = camera_object.original.evaluated_get(depsgraph)
        matrix = None
        try:
            matrix = engine.camera_model_matrix(evaluated)
        except (TypeError, RuntimeError, AttributeError):
            matrix = evaluated.matrix_world
        try:
            step.camera = _normalized_matrix(matrix)
        except CameraError:
            step.camera = None  # a camera unusable there (NaN, zero scale): it does not move
    return step


class Motion:
    """The previous and next frames' matrices and vertices (``collect``)."""

    def __init__(self, previous, next_):
        self.previous = previous
        self.next = next_

    def matrices(self, key, now):
        """(2, 4, 4) previous and next world matrices of an instance (``now``
        where it is missing), and whether they differ from ``now``."""
        out = np.empty((2, 4, 4), dtype=np.float64)
        for k, step in enumerate((self.previous, self.next)):
            m = step.matrices.get(key)
            out[k] = now if m is None or not np.isfinite(m).all() else m
        return out

    def vertex_positions(self, key, vertex_count):
        """(2, V, 3) float32 previous and next positions of a deforming mesh;
        None when it has none, False when the vertex count changes."""
        steps = [step.positions.get(key) for step in (self.previous, self.next)]
        if all(p is None for p in steps):
            return None
        if any(p is None or len(p) != vertex_count or not np.isfinite(p).all() for p in steps):
            return False
        return np.ascontiguousarray(np.stack(steps), dtype=np.float32)

    def camera(self, now):
        """(previous, next) camera matrices, or None when it does not move."""
        previous = self.previous.camera if self.previous.camera is not None else now
        next_ = self.next.camera if self.next.camera is not None else now
        if np.array_equal(previous, now) and np.array_equal(next_, now):
            return None
        return (previous, next_)


def collect(engine, depsgraph, camera_object, geometry_types):
    """Evaluates the depsgraph at the previous and the next frame (with the
    render's subframe) and back at this one; returns a ``Motion``."""
    scene = depsgraph.scene
    frame, subframe = scene.frame_current, scene.frame_subframe
    steps = []
    try:
        for offset in (-1, 1):
            engine.frame_set(frame + offset, subframe=subframe)
            steps.append(_snapshot(depsgraph, camera_object, engine, geometry_types))
    finally:
        engine.frame_set(frame, subframe=subframe)
    return Motion(steps[0], steps[1])
