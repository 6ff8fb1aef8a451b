"""Benchmark: how fast scene data reaches the native side.

Measures, for a 1M-triangle grid (flat/smooth path and auto-smooth split
normals path):
  - Blender -> numpy arrays (export/mesh.py)
  - numpy -> native Renderer.add_mesh (validation + upload on the GL thread)
and the whole depsgraph export of blend_samples/instancing.blend (10k
instances). Prints BENCH lines; fails if the 1M-triangle flat/smooth export
to the native side takes a second or more.

    BLENDER_USER_SCRIPTS=build/blender_scripts blender -b --factory-startup \
        --addons deferred_render --python-exit-code 1 --python tests/blender/bench_export.py
"""

import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_utils as U  # noqa: E402

from deferred_render import export  # noqa: E402
from deferred_render.export import mesh as mesh_export  # noqa: E402

REPEATS = 3


def best_of(func, repeats=REPEATS):
    best, result = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = func()
        best = min(best, time.perf_counter() - t0)
    return best, result


def main():
    checks = U.Checks("bench_export")
    mod = U.native_module()
    if not checks.check(mod is not None, "native module importable"):
        checks.finish()
    renderer = mod.Renderer(device_index=bpy.context.scene.deferred_render.device_index
                            if hasattr(bpy.context.scene, "deferred_render") else -1)
    print(f"  GL: {renderer.gl_info.get('renderer')}")

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=708, y_subdivisions=708, size=10)
    ob = bpy.context.active_object
    for auto_smooth in (False, True):
        ob.data.use_auto_smooth = auto_smooth
        ob_eval = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
        t_numpy, arrays = best_of(lambda: mesh_export.object_mesh_arrays(ob_eval))

        def upload():
            renderer.clear_scene()
            return renderer.add_mesh(arrays.positions, arrays.indices, corner_normals=arrays.corner_normals,
                                     corner_uvs=arrays.corner_uvs, material_indices=arrays.material_indices)
        t_native, _ = best_of(upload)
        label = "auto smooth (split normals)" if auto_smooth else "smooth/flat"
        total = t_numpy + t_native
        print(f"  BENCH 1M-triangle mesh, {label}: {arrays.triangle_count} tris, {arrays.nbytes() / 1e6:.0f} MB; "
              f"Blender->numpy {1000 * t_numpy:.0f} ms, numpy->native add_mesh {1000 * t_native:.0f} ms, "
              f"total {1000 * total:.0f} ms")
        if not auto_smooth:
    renderer.clear_scene()

    bpy.ops.wm.open_mainfile(filepath=os.path.join(U.SAMPLES, "instancing.blend"))
    depsgraph = bpy.context.evaluated_depsgraph_get()
    t_scene, (stats, _cancelled) = best_of(lambda: export.export_scene(depsgraph, renderer))
    print(f"  BENCH instancing.blend export to native: {stats.summary()} in {1000 * t_scene:.0f} ms")
    renderer = None
    checks.finish()


main()
