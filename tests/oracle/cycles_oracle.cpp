// CPU oracle for Cycles 3.4 direct lighting: see cycles_oracle.h.
#include "cycles_oracle.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace oracle {

namespace {

using glm::dvec3;

constexpr double kPi = 3.14159265358979323846;
// svm/closure.h (util/types.h): closures with a smaller weight are not allocated.
constexpr double kClosureWeightCutoff = 1e-5;
// util/color.h linear_rgb_to_gray(): dot(rgb, film.rgb_to_y). Cycles derives
// rgb_to_y from the OCIO config (aces_interchange role); for Blender 3.4's
// default config (scene_linear = Linear Rec.709) it is the Y row of
// datafiles/colormanagement/luts/srgb_to_xyz.spimtx.
const dvec3 kRgbToY(0.2126729, 0.7151522, 0.0721750);

double saturate(double x) { return std::min(std::max(x, 0.0), 1.0); }
dvec3 saturate(dvec3 v) { return glm::clamp(v, dvec3(0.0), dvec3(1.0)); }
double safe_sqrt(double x) { return std::sqrt(std::max(x, 0.0)); }
dvec3 to_dvec3(const deferred::Vec3& v) { return dvec3(v[0], v[1], v[2]); }
dvec3 column(const deferred::Mat4d& m, int c) { return dvec3(m[c * 4 + 0], m[c * 4 + 1], m[c * 4 + 2]); }
dvec3 safe_normalize(dvec3 v) {
    const double l = glm::length(v);
    return l > 0.0 ? v / l : v;
}

// util/math_float3.h make_orthonormals (any orthonormal pair works: the
// converged integral does not depend on the disk's in-plane orientation).
void make_orthonormals(dvec3 n, dvec3& a, dvec3& b) {
    if (n.x != n.y || n.x != n.z)
        a = dvec3(n.z - n.y, n.x - n.z, n.y - n.x);
    else
        a = dvec3(n.z - n.y, n.x + n.z, -n.y - n.x);
    a = glm::normalize(a);
    b = glm::cross(n, a);
}

// ---------------------------------------------------------------------------
// Principled BSDF closure set-up (svm/closure.h, CLOSURE_BSDF_PRINCIPLED_ID,
// subsurface = transmission = anisotropic = 0, distribution GGX).
// ---------------------------------------------------------------------------
struct Prepared {
    bool has_diffuse = false, has_sheen = false, has_specular = false, has_clearcoat = false;
    dvec3 diffuse_weight{0.0};  // base * (1 - m)
    double roughness = 0.0;     // Burley retro-reflection roughness (not squared)
    double diffuse_sigma = -1;  // >= 0: a Diffuse BSDF, Oren-Nayar sigma (0 = Lambert)
    int glossy_model = 0;       // 1: Glossy BSDF GGX, 2: Beckmann (weight spec_cspec0, no Fresnel)
    dvec3 sheen_weight{0.0};
    double spec_alpha = 0.0, spec_ior = 1.0, spec_F0 = 0.0;
    dvec3 spec_cspec0{0.0};
    double cc_alpha = 0.0, cc_F0 = 0.0, clearcoat = 0.0;
};

Prepared prepare(const deferred::Material& mat) {
    Prepared p;
    const dvec3 base = to_dvec3(mat.base_color);
    const double metallic = mat.metallic;
    const double specular = mat.specular;
    const double roughness = mat.roughness;
    const double transmission = 0.0;
    const double diffuse_weight = (1.0 - saturate(metallic)) * (1.0 - saturate(transmission));
    const double final_transmission = saturate(transmission) * (1.0 - saturate(metallic));
    const double specular_weight = 1.0 - final_transmission;

    // Diffuse: allocated if |average(base)| > cutoff and diffuse_weight > cutoff.
    const double avg_base = (base.x + base.y + base.z) / 3.0;
    if (std::fabs(avg_base) > kClosureWeightCutoff && diffuse_weight > kClosureWeightCutoff) {
        p.has_diffuse = true;
        p.diffuse_weight = base * diffuse_weight;
        p.roughness = roughness;
        if (mat.diffuse_roughness >= 0.0f) p.diffuse_sigma = std::min(double(mat.diffuse_roughness), 1.0);
        // A Glossy BSDF's set with a diffuse lobe (metallic 0) is a Lambert
        // Diffuse BSDF summed with it (scene.h glossy_model).
        if (mat.glossy_model != 0) p.diffuse_sigma = 0.0;
    }

    // Sheen: tint normalised by linear_rgb_to_gray (Rec.709 Y), NOT the
    // 0.3/0.6/0.1 approximation used for the specular tint.
    if (diffuse_weight > kClosureWeightCutoff && mat.sheen > kClosureWeightCutoff) {
        const double lum = glm::dot(base, kRgbToY);
        const dvec3 ctint = lum > 0.0 ? base / lum : dvec3(1.0);
        const dvec3 sheen_color = dvec3(1.0 - mat.sheen_tint) + ctint * double(mat.sheen_tint);
        p.has_sheen = true;
        p.sheen_weight = double(mat.sheen) * sheen_color * diffuse_weight;
    }

    // Specular reflection: only if specular or metallic exceeds the cut-off.
    if (specular_weight > kClosureWeightCutoff &&
        (specular > kClosureWeightCutoff || metallic > kClosureWeightCutoff)) {
        p.has_specular = true;
        p.spec_ior = 2.0 / (1.0 - safe_sqrt(0.08 * specular)) - 1.0;
        // aspect = 1 (anisotropic 0); bsdf_microfacet_ggx_fresnel_setup saturates alpha.
        p.spec_alpha = saturate(roughness * roughness);
        p.spec_cspec0 = specular_cspec0(mat);
        // bsdf_microfacet.h reflection_color: F0 = fresnel_dielectric_cos(1, ior)
        // (equals 0.08*specular analytically).
        p.spec_F0 = fresnel_dielectric_cos(1.0, p.spec_ior);
        if (mat.glossy_model != 0) {
            // A Glossy BSDF: bsdf_microfacet_{ggx,beckmann}_setup, weight = colour.
            p.glossy_model = mat.glossy_model;
            // (With metallic 0: the summed Diffuse + Glossy's grey glossy weight.)
            p.spec_cspec0 = metallic < 0.5 ? dvec3(std::max(double(mat.specular_tint), 0.0)) : glm::max(base, dvec3(0.0));
        }
    }

    // Clearcoat: closure weight 1 in 3.4; the 0.25*clearcoat is applied in eval.
    if (mat.clearcoat > kClosureWeightCutoff) {
        p.has_clearcoat = true;
        // bsdf_microfacet_ggx_clearcoat_setup saturates alpha.
        p.cc_alpha = saturate(double(mat.clearcoat_roughness) * double(mat.clearcoat_roughness));
        p.cc_F0 = fresnel_dielectric_cos(1.0, 1.5);
        p.clearcoat = mat.clearcoat;
    }
    return p;
}

// bsdf_oren_nayar.h (Cycles 3.4): bsdf_oren_nayar_get_intensity with the
// setup's A = 1 / (pi + (3 pi - 4) / 6 sigma), B = sigma A; eval is zero for
// a light below N. Returns f*cos.
double oren_nayar(double sigma, dvec3 N, dvec3 V, dvec3 L) {
    if (glm::dot(N, L) <= 0.0) return 0.0;
    const double nl = std::max(glm::dot(N, L), 0.0), nv = std::max(glm::dot(N, V), 0.0);
    double t = glm::dot(L, V) - nl * nv;
    if (t > 0.0) t /= std::max(nl, nv) + 1.17549435e-38;
    sigma = saturate(sigma);
    const double div = 1.0 / (kPi + ((3.0 * kPi - 4.0) / 6.0) * sigma);
    return nl * (div + sigma * div * t);
}

// bsdf_principled_diffuse.h bsdf_principled_diffuse_compute_brdf, components
// PRINCIPLED_DIFFUSE_FULL (Lambert part + retro-reflection). Returns f*cos.
double principled_diffuse(double roughness, dvec3 N, dvec3 V, dvec3 L) {
    const double NdotL = glm::dot(N, L);
    if (NdotL <= 0.0) return 0.0;
    const double NdotV = glm::dot(N, V);
    const double FV = schlick_fresnel(NdotV);
    const double FL = schlick_fresnel(NdotL);
    double f = (1.0 - 0.5 * FV) * (1.0 - 0.5 * FL);
    const double LH2 = glm::dot(L, V) + 1.0;
    const double RR = roughness * LH2;
    f += RR * (FL + FV + FL * FV * (RR - 1.0));
    return NdotL * f / kPi;
}

// bsdf_principled_sheen.h bsdf_principled_sheen_eval +
// calculate_principled_sheen_brdf. Returns f*cos (no 1/pi).
double principled_sheen(dvec3 N, dvec3 V, dvec3 L) {
    if (!(glm::dot(N, L) > 0.0)) return 0.0;
    const double NdotL = glm::dot(N, L);
    const double NdotV = glm::dot(N, V);
    if (NdotL < 0.0 || NdotV < 0.0) return 0.0;
    const dvec3 H = glm::normalize(L + V);
    return schlick_fresnel(glm::dot(L, H)) * NdotL;
}

// bsdf_util.h interpolate_fresnel_color.
dvec3 interpolate_fresnel_color(dvec3 L, dvec3 H, double ior, double F0, dvec3 cspec0) {
    const double F0_norm = 1.0 / (1.0 - F0);
    const double FH = (fresnel_dielectric_cos(glm::dot(L, H), ior) - F0) * F0_norm;
    return cspec0 * (1.0 - FH) + dvec3(FH);
}

// bsdf_microfacet.h bsdf_microfacet_ggx_eval + bsdf_microfacet_ggx_eval_reflect
// (isotropic branch), types MICROFACET_GGX_FRESNEL and MICROFACET_GGX_CLEARCOAT.
// Returns f*cos_l = F*D*G/(4 cos_v).
dvec3 microfacet_reflect(bool clearcoat, double alpha, double ior, double F0, dvec3 cspec0,
                         double clearcoat_amount, dvec3 N, dvec3 V, dvec3 L) {
    if (alpha * alpha <= 1e-7) return dvec3(0.0);  // "alpha_x * alpha_y <= 1e-7f"
    const double cosNO = glm::dot(N, V);
    const double cosNI = glm::dot(N, L);
    if (!(cosNI > 0.0 && cosNO > 0.0)) return dvec3(0.0);
    const dvec3 m = glm::normalize(L + V);
    const double cosThetaM = glm::dot(N, m);
    double D, alpha2;
    if (clearcoat) {
        D = gtr1_D(cosThetaM, alpha);
        alpha2 = 0.0625;  // fixed alpha 0.25 for the clearcoat's G
    } else {
        D = ggx_D(cosThetaM, alpha);
        alpha2 = alpha * alpha;
    }
    const double G = smith_G1(cosNO, alpha2) * smith_G1(cosNI, alpha2);
    const double common = D * 0.25 / cosNO;
    dvec3 F = interpolate_fresnel_color(L, m, ior, F0, cspec0);
    if (clearcoat) F *= 0.25 * clearcoat_amount;
    return F * G * common;
}

// bsdf_microfacet.h (3.4) bsdf_beckmann_G1: Smith G1 by a rational fit.
double beckmann_G1(double alpha, double cos_n) {
    const double c2 = cos_n * cos_n;
    const double inv_a = alpha * safe_sqrt((1.0 - c2) / c2);
    if (inv_a < 0.625) return 1.0;
    const double a = 1.0 / inv_a;
    return ((2.181 * a + 3.535) * a) / ((2.577 * a + 2.276) * a + 1.0);
}

// A Glossy BSDF's lobe (bsdf_microfacet_ggx_eval_reflect without Fresnel,
// bsdf_microfacet_beckmann_eval_reflect): f*cos = D G / (4 cos_v), times its colour.
dvec3 glossy_reflect(int model, double alpha, dvec3 colour, dvec3 N, dvec3 V, dvec3 L) {
    if (alpha * alpha <= 1e-7) return dvec3(0.0);
    const double cosNO = glm::dot(N, V), cosNI = glm::dot(N, L);
    if (!(cosNI > 0.0 && cosNO > 0.0)) return dvec3(0.0);
    const dvec3 m = glm::normalize(L + V);
    const double c = glm::dot(N, m), c2 = c * c, tan2 = (1.0 - c2) / c2, alpha2 = alpha * alpha;
    double D, G;
    if (model == 2) {
        D = std::exp(-tan2 / alpha2) / (kPi * alpha2 * c2 * c2);
        G = beckmann_G1(alpha, cosNO) * beckmann_G1(alpha, cosNI);
    } else {
        D = ggx_D(c, alpha);
        G = smith_G1(cosNO, alpha2) * smith_G1(cosNI, alpha2);
    }
    return colour * (D * G * 0.25 / cosNO);
}

Lobes eval_prepared(const Prepared& p, dvec3 N, dvec3 V, dvec3 L) {
    Lobes out;
    if (p.has_diffuse)
        out.diffuse = p.diffuse_weight * (p.diffuse_sigma >= 0.0 ? oren_nayar(p.diffuse_sigma, N, V, L)
                                                                  : principled_diffuse(p.roughness, N, V, L));
    if (p.has_sheen) out.sheen = p.sheen_weight * principled_sheen(N, V, L);
    if (p.has_specular && p.glossy_model != 0)
        out.specular = glossy_reflect(p.glossy_model, p.spec_alpha, p.spec_cspec0, N, V, L);
    else if (p.has_specular)
        out.specular = microfacet_reflect(false, p.spec_alpha, p.spec_ior, p.spec_F0, p.spec_cspec0,
                                          0.0, N, V, L);
    if (p.has_clearcoat)
        out.clearcoat = microfacet_reflect(true, p.cc_alpha, 1.5, p.cc_F0, dvec3(0.04), p.clearcoat,
                                           N, V, L);
    return out;
}

// ---------------------------------------------------------------------------
// Quadrature helpers
// ---------------------------------------------------------------------------
struct Node {
    double x, w;
};

// Composite 4-point Gauss-Legendre on [0, 1] with about n nodes.
std::vector<Node> composite_gauss_legendre(int n) {
    static const double xi[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                 0.8611363115940526};
    static const double wi[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                 0.3478548451374538};
    const int panels = std::max(1, (n + 3) / 4);
    const double h = 1.0 / panels;
    std::vector<Node> nodes;
    nodes.reserve(static_cast<std::size_t>(panels) * 4);
    for (int p = 0; p < panels; ++p)
        for (int i = 0; i < 4; ++i) nodes.push_back({(p + 0.5 + 0.5 * xi[i]) * h, 0.5 * h * wi[i]});
    return nodes;
}

// One Gauss-Kronrod 7/15 step on [a, b]; err = |K15 - G7|.
template <class F>
double gauss_kronrod15(const F& f, double a, double b, double& err) {
    static const double xgk[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                                  0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                                  0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                                  0.207784955007898467600689403773245, 0.0};
    static const double wgk[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                                  0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                                  0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                                  0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
    static const double wg[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                                 0.381830050505118944950369775488975, 0.417959183673469387755102040816327};
    const double c = 0.5 * (a + b), h = 0.5 * (b - a);
    const double fc = f(c);
    double k = wgk[7] * fc, g = wg[3] * fc;
    for (int i = 0; i < 7; ++i) {
        const double f1 = f(c - h * xgk[i]), f2 = f(c + h * xgk[i]);
        k += wgk[i] * (f1 + f2);
        if (i % 2 == 1) g += wg[i / 2] * (f1 + f2);
    }
    err = std::fabs((k - g) * h);
    return k * h;
}

template <class F>
double adaptive_integrate(const F& f, double a, double b, double tol, int depth) {
    double err = 0.0;
    const double k = gauss_kronrod15(f, a, b, err);
    if (err <= tol || depth >= 40) return k;
    const double m = 0.5 * (a + b);
    return adaptive_integrate(f, a, m, 0.5 * tol, depth + 1) + adaptive_integrate(f, m, b, 0.5 * tol, depth + 1);
}

// Contribution of the straight edge v0 -> v1 (relative to the shading point)
// to N . J, J = 1/2 sum theta_i normalize(v_i x v_{i+1}) (Lambert's polygon
// vector irradiance).
double edge_term(dvec3 v0, dvec3 v1, dvec3 N) {
    const dvec3 c = glm::cross(v0, v1);
    const double s = glm::length(c);
    if (s <= 0.0) return 0.0;
    const double theta = std::atan2(s, glm::dot(v0, v1));
    return 0.5 * theta * glm::dot(N, c) / s;
}

// |N . J| of a convex polygon (vertices relative to P) clipped to N.x >= 0
// (Sutherland-Hodgman): the projected solid angle of its visible part.
double polygon_projected_solid_angle(const std::vector<dvec3>& poly, dvec3 N) {
    std::vector<dvec3> clipped;
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
        const dvec3 cur = poly[i], nxt = poly[(i + 1) % n];
        const double dc = glm::dot(N, cur), dn = glm::dot(N, nxt);
        if (dc >= 0.0) clipped.push_back(cur);
        if ((dc >= 0.0) != (dn >= 0.0)) clipped.push_back(cur + (dc / (dc - dn)) * (nxt - cur));
    }
    if (clipped.size() < 3) return 0.0;
    double sum = 0.0;
    for (std::size_t i = 0; i < clipped.size(); ++i)
        sum += edge_term(clipped[i], clipped[(i + 1) % clipped.size()], N);
    return std::fabs(sum);
}

// |N . J| of the ellipse r(phi) = c + a cos(phi) + b sin(phi) (relative to P)
// clipped to N.x >= 0: J = 1/2 closed-int (r x dr)/|r|^2 over the arc above the
// horizon (adaptive Gauss-Kronrod) plus the chord, which lies in the tangent
// plane N.x = 0.
double ellipse_projected_solid_angle(dvec3 c, dvec3 a, dvec3 b, dvec3 N) {
    const double n0 = glm::dot(N, c), na = glm::dot(N, a), nb = glm::dot(N, b);
    const double amp = std::hypot(na, nb);
    double phi0 = 0.0, phi1 = 2.0 * kPi;
    bool clipped = false;
    if (n0 <= -amp) return 0.0;  // entirely below the horizon
    if (n0 < amp) {
        const double psi = std::atan2(nb, na);
        const double beta = std::acos(std::clamp(-n0 / amp, -1.0, 1.0));
        phi0 = psi - beta;
        phi1 = psi + beta;
        clipped = true;
    }
    auto r_at = [&](double phi) { return c + a * std::cos(phi) + b * std::sin(phi); };
    auto integrand = [&](double phi) {
        const dvec3 r = r_at(phi);
        const dvec3 dr = -a * std::sin(phi) + b * std::cos(phi);
        return glm::dot(N, glm::cross(r, dr)) / glm::dot(r, r);
    };
    // Scale for the tolerance: a coarse estimate of the integral of |g|.
    double scale = 0.0;
    {
        const int k = 64;
        for (int i = 0; i < k; ++i) scale += std::fabs(integrand(phi0 + (phi1 - phi0) * (i + 0.5) / k));
        scale *= (phi1 - phi0) / k;
    }
    double arc = 0.0;
    const int pieces = 16;
    const double tol = std::max(scale, 1e-300) * 1e-14 / pieces;
    for (int i = 0; i < pieces; ++i) {
        const double lo = phi0 + (phi1 - phi0) * i / pieces;
        const double hi = phi0 + (phi1 - phi0) * (i + 1) / pieces;
        arc += adaptive_integrate(integrand, lo, hi, tol, 0);
    }
    double sum = 0.5 * arc;
    if (clipped) sum += edge_term(r_at(phi1), r_at(phi0), N);
    return std::fabs(sum);
}

}  // namespace

