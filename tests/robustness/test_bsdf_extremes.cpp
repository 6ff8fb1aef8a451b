// The GPU BSDF (shaders/bsdf_lib.glsl, through unit_test_bsdf_comp.glsl) at
// the corners of its domain: roughness 0 and 1, metallic 0 and 1, specular 0,
// base colour 0 and 1, and grazing view/light directions (N.V, N.L from 0.1
// down to 1e-12), against the double-precision CPU oracle.
#include "robustness_helpers.h"

#include "cycles_oracle.h"
#include "gl_test_context.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

using namespace deferred;

namespace {

struct alignas(16) Case {
    float N[4], V[4], L[4], base_diffuse[4], params0[4], params1[4];
};

class BsdfExtremes : public deferred::testing::GLTest {
protected:
    // (diffuse, glossy) f*cos per case, as the GPU evaluates them.
    static std::vector<float> evaluate(const std::vector<Case>& cases) {
        Buffer in = make_storage_buffer(cases.data(), cases.size() * sizeof(Case), "cases");
        Buffer out = make_storage_buffer(nullptr, cases.size() * 32, "results");
        glUseProgram(shaders().compute_program("unit_test_bsdf_comp.glsl", {}));
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, in.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out.get());
        glDispatchCompute(GLuint((cases.size() + 63) / 64), 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        std::vector<float> res(cases.size() * 8);
        glGetNamedBufferSubData(out.get(), 0, GLsizeiptr(res.size() * sizeof(float)), res.data());
        check_gl("bsdf dispatch");
        return res;
    }
};

Case make_case(const Material& m, glm::dvec3 N, glm::dvec3 V, glm::dvec3 L) {
    Case c{};
    auto put = [](float* dst, glm::dvec3 v) {
        dst[0] = float(v.x); dst[1] = float(v.y); dst[2] = float(v.z); dst[3] = 0;
    };
    put(c.N, N); put(c.V, V); put(c.L, L);
    const float ba[4] = {m.base_color[0], m.base_color[1], m.base_color[2], oracle::gbuffer_closure_model(m)};
    const float p0[4] = {m.metallic, m.roughness, m.specular, m.specular_tint};
    const float p1[4] = {m.sheen, m.sheen_tint, m.clearcoat, m.clearcoat_roughness};
    std::copy(ba, ba + 4, c.base_diffuse);
    std::copy(p0, p0 + 4, c.params0);
    std::copy(p1, p1 + 4, c.params1);
    return c;
}

// Direction at elevation `e` (radians above the plane z = 0) and azimuth `phi`.
glm::dvec3 dir(double e, double phi) { return {std::cos(e) * std::cos(phi), std::cos(e) * std::sin(phi), std::sin(e)}; }

// Same floats for the oracle as for the GPU.
glm::dvec3 as_float(glm::dvec3 v) { return glm::dvec3(glm::vec3(v)); }

// The shared corners (roughness 0, 0.01, 0.5, 1) plus clearcoat and sheen at their ends.
std::vector<Material> corner_materials() {
    std::vector<Material> out = robustness::corner_materials({0.0f, 0.01f, 0.5f, 1.0f});
    Material cc;
    cc.clearcoat = 1.0f;
    cc.clearcoat_roughness = 0.0f;
    cc.sheen = 1.0f;
    out.push_back(cc);
    cc.clearcoat_roughness = 1.0f;
    out.push_back(cc);
    return out;
}

}  // namespace

// Parameter corners at ordinary angles: GPU = oracle, and no highlight from
// lights when alpha^2 <= 1e-7 (roughness 0 and 0.01: alpha^2 = 1e-8), as Cycles.
TEST_F(BsdfExtremes, ParameterCornersMatchOracle) {
    std::vector<Case> cases;
    std::vector<Material> mats;
    std::vector<glm::dvec3> Ns, Vs, Ls;
    const glm::dvec3 N(0, 0, 1);
    for (const Material& m : corner_materials())
        for (double ev : {0.2, 0.7, 1.5707})
            for (double el : {0.2, 0.7, 1.5707})
                for (double phi : {0.0, 2.0, M_PI}) {
                    const glm::dvec3 V = as_float(dir(ev, 0.0)), L = as_float(dir(el, phi));
                    cases.push_back(make_case(m, N, V, L));
                    mats.push_back(m);
                    Ns.push_back(N); Vs.push_back(V); Ls.push_back(L);
                }
    const std::vector<float> res = evaluate(cases);
    double worst = 0, worst_glossy_delta = 0;
    std::size_t nonfinite = 0;
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const oracle::Lobes o = oracle::eval_principled(mats[i], Ns[i], Vs[i], Ls[i]);
        const glm::dvec3 od = o.diffuse + o.sheen, og = o.specular + o.clearcoat;
        const float r = mats[i].roughness;
        for (int c = 0; c < 3; ++c) {
            const double gd = res[i * 8 + std::size_t(c)], gg = res[i * 8 + 4 + std::size_t(c)];
            if (!std::isfinite(gd) || !std::isfinite(gg)) { ++nonfinite; continue; }
            worst = std::max({worst, std::abs(gd - od[c]) / std::max(std::abs(od[c]), 1e-2),
                              std::abs(gg - og[c]) / std::max(std::abs(og[c]), 1e-2)});
            if (r * r * r * r <= 1e-7f && mats[i].clearcoat == 0.0f)
                worst_glossy_delta = std::max(worst_glossy_delta, std::abs(gg));
        }
    }
    std::printf("parameter corners: %zu cases, max relative error vs oracle %.3g, non-finite %zu, "
                "max glossy for alpha^2 <= 1e-7: %.3g\n",
                cases.size(), worst, nonfinite, worst_glossy_delta);
    EXPECT_EQ(nonfinite, 0u);
    EXPECT_LT(worst, 1e-4);
    EXPECT_EQ(worst_glossy_delta, 0.0) << "Cycles gives no highlight from lights at alpha^2 <= 1e-7";
}

