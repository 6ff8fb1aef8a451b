"""The scene camera -> keyword arguments of ``deferred_native.Camera``.

The native side builds the projection exactly as Cycles does from these
Blender values (sensor fit, shift, pixel aspect), so nothing is converted
here except the matrix: the camera object's world matrix with its scale
removed, as ``RenderEngine.camera_model_matrix`` gives it and Cycles uses.
"""

import numpy as np

CAMERA_TYPES = {"PERSP", "ORTHO"}


class CameraError(Exception):
    """The scene cannot be rendered from its camera; the message says why."""


# The native input contract (native/src/camera.cpp): positions within 1e15 m.
MAX_COORDINATE = 1e15


def _normalized_matrix(matrix):
    m = np.array(matrix, dtype=np.float64)
    if m.shape != (4, 4) or not np.isfinite(m).all():
        raise CameraError("the camera has a NaN/Inf transform")
    if np.abs(m[:3, 3]).max() > MAX_COORDINATE:
        raise CameraError(f"the camera is farther than {MAX_COORDINATE:g} m from the origin (float32 rendering limit)")
    for axis in range(3):
        n = np.linalg.norm(m[:3, axis])
        if n < 1e-12:
            raise CameraError("the camera has a zero scale on one axis")
        m[:3, axis] /= n
    return m


def camera_params(scene, camera_object, engine=None):
    """Return (params, warnings) for the camera object (an evaluated object)."""
    if camera_object is None:
        raise CameraError("the scene has no active camera (Scene > Camera)")
    if camera_object.type != "CAMERA":
        raise CameraError(f"the active camera '{camera_object.name}' is not a camera object")
    cam = camera_object.data
    warnings = []
    cam_type = cam.type
    if cam_type not in CAMERA_TYPES:
        warnings.append(f"camera '{camera_object.name}': {cam_type} cameras are not supported, rendered as perspective")
        cam_type = "PERSP"
    if cam.dof.use_dof:
        warnings.append(f"camera '{camera_object.name}': depth of field is not rendered")

    matrix = None
    if engine is not None:
        try:
            matrix = engine.camera_model_matrix(camera_object)
        except (TypeError, RuntimeError, AttributeError):
            matrix = None
    if matrix is None:
        matrix = camera_object.matrix_world
    render = scene.render
    clip_start = float(cam.clip_start)
    clip_end = float(cam.clip_end)
    if not (clip_end > clip_start > 0.0):
        raise CameraError(
            f"camera '{camera_object.name}' has invalid clipping ({clip_start:g} .. {clip_end:g})")
    params = {
        "type": cam_type,
        "matrix": _normalized_matrix(matrix),
        "lens": float(cam.lens),
        "sensor_width": float(cam.sensor_width),
        "sensor_height": float(cam.sensor_height),
        "sensor_fit": cam.sensor_fit,
        "shift_x": float(cam.shift_x),
        "shift_y": float(cam.shift_y),
        "clip_start": clip_start,
        "clip_end": clip_end,
        "ortho_scale": float(cam.ortho_scale),
        "pixel_aspect_x": float(render.pixel_aspect_x),
        "pixel_aspect_y": float(render.pixel_aspect_y),
    }
    return params, warnings