// ---------------------------------------------------------------------------
// Public BSDF pieces
// ---------------------------------------------------------------------------
double schlick_fresnel(double u) {
    const double m = std::min(std::max(1.0 - u, 0.0), 1.0);
    const double m2 = m * m;
    return m2 * m2 * m;
}

double fresnel_dielectric_cos(double cosi, double eta) {
    const double c = std::fabs(cosi);
    double g = eta * eta - 1.0 + c * c;
    if (g > 0.0) {
        g = std::sqrt(g);
        const double A = (g - c) / (g + c);
        const double B = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
        return 0.5 * A * A * (1.0 + B * B);
    }
    return 1.0;  // total internal reflection
}

double specular_ior(const deferred::Material& m) {
    return 2.0 / (1.0 - safe_sqrt(0.08 * double(m.specular))) - 1.0;
}

dvec3 specular_cspec0(const deferred::Material& mat) {
    const dvec3 base = to_dvec3(mat.base_color);
    const double metallic = mat.metallic;
    // "luminance approx." of svm/closure.h, used for the specular tint only.
    const double lum = 0.3 * base.x + 0.6 * base.y + 0.1 * base.z;
    const dvec3 ctint = lum > 0.0 ? base / lum : dvec3(1.0);
    const dvec3 tmp_col = dvec3(1.0 - mat.specular_tint) + ctint * double(mat.specular_tint);
    // bsdf_microfacet_ggx_fresnel_setup: cspec0 = saturate(cspec0).
    return saturate((double(mat.specular) * 0.08 * tmp_col) * (1.0 - metallic) + base * metallic);
}

