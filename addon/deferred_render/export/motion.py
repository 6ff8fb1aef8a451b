"""The scene at other times: the neighbouring frames for the Vector pass, the
shutter's open and close for motion blur.

Cycles fills its motion pass from the depsgraph evaluated at frame - 1 and
frame + 1 (blender/sync.cpp ``sync_motion``; ``Scene::motion_shutter_time()``
is 2 frames for the motion pass, so the relative times -1 and +1 land on the
neighbouring frames), with the render's subframe. For motion blur the same
three steps are the shutter's open, middle and close: the middle at the frame
for Shutter Position Center, half a shutter later for Start and earlier for
End (the frame is then the shutter's open or close), each step half a
shutter (Render Properties > Motion Blur > Shutter, in frames) away. For each object instance it
keeps the world matrix there; for a deforming mesh, the vertex positions,
when their count is the same as at this frame (otherwise the deformation is
left out: Cycles disables it and only logs "Topology differs"; here it is a
warning). The camera's matrices come with this frame's lens (Cycles 3.4's
motion pass projects with this frame's ``cameratoraster``).

Instances are matched across frames as Cycles' ``ObjectKey`` does: the
object itself, or for an instance its instancer and ``persistent_id``. An
instance missing at a neighbouring frame does not move, and neither does an
object (or camera) whose Object > Motion Blur is off (Cycles' per-object
``use_motion_blur``); ``use_deform_motion`` off keeps its vertices still.
Cycles' Motion Steps above 1 (more than three steps) are rendered with three.
"""

import math

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


def _cycles_setting(ob, name, default):
    original = getattr(ob, "original", None) or ob
    settings = getattr(original, "cycles", None)
    return getattr(settings, name, default) if settings is not None else default


def moves(ob):
    """Object > Motion Blur (Cycles' per-object switch, on by default)."""
    return bool(_cycles_setting(ob, "use_motion_blur", True))


def motion_steps(ob):
    """Cycles' Motion Steps of an object: 2^(steps - 1) + 1 transforms."""
    try:
        return int(_cycles_setting(ob, "motion_steps", 1))
    except (TypeError, ValueError):
        return 1


def deforms(ob):
    """Whether a mesh object's vertices can move within it between frames:
    modifiers (armatures, simulations, geometry nodes, ...) or shape keys,
    as Blender's ``BKE_object_is_deform_modified`` asks, and its Deformation
    motion (Cycles' ``use_deform_motion``) is on."""
    if ob.type != "MESH" or not bool(_cycles_setting(ob, "use_deform_motion", True)):
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
        self.camera_lens = None  # (lens, ortho_scale, shift_x, shift_y): what the matrices do not say


def _snapshot(depsgraph, camera_object, engine, geometry_types):
    step = _Step()
    for inst in depsgraph.object_instances:
        ob = inst.object
        if ob.type not in geometry_types or not inst.show_self or not moves(ob):
            continue
        key = instance_key(inst, ob)
        step.matrices[key] = np.array(inst.matrix_world, dtype=np.float64)
        if deforms(ob):
            positions = _vertex_positions(ob)
            if positions is not None:
                step.positions[key] = positions
    if camera_object is not None and moves(camera_object):
        evaluated = camera_object.original.evaluated_get(depsgraph)
        data = getattr(evaluated, "data", None)
        if data is not None:
            step.camera_lens = tuple(float(getattr(data, k, 0.0)) for k in ("lens", "ortho_scale", "shift_x", "shift_y"))
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

    def lens_moves(self, params):
        """Whether the camera's lens, ortho scale or shift differ at the other
        times from ``params`` (camera.camera_params of this frame)."""
        now = tuple(float(params.get(k, 0.0)) for k in ("lens", "ortho_scale", "shift_x", "shift_y"))
        return any(step.camera_lens is not None and
                   any(abs(a - b) > 1e-6 * max(1.0, abs(b)) for a, b in zip(step.camera_lens, now))
                   for step in (self.previous, self.next))

    def camera(self, now):
        """(previous, next) camera matrices, or None when it does not move."""
        previous = self.previous.camera if self.previous.camera is not None else now
        next_ = self.next.camera if self.next.camera is not None else now
        if np.array_equal(previous, now) and np.array_equal(next_, now):
            return None
        return (previous, next_)


def _frame_set(engine, time):
    frame = math.floor(time)
    engine.frame_set(int(frame), subframe=float(time - frame))


def collect(engine, depsgraph, camera_object, geometry_types, half_span=1.0, middle_delta=0.0):
    """Evaluates the depsgraph ``half_span`` frames before and after the
    middle step (the render's frame and subframe + ``middle_delta``) and
    leaves it at the middle step, where this frame's export reads it;
    ``restore`` goes back to the render's frame after that. Returns a
    ``Motion``."""
    scene = depsgraph.scene
    middle = scene.frame_current + scene.frame_subframe + middle_delta
    steps = []
    try:
        for offset in (-half_span, half_span):
            _frame_set(engine, middle + offset)
            steps.append(_snapshot(depsgraph, camera_object, engine, geometry_types))
    finally:
        _frame_set(engine, middle)
    return Motion(steps[0], steps[1])


def restore(engine, frame, subframe):
    """Back at the render's own frame (after a middle step elsewhere)."""
    engine.frame_set(frame, subframe=subframe)


def blur_settings(scene):
    """(shutter in frames, the middle step's offset from the frame) of
    Render Properties > Motion Blur (Cycles' Shutter Position: Center, or
    Start / End, the frame being the shutter's open / close)."""
    shutter = float(getattr(scene.render, "motion_blur_shutter", 0.5))
    if not math.isfinite(shutter) or shutter < 0.0:
        shutter = 0.5
    position = getattr(getattr(scene, "cycles", None), "motion_blur_position", "CENTER")
    return shutter, {"START": 0.5 * shutter, "END": -0.5 * shutter}.get(position, 0.0)


def blur_warnings(depsgraph):
    """What of Render Properties > Motion Blur this engine does not render."""
    scene = depsgraph.scene
    notes = []
    curve = getattr(scene.render, "motion_blur_shutter_curve", None)
    try:
        flat = all(abs(p.location[1] - 1.0) < 1e-6 for c in curve.curves for p in c.points)
    except (AttributeError, TypeError):
        flat = True
    if not flat:
        notes.append("Motion Blur: the Shutter Curve is not rendered (the shutter is open evenly)")
    rolling = getattr(getattr(scene, "cycles", None), "rolling_shutter_type", "NONE")
    if rolling != "NONE":
        notes.append("Motion Blur: the Rolling Shutter is not rendered")
    many = sorted({inst.object.original.name for inst in depsgraph.object_instances
                   if inst.object.type != "LIGHT" and moves(inst.object) and motion_steps(inst.object) > 1})
    if many:
        names = ", ".join(f"'{n}'" for n in many[:3]) + (" ..." if len(many) > 3 else "")
        notes.append(f"Motion Blur: Motion Steps above 1 are rendered with 3 steps (open, middle, close): {names}")
    return notes
