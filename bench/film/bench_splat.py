#!/usr/bin/python3.11
"""The film's filter splatting against each pixel's own samples: time per
render of a lit plane (warm renderer, 16 samples) with Combined only and with
every pass, at 32x32 and 256x256, each pair twice (the first pair warms the
programs). Not part of the test suite.

    PYTHONPATH=build/blender_scripts/addons/deferred_render:tests/python \\
        /usr/bin/python3.11 bench/film/bench_splat.py
"""
import time

import numpy as np

import deferred_native as dn
from test_module import camera, plane

r = dn.Renderer()
p, i, n = plane()
mesh = r.add_mesh(p, i, corner_normals=n)
r.add_instances(mesh, np.eye(4)[None], material_slots=[r.add_material(base_color=(0.5, 0.5, 0.5))])
r.add_light(type="SUN", energy=2.0)
every_pass = [name for name, *_ in dn.PASSES]
print("| size | passes | filter splatting | ms per 16-sample render |\n|---|---:|---|---:|")
for size in (32, 256):
    for passes in (["Combined"], every_pass):
        for splat in (False, True, False, True):
            t = time.perf_counter()
            for _ in range(3):
                r.render(camera(), size, size, passes=passes, samples=16, filter_splat=splat)
            print(f"| {size} | {len(passes)} | {'on' if splat else 'off'} | "
                  f"{(time.perf_counter() - t) / 3 * 1000:.1f} |")
