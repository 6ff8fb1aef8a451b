"""Sanity: EXR round trip is linear, pixel->world mapping is right.
Emission plane with colour = world position: pixel value must equal the
world point predicted by common.pixel_world_xy (straight and tilted ortho)."""
import os, sys
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np
import common as C

ok = True
for name, vdir in [("straight", (0, 0, 1)), ("tilted", (0.5, 0.3, 0.8))]:
    C.reset(24, 16, samples=256)
    C.add_plane(mat=C.emission_mat(position=True))
    cam = C.add_ortho_camera(center=(1.3, -0.7), scale=3.0, view_dir=vdir)
    img, _ = C.render("sanity_" + name)
    xy = C.pixel_world_xy(cam)
    err = np.abs(img[..., :2] - xy).max()
    zmax = np.abs(img[..., 2]).max()
    print("[sanity] %s: max |pos - predicted| = %.3g, max |z| = %.3g" % (name, err, zmax))
    ok &= err < 0.01 * 3.0 / 24  # < 1% of a pixel (filter jitter)
# linearity of EXR round trip: constant emission 0.3721 strength 2.5
C.reset(8, 8, samples=4)
C.add_plane(mat=C.emission_mat(color=(0.3721, 0.5, 0.01), strength=2.5))
C.add_ortho_camera()
img, _ = C.render("sanity_lin")
print("[sanity] emission 2.5*(0.3721,0.5,0.01) ->", img.reshape(-1, 3).mean(0), "expected", (0.93025, 1.25, 0.025))
print("[sanity] OK" if ok else "[sanity] FAIL")