double ggx_D(double cos_h, double alpha) {
    const double alpha2 = alpha * alpha;
    const double c2 = cos_h * cos_h;
    const double c4 = c2 * c2;
    const double tan2 = (1.0 - c2) / c2;
    return alpha2 / (kPi * c4 * (alpha2 + tan2) * (alpha2 + tan2));
}

double gtr1_D(double cos_h, double alpha) {
    if (alpha >= 1.0) return 1.0 / kPi;
    const double alpha2 = alpha * alpha;
    const double t = 1.0 + (alpha2 - 1.0) * cos_h * cos_h;
    return (alpha2 - 1.0) / (kPi * std::log(alpha2) * t);
}

double smith_G1(double cos_theta, double alpha2) {
    const double c2 = cos_theta * cos_theta;
    return 2.0 / (1.0 + safe_sqrt(1.0 + alpha2 * (1.0 - c2) / c2));
}

Lobes eval_principled(const deferred::Material& m, dvec3 N, dvec3 V, dvec3 L) {
    return eval_prepared(prepare(m), glm::normalize(N), glm::normalize(V), glm::normalize(L));
}

dvec3 diffuse_color(const deferred::Material& m) {
    const Prepared p = prepare(m);
    dvec3 c(0.0);
    if (p.has_diffuse) c += p.diffuse_weight;
    if (p.has_sheen) c += p.sheen_weight;
    return c;
}

