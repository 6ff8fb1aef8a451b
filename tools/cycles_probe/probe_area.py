"""Q4: area lights (square, rectangle, disk, ellipse) at height d facing down (-Z)
over a white Lambert plane (pixel = E/pi).  Candidate: radiance L = k * P / A
(A = u*v, x pi/4 for disk/ellipse) and E = L * Int cos_l cos_s / t^2 dA, computed
exactly per pixel with the polygon (Lambert) formula (disk/ellipse as a 4096-gon).
The fitted k is reported (REFERENCE says k = 1/4).  Also: the closed-form on-axis
square / disk formulas, and one-sidedness (light flipped to face +Z)."""
import os, sys, math
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np
import common as C

P, D = 100.0, 1.0
SPP = int(os.environ.get("PROBE_SPP", 2048))


def outline(shape, u, v, n=4096):
    if shape in ("SQUARE", "RECTANGLE"):
        return np.array([[-u / 2, -v / 2], [u / 2, -v / 2], [u / 2, v / 2], [-u / 2, v / 2]])
    ph = np.arange(n) * 2 * math.pi / n
    return np.stack([u / 2 * np.cos(ph), v / 2 * np.sin(ph)], 1)


def polygon_ff(px, py, poly2d, d):
    """Int cos_l cos_s / t^2 dA over a polygon at height d (parallel to z=0),
    seen from points (px, py, 0) with normal +Z. Exact (Lambert's formula)."""
    p = np.stack([px, py, np.zeros_like(px)], -1).reshape(-1, 3)
    q = np.concatenate([poly2d, np.full((len(poly2d), 1), d)], 1)
    acc = np.zeros(len(p))
    for i in range(len(q)):
        a = q[i][None] - p; b = q[(i + 1) % len(q)][None] - p
        a /= np.linalg.norm(a, axis=1, keepdims=True); b /= np.linalg.norm(b, axis=1, keepdims=True)
        cr = np.cross(a, b)
        s = np.linalg.norm(cr, axis=1)
        ang = np.arctan2(s, (a * b).sum(1))
        acc += ang * cr[:, 2] / np.maximum(s, 1e-300)
    return np.abs(acc).reshape(px.shape) / 2 * math.pi  # (1/2pi) sum * pi ... see note


# note: irradiance from a unit-radiance polygon is E = 1/2 sum_i theta_i (n . g_i);
# we return pi * (E/pi) = E directly:
def unit_radiance_E(px, py, poly2d, d):
    return polygon_ff(px, py, poly2d, d) / math.pi


