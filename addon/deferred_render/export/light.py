"""Light objects -> keyword arguments of ``Renderer.add_light``.

Blender 3.4 light data is copied field by field (units as in Blender: W,
sun W/m^2, metres, radians); the world matrix carries position, direction
(-Z) and, for area lights, the X/Y scale of ``size``/``size_y`` (Cycles 3.4).

Documented fallbacks (each gives one warning, the render goes on):
- an area light with zero area (size 0 or a zero X/Y scale) emits nothing
  that can be rendered (its radiance S/(4A) is infinite), so it is skipped;
- a light with a non-finite matrix, colour or energy is skipped;
- lights with zero energy or a black colour are skipped silently (they add
  nothing).
A point or spot light of radius 0 is a valid hard light and is kept.
"""

import math

import numpy as np

LIGHT_TYPES = {"POINT", "SPOT", "SUN", "AREA"}


class LightSkipped(Exception):
    """The light is not rendered; the message says why."""


def _axis_lengths(matrix):
    m = np.asarray(matrix, dtype=np.float64)
    return float(np.linalg.norm(m[:3, 0])), float(np.linalg.norm(m[:3, 1]))


def light_params(light, matrix, name=None):
    """Keyword arguments for add_light from a bpy.types.Light and its world matrix.

    Returns None for lights that add nothing; raises LightSkipped for lights
    that cannot be rendered."""
    name = name or light.name
    if light.type not in LIGHT_TYPES:
        raise LightSkipped(f"light '{name}' has unsupported type {light.type}")
    matrix = np.array(matrix, dtype=np.float64)
    if matrix.shape != (4, 4) or not np.isfinite(matrix).all():
        raise LightSkipped(f"light '{name}' has a NaN/Inf transform")
    color = tuple(float(c) for c in light.color)
    energy = float(light.energy)
    if not (all(math.isfinite(c) for c in color) and math.isfinite(energy)):
        raise LightSkipped(f"light '{name}' has a NaN/Inf colour or power")
    if energy == 0.0 or max(color) <= 0.0:
        return None

    params = {
        "type": light.type,
        "matrix": matrix,
        "color": color,
        "energy": energy,
        "cast_shadow": bool(light.use_shadow),
    }
    if light.type in {"POINT", "SPOT"}:
        params["radius"] = max(0.0, float(light.shadow_soft_size))
    if light.type == "SPOT":
        params["spot_size"] = float(light.spot_size)
        params["spot_blend"] = float(light.spot_blend)
    elif light.type == "SUN":
        params["angle"] = max(0.0, float(light.angle))
    elif light.type == "AREA":
        shape = light.shape
        size = float(light.size)
        size_y = float(light.size_y) if shape in {"RECTANGLE", "ELLIPSE"} else size
        sx, sy = _axis_lengths(matrix)
        if size * sx <= 0.0 or size_y * sy <= 0.0:
            raise LightSkipped(
                f"area light '{name}' has zero size ({size:g} x {size_y:g} m at scale "
                f"{sx:g} x {sy:g}): skipped")
        params["shape"] = shape
        params["size"] = size
        params["size_y"] = size_y
    return params
