// Shadow catchers (lighting_comp.glsl SHADOW_CATCHER, passes_comp.glsl
// RESOLVE_CATCHER*), as Cycles 3.4 writes them (kernel/film/read.h).
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace deferred;

namespace {
constexpr int kSize = 48;  // 6 m across: 8 px per metre

// A white Lambert floor (the catcher) under a white box, lit by a sun 45
// degrees from +x and a constant world of 0.1; seen from above.
struct CatcherScene {
    Renderer r;
    Camera cam = deferred::testing::top_down_ortho(6.0, 6.0f);
    explicit CatcherScene(bool catcher = true) {
        tools::MeshArrays floor = tools::make_plane(3.0f, 4), box = tools::make_box(0.5f, 0.5f, 0.5f);
        Material white;
        white.base_color = {1.0f, 1.0f, 1.0f};
        white.specular = 0.0f;
        white.diffuse_roughness = 0.0f;
        const std::uint32_t mat = r.add_material(white);
        const Mat4d at_origin = tools::translation(0, 0, 0), raised = tools::translation(-1.0, 0, 0.5);
        r.add_instances(r.add_mesh(floor.view()), at_origin.data(), 1, nullptr, {mat}, true, nullptr, nullptr,
                        nullptr, false, 0, nullptr, nullptr, catcher);
        r.add_instances(r.add_mesh(box.view()), raised.data(), 1, nullptr, {mat});
        Light sun;
        sun.type = LightType::Sun;
        const double from[3] = {-3.0, 0.0, 3.0}, to[3] = {0.0, 0.0, 0.0};
        sun.matrix = tools::look_at(from, to);
        sun.energy = 3.0f;
        sun.angle = 0.0f;
        r.add_light(sun);
        deferred::testing::set_world_color(r, 0.1f, 0.1f, 0.1f);
    }
    FrameResult render(bool pass, bool transparent) {
        RenderSettings s;
        s.width = s.height = kSize;
        s.samples = 4;
        s.film_transparent = transparent;
        if (pass) s.passes = {Pass::ShadowCatcher};
        return r.render(cam, s);
    }
};

glm::dvec4 at(const PassImage& img, double x, double y) {  // metres on the floor
    const int px = int((x + 3.0) * 8.0), py = int((y + 3.0) * 8.0);
    const float* p = &img.pixels[(std::size_t(py) * img.width + std::size_t(px)) * img.channels];
    return {p[0], p[1], p[2], img.channels > 3 ? p[3] : 0.0};
}

// The sun's radiance off white Lambert at 45 degrees and the world's (all
// of the sky), so lit / shadowed ratios of the catcher's light.
const double kSun = 3.0 * std::sqrt(0.5) / M_PI, kWorld = 0.1;
}  // namespace

TEST(ShadowCatcher, PassIsShadowedOverUnshadowedLightAndCombinedHasAHole) {
    CatcherScene s;
    const FrameResult f = s.render(true, true);
    const PassImage& sc = *f.find(Pass::ShadowCatcher);
    const PassImage& combined = *f.find(Pass::Combined);
    ASSERT_EQ(sc.channels, 3);
    // Far from the box: all the sun, nearly all the sky.
    const glm::dvec4 lit = at(sc, 2.5, 2.5);
    EXPECT_GT(lit.x, 0.97);
    EXPECT_LE(lit.x, 1.0 + 1e-5);
    // The box's shadow falls towards +x (the sun is up from -x): the sun's
    // light is gone, some of the sky too.
    const glm::dvec4 shadow = at(sc, 0.3, 0.0);
    EXPECT_LT(shadow.x, kWorld / (kSun + kWorld) + 1e-3);
    EXPECT_GT(shadow.x, 0.3 * kWorld / (kSun + kWorld));
    // Off the catcher (the box's top): 1.
    EXPECT_NEAR(at(sc, -1.0, 0.0).x, 1.0, 1e-6);
    // Combined: the catcher a hole (the matte), the box lit and opaque.
    EXPECT_EQ(at(combined, 2.5, 2.5), glm::dvec4(0.0));
    EXPECT_EQ(at(combined, 0.3, 0.0), glm::dvec4(0.0));
    EXPECT_NEAR(at(combined, -1.0, 0.0).w, 1.0, 1e-6);
    EXPECT_GT(at(combined, -1.0, 0.0).x, 0.1);
}

TEST(ShadowCatcher, WithoutThePassCombinedCarriesTheShadow) {
    CatcherScene s;
    // Film transparent: black with the shadow as alpha, 1 - shadow catcher.
    const FrameResult t = s.render(false, true);
    EXPECT_EQ(t.find(Pass::ShadowCatcher), nullptr);
    const PassImage& combined = *t.find(Pass::Combined);
    EXPECT_LT(at(combined, 2.5, 2.5).w, 0.03);
    EXPECT_GT(at(combined, 0.3, 0.0).w, 1.0 - kWorld / (kSun + kWorld) - 1e-3);
    EXPECT_EQ(glm::dvec3(at(combined, 0.3, 0.0)), glm::dvec3(0.0));
    // Film opaque: the world behind, darkened by the shadow.
    const FrameResult o = s.render(false, false);
    const PassImage& opaque = *o.find(Pass::Combined);
    EXPECT_NEAR(at(opaque, 2.5, 2.5).x, kWorld * at(*s.render(true, false).find(Pass::ShadowCatcher), 2.5, 2.5).x,
                1e-4);
    EXPECT_LT(at(opaque, 0.3, 0.0).x, kWorld * kWorld / (kSun + kWorld) + 1e-4);
    EXPECT_NEAR(at(opaque, 0.3, 0.0).w, 1.0, 1e-6);
}

TEST(ShadowCatcher, PassIsOneWithoutCatchers) {
    CatcherScene s(false);
    const FrameResult f = s.render(true, true);
    for (float v : f.find(Pass::ShadowCatcher)->pixels) ASSERT_EQ(v, 1.0f);
    // And the floor is an ordinary surface.
    EXPECT_NEAR(at(*f.find(Pass::Combined), 2.5, 2.5).w, 1.0, 1e-6);
}