dvec3 glossy_color(const deferred::Material& m) {
    const Prepared p = prepare(m);
    dvec3 c(0.0);
    // Principled: specular_weight = 1 - T(1-m) = 1; a Glossy BSDF: its colour.
    if (p.has_specular) c += p.glossy_model != 0 ? p.spec_cspec0 : dvec3(1.0);
    if (p.has_clearcoat) c += dvec3(1.0);
    return c;
}

// ---------------------------------------------------------------------------
// Lights
// ---------------------------------------------------------------------------
LightFrame light_frame(const deferred::Light& light) {
    LightFrame f;
    f.position = column(light.matrix, 3);
    f.direction = safe_normalize(-column(light.matrix, 2));
    if (light.type == deferred::LightType::Area) {
        const bool rect_y = light.shape == deferred::AreaShape::Rectangle ||
                            light.shape == deferred::AreaShape::Ellipse;
        const double size_v = rect_y ? light.size_y : light.size;
        f.half_u = 0.5 * double(light.size) * column(light.matrix, 0);
        f.half_v = 0.5 * size_v * column(light.matrix, 1);
        f.round = light.shape == deferred::AreaShape::Disk || light.shape == deferred::AreaShape::Ellipse;
        // scene/light.cpp: area = len(extentu) * len(extentv) (* pi/4 if round).
        f.area = 4.0 * glm::length(f.half_u) * glm::length(f.half_v);
        if (f.round) f.area *= kPi / 4.0;
    }
    return f;
}

