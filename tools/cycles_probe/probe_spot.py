"""Q2: spot light over a white Lambert plane (pixel = E/pi), measured across the
cone edge. c = cos(angle between spot axis (-Z) and light->point), cs =
cos(spot_size/2), w = (1-cs)*spot_blend, t = c - cs.
  (i)  att = c * smoothstep(t/w)    (REFERENCE.md, 3.4 with leading c)
  (ii) att = smoothstep(t/w)        (no leading c, 3.5+)
E = P cos(th)/(4 pi t0^2) * att for R = 0.  For R > 0 the point-light disk
integral (b1 of probe_point) is used, with att evaluated either per disk sample
(direction sample->point) or once at the light centre."""
import os, sys, math
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np
import common as C
from probe_point import disk_integrals  # noqa: E402  (no render on import? guarded below)

P, D = 100.0, 1.0
SPP = int(os.environ.get("PROBE_SPP", 1024))


def smooth(x):
    x = np.clip(x, 0, 1)
    return x * x * (3 - 2 * x)


def att(c, size, blend, lead):
    cs = math.cos(size / 2)
    w = (1 - cs) * blend
    t = c - cs
    s = np.where(t <= 0, 0.0, np.where(t < w, smooth(t / w) if w > 0 else 1.0, 1.0))
    return (c if lead else 1.0) * s


def disk_att_integral(px, py, d, R, size, blend, lead, nr=48, nphi=96):
    """1/(pi R^2) Int cos_l cos_s att(dir sample->p) / t^2 dA (disk faces p)."""
    p = np.stack([px, py, np.zeros_like(px)], -1).reshape(-1, 3)
    c0 = np.array([0.0, 0.0, d])
    nl = p - c0; nl /= np.linalg.norm(nl, axis=1, keepdims=True)
    a = np.where(np.abs(nl[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    u = np.cross(nl, a); u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(nl, u)
    xg, wg = np.polynomial.legendre.leggauss(nr)
    r = (xg + 1) / 2 * R; wr = wg / 2 * R * r
    phi = (np.arange(nphi) + 0.5) * 2 * math.pi / nphi
    w = (wr[:, None] * (2 * math.pi / nphi) * np.ones(nphi)[None]).ravel()
    cr = (r[:, None] * np.cos(phi)[None]).ravel(); sr = (r[:, None] * np.sin(phi)[None]).ravel()
    q = c0[None, None] + cr[None, :, None] * u[:, None] + sr[None, :, None] * v[:, None]
    om = q - p[:, None]; t = np.linalg.norm(om, axis=2); om /= t[..., None]
    cos_s = np.clip(om[..., 2], 0, None)
    cos_l = np.einsum("nkj,nj->nk", -om, nl)
    cspot = om[..., 2]  # direction sample->p is -om; spot axis (0,0,-1): c = dot(-om, (0,0,-1)) = om_z
    A = att(cspot, size, blend, lead)
    return ((cos_l * cos_s * A / t**2) * w).sum(1).reshape(px.shape) / (math.pi * R * R)


if __name__ == "__main__":
    cases = [(math.radians(60), 0.5, 0.0), (math.radians(90), 1.0, 0.0),
             (math.radians(60), 0.0, 0.0), (math.radians(60), 0.5, 0.25)]
    for size, blend, R in cases:
        C.reset(128, 8, samples=SPP if R > 0 else 64, seed=3)
        C.add_plane(mat=C.diffuse_mat(1.0, 0.0))
        C.add_light("SPOT", P, loc=(0, 0, D), spot_size=size, spot_blend=blend, shadow_soft_size=R)
        cam = C.add_ortho_camera(center=(0.6, 0.0), scale=1.4 if size > 1.2 else 1.0)
        img, dt = C.render("spot_%d_%g_%g" % (round(math.degrees(size)), blend, R))
        xy = C.pixel_world_xy(cam)
        meas = img.mean(2) * math.pi
        rho = np.hypot(xy[..., 0], xy[..., 1])
        t0 = np.sqrt(rho**2 + D * D)
        c = D / t0
        cs = math.cos(size / 2); w = (1 - cs) * blend
        if R == 0:
            Ep = P * c / (4 * math.pi * t0**2)
            Ei, Eii = Ep * att(c, size, blend, True), Ep * att(c, size, blend, False)
            extra = []
        else:
            i1, _ = disk_integrals(xy[..., 0], xy[..., 1], D, R)
            Ep = P / (4 * math.pi) * i1
            Ei, Eii = Ep * att(c, size, blend, True), Ep * att(c, size, blend, False)
            Eis = P / (4 * math.pi) * disk_att_integral(xy[..., 0], xy[..., 1], D, R, size, blend, True)
            Eiis = P / (4 * math.pi) * disk_att_integral(xy[..., 0], xy[..., 1], D, R, size, blend, False)
            extra = [("c*ss per sample", Eis), ("ss per sample", Eiis)]
        print("\n[spot] size=%g deg blend=%g R=%g: cs=%.5f w=%.5f  edge rho=%.4f, blend starts rho=%.4f (%.1fs)" % (
            math.degrees(size), blend, R, cs, w, math.tan(size / 2), math.tan(math.acos(min(1, cs + w))), dt))
        names = ["(i) c*ss centre", "(ii) ss centre"] + [e[0] for e in extra]
        cands = [Ei, Eii] + [e[1] for e in extra]
        print("[spot] %-7s %-7s %-11s " % ("rho", "c", "E_meas") + " ".join("%-17s" % n for n in names))
        row = 0
        H, W = meas.shape
        for i in range(0, W, 4 if R == 0 else 6):
            rr, cc, mm = rho[row, i], c[row, i], meas[:, i].mean()
            # the 8 pixels of a column share x; rho differs slightly with y -> compare per pixel
            rel = ["%+.2e" % ((meas[:, i] / E[:, i]).mean() - 1) if E[:, i].min() > 1e-9 else
                   ("meas %.1e" % mm if True else "") for E in cands]
            print("[spot] %-7.4f %-7.5f %-11.5g " % (rho[:, i].mean(), c[:, i].mean(), mm) + " ".join("%-17s" % x for x in rel))
        for n, E in zip(names, cands):
            m = E > 0.01 * E.max()
            r = meas[m] / E[m] - 1
            z = E <= 1e-9
            print("[spot] %-17s px with cand > 1%% of peak: rms rel err %.2e, max |rel| %.2e; max meas where cand=0: %.2e" % (
                n, math.sqrt((r**2).mean()), np.abs(r).max(), meas[z].max() if z.any() else 0))
