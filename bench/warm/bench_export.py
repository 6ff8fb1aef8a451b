"""The depsgraph export alone (export_scene into a native renderer), the
part of every render that walks the instances in Python: seven exports of
the open file's evaluated scene, the first apart (it uploads the meshes
into a new renderer). Prints one line.

    BLENDER_USER_SCRIPTS=build/blender_scripts blender -b --factory-startup --addons deferred_render \\
        blend_samples/instancing.blend --python bench/warm/bench_export.py
"""

import time

import bpy

from deferred_render import native
from deferred_render.export import export_scene


def main():
    renderer = native.load().Renderer()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    seconds, stats = [], None
    for _ in range(7):
        t0 = time.perf_counter()
        stats, _ = export_scene(depsgraph, renderer)
        seconds.append(time.perf_counter() - t0)
    print(f"{bpy.data.filepath}: {stats.summary()}; export s: first {seconds[0]:.3f}, "
          f"then best {min(seconds[1:]):.3f}, median {sorted(seconds[1:])[3]:.3f} "
          f"({' '.join(f'{s:.3f}' for s in seconds[1:])})")


main()
