"""Q1: point light (energy P, radius R) at height d over a white Lambert plane.
Pixel value of a white Diffuse BSDF = E/pi. Candidates per pixel:
  (a)  E = P cos(th) / (4 pi (t0^2 + R^2))          t0 = distance to light centre
  (b1) E = P/(4pi) * 1/(pi R^2) * Int_disk cos_l cos_s / t^2 dA  (disk faces the point)
  (b2) E = P/(4pi) * 1/(pi R^2) * Int_disk cos_s / t^2 dA         (no cos_l; = the brief's
       on-axis value 2(1 - d/sqrt(d^2+R^2))/R^2)
  (c)  E = P cos(th) / (4 pi t0^2)
"""
import os, sys, math
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np
import common as C

P, D = 100.0, 1.0
SPP = int(os.environ.get("PROBE_SPP", 4096))
RADII = [0.0, 0.5, 1.0, 2.0]


def disk_integrals(px, py, d, R, nr=48, nphi=96):
    """Return (Int cos_l cos_s/t^2 dA, Int cos_s/t^2 dA) / (pi R^2) per point."""
    p = np.stack([px, py, np.zeros_like(px)], -1).reshape(-1, 3)
    c = np.array([0.0, 0.0, d])
    nl = p - c
    nl /= np.linalg.norm(nl, axis=1, keepdims=True)
    a = np.where(np.abs(nl[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    u = np.cross(nl, a); u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(nl, u)
    xg, wg = np.polynomial.legendre.leggauss(nr)
    r = (xg + 1) / 2 * R; wr = wg / 2 * R * r            # r dr
    phi = (np.arange(nphi) + 0.5) * 2 * math.pi / nphi; wphi = 2 * math.pi / nphi
    cr = r[:, None] * np.cos(phi)[None]; sr = r[:, None] * np.sin(phi)[None]
    w = (wr[:, None] * wphi * np.ones_like(phi)[None]).ravel()
    off = cr.ravel()[None, :, None] * u[:, None] + sr.ravel()[None, :, None] * v[:, None]
    q = c[None, None] + off                                 # (N, K, 3)
    om = q - p[:, None]
    t = np.linalg.norm(om, axis=2)
    om /= t[..., None]
    cos_s = np.clip(om[..., 2], 0, None)
    cos_l = np.einsum("nkj,nj->nk", -om, nl)               # disk normal nl faces p; -om is q->p
    i1 = (cos_l * cos_s / t**2 * w).sum(1) / (math.pi * R * R)
    i2 = (cos_s / t**2 * w).sum(1) / (math.pi * R * R)
    return i1.reshape(px.shape), i2.reshape(px.shape)


if __name__ != "__main__":
    RADII = []
rows = []
for R in RADII:
    C.reset(64, 16, samples=SPP, seed=1)
    C.add_plane(mat=C.diffuse_mat(1.0, 0.0))
    C.add_light("POINT", P, loc=(0, 0, D), shadow_soft_size=R)
    cam = C.add_ortho_camera(center=(1.75, 0.0), scale=4.0)
    img, dt = C.render("point_R%g" % R)
    xy = C.pixel_world_xy(cam)
    meas = img.mean(2) * math.pi                            # E
    rho = np.hypot(xy[..., 0], xy[..., 1])
    t0sq = rho**2 + D * D
    cos_t = D / np.sqrt(t0sq)
    Ea = P * cos_t / (4 * math.pi * (t0sq + R * R))
    Ec = P * cos_t / (4 * math.pi * t0sq)
    if R > 0:
        i1, i2 = disk_integrals(xy[..., 0], xy[..., 1], D, R)
        Eb1 = P / (4 * math.pi) * i1
        Eb2 = P / (4 * math.pi) * i2
    else:
        Eb1 = Eb2 = Ec
    edges = [0, 0.15, 0.4, 0.75, 1.25, 1.75, 2.5, 3.8]
    print("\n[point] R=%g d=%g P=%g spp=%d (%.1fs)" % (R, D, P, SPP, dt))
    print("[point] rho-bin      n   E_meas      meas/(a)   meas/(b1)  meas/(b2)  meas/(c)   noise vs (b1): s.e. of bin mean (per-pixel sd)")
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (rho >= lo) & (rho < hi)
        if not m.any():
            continue
        st = [C.stats(meas[m] / E[m]) for E in (Ea, Eb1, Eb2, Ec)]
        print("[point] %4.2f-%4.2f %5d  %-10.5g  %9.5f  %9.5f  %9.5f  %9.5f   %.2e (pixel sd %.2e)" % (
            lo, hi, m.sum(), meas[m].mean(), st[0][0], st[1][0], st[2][0], st[3][0], st[1][2], st[1][1]))
    m = rho < 3.8
    for nm, E in (("a", Ea), ("b1", Eb1), ("b2", Eb2), ("c", Ec)):
        chi = ((meas[m] / E[m] - 1) ** 2).mean()
        print("[point] R=%g overall rms rel. error vs (%s): %.4f" % (R, nm, math.sqrt(chi)))
    # on-axis pixel values (nearest pixels to rho=0 are at rho~0.044)
    k = np.unravel_index(np.argmin(rho), rho.shape)
    print("[point] R=%g nearest-axis pixel rho=%.4f: meas %.5f  a %.5f  b1 %.5f  b2 %.5f  c %.5f" % (
        R, rho[k], meas[k], Ea[k], Eb1[k], Eb2[k], Ec[k]))

# exactly on axis: 3x3 image with the centre pixel at (0, 0)
for R in RADII:
    C.reset(3, 3, samples=8192, seed=9)
    C.add_plane(mat=C.diffuse_mat(1.0, 0.0))
    C.add_light("POINT", P, loc=(0, 0, D), shadow_soft_size=R)
    C.add_ortho_camera(center=(0, 0), scale=0.003)
    img, dt = C.render("point_axis_R%g" % R)
    E = img.mean() * math.pi  # 9 px within 1.5 mm of the axis
    a = P / (4 * math.pi * (D * D + R * R))
    b2 = P / (4 * math.pi) * (2 * (1 - D / math.sqrt(D * D + R * R)) / (R * R) if R else 1 / (D * D))
    c = P / (4 * math.pi * D * D)
    print("[point] on-axis R=%g: E_meas %.6f | (a)=(b1) %.6f rel %+.2e | (b2) brief's on-axis %.6f rel %+.2e | (c) %.6f rel %+.2e" % (
        R, E, a, E / a - 1, b2, E / b2 - 1, c, E / c - 1))