// Grazing view and light: N.V and N.L from 1e-1 down to 1e-12 (and the
// shading normal facing away, N.V < 0). Finite everywhere; no value above
// the oracle's maximum over the same set (no fireflies); the oracle
// agreement is reported down to N.V = N.L = 1e-4 (below, float cosines
// carry no digits any more).
TEST_F(BsdfExtremes, GrazingAnglesAreFiniteAndBounded) {
    std::vector<Case> cases;
    std::vector<Material> mats;
    std::vector<glm::dvec3> Ns, Vs, Ls;
    std::vector<double> grazing;  // min(N.V, N.L) of the case
    const glm::dvec3 N(0, 0, 1);
    const double elevations[] = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-8, 1e-10, 1e-12, 0.0, -1e-6};
    for (const Material& m : corner_materials())
        for (double ev : elevations)
            for (double el : elevations)
                for (double phi : {0.0, 1e-3, 1.0, M_PI}) {  // light behind the viewer, beside, opposite
                    const glm::dvec3 V = as_float(dir(ev, 0.0)), L = as_float(dir(el, phi));
                    cases.push_back(make_case(m, N, V, L));
                    mats.push_back(m);
                    Ns.push_back(N); Vs.push_back(V); Ls.push_back(L);
                    grazing.push_back(std::min(ev, el));
                }
    const std::vector<float> res = evaluate(cases);
    std::size_t nonfinite = 0, above = 0;
    double worst_rel = 0, oracle_max = 0, gpu_max = 0;
    std::string first_bad, worst_case;
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const oracle::Lobes o = oracle::eval_principled(mats[i], Ns[i], Vs[i], Ls[i]);
        const glm::dvec3 od = o.diffuse + o.sheen, og = o.specular + o.clearcoat;
        for (int c = 0; c < 3; ++c) oracle_max = std::max({oracle_max, od[c] + og[c]});
    }
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const oracle::Lobes o = oracle::eval_principled(mats[i], Ns[i], Vs[i], Ls[i]);
        const glm::dvec3 od = o.diffuse + o.sheen, og = o.specular + o.clearcoat;
        for (int c = 0; c < 3; ++c) {
            const double gd = res[i * 8 + std::size_t(c)], gg = res[i * 8 + 4 + std::size_t(c)];
            if (!std::isfinite(gd) || !std::isfinite(gg)) {
                if (nonfinite++ == 0) {
                    char buf[256];
                    std::snprintf(buf, sizeof buf, "N.V %.3g N.L %.3g (L.V %.3g) roughness %.3g: diffuse %g glossy %g",
                                  glm::dot(Ns[i], Vs[i]), glm::dot(Ns[i], Ls[i]), glm::dot(Ls[i], Vs[i]),
                                  double(mats[i].roughness), gd, gg);
                    first_bad = buf;
                }
                continue;
            }
            gpu_max = std::max(gpu_max, gd + gg);
            if (gd + gg > oracle_max * (1 + 1e-3)) ++above;
            if (grazing[i] >= 1e-4) {
                const double rel = std::max(std::abs(gd - od[c]) / std::max(std::abs(od[c]), 1e-2),
                                            std::abs(gg - og[c]) / std::max(std::abs(og[c]), 1e-2));
                if (rel > worst_rel) {
                    // The case, so a failure on another driver says where to look.
                    const Material& m = mats[i];
                    char buf[384];
                    std::snprintf(buf, sizeof buf,
                                  "N.V %.3g N.L %.3g (L.V %.3g) channel %d, roughness %.3g metallic %.3g specular %.3g "
                                  "sheen %.3g clearcoat %.3g (roughness %.3g): diffuse %.6g vs %.6g, glossy %.6g vs %.6g",
                                  glm::dot(Ns[i], Vs[i]), glm::dot(Ns[i], Ls[i]), glm::dot(Ls[i], Vs[i]), c,
                                  double(m.roughness), double(m.metallic), double(m.specular), double(m.sheen),
                                  double(m.clearcoat), double(m.clearcoat_roughness), gd, od[c], gg, og[c]);
                    worst_case = buf;
                }
                worst_rel = std::max(worst_rel, rel);
            }
        }
    }
    std::printf("grazing: %zu cases, non-finite %zu%s%s, GPU max %.4g vs oracle max %.4g (%zu above), "
                "max relative error vs oracle (N.V, N.L >= 1e-4) %.3g\n",
                cases.size(), nonfinite, nonfinite ? ", first: " : "", first_bad.c_str(), gpu_max, oracle_max, above,
                worst_rel);
    EXPECT_EQ(above, 0u);
    EXPECT_LT(worst_rel, 2e-3) << "worst case: " << worst_case;
    EXPECT_EQ(nonfinite, 0u) << "first non-finite case: " << first_bad;
}
