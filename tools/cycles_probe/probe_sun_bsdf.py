"""Q3 sun irradiance, Q5 Principled diffuse (Burley), Q6 Principled GGX specular.
Infinite plane, sun (delta when angle=0), ortho camera: every pixel has the same
L and V, so each render gives one number (mean of 8x8 px; the sd is the noise).
L = direction to the sun = (sin a, 0, cos a); V = direction to the camera."""
import os, sys, math
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np
import bpy
import common as C

S = 3.0
SPP = int(os.environ.get("PROBE_SPP", 64))


def vec(theta_deg, phi_deg=0.0):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def run(mat, sun_theta, view, sun_angle=0.0, spp=SPP, tag="x"):
    C.reset(8, 8, samples=spp, seed=7)
    C.add_plane(size=2000.0, mat=mat())  # mat: factory (reset() wipes data)
    C.add_light("SUN", S, loc=(0, 0, 5), rot=(0, math.radians(sun_theta), 0), angle=sun_angle)
    C.add_ortho_camera(center=(0, 0), scale=1.0, view_dir=tuple(view), dist=50.0)
    img, dt = C.render(tag)
    v = img.mean(2)
    return v.mean(), v.std(ddof=1)


def fresnel_dielectric_cos(cosi, eta):
    c = abs(cosi)
    g = eta * eta - 1 + c * c
    if g <= 0:
        return 1.0
    g = math.sqrt(g)
    A = (g - c) / (g + c)
    B = (c * (g + c) - 1) / (c * (g - c) + 1)
    return 0.5 * A * A * (1 + B * B)


def burley(base, rough, L, V, N=np.array([0, 0, 1.0])):
    cl, cv = L @ N, V @ N
    FL, FV = (1 - cl) ** 5, (1 - cv) ** 5
    RR = rough * (1 + L @ V)
    return base / math.pi * cl * ((1 - 0.5 * FL) * (1 - 0.5 * FV) + RR * (FL + FV + FL * FV * (RR - 1)))


def ggx(spec, rough, L, V, N=np.array([0, 0, 1.0]), fresnel="principled", base=0.0, metallic=0.0):
    a = min(max(rough * rough, 0.0), 1.0)
    a2 = a * a
    H = L + V; H /= np.linalg.norm(H)
    cl, cv, ch = L @ N, V @ N, H @ N
    if cl <= 0 or cv <= 0:
        return 0.0
    tan2h = (1 - ch * ch) / (ch * ch)
    D = a2 / (math.pi * ch**4 * (a2 + tan2h) ** 2)
    G1 = lambda c: 2.0 / (1.0 + math.sqrt(1.0 + a2 * (1 - c * c) / (c * c)))
    G = G1(cl) * G1(cv)
    F0 = 0.08 * spec
    eta = 2.0 / (1.0 - math.sqrt(0.08 * spec)) - 1.0
    LH = L @ H
    cspec0 = F0 * (1 - metallic) + base * metallic   # specular_tint 0
    if fresnel == "principled":
        FH = (fresnel_dielectric_cos(LH, eta) - F0) / (1 - F0)
        F = cspec0 * (1 - FH) + FH
    elif fresnel == "schlick":
        F = cspec0 + (1 - cspec0) * (1 - LH) ** 5
    elif fresnel == "const":
        F = cspec0
    else:  # plain dielectric
        F = fresnel_dielectric_cos(LH, eta)
    return F * D * G / (4 * cv)


def line(tag, meas, sd, cands):
    s = "[%s] meas %-11.6g (px sd %.1e) " % (tag, meas, sd)
    for n, v in cands:
        s += "| %s %-10.6g rel %+.2e " % (n, v, meas / v - 1 if v else float("nan"))
    print(s)