double spot_attenuation(const deferred::Light& light, dvec3 dir_light_to_point) {
    if (light.type != deferred::LightType::Spot) return 1.0;
    // scene/light.cpp: spot_angle = cos(spot_size/2), spot_smooth = (1-spot_angle)*blend.
    const dvec3 dir = safe_normalize(-column(light.matrix, 2));
    const double spot_angle = std::cos(0.5 * double(light.spot_size));
    const double spot_smooth = (1.0 - spot_angle) * double(light.spot_blend);
    // light/common.h spot_light_attenuation.
    double attenuation = glm::dot(dir, dir_light_to_point);
    if (attenuation <= spot_angle) return 0.0;
    const double t = attenuation - spot_angle;
    if (t < spot_smooth && spot_smooth != 0.0) {
        const double x = t / spot_smooth;
        attenuation *= x * x * (3.0 - 2.0 * x);  // smoothstepf
    }
    return attenuation;
}

void for_each_light_sample(const deferred::Light& light, dvec3 P, int resolution,
                           const std::function<void(const dvec3& omega, double weight)>& fn) {
    const LightFrame f = light_frame(light);
    const double energy = light.energy;
    resolution = std::max(resolution, 4);

    if (light.type == deferred::LightType::Sun) {
        // Delta direction: the sun's angular size is ignored.
        fn(-f.direction, energy);
        return;
    }

    if (light.type == deferred::LightType::Point || light.type == deferred::LightType::Spot) {
        const dvec3 to_light = f.position - P;
        const double d = glm::length(to_light);
        if (!(d > 0.0)) return;
        const double R = light.radius;
        if (!(R > 0.0)) {
            // light.h: invarea = 1, eval_fac = 1/(4 pi) * spot att, pdf = t^2 / cos(=1).
            const dvec3 omega = to_light / d;
            const double w = energy / (4.0 * kPi * d * d) * spot_attenuation(light, -omega);
            if (w != 0.0) fn(omega, w);
            return;
        }
        // Disk of radius R centred on the light, normal lightN = normalize(P - centre);
        // radiance eval_fac = 1/(4 pi) * 1/(pi R^2); pdf per area -> cos_light / t^2.
        const dvec3 lightN = (P - f.position) / d;
        dvec3 u, v;
        make_orthonormals(lightN, u, v);
        const double Le = energy / (4.0 * kPi * kPi * R * R);
        const std::vector<Node> rn = composite_gauss_legendre(resolution);
        const int nphi = resolution;
        const double wphi = 2.0 * kPi / nphi;
        for (int k = 0; k < nphi; ++k) {
            const double phi = (k + 0.5) * wphi;
            const dvec3 dir = u * std::cos(phi) + v * std::sin(phi);
            for (const Node& r : rn) {
                const dvec3 X = f.position + (R * r.x) * dir;
                const dvec3 D = X - P;
                const double t2 = glm::dot(D, D);
                const double t = std::sqrt(t2);
                const dvec3 omega = D / t;
                const double cos_light = glm::dot(lightN, -omega);
                if (!(cos_light > 0.0)) continue;
                // Spot attenuation per sample, for the direction sample -> P (-ls->D).
                const double att = spot_attenuation(light, -omega);
                if (att == 0.0) continue;
                const double dA = R * R * r.x * r.w * wphi;
                fn(omega, Le * att * cos_light / t2 * dA);
            }
        }
        return;
    }

    // Area light: one-sided, emits along `direction`; light.h rejects shading
    // points behind the light's plane (dot(centre - P, Ng) > 0).
    const dvec3 Ng = f.direction;
    if (glm::dot(f.position - P, Ng) > 0.0 || !(f.area > 0.0)) return;
    const double Le = energy / (4.0 * f.area);  // eval_fac = 0.25 * invarea
    const double jac = glm::length(glm::cross(f.half_u, f.half_v));
    const std::vector<Node> gl = composite_gauss_legendre(resolution);
    auto emit = [&](const dvec3& X, double dA) {
        const dvec3 D = X - P;
        const double t2 = glm::dot(D, D);
        if (!(t2 > 0.0)) return;
        const dvec3 omega = D / std::sqrt(t2);
        const double cos_light = glm::dot(Ng, -omega);
        if (!(cos_light > 0.0)) return;
        fn(omega, Le * cos_light / t2 * dA);
    };
    if (!f.round) {
        // Parallelogram c + s a + t b, s,t in [-1,1]: dA = 4 |a x b| dx dy.
        for (const Node& x : gl)
            for (const Node& y : gl)
                emit(f.position + (2.0 * x.x - 1.0) * f.half_u + (2.0 * y.x - 1.0) * f.half_v,
                     4.0 * jac * x.w * y.w);
    } else {
        // Polar grid on the unit disk mapped by x*a + y*b: dA = |a x b| r dr dphi.
        const int nphi = resolution;
        const double wphi = 2.0 * kPi / nphi;
        for (int k = 0; k < nphi; ++k) {
            const double phi = (k + 0.5) * wphi;
            const double cp = std::cos(phi), sp = std::sin(phi);
            for (const Node& r : gl)
                emit(f.position + r.x * (cp * f.half_u + sp * f.half_v), jac * r.x * r.w * wphi);
        }
    }
}

