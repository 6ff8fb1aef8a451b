// Tests of the CPU Cycles 3.4 oracle (tests/oracle/cycles_oracle.*) against
// closed forms and independent brute-force integrals. Every EXPECT states its
// tolerance; "rel" means |a - b| <= tol * |b|.
#include "cycles_oracle.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

using glm::dvec3;
constexpr double kPi = 3.14159265358979323846;

// ----------------------------------------------------------------------------
// Helpers (independent of the oracle's internals)
// ----------------------------------------------------------------------------

::testing::AssertionResult RelNear(double a, double b, double tol) {
    const double err = std::fabs(a - b);
    if (err <= tol * std::fabs(b)) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "a=" << a << " b=" << b << " rel.err=" << err / std::fabs(b)
                                         << " > " << tol;
}

::testing::AssertionResult RelNear3(dvec3 a, dvec3 b, double tol) {
    for (int i = 0; i < 3; ++i) {
        const double err = std::fabs(a[i] - b[i]);
        if (err > tol * std::fabs(b[i]))
            return ::testing::AssertionFailure() << "component " << i << ": a=" << a[i] << " b=" << b[i]
                                                 << " rel.err=" << err / std::fabs(b[i]) << " > " << tol;
    }
    return ::testing::AssertionSuccess();
}

dvec3 dir_from_angles(double theta_deg, double phi_deg) {
    const double t = theta_deg * kPi / 180.0, p = phi_deg * kPi / 180.0;
    return dvec3(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
}

// World matrix of an object at `pos` whose -Z axis points along `dir`, with
// object scale `scale` (applied to the X/Y/Z columns). Column-major m[col*4+row].
deferred::Mat4d frame_matrix(dvec3 pos, dvec3 dir, dvec3 scale = dvec3(1.0)) {
    const dvec3 z = -glm::normalize(dir);
    const dvec3 helper = std::fabs(z.x) < 0.9 ? dvec3(1, 0, 0) : dvec3(0, 1, 0);
    const dvec3 x = glm::normalize(glm::cross(helper, z));
    const dvec3 y = glm::cross(z, x);
    const dvec3 cols[4] = {x * scale.x, y * scale.y, z * scale.z, pos};
    deferred::Mat4d m{};
    for (int c = 0; c < 4; ++c) {
        m[c * 4 + 0] = cols[c].x;
        m[c * 4 + 1] = cols[c].y;
        m[c * 4 + 2] = cols[c].z;
        m[c * 4 + 3] = c == 3 ? 1.0 : 0.0;
    }
    return m;
}

// Aggregate initialisation that sets the matrix explicitly, so the default
// member initialiser (deferred::identity_matrix(), defined in the renderer
// library) is never needed by this standalone test.
deferred::Light make_light(deferred::LightType type, const deferred::Mat4d& m, float energy = 100.0f) {
    deferred::Light l{type, m};
    l.energy = energy;
    return l;
}

deferred::Light point_light(dvec3 pos, float radius, float energy = 100.0f) {
    deferred::Light l = make_light(deferred::LightType::Point, frame_matrix(pos, dvec3(0, 0, -1)), energy);
    l.radius = radius;
    return l;
}

deferred::Light area_light(deferred::AreaShape shape, dvec3 pos, dvec3 dir, float size, float size_y,
                           dvec3 scale = dvec3(1.0), float energy = 100.0f) {
    deferred::Light l = make_light(deferred::LightType::Area, frame_matrix(pos, dir, scale), energy);
    l.shape = shape;
    l.size = size;
    l.size_y = size_y;
    return l;
}

// Independent brute-force irradiance of an area light: midpoint rule over
// the emitter (n x n cells; for round shapes a polar midpoint grid), radiance
// L = energy / (4 A), one-sided towards -Z of the matrix.
double brute_force_area_irradiance(const deferred::Light& l, dvec3 P, dvec3 N, int n) {
    const auto& m = l.matrix;
    const dvec3 c0(m[0], m[1], m[2]), c1(m[4], m[5], m[6]), c2(m[8], m[9], m[10]), pos(m[12], m[13], m[14]);
    const bool round = l.shape == deferred::AreaShape::Disk || l.shape == deferred::AreaShape::Ellipse;
    const bool has_y = l.shape == deferred::AreaShape::Rectangle || l.shape == deferred::AreaShape::Ellipse;
    const dvec3 a = 0.5 * double(l.size) * c0;
    const dvec3 b = 0.5 * double(has_y ? l.size_y : l.size) * c1;
    const dvec3 Ng = -glm::normalize(c2);
    const double A = (round ? kPi : 4.0) * glm::length(a) * glm::length(b);
    const double L = l.energy / (4.0 * A);
    N = glm::normalize(N);
    if (glm::dot(pos - P, Ng) > 0.0) return 0.0;
    double e = 0.0;
    auto add = [&](dvec3 X, double dA) {
        const dvec3 D = X - P;
        const double t2 = glm::dot(D, D);
        const dvec3 w = D / std::sqrt(t2);
        e += L * std::max(glm::dot(N, w), 0.0) * std::max(-glm::dot(Ng, w), 0.0) / t2 * dA;
    };
    if (!round) {
        const double cell = 4.0 * glm::length(a) * glm::length(b) / (double(n) * n);
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) add(pos + (2.0 * (i + 0.5) / n - 1.0) * a + (2.0 * (j + 0.5) / n - 1.0) * b, cell);
    } else {
        for (int i = 0; i < n; ++i) {
            const double r = (i + 0.5) / n;
            for (int k = 0; k < n; ++k) {
                const double p = 2.0 * kPi * (k + 0.5) / n;
                add(pos + r * std::cos(p) * a + r * std::sin(p) * b,
                    glm::length(a) * glm::length(b) * r * (1.0 / n) * (2.0 * kPi / n));
            }
        }
    }
    return e;
}

