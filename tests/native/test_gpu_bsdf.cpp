// GPU BSDF (shaders/bsdf_lib.glsl) against the double-precision CPU oracle
// for random (N, V, L, material) configurations.
#include "gl_test_context.h"

#include "cycles_oracle.h"

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include <random>
#include <vector>

using namespace deferred;

namespace {
struct alignas(16) Case {
    float N[4], V[4], L[4], base_diffuse[4], params0[4], params1[4];
};

// Values representable exactly as half floats, as the G-buffer stores them.
float half_exact(float v) { return std::round(v * 1024.0f) / 1024.0f; }

glm::dvec3 random_dir(std::mt19937& rng, const glm::dvec3& around, double min_cos) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (;;) {
        glm::dvec3 d(2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1);
        const double l = glm::length(d);
        if (l < 1e-3 || l > 1) continue;
        d /= l;
        if (glm::dot(d, around) >= min_cos) return d;
    }
}
}  // namespace

class GpuBsdf : public deferred::testing::GLTest {};

TEST_F(GpuBsdf, MatchesOracleWithin1e4Relative) {
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const int n = 4096;
    std::vector<Case> cases(n);
    std::vector<Material> mats(n);
    std::vector<glm::dvec3> Ns(n), Vs(n), Ls(n);
    for (int i = 0; i < n; ++i) {
        Material m;
        m.base_color = {half_exact(u(rng)), half_exact(u(rng)), half_exact(u(rng))};
        m.metallic = half_exact(u(rng) < 0.3f ? (u(rng) < 0.5f ? 0.0f : 1.0f) : u(rng));
        m.roughness = half_exact(0.1f + 0.9f * u(rng));
        m.specular = half_exact(u(rng));
        m.specular_tint = half_exact(u(rng));
        m.sheen = half_exact(u(rng) < 0.5f ? 0.0f : u(rng));
        m.sheen_tint = half_exact(u(rng));
        m.clearcoat = half_exact(u(rng) < 0.5f ? 0.0f : u(rng));
        m.clearcoat_roughness = half_exact(0.1f + 0.9f * u(rng));
        // One case in four is a Diffuse BSDF (Oren-Nayar, sigma 0 = Lambert
        // included), which has no specular, sheen or clearcoat.
        if (i % 4 == 3) {
            m.diffuse_roughness = half_exact(u(rng) < 0.25f ? 0.0f : u(rng));
            m.metallic = m.specular = m.sheen = m.clearcoat = 0.0f;
        }
        // And one in eight a Glossy BSDF (GGX or Beckmann, weight = colour).
        if (i % 8 == 1) {
            m.glossy_model = 1 + (i / 8) % 2;
            m.metallic = 1.0f;
            m.sheen = m.clearcoat = 0.0f;
        }
        // And one in sixteen a Lambert Diffuse BSDF summed with a grey Glossy
        // one (a Mix or Add of the two, scene.h glossy_model): metallic 0,
        // the glossy weight in specular_tint.
        if (i % 16 == 5) {
            m.glossy_model = 1 + (i / 16) % 2;
            m.metallic = m.sheen = m.clearcoat = 0.0f;
            m.specular = 0.5f;
            m.diffuse_roughness = 0.0f;
        }
        const glm::dvec3 N = random_dir(rng, glm::dvec3(0, 0, 1), -1.0);
        // Keep away from exactly grazing configurations, where float cos
        // cannot carry 1e-4 relative precision.
        const glm::dvec3 V = random_dir(rng, N, 0.05), L = random_dir(rng, N, 0.05);
        Ns[i] = N; Vs[i] = V; Ls[i] = L; mats[i] = m;
        Case& c = cases[i];
        auto put = [](float* dst, glm::dvec3 v) { dst[0] = float(v.x); dst[1] = float(v.y); dst[2] = float(v.z); dst[3] = 0; };
        put(c.N, N); put(c.V, V); put(c.L, L);
        float ba[4] = {m.base_color[0], m.base_color[1], m.base_color[2], oracle::gbuffer_closure_model(m)};
        float p0[4] = {m.metallic, m.roughness, m.specular, m.specular_tint};
        float p1[4] = {m.sheen, m.sheen_tint, m.clearcoat, m.clearcoat_roughness};
        std::copy(ba, ba + 4, c.base_diffuse); std::copy(p0, p0 + 4, c.params0); std::copy(p1, p1 + 4, c.params1);
    }
    Buffer in = make_storage_buffer(cases.data(), cases.size() * sizeof(Case), "cases");
    Buffer out = make_storage_buffer(nullptr, std::size_t(n) * 32, "results");
    glUseProgram(shaders().compute_program("unit_test_bsdf_comp.glsl", {}));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, in.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out.get());
    glDispatchCompute(GLuint((n + 63) / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<float> res(std::size_t(n) * 8);
    glGetNamedBufferSubData(out.get(), 0, GLsizeiptr(res.size() * sizeof(float)), res.data());
    check_gl("bsdf dispatch");

    double worst = 0;
    int worst_i = -1;
    for (int i = 0; i < n; ++i) {
        // The GPU works from float inputs: give the oracle the same floats.
        const glm::dvec3 N(cases[i].N[0], cases[i].N[1], cases[i].N[2]);
        const glm::dvec3 V(cases[i].V[0], cases[i].V[1], cases[i].V[2]);
        const glm::dvec3 L(cases[i].L[0], cases[i].L[1], cases[i].L[2]);
        const oracle::Lobes o = oracle::eval_principled(mats[i], N, V, L);
        const glm::dvec3 od = o.diffuse + o.sheen, og = o.specular + o.clearcoat;
        for (int c = 0; c < 3; ++c) {
            const double gd = res[std::size_t(i) * 8 + c], gg = res[std::size_t(i) * 8 + 4 + c];
            // Relative error with a floor of 1e-6 absolute for values that are ~0.
            const double ed = std::abs(gd - od[c]) / std::max(std::abs(od[c]), 1e-2);
            const double eg = std::abs(gg - og[c]) / std::max(std::abs(og[c]), 1e-2);
            if (std::max(ed, eg) > worst) { worst = std::max(ed, eg); worst_i = i; }
        }
    }
    std::printf("GPU vs oracle BSDF: max relative error %.3g over %d cases (case %d)\n", worst, n, worst_i);
    if (worst_i >= 0) {
        const Case& c = cases[worst_i];
        const Material& m = mats[worst_i];
        std::printf("  worst: N.V %.4f N.L %.4f metallic %.3f roughness %.3f specular %.3f clearcoat %.3f ccr %.3f sheen %.3f\n",
                    glm::dot(glm::dvec3(c.N[0], c.N[1], c.N[2]), glm::dvec3(c.V[0], c.V[1], c.V[2])),
                    glm::dot(glm::dvec3(c.N[0], c.N[1], c.N[2]), glm::dvec3(c.L[0], c.L[1], c.L[2])), m.metallic,
                    m.roughness, m.specular, m.clearcoat, m.clearcoat_roughness, m.sheen);
    }
    EXPECT_LT(worst, 1e-4);
}