if __name__ == "__main__":
    # ---------- Q3: sun irradiance, white Diffuse BSDF, pixel = E/pi
    print("\n[sun] Diffuse white, S=%g, candidate pixel = S cos(theta)/pi" % S)
    for th in (0, 30, 60, 85):
        for ang in (0.0, math.radians(0.526), math.radians(10.0)):
            m, sd = run(lambda: C.diffuse_mat(1.0, 0.0), th, (0, 0, 1), sun_angle=ang, spp=256 if ang else SPP,
                        tag="sun_%d_%g" % (th, ang))
            line("sun th=%2d angle=%5.3fdeg" % (th, math.degrees(ang)), m, sd,
                 [("S cos/pi", S * math.cos(math.radians(th)) / math.pi),
                  ("S cos/pi*(1+cos(angle/2))/2", S * math.cos(math.radians(th)) / math.pi * (1 + math.cos(ang / 2)) / 2)])

    # ---------- Q5: Principled diffuse
    nd = bpy.data.materials.new("tmp"); nd.use_nodes = True
    pn = nd.node_tree.nodes.new("ShaderNodeBsdfPrincipled")
    print("\n[burley] new Principled node default distribution = %s, subsurface_method = %s" % (
        pn.distribution, pn.subsurface_method))
    print("[burley] base 1, specular 0, metallic 0; candidates: Burley (REFERENCE 2) and Lambert cos/pi; x S")
    for rough in (0.0, 0.5, 1.0):
        for th, view in ((0, vec(0)), (60, vec(0)), (60, vec(70, 180)), (60, vec(70, 0)), (30, vec(45, 90))):
            m, sd = run(lambda: C.principled_mat(base=1.0, specular=0.0, roughness=rough), th, view,
                        tag="burley_%g_%d" % (rough, th))
            L = vec(th)
            line("burley r=%.1f L=%2d V=(%4.1f,%4.1f,%4.2f)" % (rough, th, *view), m, sd,
                 [("Burley", S * burley(1.0, rough, L, view)), ("Lambert", S * L[2] / math.pi)])

    # ---------- Q6: Principled specular (GGX), base black
    print("\n[ggx] base 0, specular 0.5, roughness 0.3, metallic 0, GGX; sun theta 30; candidates x S")
    for dist in ("GGX", "MULTI_GGX"):
        for th, view in ((30, vec(0)), (30, vec(30, 180)), (30, vec(45, 180)), (30, vec(60, 180)),
                         (30, vec(20, 0)), (30, vec(30, 90)), (60, vec(60, 180)), (60, vec(0))):
            for rough in ((0.3, 0.6) if th == 30 and view[2] > 0.99 or abs(view[0] + 0.5) < 1e-9 else (0.3,)):
                m, sd = run(lambda: C.principled_mat(base=0.0, specular=0.5, roughness=rough, distribution=dist),
                            th, view, spp=SPP if dist == "GGX" else 4096, tag="ggx_%s_%d" % (dist, th))
                L = vec(th)
                H = L + view; H /= np.linalg.norm(H)
                line("ggx %-9s r=%.1f L=%2d V=(%5.2f,%4.2f,%4.2f) th_h=%4.1f" % (
                    dist, rough, th, *view, math.degrees(math.acos(H[2]))), m, sd,
                     [("GGX+princF", S * ggx(0.5, rough, L, view)),
                      ("GGX+Schlick", S * ggx(0.5, rough, L, view, fresnel="schlick")),
                      ("GGX+dielF", S * ggx(0.5, rough, L, view, fresnel="diel"))])

    # metallic: cspec0 = base, distinguishes the principled Fresnel interpolation
    print("\n[metal] base 0.8, metallic 1, specular 0.5, GGX; candidates x S")
    for rough, th, view in ((0.3, 30, vec(30, 180)), (0.3, 60, vec(60, 180)), (0.3, 75, vec(75, 180)),
                            (0.5, 60, vec(0)), (0.3, 30, vec(0))):
        m, sd = run(lambda: C.principled_mat(base=0.8, metallic=1.0, specular=0.5, roughness=rough),
                    th, view, tag="metal_%d" % th)
        L = vec(th)
        H = L + view; H /= np.linalg.norm(H)
        line("metal r=%.1f L=%2d V=(%5.2f,%4.2f,%4.2f) L.H=%.3f" % (rough, th, *view, L @ H), m, sd,
             [(n, S * ggx(0.5, rough, L, view, fresnel=f, base=0.8, metallic=1.0))
              for n, f in (("princF", "principled"), ("Schlick", "schlick"), ("F=base", "const"))])