// Hemisphere integral of g(L) over L.N > 0 around N = +Z: theta in [0, pi/2]
// by composite Gauss-Legendre, phi by the midpoint rule.
template <class F>
double hemisphere_integral(const F& g, int ntheta, int nphi) {
    static const double xi[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
    static const double wi[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
    const double h = 0.5 * kPi / ntheta;
    double sum = 0.0;
    for (int p = 0; p < ntheta; ++p)
        for (int i = 0; i < 4; ++i) {
            const double th = (p + 0.5 + 0.5 * xi[i]) * h;
            const double wt = 0.5 * h * wi[i] * std::sin(th);
            for (int k = 0; k < nphi; ++k) {
                const double ph = 2.0 * kPi * (k + 0.5) / nphi;
                sum += wt * (2.0 * kPi / nphi) *
                       g(dvec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
            }
        }
    return sum;
}

deferred::Material material(dvec3 base, float metallic, float roughness, float specular = 0.5f) {
    deferred::Material m;
    m.base_color = {float(base.x), float(base.y), float(base.z)};
    m.metallic = metallic;
    m.roughness = roughness;
    m.specular = specular;
    return m;
}

// ----------------------------------------------------------------------------
// Principled BSDF
// ----------------------------------------------------------------------------

// fresnel_dielectric_cos: F(1, eta) = ((eta-1)/(eta+1))^2, and the Principled
// ior 2/(1-sqrt(0.08 s))-1 gives F0 = 0.08 s exactly. Tolerance 1e-14 abs.
TEST(OracleBsdf, FresnelDielectric) {
    for (double eta : {1.0, 1.33, 1.5, 2.4}) {
        const double f0 = (eta - 1) / (eta + 1);
        EXPECT_NEAR(oracle::fresnel_dielectric_cos(1.0, eta), f0 * f0, 1e-14);
        EXPECT_NEAR(oracle::fresnel_dielectric_cos(-1.0, eta), f0 * f0, 1e-14);  // |cos|
    }
    EXPECT_NEAR(oracle::fresnel_dielectric_cos(0.0, 1.5), 1.0, 1e-14);       // grazing
    EXPECT_NEAR(oracle::fresnel_dielectric_cos(0.1, 1.0 / 1.5), 1.0, 1e-14);  // total internal reflection
    for (float s : {0.0f, 0.25f, 0.5f, 1.0f}) {
        deferred::Material m;
        m.specular = s;
        EXPECT_NEAR(oracle::fresnel_dielectric_cos(1.0, oracle::specular_ior(m)), 0.08 * double(s), 1e-14);
    }
}

// At V = L = N: H = N, FH = 0 so F = cspec0, G = 1, D = 1/(pi alpha^2):
// specular = cspec0 / (4 pi alpha^2). Tolerance 1e-12 rel.
TEST(OracleBsdf, NormalIncidenceSpecularIsCspec0) {
    const dvec3 N(0, 0, 1);
    const dvec3 base(0.9, 0.6, 0.3);
    struct Case {
        float metallic, specular, tint;
        dvec3 expected_cspec0;
    };
    const double lum = 0.3 * base.x + 0.6 * base.y + 0.1 * base.z;  // svm/closure.h "luminance approx."
    const Case cases[] = {
        {0.0f, 0.5f, 0.0f, dvec3(0.04)},
        {0.0f, 1.0f, 0.0f, dvec3(0.08)},
        {1.0f, 0.5f, 0.0f, base},
        {0.0f, 0.5f, 1.0f, 0.04 * base / lum},
        {0.5f, 0.5f, 0.5f, 0.04 * (dvec3(0.5) + 0.5 * base / lum) * 0.5 + base * 0.5},
    };
    for (const Case& c : cases) {
        deferred::Material m = material(base, c.metallic, 0.4f, c.specular);
        m.specular_tint = c.tint;
        EXPECT_TRUE(RelNear3(oracle::specular_cspec0(m), c.expected_cspec0, 1e-6));  // float inputs
        const double alpha = double(m.roughness) * double(m.roughness);
        const oracle::Lobes l = oracle::eval_principled(m, N, N, N);
        EXPECT_TRUE(RelNear3(l.specular, oracle::specular_cspec0(m) / (4.0 * kPi * alpha * alpha), 1e-12));
    }
}

// Cycles returns 0 from light sampling when alpha_x*alpha_y <= 1e-7.
TEST(OracleBsdf, TinyAlphaGivesNoHighlight) {
    const dvec3 N(0, 0, 1), V = dir_from_angles(30, 0), L = dir_from_angles(30, 180);  // mirror pair
    deferred::Material m = material(dvec3(0.8), 0.0f, 0.01f);  // alpha^2 = 1e-8
    EXPECT_EQ(oracle::eval_principled(m, N, V, L).specular, dvec3(0.0));
    m.roughness = 0.02f;  // alpha^2 = 1.6e-7
    EXPECT_GT(oracle::eval_principled(m, N, V, L).specular.x, 0.0);
    m.clearcoat = 1.0f;
    m.clearcoat_roughness = 0.01f;
    EXPECT_EQ(oracle::eval_principled(m, N, V, L).clearcoat, dvec3(0.0));
    m.clearcoat_roughness = 0.03f;  // the default: alpha^2 = 8.1e-7
    EXPECT_GT(oracle::eval_principled(m, N, V, L).clearcoat.x, 0.0);
}

// Helmholtz reciprocity of every lobe: lobe(V,L)/cos_l == lobe(L,V)/cos_v.
// Tolerance 1e-12 rel.
TEST(OracleBsdf, Reciprocity) {
    deferred::Material m = material(dvec3(0.7, 0.4, 0.2), 0.3f, 0.45f, 0.7f);
    m.specular_tint = 0.4f;
    m.sheen = 0.8f;
    m.clearcoat = 0.6f;
    m.clearcoat_roughness = 0.2f;
    const dvec3 N = glm::normalize(dvec3(0.1, -0.2, 1.0));
    const double angles[][4] = {{10, 0, 40, 170}, {60, 30, 20, 250}, {75, 90, 80, 260}, {5, 0, 85, 10}};
    for (const auto& a : angles) {
        // Directions around N: rotate the +Z-based directions to N's frame crudely by adding N.
        const dvec3 V = glm::normalize(dir_from_angles(a[0], a[1]) + 0.1 * N);
        const dvec3 L = glm::normalize(dir_from_angles(a[2], a[3]) + 0.1 * N);
        const double cv = glm::dot(N, V), cl = glm::dot(N, L);
        ASSERT_GT(cv, 0.0);
        ASSERT_GT(cl, 0.0);
        const oracle::Lobes f = oracle::eval_principled(m, N, V, L);
        const oracle::Lobes r = oracle::eval_principled(m, N, L, V);
        EXPECT_TRUE(RelNear3(f.diffuse / cl, r.diffuse / cv, 1e-12));
        EXPECT_TRUE(RelNear3(f.sheen / cl, r.sheen / cv, 1e-12));
        EXPECT_TRUE(RelNear3(f.specular / cl, r.specular / cv, 1e-12));
        EXPECT_TRUE(RelNear3(f.clearcoat / cl, r.clearcoat / cv, 1e-12));
    }
}

// Burley diffuse with retro-reflection, written out by hand. Tolerance 1e-13 rel.
TEST(OracleBsdf, DiffuseFormula) {
    const dvec3 N(0, 0, 1), V = dir_from_angles(50, 0), L = dir_from_angles(35, 120);
    const dvec3 base(0.8, 0.5, 0.2);
    const deferred::Material m = material(base, 0.25f, 0.6f);
    const double cl = L.z, cv = V.z;
    const double FL = std::pow(1 - cl, 5), FV = std::pow(1 - cv, 5);
    const double RR = double(m.roughness) * (1 + glm::dot(L, V));
    const double f = (1 - 0.5 * FL) * (1 - 0.5 * FV) + RR * (FL + FV + FL * FV * (RR - 1));
    const dvec3 expected =
        dvec3(m.base_color[0], m.base_color[1], m.base_color[2]) * (1.0 - double(m.metallic)) / kPi * cl * f;
    EXPECT_TRUE(RelNear3(oracle::eval_principled(m, N, V, L).diffuse, expected, 1e-13));
    // Below the horizon: 0 (N.L <= 0).
    EXPECT_EQ(oracle::eval_principled(m, N, V, dir_from_angles(95, 0)).diffuse, dvec3(0.0));
}

// Directional albedo at V = N (then RR = roughness (1 + cos_l), FV = 0):
// roughness 0: 1 - 1/42; roughness 1: 1 - 1/42 + 5/84 = 87/84 (Burley is not
// energy conserving). White base, metallic 0, specular 0 (no specular closure).
// The integrand is a polynomial in cos_l: tolerance 1e-12 rel.
TEST(OracleBsdf, DiffuseDirectionalAlbedo) {
    const dvec3 N(0, 0, 1);
    for (float rough : {0.0f, 1.0f}) {
        const deferred::Material m = material(dvec3(1.0), 0.0f, rough, 0.0f);
        const double albedo = hemisphere_integral(
            [&](dvec3 L) { return oracle::eval_principled(m, N, N, L).diffuse.x; }, 64, 8);
        EXPECT_TRUE(RelNear(albedo, rough == 0.0f ? 41.0 / 42.0 : 87.0 / 84.0, 1e-12)) << "roughness " << rough;
    }
}

// Microfacet distributions are normalised: integral D(cos h) cos h d omega_h = 1.
// Integrated in u = ln(tan theta_h) (smooth for every alpha). Tolerance 1e-9.
TEST(OracleBsdf, DistributionsAreNormalised) {
    auto integrate = [](auto D) {
        static const double xi[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
        static const double wi[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
        const double lo = -40.0, hi = 12.0;
        const int panels = 4000;
        const double h = (hi - lo) / panels;
        double s = 0.0;
        for (int p = 0; p < panels; ++p)
            for (int i = 0; i < 4; ++i) {
                const double u = lo + (p + 0.5 + 0.5 * xi[i]) * h;
                const double th = std::atan(std::exp(u));
                const double dth = std::exp(u) / (1.0 + std::exp(2.0 * u));
                s += 0.5 * h * wi[i] * D(std::cos(th)) * std::cos(th) * 2.0 * kPi * std::sin(th) * dth;
            }
        return s;
    };
    for (double alpha : {0.01, 0.1, 0.5, 1.0})
        EXPECT_NEAR(integrate([&](double c) { return oracle::ggx_D(c, alpha); }), 1.0, 1e-9) << "GGX " << alpha;
    for (double alpha : {0.0009, 0.1, 0.5, 0.99, 1.0})
        EXPECT_NEAR(integrate([&](double c) { return oracle::gtr1_D(c, alpha); }), 1.0, 1e-9) << "GTR1 " << alpha;
}

// Sheen: sheen*(1-m)*mix(1, base/Y709, tint) * (1-L.H)^5 * cos_l. Cycles 3.4
// normalises the sheen tint with linear_rgb_to_gray (Rec.709 Y from the OCIO
// config), unlike the specular tint. Tolerance 1e-6 rel (float inputs).
TEST(OracleBsdf, SheenFormula) {
    const dvec3 N(0, 0, 1), V = dir_from_angles(70, 0), L = dir_from_angles(60, 150);
    const dvec3 base(0.8, 0.3, 0.1);
    deferred::Material m = material(base, 0.2f, 0.5f);
    m.sheen = 0.7f;
    m.sheen_tint = 0.5f;
    const double lum = 0.2126729 * base.x + 0.7151522 * base.y + 0.0721750 * base.z;
    const dvec3 weight = 0.7 * (1.0 - 0.2) * (dvec3(0.5) + 0.5 * base / lum);
    const dvec3 H = glm::normalize(L + V);
    const dvec3 expected = weight * std::pow(1.0 - glm::dot(L, H), 5) * L.z;
    EXPECT_TRUE(RelNear3(oracle::eval_principled(m, N, V, L).sheen, expected, 1e-6));
    EXPECT_TRUE(RelNear3(oracle::diffuse_color(m), base * 0.8 + weight, 1e-6));
}

// Clearcoat: Fdielectric(L.H, 1.5)*0.25*cc * D_GTR1(alpha=ccr^2) * G(alpha^2=0.0625)/(4 cos_v).
// Tolerance 1e-6 rel (float inputs).
TEST(OracleBsdf, ClearcoatFormula) {
    const dvec3 N(0, 0, 1), V = dir_from_angles(40, 0), L = dir_from_angles(45, 170);
    deferred::Material m = material(dvec3(0.5), 0.0f, 0.5f);
    m.clearcoat = 0.8f;
    m.clearcoat_roughness = 0.3f;
    const dvec3 H = glm::normalize(L + V);
    const double a = 0.09, a2 = a * a, ch = H.z;
    const double D = (a2 - 1) / (kPi * std::log(a2) * (1 + (a2 - 1) * ch * ch));
    auto G1 = [](double c) { return 2.0 / (1.0 + std::sqrt(1.0 + 0.0625 * (1 - c * c) / (c * c))); };
    const double expected =
        oracle::fresnel_dielectric_cos(glm::dot(L, H), 1.5) * 0.25 * 0.8 * D * G1(V.z) * G1(L.z) / (4.0 * V.z);
    EXPECT_TRUE(RelNear3(oracle::eval_principled(m, N, V, L).clearcoat, dvec3(expected), 1e-6));
}

// Full GGX specular at an off-specular configuration, written out by hand.
// Tolerance 1e-12 rel (computed from the float-rounded inputs).
TEST(OracleBsdf, SpecularFormula) {
    const dvec3 N(0, 0, 1), V = dir_from_angles(55, 0), L = dir_from_angles(40, 160);
    const dvec3 base(0.9, 0.7, 0.2);
    deferred::Material m = material(base, 0.4f, 0.35f, 0.6f);
    m.specular_tint = 0.3f;
    const dvec3 basef(m.base_color[0], m.base_color[1], m.base_color[2]);
    const double rough = m.roughness, spec = m.specular, tint = m.specular_tint, met = m.metallic;
    const double lum = 0.3 * basef.x + 0.6 * basef.y + 0.1 * basef.z;
    const dvec3 cspec0 = spec * 0.08 * (dvec3(1 - tint) + tint * basef / lum) * (1 - met) + basef * met;
    const double eta = 2.0 / (1.0 - std::sqrt(0.08 * spec)) - 1.0;
    const double F0 = 0.08 * spec;
    const dvec3 H = glm::normalize(L + V);
    const double FH = (oracle::fresnel_dielectric_cos(glm::dot(L, H), eta) - F0) / (1 - F0);
    const dvec3 F = cspec0 * (1 - FH) + dvec3(FH);
    const double alpha = rough * rough, a2 = alpha * alpha;
    const double ch = H.z, tan2 = (1 - ch * ch) / (ch * ch);
    const double D = a2 / (kPi * std::pow(ch, 4) * (a2 + tan2) * (a2 + tan2));
    auto G1 = [&](double c) { return 2.0 / (1.0 + std::sqrt(1.0 + a2 * (1 - c * c) / (c * c))); };
    const dvec3 expected = F * D * G1(V.z) * G1(L.z) / (4.0 * V.z);
    EXPECT_TRUE(RelNear3(oracle::eval_principled(m, N, V, L).specular, expected, 1e-12));
}

TEST(OracleBsdf, HorizonAndClosureColours) {
    const dvec3 N(0, 0, 1);
    deferred::Material m = material(dvec3(0.8, 0.6, 0.4), 0.0f, 0.5f);
    m.sheen = 0.5f;
    m.clearcoat = 0.5f;
    // Light below the horizon: every lobe 0.
    const oracle::Lobes below = oracle::eval_principled(m, N, dir_from_angles(30, 0), dir_from_angles(100, 180));
    EXPECT_EQ(below.diffuse + below.sheen + below.specular + below.clearcoat, dvec3(0.0));
    // Viewer below the horizon: Cycles' diffuse does not test N.V (FV = 1), the others do.
    const oracle::Lobes vb = oracle::eval_principled(m, N, dir_from_angles(100, 0), dir_from_angles(30, 180));
    EXPECT_GT(vb.diffuse.x, 0.0);
    EXPECT_EQ(vb.sheen + vb.specular + vb.clearcoat, dvec3(0.0));

    // Closure colours (exact up to float inputs: 1e-6 rel).
    const deferred::Material plain = material(dvec3(0.8, 0.6, 0.4), 0.0f, 0.5f);
    EXPECT_TRUE(RelNear3(oracle::diffuse_color(plain), dvec3(0.8, 0.6, 0.4), 1e-6));
    EXPECT_EQ(oracle::glossy_color(plain), dvec3(1.0));
    EXPECT_EQ(oracle::glossy_color(m), dvec3(2.0));  // + clearcoat
    const deferred::Material metal = material(dvec3(0.8, 0.6, 0.4), 1.0f, 0.5f);
    EXPECT_EQ(oracle::diffuse_color(metal), dvec3(0.0));
    EXPECT_EQ(oracle::glossy_color(metal), dvec3(1.0));
    // specular = metallic = 0: Cycles allocates no specular closure.
    const deferred::Material nospec = material(dvec3(0.8), 0.0f, 0.5f, 0.0f);
    EXPECT_EQ(oracle::glossy_color(nospec), dvec3(0.0));
    EXPECT_EQ(oracle::eval_principled(nospec, N, N, N).specular, dvec3(0.0));
}

// ----------------------------------------------------------------------------
// Lights: closed forms
// ----------------------------------------------------------------------------

// Point light radius 0: E = S cos(theta) / (4 pi d^2); shade = S/(4 pi d^2) * lobes.
// Tolerance 1e-12 rel.
TEST(OracleLights, PointLightDelta) {
    const dvec3 P(0.3, -0.2, 0.1);
    const double d = 2.5;
    for (double th : {0.0, 30.0, 60.0, 85.0}) {
        const dvec3 w = dir_from_angles(th, 40);
        const deferred::Light l = point_light(P + d * w, 0.0f, 100.0f);
        const double expected = 100.0 * std::cos(th * kPi / 180) / (4 * kPi * d * d);
        EXPECT_TRUE(RelNear(oracle::irradiance(l, P, dvec3(0, 0, 1)), expected, 1e-12)) << th;
        EXPECT_TRUE(RelNear(oracle::irradiance_numeric(l, P, dvec3(0, 0, 1)), expected, 1e-12)) << th;
        const deferred::Material m = material(dvec3(0.7, 0.5, 0.3), 0.2f, 0.4f);
        const dvec3 V = dir_from_angles(20, 200);
        const oracle::Lobes lob = oracle::eval_principled(m, dvec3(0, 0, 1), V, w);
        const oracle::Shade s = oracle::shade(l, m, P, dvec3(0, 0, 1), V);
        const double k = 100.0 / (4 * kPi * d * d);
        EXPECT_TRUE(RelNear3(s.diffuse, k * (lob.diffuse + lob.sheen), 1e-12));
        EXPECT_TRUE(RelNear3(s.glossy, k * (lob.specular + lob.clearcoat), 1e-12));
    }
    EXPECT_EQ(oracle::irradiance(point_light(P + dir_from_angles(100, 0), 0.0f), P, dvec3(0, 0, 1)), 0.0);
}

// Sun: E = S cos(theta). Tolerance 1e-12 rel.
TEST(OracleLights, Sun) {
    for (double th : {0.0, 45.0, 80.0}) {
        const dvec3 to_sun = dir_from_angles(th, 10);
        const deferred::Light l = make_light(deferred::LightType::Sun, frame_matrix(dvec3(5, 5, 5), -to_sun), 3.0f);
        EXPECT_TRUE(RelNear(oracle::irradiance(l, dvec3(0.0), dvec3(0, 0, 1)), 3.0 * std::cos(th * kPi / 180), 1e-12));
    }
    const deferred::Light below = make_light(deferred::LightType::Sun, frame_matrix(dvec3(0.0), dvec3(0, 0, 1)), 3.0f);
    EXPECT_EQ(oracle::irradiance(below, dvec3(0.0), dvec3(0, 0, 1)), 0.0);
}

// Spot, radius 0: Cycles 3.4 attenuation c * smoothstep((c-cs)/w) with the
// leading cos factor. Tolerance 1e-12 rel.
TEST(OracleLights, SpotAttenuationDelta) {
    const double size = 60.0 * kPi / 180.0, blend = 0.3;
    const dvec3 pos(0, 0, 3);
    deferred::Light l = make_light(deferred::LightType::Spot, frame_matrix(pos, dvec3(0, 0, -1)), 50.0f);
    l.radius = 0.0f;
    l.spot_size = float(size);
    l.spot_blend = float(blend);
    // Use the float-rounded parameters for the expectation.
    const double csf = std::cos(0.5 * double(l.spot_size)), wf = (1 - csf) * double(l.spot_blend);
    for (double ang : {0.0, 10.0, 25.0, 28.0, 29.9, 31.0}) {
        const dvec3 Pp(3.0 * std::tan(ang * kPi / 180), 0.0, 0.0);  // on the plane z = 0
        const dvec3 D = Pp - pos;
        const double dist = glm::length(D);
        const double c = -D.z / dist;  // dot(spot axis (0,0,-1), direction light -> P)
        double att = 0.0;
        if (c > csf) {
            const double t = c - csf;
            att = c;
            if (t < wf) {
                const double x = t / wf;
                att *= 3 * x * x - 2 * x * x * x;
            }
        }
        const double expected = 50.0 / (4 * kPi * dist * dist) * att * c;  // N = +Z, cos_theta = c
        if (expected == 0.0)
            EXPECT_EQ(oracle::irradiance(l, Pp, dvec3(0, 0, 1)), 0.0) << ang;
        else
            EXPECT_TRUE(RelNear(oracle::irradiance(l, Pp, dvec3(0, 0, 1)), expected, 1e-12)) << ang;
        EXPECT_NEAR(oracle::spot_attenuation(l, D / dist), att, 1e-14);
    }
}

// On-axis square of half side h at distance d:
// E = L * 4 (h/sqrt(h^2+d^2)) atan(h/sqrt(h^2+d^2)), L = S/(4 A), A = (2h)^2.
// Closed form: 1e-12 rel. Shade-path quadrature (512 Gauss-Legendre nodes per
// axis, smooth integrand): 1e-9 rel. Brute-force midpoint 1000^2: 1e-5 rel.
TEST(OracleLights, SquareOnAxis) {
    const double h = 0.5;
    for (double d : {0.1, 0.5, 1.0, 3.0}) {
        const deferred::Light l = area_light(deferred::AreaShape::Square, dvec3(0, 0, d), dvec3(0, 0, -1), 1.0f, 1.0f);
        const double L = 100.0 / (4.0 * 4 * h * h);
        const double s = h / std::sqrt(h * h + d * d);
        const double expected = L * 4.0 * s * std::atan(s);
        EXPECT_TRUE(RelNear(oracle::irradiance(l, dvec3(0.0), dvec3(0, 0, 1)), expected, 1e-12)) << d;
        EXPECT_TRUE(RelNear(oracle::irradiance_numeric(l, dvec3(0.0), dvec3(0, 0, 1), 512), expected, 1e-9)) << d;
        EXPECT_TRUE(RelNear(brute_force_area_irradiance(l, dvec3(0.0), dvec3(0, 0, 1), 1000), expected, 1e-5)) << d;
    }
}

// On-axis rectangle (half sides a, b; object X scale 2 and size_y):
// E = 2 L [a/sqrt(a^2+d^2) atan(b/sqrt(a^2+d^2)) + b/sqrt(b^2+d^2) atan(a/sqrt(b^2+d^2))].
// Closed form 1e-12 rel; quadrature 1e-9 rel.
TEST(OracleLights, RectangleOnAxisWithScale) {
    deferred::Light l = area_light(deferred::AreaShape::Rectangle, dvec3(1, 2, 3), dvec3(0, 0, -1), 0.5f, 0.75f,
                                   dvec3(2.0, 1.0, 1.0));
    const double a = 0.5, b = 0.375, d = 0.8;  // half extents: 0.5*0.5*2, 0.5*0.75
    const dvec3 P(1, 2, 3 - d);
    const double L = 100.0 / (4.0 * (2 * a) * (2 * b));
    const double sa = std::sqrt(a * a + d * d), sb = std::sqrt(b * b + d * d);
    const double expected = 2.0 * L * (a / sa * std::atan(b / sa) + b / sb * std::atan(a / sb));
    EXPECT_TRUE(RelNear(oracle::irradiance(l, P, dvec3(0, 0, 1)), expected, 1e-12));
    EXPECT_TRUE(RelNear(oracle::irradiance_numeric(l, P, dvec3(0, 0, 1)), expected, 1e-9));
    EXPECT_TRUE(RelNear(oracle::light_frame(l).area, 4 * a * b, 1e-12));
}

// On-axis disk of radius rho at distance d: E = L pi rho^2/(d^2+rho^2),
// L = S/(4 pi rho^2). Closed form (contour integral, adaptive GK15): 1e-12 rel;
// polar quadrature: 1e-9 rel; brute-force polar midpoint 1000^2: 1e-5 rel.
TEST(OracleLights, DiskOnAxis) {
    const double rho = 0.4;
    for (double d : {0.05, 0.5, 2.0}) {
        const deferred::Light l = area_light(deferred::AreaShape::Disk, dvec3(0, 0, d), dvec3(0, 0, -1), 0.8f, 0.3f);
        const double L = 100.0 / (4.0 * kPi * rho * rho);
        const double rhof = 0.5 * double(0.8f);
        const double expected = L * rho * rho / (rhof * rhof) * kPi * rhof * rhof / (d * d + rhof * rhof);
        EXPECT_TRUE(RelNear(oracle::irradiance(l, dvec3(0.0), dvec3(0, 0, 1)), expected, 1e-12)) << d;
        EXPECT_TRUE(RelNear(oracle::irradiance_numeric(l, dvec3(0.0), dvec3(0, 0, 1)), expected, 1e-9)) << d;
        EXPECT_TRUE(RelNear(brute_force_area_irradiance(l, dvec3(0.0), dvec3(0, 0, 1), 1000), expected, 1e-5)) << d;
    }
}

// Point light with radius R (Cycles 3.4: a disk facing P): unclipped,
// E = S cos(theta) / (4 pi (d^2 + R^2)) exactly. Closed form 1e-12 rel,
// quadrature 1e-9 rel.
TEST(OracleLights, SphereLight) {
    const double R = 0.25, d = 1.5;
    const dvec3 P(0.0);
    for (double th : {0.0, 40.0, 70.0}) {  // theta + asin(R/d) < 90: no clipping
        const deferred::Light l = point_light(P + d * dir_from_angles(th, 0), float(R));
        const double Rf = double(float(R));
        const double expected = 100.0 * std::cos(th * kPi / 180) / (4 * kPi * (d * d + Rf * Rf));
        EXPECT_TRUE(RelNear(oracle::irradiance(l, P, dvec3(0, 0, 1)), expected, 1e-12)) << th;
        EXPECT_TRUE(RelNear(oracle::irradiance_numeric(l, P, dvec3(0, 0, 1)), expected, 1e-9)) << th;
    }
}

// Off-axis, tilted emitters and receivers, fully above the horizon: closed
// form vs the shade-path quadrature (1e-9 rel) and vs the independent
// brute-force midpoint integral, 1000^2 cells (1e-6 rel; observed <= 1e-7).
TEST(OracleLights, OffAxisTilted) {
    const dvec3 P(0.2, -0.1, 0.0);
    const dvec3 N = glm::normalize(dvec3(0.2, 0.1, 1.0));
    const std::vector<deferred::Light> lights = {
        area_light(deferred::AreaShape::Rectangle, dvec3(0.8, 0.5, 1.2), glm::normalize(dvec3(-0.4, -0.3, -1.0)), 0.9f, 0.4f),
        area_light(deferred::AreaShape::Square, dvec3(-0.6, 0.4, 0.9), glm::normalize(dvec3(0.6, -0.2, -0.7)), 0.5f, 0.5f,
                   dvec3(1.0, 1.5, 1.0)),
        area_light(deferred::AreaShape::Ellipse, dvec3(0.8, 0.5, 1.2), glm::normalize(dvec3(-0.4, -0.3, -1.0)), 0.9f, 0.4f),
        area_light(deferred::AreaShape::Disk, dvec3(-0.6, 0.4, 0.3), glm::normalize(dvec3(0.6, -0.2, -0.3)), 0.3f, 0.3f),
    };
    for (std::size_t i = 0; i < lights.size(); ++i) {
        const double e = oracle::irradiance(lights[i], P, N);
        EXPECT_GT(e, 0.0);
        EXPECT_TRUE(RelNear(oracle::irradiance_numeric(lights[i], P, N), e, 1e-9)) << i;
        EXPECT_TRUE(RelNear(brute_force_area_irradiance(lights[i], P, N, 1000), e, 1e-6)) << i;
    }
    const deferred::Light sphere = point_light(dvec3(0.9, 0.7, 1.1), 0.3f);
    EXPECT_TRUE(RelNear(oracle::irradiance_numeric(sphere, P, N), oracle::irradiance(sphere, P, N), 1e-9));
}

// Emitters straddling the receiver's horizon: the closed form clips
// (Sutherland-Hodgman / arc + chord). The quadratures see a kink, so they
// converge only like h^2: 1e-6 rel against the shade path at 1024 nodes per
// axis, and the brute-force midpoint at 2000^2 cells (observed <= 1e-7).
TEST(OracleLights, HorizonClipping) {
    const dvec3 P(0.0), N(0, 0, 1);
    const std::vector<deferred::Light> lights = {
        area_light(deferred::AreaShape::Square, dvec3(1.0, 0.0, 0.1), dvec3(-1, 0, 0), 1.0f, 1.0f),
        area_light(deferred::AreaShape::Rectangle, dvec3(0.7, 0.3, 0.05), glm::normalize(dvec3(-1, -0.5, -0.3)), 1.2f, 0.6f),
        area_light(deferred::AreaShape::Disk, dvec3(1.0, 0.0, 0.1), dvec3(-1, 0, 0), 1.0f, 1.0f),
        area_light(deferred::AreaShape::Ellipse, dvec3(0.7, 0.3, -0.05), glm::normalize(dvec3(-1, -0.5, -0.3)), 1.2f, 0.6f),
    };
    for (std::size_t i = 0; i < lights.size(); ++i) {
        const double e = oracle::irradiance(lights[i], P, N);
        EXPECT_GT(e, 0.0);
        EXPECT_TRUE(RelNear(oracle::irradiance_numeric(lights[i], P, N, 1024), e, 1e-6)) << i;
        EXPECT_TRUE(RelNear(brute_force_area_irradiance(lights[i], P, N, 2000), e, 1e-6)) << i;
        // Without clipping (receiver turned to face the light) the value differs a lot.
        const double e_unclipped_like = oracle::irradiance(lights[i], P, glm::normalize(dvec3(1, 0, 0.2)));
        EXPECT_GT(std::fabs(e_unclipped_like - e), 0.1 * e) << i;
    }
    // Sphere light whose facing disk straddles the horizon.
    const deferred::Light sphere = point_light(dvec3(1.0, 0.0, 0.1), 0.5f);
    const double e = oracle::irradiance(sphere, P, N);
    EXPECT_GT(e, 0.0);
    EXPECT_TRUE(RelNear(oracle::irradiance_numeric(sphere, P, N, 1024), e, 1e-6));
    // Entirely below the horizon: 0.
    EXPECT_EQ(oracle::irradiance(point_light(dvec3(1.0, 0.0, -0.6), 0.5f), P, N), 0.0);
}

// One-sided area lights: a point behind the emitter gets nothing.
TEST(OracleLights, AreaLightIsOneSided) {
    const deferred::Light l = area_light(deferred::AreaShape::Square, dvec3(0, 0, 1), dvec3(0, 0, 1), 1.0f, 1.0f);
    EXPECT_EQ(oracle::irradiance(l, dvec3(0.0), dvec3(0, 0, 1)), 0.0);
    EXPECT_EQ(oracle::irradiance_numeric(l, dvec3(0.0), dvec3(0, 0, 1)), 0.0);
    const oracle::Shade s = oracle::shade(l, deferred::Material{}, dvec3(0.0), dvec3(0, 0, 1), dvec3(0, 0, 1));
    EXPECT_EQ(s.diffuse + s.glossy, dvec3(0.0));
}

// Spot with radius: 3.4 evaluates the attenuation per disk sample (for the
// direction sample -> P), so there is no closed form; irradiance() integrates
// numerically. For a small disk it tends to the point result times the
// centre attenuation, with an O((R/d)^2 * att'') difference: 2e-4 rel for
// R/d ~ 0.02 inside the cone, and for R/d ~ 0.002 in the blend zone (where
// att'' ~ 6/w^2 is large; at R/d ~ 0.02 there the difference is ~0.7 %).
// The numeric fallback itself is converged: 1024 vs 512 nodes agree to 1e-8.
TEST(OracleLights, SpotWithRadiusNearPointLimit) {
    const dvec3 pos(0, 0, 2);
    struct Case {
        float radius;
        dvec3 P;
    };
    const Case cases[] = {{0.04f, dvec3(0.3, 0.0, 0.0)}, {0.004f, dvec3(0.8, 0.0, 0.0)}};
    for (const Case& c : cases) {
        deferred::Light l = make_light(deferred::LightType::Spot, frame_matrix(pos, dvec3(0, 0, -1)), 50.0f);
        l.radius = c.radius;
        l.spot_size = float(60.0 * kPi / 180.0);
        l.spot_blend = 0.5f;
        const dvec3 D = glm::normalize(c.P - pos);
        const double R = l.radius, d = glm::length(c.P - pos);
        const double point_like = 50.0 / (4 * kPi * (d * d + R * R)) * oracle::spot_attenuation(l, D) * (-D.z);
        const double e = oracle::irradiance(l, c.P, dvec3(0, 0, 1));
        EXPECT_TRUE(RelNear(e, point_like, 2e-4)) << c.radius;
        EXPECT_TRUE(RelNear(oracle::irradiance_numeric(l, c.P, dvec3(0, 0, 1), 512), e, 1e-8)) << c.radius;
    }
}

// ----------------------------------------------------------------------------
// shade()
// ----------------------------------------------------------------------------

// A tiny, distant square (side s << d) is a point-like emitter of intensity
// L A cos_l: shade = colour * L A cos_l / d^2 * lobes(omega). Tolerance 1e-6 rel.
TEST(OracleShade, TinyAreaLightIsPointLike) {
    const dvec3 P(0.0), N(0, 0, 1), V = dir_from_angles(35, 20);
    const dvec3 w = dir_from_angles(40, 200);
    const double d = 10.0, size = 1e-3;
    deferred::Light l = area_light(deferred::AreaShape::Square, P + d * w, glm::normalize(dvec3(0.3, 0.1, -1.0)),
                                   float(size), float(size));
    l.color = {1.0f, 0.5f, 0.25f};
    deferred::Material m = material(dvec3(0.7, 0.6, 0.5), 0.3f, 0.5f);
    m.sheen = 0.3f;
    m.clearcoat = 0.4f;
    m.clearcoat_roughness = 0.3f;
    const oracle::LightFrame f = oracle::light_frame(l);
    const double cos_l = glm::dot(f.direction, -w);
    const double k = 100.0 / (4.0 * f.area) * f.area * cos_l / (d * d);
    const dvec3 col(1.0, 0.5, 0.25);
    const oracle::Lobes lob = oracle::eval_principled(m, N, V, w);
    const oracle::Shade s = oracle::shade(l, m, P, N, V, 64);
    EXPECT_TRUE(RelNear3(s.diffuse, k * col * (lob.diffuse + lob.sheen), 1e-6));
    EXPECT_TRUE(RelNear3(s.glossy, k * col * (lob.specular + lob.clearcoat), 1e-6));
}

// The quadrature of shade() has converged at the default resolution for a
// moderately rough material: 512 vs 1024 nodes per axis agree to 1e-8 rel
// (diffuse) and 1e-6 rel (glossy).
TEST(OracleShade, Converged) {
    const dvec3 P(0.0), N(0, 0, 1), V = dir_from_angles(45, 0);
    const deferred::Material m = material(dvec3(0.8, 0.5, 0.3), 0.5f, 0.3f);
    const std::vector<deferred::Light> lights = {
        area_light(deferred::AreaShape::Rectangle, dvec3(-0.7, 0.1, 0.8), glm::normalize(dvec3(0.6, 0, -0.8)), 0.6f, 0.3f),
        area_light(deferred::AreaShape::Disk, dvec3(-0.7, 0.1, 0.8), glm::normalize(dvec3(0.6, 0, -0.8)), 0.6f, 0.6f),
        point_light(dvec3(-0.7, 0.1, 0.8), 0.2f),
    };
    for (std::size_t i = 0; i < lights.size(); ++i) {
        const oracle::Shade a = oracle::shade(lights[i], m, P, N, V, 512);
        const oracle::Shade b = oracle::shade(lights[i], m, P, N, V, 1024);
        EXPECT_TRUE(RelNear3(a.diffuse, b.diffuse, 1e-8)) << i;
        EXPECT_TRUE(RelNear3(a.glossy, b.glossy, 1e-6)) << i;
    }
}

}  // namespace
