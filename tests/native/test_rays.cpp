// Shadow rays' hierarchy (native/src/ray_scene.h): the CPU traversal against
// every triangle tested one by one, the GPU traversal (shaders/ray_lib.glsl)
// against the CPU one, transparency as a product of 1 - alpha, degenerate
// input (coincident triangles, an empty scene, a flattened instance).
#include "gl_test_context.h"
#include "ray_scene.h"
#include "../../shaders/shader_defines.h"

#include <gtest/gtest.h>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <random>
#include <vector>

using namespace deferred;

namespace {

struct Soup {
    std::vector<float> corners;  // 9 per triangle
    std::vector<std::uint32_t> slots;
};

Soup random_soup(std::mt19937& rng, int n, int slots) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), e(-0.15f, 0.15f);
    Soup s;
    for (int t = 0; t < n; ++t) {
        const glm::vec3 c(u(rng), u(rng), u(rng));
        for (int k = 0; k < 3; ++k) {
            s.corners.push_back(c.x + e(rng));
            s.corners.push_back(c.y + e(rng));
            s.corners.push_back(c.z + e(rng));
        }
        s.slots.push_back(std::uint32_t(t % slots));
    }
    return s;
}

// The reference: every instance's every triangle, in double precision, in
// world space.
struct BruteInstance {
    const Soup* soup;
    glm::dmat4 model;
    std::vector<float> alpha;
};

double brute_transmittance(const std::vector<BruteInstance>& instances, const glm::dvec3& o, const glm::dvec3& d,
                           double tmax) {
    double T = 1.0;
    for (const BruteInstance& inst : instances) {
        const std::size_t n = inst.soup->slots.size();
        for (std::size_t t = 0; t < n; ++t) {
            glm::dvec3 v[3];
            for (int k = 0; k < 3; ++k) {
                const float* p = &inst.soup->corners[t * 9 + std::size_t(k) * 3];
                v[k] = glm::dvec3(inst.model * glm::dvec4(p[0], p[1], p[2], 1.0));
            }
            const glm::dvec3 e1 = v[1] - v[0], e2 = v[2] - v[0];
            const glm::dvec3 p = glm::cross(d, e2);
            const double det = glm::dot(e1, p);
            if (det == 0.0) continue;
            const glm::dvec3 s = o - v[0];
            const double a = glm::dot(s, p) / det;
            if (a < 0.0 || a > 1.0) continue;
            const glm::dvec3 q = glm::cross(s, e1);
            const double b = glm::dot(d, q) / det;
            if (b < 0.0 || a + b > 1.0) continue;
            const double th = glm::dot(e2, q) / det;
            if (!(th > 0.0 && th < tmax)) continue;
            T *= inst.alpha.empty() ? 0.0 : 1.0 - inst.alpha[inst.soup->slots[t]];
        }
    }
    return T;
}

struct Ray {
    glm::vec3 o, d;
    float tmax;
};

std::vector<Ray> random_rays(std::mt19937& rng, int n) {
    std::uniform_real_distribution<float> u(-3.0f, 3.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    std::vector<Ray> rays;
    for (int i = 0; i < n; ++i) {
        Ray r;
        r.o = glm::vec3(u(rng), u(rng), u(rng));
        r.d = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
        r.tmax = i % 3 == 0 ? 1e30f : std::abs(u(rng)) * 2.0f;
        rays.push_back(r);
    }
    return rays;
}

// A scene of three instances of one soup (one partly transparent: slot
// alphas 0.5 and 1, 0.25 and 1) and one of a second soup.
struct TestScene {
    Soup a, b;
    std::shared_ptr<const MeshBvh> bvh_a, bvh_b;
    std::vector<RayScene::Instance> instances;
    std::vector<BruteInstance> brute;
};

TestScene make_scene(std::mt19937& rng) {
    TestScene s;
    s.a = random_soup(rng, 3000, 2);
    s.b = random_soup(rng, 500, 1);
    s.bvh_a = std::make_shared<const MeshBvh>(build_mesh_bvh(s.a.corners.data(), s.a.slots.data(), s.a.slots.size()));
    s.bvh_b = std::make_shared<const MeshBvh>(build_mesh_bvh(s.b.corners.data(), s.b.slots.data(), s.b.slots.size()));
    const glm::dmat4 I(1.0);
    const glm::dmat4 m0 = glm::translate(I, glm::dvec3(-1.5, 0.0, 0.0));
    const glm::dmat4 m1 = glm::scale(glm::rotate(glm::translate(I, glm::dvec3(1.2, 0.5, -0.3)), 0.7, glm::dvec3(1, 2, 3)),
                                     glm::dvec3(0.8, 1.3, 0.6));
    const glm::dmat4 m2 = glm::scale(glm::translate(I, glm::dvec3(0.0, -1.5, 1.0)), glm::dvec3(-1.0, 1.0, 1.0));  // mirrored
    const glm::dmat4 m3 = glm::rotate(glm::translate(I, glm::dvec3(0.3, 1.8, 0.2)), 1.9, glm::dvec3(0, 0, 1));
    s.instances = {{s.bvh_a, m0, {1.0f, 1.0f}}, {s.bvh_a, m1, {0.5f, 1.0f}}, {s.bvh_a, m2, {0.25f, 1.0f}},
                   {s.bvh_b, m3, {1.0f}}};
    for (const RayScene::Instance& i : s.instances) {
        const bool transparent = std::any_of(i.slot_alpha.begin(), i.slot_alpha.end(), [](float x) { return x < 1.0f; });
        s.brute.push_back({i.bvh == s.bvh_a ? &s.a : &s.b, i.model, transparent ? i.slot_alpha : std::vector<float>{}});
    }
    return s;
}

}  // namespace

