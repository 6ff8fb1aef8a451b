"""Light objects -> keyword arguments of ``Renderer.add_light``.

Blender 3.4 light data is copied field by field (units as in Blender: W,
sun W/m^2, metres, radians); the world matrix carries position, direction
(-Z) and, for area lights, the X/Y scale of ``size``/``size_y`` (Cycles 3.4).

Documented fallbacks (each gives one warning, the render goes on):
- an area light with zero area (size 0 or a zero X/Y scale) emits nothing
  that can be rendered (its radiance S/(4A) is infinite), so it is skipped;
- a light with a non-finite matrix, colour or energy is skipped;
- so is a light beyond 1e15 m or brighter than 1e12 W (colour x energy; the
  native input contract, native/src/scene_store.h: float32 lighting would
  overflow); sizes beyond 1e6 m are clamped to it;
- lights with zero energy or a black colour are skipped silently (they add
  nothing).
A point or spot light of radius 0 is a valid hard light and is kept.
"""

import math

import numpy as np

LIGHT_TYPES = {"POINT", "SPOT", "SUN", "AREA"}

# The native input contract (native/src/scene_store.h, InputLimits).
MAX_COORDINATE = 1e15
MAX_POWER = 1e12
MAX_SIZE = 1e6


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
    color = tuple(max(0.0, c) for c in color)
    if energy == 0.0 or max(color) <= 0.0:
        return None
    if np.abs(matrix).max() > MAX_COORDINATE:
        raise LightSkipped(f"light '{name}' is beyond {MAX_COORDINATE:g} m (float32 rendering limit)")
    if abs(energy) * max(color) > MAX_POWER:
        raise LightSkipped(f"light '{name}' has colour x power {abs(energy) * max(color):g}, "
                           f"beyond the renderer's limit of {MAX_POWER:g}")

    def size(value):
        value = float(value)
        return min(max(0.0, value), MAX_SIZE) if math.isfinite(value) else 0.0

    params = {
        "type": light.type,
        "matrix": matrix,
        "color": color,
        "energy": energy,
        "cast_shadow": bool(light.use_shadow),
    }
    if light.type in {"POINT", "SPOT"}:
        params["radius"] = size(light.shadow_soft_size)
    if light.type == "SPOT":
        params["spot_size"] = min(max(0.0, float(light.spot_size)), math.pi)
        params["spot_blend"] = min(max(0.0, float(light.spot_blend)), 1.0)
    elif light.type == "SUN":
        params["angle"] = min(max(0.0, float(light.angle)), math.pi)
    elif light.type == "AREA":
        shape = light.shape
        size_x = size(light.size)
        size_y = size(light.size_y) if shape in {"RECTANGLE", "ELLIPSE"} else size_x
        sx, sy = _axis_lengths(matrix)
        if size_x * sx <= 0.0 or size_y * sy <= 0.0:
            raise LightSkipped(
                f"area light '{name}' has zero size ({size_x:g} x {size_y:g} m at scale "
                f"{sx:g} x {sy:g}): skipped")
        params["shape"] = shape
        params["size"] = size_x
        params["size_y"] = size_y
    return params