Shade shade(const deferred::Light& light, const deferred::Material& m, dvec3 P, dvec3 N, dvec3 V,
            int resolution) {
    const Prepared p = prepare(m);
    N = glm::normalize(N);
    V = glm::normalize(V);
    Shade s;
    for_each_light_sample(light, P, resolution, [&](const dvec3& omega, double w) {
        const Lobes l = eval_prepared(p, N, V, omega);
        s.diffuse += w * (l.diffuse + l.sheen);
        s.glossy += w * (l.specular + l.clearcoat);
    });
    const dvec3 color = to_dvec3(light.color);
    s.diffuse *= color;
    s.glossy *= color;
    return s;
}

double irradiance_numeric(const deferred::Light& light, dvec3 P, dvec3 N, int resolution) {
    N = glm::normalize(N);
    double e = 0.0;
    for_each_light_sample(light, P, resolution,
                          [&](const dvec3& omega, double w) { e += w * std::max(glm::dot(N, omega), 0.0); });
    return e;
}

double irradiance(const deferred::Light& light, dvec3 P, dvec3 N) {
    N = glm::normalize(N);
    const LightFrame f = light_frame(light);
    const double energy = light.energy;

    if (light.type == deferred::LightType::Sun) return energy * std::max(glm::dot(N, -f.direction), 0.0);

    if (light.type == deferred::LightType::Point || light.type == deferred::LightType::Spot) {
        const dvec3 to_light = f.position - P;
        const double d = glm::length(to_light);
        if (!(d > 0.0)) return 0.0;
        const double R = light.radius;
        if (!(R > 0.0)) {
            const dvec3 omega = to_light / d;
            return energy / (4.0 * kPi * d * d) * spot_attenuation(light, -omega) *
                   std::max(glm::dot(N, omega), 0.0);
        }
        if (light.type == deferred::LightType::Spot) return irradiance_numeric(light, P, N, 1024);
        // Point light with radius: uniform Lambertian disk facing P.
        const dvec3 lightN = (P - f.position) / d;
        dvec3 u, v;
        make_orthonormals(lightN, u, v);
        const double Le = energy / (4.0 * kPi * kPi * R * R);
        return Le * ellipse_projected_solid_angle(to_light, R * u, R * v, N);
    }

    // Area light.
    if (glm::dot(f.position - P, f.direction) > 0.0 || !(f.area > 0.0)) return 0.0;
    const double Le = energy / (4.0 * f.area);
    const dvec3 c = f.position - P;
    if (!f.round) {
        const std::vector<dvec3> poly = {c - f.half_u - f.half_v, c + f.half_u - f.half_v,
                                         c + f.half_u + f.half_v, c - f.half_u + f.half_v};
        return Le * polygon_projected_solid_angle(poly, N);
    }
    return Le * ellipse_projected_solid_angle(c, f.half_u, f.half_v, N);
}

Lobes hemisphere_albedo(const deferred::Material& m, dvec3 N, dvec3 V, int n) {
    N = glm::normalize(N);
    const dvec3 up = std::abs(N.z) < 0.999 ? dvec3(0, 0, 1) : dvec3(1, 0, 0);
    const dvec3 T = glm::normalize(glm::cross(up, N)), B = glm::cross(N, T);
    Lobes sum;
    // d omega = d(cos theta) d phi: cells of equal solid angle.
    const double cell = (1.0 / n) * (2.0 * M_PI / (4 * n));
    for (int i = 0; i < n; ++i) {
        const double c = (i + 0.5) / n, s = std::sqrt(std::max(0.0, 1.0 - c * c));
        for (int j = 0; j < 4 * n; ++j) {
            const double phi = 2.0 * M_PI * (j + 0.5) / (4 * n);
            const dvec3 L = T * (s * std::cos(phi)) + B * (s * std::sin(phi)) + N * c;
            const Lobes e = eval_principled(m, N, V, L);
            sum.diffuse += e.diffuse * cell;
            sum.sheen += e.sheen * cell;
            sum.specular += e.specular * cell;
            sum.clearcoat += e.clearcoat * cell;
        }
    }
    return sum;
}

}  // namespace oracle