TEST(RayHierarchy, CpuTraversalMatchesEveryTriangle) {
    std::mt19937 rng(7);
    TestScene s = make_scene(rng);
    RayScene scene;
    scene.build(s.instances);
    EXPECT_EQ(scene.instances(), 4u);
    EXPECT_EQ(scene.triangles(), 3u * 3000u + 500u);
    EXPECT_LE(s.bvh_a->depth, RAY_MAX_DEPTH);
    const std::vector<Ray> rays = random_rays(rng, 20000);
    int differ = 0, blocked = 0, partial = 0;
    for (const Ray& r : rays) {
        const double ref = brute_transmittance(s.brute, r.o, r.d, r.tmax);
        const float got = trace_transmittance(scene.data(), r.o, r.d, r.tmax);
        if (std::abs(got - ref) > 1e-5) ++differ;
        if (ref == 0.0) ++blocked;
        if (ref > 0.0 && ref < 1.0) ++partial;
    }
    std::printf("CPU traversal: %d of %zu rays differ from the brute force (%d blocked, %d partly)\n", differ,
                rays.size(), blocked, partial);
    // Rays through a shared edge or a box face in float may differ.
    EXPECT_LE(differ, int(rays.size() / 2000));
    EXPECT_GT(blocked, int(rays.size() / 10));  // the test means something
    EXPECT_GT(partial, int(rays.size() / 100));
}

class RayTraversalGpu : public deferred::testing::GLTest {};

TEST_F(RayTraversalGpu, MatchesTheCpuTraversal) {
    std::mt19937 rng(11);
    TestScene s = make_scene(rng);
    RayScene scene;
    scene.build(s.instances);
    scene.upload();
    const std::vector<Ray> rays = random_rays(rng, 16384);
    std::vector<glm::vec4> packed;
    for (const Ray& r : rays) {
        packed.emplace_back(r.o, r.tmax);
        packed.emplace_back(r.d, 0.0f);
    }
    Buffer in = make_storage_buffer(packed.data(), packed.size() * sizeof(glm::vec4), "rays");
    Buffer out = make_storage_buffer(nullptr, rays.size() * sizeof(float), "transmittance");
    glUseProgram(shaders().compute_program("unit_test_rays_comp.glsl", {}));
    scene.bind();
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, in.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out.get());
    glDispatchCompute(GLuint(rays.size() / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<float> T(rays.size());
    glGetNamedBufferSubData(out.get(), 0, GLsizeiptr(T.size() * sizeof(float)), T.data());
    check_gl("ray traversal dispatch");
    int differ = 0;
    for (std::size_t i = 0; i < rays.size(); ++i)
        if (std::abs(T[i] - trace_transmittance(scene.data(), rays[i].o, rays[i].d, rays[i].tmax)) > 1e-5) ++differ;
    std::printf("GPU traversal: %d of %zu rays differ from the CPU's\n", differ, rays.size());
    EXPECT_LE(differ, int(rays.size() / 2000));
}

TEST(RayHierarchy, CoincidentTrianglesStayWithinTheDepthLimit) {
    // 20 000 copies of one triangle: no split separates them; the hierarchy
    // stops at RAY_MAX_DEPTH levels and still finds them.
    std::vector<float> corners;
    for (int t = 0; t < 20000; ++t)
        for (float v : {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f}) corners.push_back(v);
    const MeshBvh bvh = build_mesh_bvh(corners.data(), nullptr, 20000);
    EXPECT_LE(bvh.depth, RAY_MAX_DEPTH);
    RayScene scene;
    scene.build({{std::make_shared<const MeshBvh>(bvh), glm::dmat4(1.0), {}}});
    EXPECT_EQ(trace_transmittance(scene.data(), {0.2f, 0.2f, 1.0f}, {0.0f, 0.0f, -1.0f}, 10.0f), 0.0f);
    EXPECT_EQ(trace_transmittance(scene.data(), {0.8f, 0.8f, 1.0f}, {0.0f, 0.0f, -1.0f}, 10.0f), 1.0f);
    EXPECT_EQ(trace_transmittance(scene.data(), {0.2f, 0.2f, 1.0f}, {0.0f, 0.0f, -1.0f}, 0.5f), 1.0f);  // short
}

TEST(RayHierarchy, EmptyAndFlattenedInstancesBlockNothing) {
    RayScene scene;
    scene.build({});
    EXPECT_EQ(trace_transmittance(scene.data(), {0, 0, 0}, {0, 0, 1}, 1e30f), 1.0f);
    std::vector<float> corners = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
    auto bvh = std::make_shared<const MeshBvh>(build_mesh_bvh(corners.data(), nullptr, 1));
    glm::dmat4 flat(1.0);
    flat[2][2] = 0.0;  // no inverse: left out
    scene.build({{bvh, flat, {}}, {std::make_shared<const MeshBvh>(), glm::dmat4(1.0), {}}});
    EXPECT_EQ(scene.instances(), 0u);
    EXPECT_EQ(trace_transmittance(scene.data(), {0, 0, 1}, {0, 0, -1}, 1e30f), 1.0f);
}