if __name__ == "__main__":
    # closed-form checks of the on-axis formulas against the polygon integral
    h = 0.5
    sq_closed = 4 * h / math.sqrt(h * h + D * D) * math.atan(h / math.sqrt(h * h + D * D))
    sq_poly = unit_radiance_E(np.array([0.0]), np.array([0.0]), outline("SQUARE", 1, 1), D)[0]
    a = 0.5
    dk_closed = math.pi * a * a / (D * D + a * a)
    dk_poly = unit_radiance_E(np.array([0.0]), np.array([0.0]), outline("DISK", 1, 1), D)[0]
    print("[area] on-axis unit-radiance E: square h=0.5 d=1 closed %.7f polygon %.7f | disk a=0.5 closed %.7f 4096-gon %.7f" % (
        sq_closed, sq_poly, dk_closed, dk_poly))

    cases = [("SQUARE", 1.0, 1.0), ("RECTANGLE", 1.0, 2.0), ("DISK", 1.0, 1.0), ("ELLIPSE", 1.0, 2.0),
             ("SQUARE", 2.0, 2.0)]
    for shape, u, v in cases:
        A = u * v * (math.pi / 4 if shape in ("DISK", "ELLIPSE") else 1.0)
        C.reset(64, 16, samples=SPP, seed=5)
        C.add_plane(mat=C.diffuse_mat(1.0, 0.0))
        props = dict(shape=shape, size=u)
        if shape in ("RECTANGLE", "ELLIPSE"):
            props["size_y"] = v
        C.add_light("AREA", P, loc=(0, 0, D), **props)
        cam = C.add_ortho_camera(center=(1.75, 0.0), scale=4.0)
        img, dt = C.render("area_%s_%g_%g" % (shape, u, v))
        xy = C.pixel_world_xy(cam)
        meas = img.mean(2) * math.pi
        E1 = unit_radiance_E(xy[..., 0], xy[..., 1], outline(shape, u, v), D)   # E for L = 1
        k = meas / (E1 * P / A)                                                   # fitted L*A/P
        rho = xy[..., 0]
        L = P / (4 * A)
        print("\n[area] %s %gx%g A=%.5f P=%g d=%g spp=%d (%.1fs): L=P/(4A)=%.5f" % (shape, u, v, A, P, D, SPP, dt, L))
        print("[area]  x-bin       n   E_meas     E_cand(P/4A)  meas/cand-1   s.e.      px sd     fitted k=L*A/P")
        for lo, hi in [(-0.25, 0.15), (0.15, 0.45), (0.45, 0.75), (0.75, 1.25), (1.25, 2.0), (2.0, 3.0), (3.0, 3.75)]:
            m = (rho >= lo) & (rho < hi)
            r = meas[m] / (L * E1[m])
            mm, sd, se = C.stats(r)
            print("[area] %5.2f-%4.2f %4d  %-10.5g %-12.5g  %+.2e   %.1e   %.1e   %.6f" % (
                lo, hi, m.sum(), meas[m].mean(), (L * E1[m]).mean(), mm - 1, se, sd, k[m].mean()))
        mm, sd, se = C.stats(meas / (L * E1))
        print("[area] %s all px: meas/cand - 1 = %+.2e +- %.1e (s.e.), px sd %.1e; k = %.6f" % (shape, mm - 1, se, sd, k.mean()))
        j = np.unravel_index(np.argmin(np.hypot(xy[..., 0], xy[..., 1])), rho.shape)
        extra = ""
        if shape == "SQUARE":
            hh = u / 2
            extra = "closed-form on-axis L*4h/sqrt(h2+d2)*atan(h/sqrt(h2+d2)) = %.5f" % (
                L * 4 * hh / math.sqrt(hh * hh + D * D) * math.atan(hh / math.sqrt(hh * hh + D * D)))
        if shape == "DISK":
            extra = "closed-form on-axis L*pi*a2/(d2+a2) = %.5f" % (L * math.pi * (u / 2) ** 2 / (D * D + (u / 2) ** 2))
        print("[area] nearest-axis pixel (%.3f,%.3f): meas %.5f cand %.5f %s" % (
            xy[j][0], xy[j][1], meas[j], L * E1[j], extra))

    # exactly on axis: 3x3 image, centre pixel at (0, 0); 8192 spp
    for shape, u in (("SQUARE", 1.0), ("SQUARE", 2.0), ("DISK", 1.0), ("DISK", 2.0)):
        C.reset(3, 3, samples=8192, seed=9)
        C.add_plane(mat=C.diffuse_mat(1.0, 0.0))
        C.add_light("AREA", P, loc=(0, 0, D), shape=shape, size=u)
        C.add_ortho_camera(center=(0, 0), scale=0.003)
        img, dt = C.render("area_axis_%s_%g" % (shape, u))
        A = u * u * (math.pi / 4 if shape == "DISK" else 1.0)
        L = P / (4 * A)
        hh = u / 2
        if shape == "SQUARE":
            cf = L * 4 * hh / math.sqrt(hh * hh + D * D) * math.atan(hh / math.sqrt(hh * hh + D * D))
        else:
            cf = L * math.pi * hh * hh / (D * D + hh * hh)
        meas = img.mean() * math.pi  # 9 px within 1.5 mm of the axis: E varies < 1e-6 there
        print("[area] on-axis %s size %g d=%g: E_meas %.6f closed-form(L=P/4A) %.6f rel %+.2e (s.e. %.1e from 9 px)" % (
            shape, u, D, meas, cf, meas / cf - 1, (img.mean(2) * math.pi / cf).std(ddof=1) / 3))

    # one-sidedness: light flipped to face +Z (away from the plane)
    for shape in ("SQUARE", "DISK"):
        C.reset(32, 32, samples=256, seed=5)
        C.add_plane(mat=C.diffuse_mat(1.0, 0.0))
        C.add_light("AREA", P, loc=(0, 0, D), rot=(math.pi, 0, 0), shape=shape, size=1.0)
        cam = C.add_ortho_camera(center=(0, 0), scale=4.0)
        img, dt = C.render("area_flip_%s" % shape)
        print("[area] one-sided check %s facing +Z (away from plane): max pixel %.3g (facing-down peak E/pi ~ %.3g)" % (
            shape, img.max(), P / 4 * (sq_closed if shape == "SQUARE" else dk_closed / (math.pi / 4)) / math.pi))
