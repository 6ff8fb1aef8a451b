// The forward pass (forward_module.h): Blend-mode surfaces composited over
// the deferred frame. Scenes seen from straight above (orthographic), lit by
// a hard sun with shadows and a grey world (its light and occlusion run too):
// a floor, panes above it. Panes cast no shadow here, so each surface's light
// is the same whatever is in front of it and the compositing alone is
// measured. Colours and roughness are exact in half floats, the G-buffer's
// precision: the forward pass rounds its values to half with packHalf2x16,
// the driver rounds on storing to the G-buffer, and the two may round a
// value that is not exact in opposite directions (one half ulp, 4.9e-4).
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace deferred;
using namespace deferred::testing;

namespace {

constexpr int kSize = 48;

Material diffuse(float r, float g, float b) {
    Material m;
    m.base_color = {r, g, b};
    m.roughness = 0.5f;
    return m;
}

struct Pane {
    Material material;
    double height;
};

// The scenes' light and floor: a grey world, a hard sun from (1, 0.5, 3)
// (its light the same at every sample), the floor (half size 10).
void add_sun_and_floor(Renderer& r, float world, bool with_floor = true) {
    set_world_color(r, world, world, world);
    Light sun;
    sun.type = LightType::Sun;
    sun.angle = 0.0f;
    const double eye[3] = {1.0, 0.5, 3.0}, target[3] = {0.0, 0.0, 0.0};
    sun.matrix = tools::look_at(eye, target);
    sun.energy = 3.0f;
    r.add_light(sun);
    if (with_floor) add_plane(r, diffuse(0.75f, 0.375f, 0.25f), 10.0f);
}

// A floor and the given panes (half size 2, z = height, no shadow of their
// own); the camera covers 6 m, so the panes cover the middle of the frame.
// `rays`: shadow rays instead of maps, and an opaque caster out of the
// camera's view (half size 1 at (4.5, 1.5, 8.5)) whose shadow falls on the
// right of the panes (x 1..2, y -0.75..1.25 at z = 1). `emitter`: a blue
// emissive panel out of view too (half size 0.5 at (-4, -1, 2.5), facing
// both ways), a mesh light.
// `stochastic`: partly transparent panes (not Blend) by stochastic coverage
// (RenderSettings::exact_transparent_planes off), not as exact layers.
FrameResult render_scene(const std::vector<Pane>& panes, int samples, bool film_transparent = false,
                         bool with_floor = true, float world = 0.25f, bool rays = false, bool emitter = false,
                         bool stochastic = false) {
    Renderer r;
    add_sun_and_floor(r, world, with_floor);
    // Added nearest first, so the pass's own sorting is what orders them.
    std::vector<Pane> order = panes;
    std::sort(order.begin(), order.end(), [](const Pane& a, const Pane& b) { return a.height > b.height; });
    for (const Pane& p : order)
        add_plane(r, p.material, 2.0f, 1, tools::translation(0, 0, p.height), /*cast_shadow=*/false);
    if (rays) add_plane(r, diffuse(0.5f, 0.5f, 0.5f), 1.0f, 1, tools::translation(4.5, 1.5, 8.5));
    if (emitter) {
        Material blue = diffuse(0.0f, 0.0f, 0.0f);
        blue.specular = 0.0f;
        blue.emission = {0.2f, 0.4f, 1.0f};
        blue.emission_strength = 20.0f;
        add_plane(r, blue, 0.5f, 2, tools::translation(-4.0, -1.0, 2.5));
    }
    RenderSettings s;
    s.shadow_rays = rays;
    s.width = s.height = kSize;
    s.samples = samples;
    s.film_transparent = film_transparent;
    s.filter_width = 0.01f;  // pixel centres: the same points at every sample
    s.exact_transparent_planes = !stochastic;
    return r.render(top_down_ortho(10.0, 6.0f), s);
}

// Largest per-pixel |a - b| / max(|b|, 0.05) over the pixels the panes cover
// (the middle 16 x 16).
double worst_inside(const PassImage& a, const std::function<glm::dvec4(int, int)>& expect) {
    double worst = 0;
    for (int y = 16; y < 32; ++y)
        for (int x = 16; x < 32; ++x) {
            const float* p = &a.pixels[(std::size_t(y) * a.width + x) * 4];
            const glm::dvec4 want = expect(x, y);
            for (int c = 0; c < 4; ++c)
                worst = std::max(worst, std::abs(p[c] - want[c]) / std::max(std::abs(want[c]), 0.05));
        }
    return worst;
}

glm::dvec4 pixel4(const PassImage& img, int x, int y) {
    const float* p = &img.pixels[(std::size_t(y) * img.width + x) * 4];
    return {p[0], p[1], p[2], p[3]};
}

Material blend_of(Material m, float alpha) {
    m.alpha = alpha;
    m.blend = true;
    return m;
}

}  // namespace

TEST(ForwardPass, OneLayerAtOneSampleIsTheExactComposite) {
    // A green pane of alpha 0.4 over the floor: the forward pass at ONE
    // sample gives 0.4 pane + 0.6 floor, each lit as it is when opaque. The
    // only differences are float rounding of the same arithmetic in another
    // order (bound 1e-6 relative).
    const Material green = diffuse(0.25f, 0.75f, 0.375f);
    FrameResult floor_only = render_scene({}, 1);
    FrameResult pane_opaque = render_scene({{green, 1.0}}, 1);
    FrameResult forward = render_scene({{blend_of(green, 0.4f), 1.0}}, 1);
    const PassImage& F = *floor_only.find(Pass::Combined);
    const PassImage& P = *pane_opaque.find(Pass::Combined);
    const double worst = worst_inside(*forward.find(Pass::Combined), [&](int x, int y) {
        return 0.4 * pixel4(P, x, y) + 0.6 * pixel4(F, x, y);
    });
    std::printf("one layer, 1 sample: worst relative difference to 0.4 P + 0.6 F: %.2e (forward pass %.1f ms)\n",
                worst, forward.timings.forward_ms);
    EXPECT_LT(worst, 1e-6);
    EXPECT_GT(forward.timings.forward_ms, 0.0);
    EXPECT_EQ(floor_only.timings.forward_ms, 0.0);  // no Blend material: no forward pass
}

TEST(ForwardPass, ShadowRaysLightTheLayerAsTheLightingPassDoes) {
    // With shadow rays the forward pass traces them itself (a fragment
    // shader calling the traversal through its subroutine, selected after
    // each glUseProgram): 0.4 pane + 0.6 floor as in the first test, and the
    // caster's shadow on the pane's right, where the sun's light is gone. An
    // emissive panel lights both too: the forward pass picks the mesh
    // lights' one ray as the lighting pass does (MESH_LIGHT_RAY_POOL).
    const Material green = diffuse(0.25f, 0.75f, 0.375f);
    FrameResult floor_only = render_scene({}, 1, false, true, 0.25f, true, true);
    FrameResult pane_opaque = render_scene({{green, 1.0}}, 1, false, true, 0.25f, true, true);
    FrameResult forward = render_scene({{blend_of(green, 0.4f), 1.0}}, 1, false, true, 0.25f, true, true);
    FrameResult no_emitter = render_scene({{blend_of(green, 0.4f), 1.0}}, 1, false, true, 0.25f, true, false);
    ASSERT_TRUE(forward.timings.shadow_rays);
    const PassImage& F = *floor_only.find(Pass::Combined);
    const PassImage& P = *pane_opaque.find(Pass::Combined);
    const PassImage& C = *forward.find(Pass::Combined);
    const double worst = worst_inside(C, [&](int x, int y) { return 0.4 * pixel4(P, x, y) + 0.6 * pixel4(F, x, y); });
    // The pane at x = 1.5, y = 0.25 (in the shadow) against x = -1.5 (in the
    // sun): pixel (x + 3) * 8, rows from the bottom.
    const glm::dvec4 shadowed = pixel4(C, 36, 26), lit = pixel4(C, 12, 26);
    std::printf("one layer with shadow rays: worst relative difference %.2e; green in and out of the shadow %.4f, "
                "%.4f\n", worst, shadowed.y, lit.y);
    EXPECT_LT(worst, 1e-4);
    EXPECT_LT(shadowed.y, 0.5 * lit.y);  // the caster shadows the pane
    const glm::dvec4 unlit = pixel4(*no_emitter.find(Pass::Combined), 12, 26);
    std::printf("blue of the pane with and without the emissive panel: %.4f, %.4f\n", lit.z, unlit.z);
    EXPECT_GT(lit.z, unlit.z + 0.02);  // the emitter lights the layer
}

TEST(ForwardPass, EqualsStochasticTransparencyConverged) {
    // The same pane with stochastic alpha (Cycles' way) at 256 samples
    // converges to the same composite. Each pixel is the mean of 256
    // Bernoulli(0.4) picks between pane and floor: its standard deviation is
    // |P - F| sqrt(0.24 / 256) = 0.031 |P - F|; over the 256 pane pixels the
    // mean's is 16 x smaller, 0.0019 |P - F|. Bound: 4 of those, on the
    // mean over the pane, channel by channel. The world is black here: its
    // light is itself a one-sample estimate, whose noise is not the subject.
    const Material green = diffuse(0.25f, 0.75f, 0.375f);
    FrameResult forward = render_scene({{blend_of(green, 0.4f), 1.0}}, 1, false, true, 0.0f);
    Material hashed = green;
    hashed.alpha = 0.4f;
    FrameResult stochastic = render_scene({{hashed, 1.0}}, 256, false, true, 0.0f, false, false, true);
    FrameResult floor_only = render_scene({}, 1, false, true, 0.0f);
    FrameResult pane_opaque = render_scene({{green, 1.0}}, 1, false, true, 0.0f);
    glm::dvec4 mean_f(0), mean_s(0), mean_diff(0);
    for (int y = 16; y < 32; ++y)
        for (int x = 16; x < 32; ++x) {
            mean_f += pixel4(*forward.find(Pass::Combined), x, y) / 256.0;
            mean_s += pixel4(*stochastic.find(Pass::Combined), x, y) / 256.0;
            mean_diff += glm::abs(pixel4(*pane_opaque.find(Pass::Combined), x, y) -
                                  pixel4(*floor_only.find(Pass::Combined), x, y)) / 256.0;
        }
    for (int c = 0; c < 3; ++c) {
        std::printf("channel %d: forward %.5f, stochastic x256 %.5f (bound %.5f)\n", c, mean_f[c], mean_s[c],
                    4 * 0.0019 * mean_diff[c]);
        EXPECT_NEAR(mean_f[c], mean_s[c], 4 * 0.0019 * mean_diff[c] + 1e-6);
    }
}

TEST(ForwardPass, PaneBehindAnOpaqueSurfaceIsHiddenExactly) {
    // An opaque plane at z = 2 over a Blend pane at z = 1: the image is the
    // same as without the pane, to the bit.
    Material top = diffuse(0.5f, 0.5f, 0.8f);
    FrameResult without = render_scene({{top, 2.0}}, 4);
    FrameResult with = render_scene({{top, 2.0}, {blend_of(diffuse(0.9f, 0.9f, 0.1f), 0.5f), 1.0}}, 4);
    const PassImage& a = *without.find(Pass::Combined);
    const PassImage& b = *with.find(Pass::Combined);
    double worst = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) worst = std::max(worst, double(std::abs(a.pixels[i] - b.pixels[i])));
    EXPECT_EQ(worst, 0.0);
}

TEST(ForwardPass, LayersAreCompositedInDepthOrder) {
    // Two panes of alpha 0.5 (red at z = 1, blue at z = 2), added nearest
    // first: 0.5 blue + 0.25 red + 0.25 floor.
    const Material red = diffuse(0.75f, 0.125f, 0.125f), blue = diffuse(0.125f, 0.125f, 0.75f);
    FrameResult F = render_scene({}, 1), R = render_scene({{red, 1.0}}, 1), B = render_scene({{blue, 2.0}}, 1);
    FrameResult both = render_scene({{blend_of(red, 0.5f), 1.0}, {blend_of(blue, 0.5f), 2.0}}, 1);
    const double worst = worst_inside(*both.find(Pass::Combined), [&](int x, int y) {
        return 0.5 * pixel4(*B.find(Pass::Combined), x, y) + 0.25 * pixel4(*R.find(Pass::Combined), x, y) +
               0.25 * pixel4(*F.find(Pass::Combined), x, y);
    });
    std::printf("two layers: worst relative difference %.2e\n", worst);
    EXPECT_LT(worst, 1e-6);
}

TEST(ForwardPass, FilmTransparentAlphaIsOneMinusTransmittance) {
    // Over nothing, with Film > Transparent: alpha 1 - (1 - 0.4)(1 - 0.5) = 0.7.
    FrameResult f = render_scene({{blend_of(diffuse(0.5f, 0.5f, 0.5f), 0.4f), 1.0},
                                  {blend_of(diffuse(0.5f, 0.5f, 0.5f), 0.5f), 2.0}},
                                 1, /*film_transparent=*/true, /*with_floor=*/false);
    const glm::dvec4 p = pixel4(*f.find(Pass::Combined), 24, 24);
    EXPECT_NEAR(p.a, 0.7, 1e-6);
    EXPECT_EQ(pixel4(*f.find(Pass::Combined), 2, 2).a, 0.0);  // outside the panes: transparent
}

// Stochastic alpha (frame_lib.glsl transparency_random) is stratified over a
// pixel's samples: a pane of alpha 0.3 over the floor, at the pixel centres
// and under a black world (nothing else varies between samples), is kept in
// N a samples out of N give or take one, where independent picks would give
// a per-pixel RMS error of sqrt(a (1 - a) / N) of the pane-floor contrast
// (0.229 at 4 samples, 0.115 at 16). Measured 0.10 and 0.026 (the
// expectations for one point per 1/N of [0, 1): 0.10, 0.025).
TEST(StochasticAlpha, IsStratifiedOverAPixelsSamples) {
    const Material green = diffuse(0.25f, 0.75f, 0.375f);
    Material hashed = green;
    hashed.alpha = 0.3f;
    const FrameResult floor_only = render_scene({}, 1, false, true, 0.0f);
    const FrameResult pane_opaque = render_scene({{green, 1.0}}, 1, false, true, 0.0f);
    for (int samples : {4, 16}) {
        const FrameResult stochastic = render_scene({{hashed, 1.0}}, samples, false, true, 0.0f, false, false, true);
        double sum = 0.0;
        int n = 0;
        for (int y = 16; y < 32; ++y)
            for (int x = 16; x < 32; ++x) {
                const double P = pixel4(*pane_opaque.find(Pass::Combined), x, y).y;
                const double F = pixel4(*floor_only.find(Pass::Combined), x, y).y;
                const double C = pixel4(*stochastic.find(Pass::Combined), x, y).y;
                const double e = (C - (0.3 * P + 0.7 * F)) / (P - F);
                sum += e * e;
                ++n;
            }
        const double rms = std::sqrt(sum / n), independent = std::sqrt(0.3 * 0.7 / samples);
        std::printf("%d samples: per-pixel RMS error %.4f of the contrast, independent picks %.4f\n", samples, rms,
                    independent);
        EXPECT_LT(rms, 0.6 * independent);
    }
}

// ... and two surfaces' sequences do not pair up: two panes of alpha 0.5
// converge in every pixel to 0.5 blue + 0.25 red + 0.25 floor (a shared
// sequence would keep or drop both together in a pixel-dependent share of
// the samples: errors up to a quarter of the contrast that no sample count
// removes). 256 samples: measured worst 0.05 of the contrast, RMS 0.02
// (independent picks: RMS ~0.03).
TEST(StochasticAlpha, StackedLayersConvergeInEveryPixel) {
    const Material red = diffuse(0.75f, 0.125f, 0.125f), blue = diffuse(0.125f, 0.125f, 0.75f);
    Material red_hashed = red, blue_hashed = blue;
    red_hashed.alpha = blue_hashed.alpha = 0.5f;
    const FrameResult F = render_scene({}, 1, false, true, 0.0f), R = render_scene({{red, 1.0}}, 1, false, true, 0.0f),
                      B = render_scene({{blue, 2.0}}, 1, false, true, 0.0f);
    const FrameResult both =
        render_scene({{red_hashed, 1.0}, {blue_hashed, 2.0}}, 256, false, true, 0.0f, false, false, true);
    double worst = 0.0, sum = 0.0;
    int n = 0;
    for (int y = 16; y < 32; ++y)
        for (int x = 16; x < 32; ++x) {
            const glm::dvec4 f = pixel4(*F.find(Pass::Combined), x, y), r = pixel4(*R.find(Pass::Combined), x, y),
                             b = pixel4(*B.find(Pass::Combined), x, y);
            const glm::dvec4 want = 0.5 * b + 0.25 * r + 0.25 * f, got = pixel4(*both.find(Pass::Combined), x, y);
            for (int c = 0; c < 3; ++c) {
                const double contrast = std::max({std::abs(b[c] - f[c]), std::abs(r[c] - f[c]), std::abs(b[c] - r[c])});
                const double e = (got[c] - want[c]) / contrast;
                worst = std::max(worst, std::abs(e));
                sum += e * e;
                ++n;
            }
        }
    std::printf("two layers, 256 samples: worst %.4f, RMS %.4f of the contrast\n", worst, std::sqrt(sum / n));
    EXPECT_LT(worst, 0.12);
    EXPECT_LT(std::sqrt(sum / n), 0.05);
}

// A cloud of `count` tiny triangles (1 cm) scattered over x, y in [-6, 6],
// z in [2, 6], in one mesh: shadow rays crossing it visit many boxes.
tools::MeshArrays triangle_cloud(int count) {
    tools::MeshArrays m;
    std::uint32_t state = 12345u;
    auto random = [&]() {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1 << 24);
    };
    for (int t = 0; t < count; ++t) {
        const float c[3] = {-6.0f + 12.0f * random(), -6.0f + 12.0f * random(), 2.0f + 4.0f * random()};
        for (int k = 0; k < 3; ++k) {
            for (int axis = 0; axis < 3; ++axis) m.positions.push_back(c[axis] + 0.01f * random());
            m.indices.push_back(std::uint32_t(3 * t + k));
        }
    }
    return m;
}

// The forward pass shades its lights in the lighting pass's batches
// (forward_module.h): llvmpipe ends all loops of an invocation after 65 535
// iterations, and one fragment looping over 160 point lights whose shadow
// rays cross a cloud of 40 000 triangles kept about a third of their light
// (the pane at 0.40 of the opaque pane's 1.38 with 256 lights), silently.
// A Blend pane of alpha 1 is the opaque pane lit by the forward pass: with
// 160 lights and rays it takes 20 draws of 8 lights and equals the lighting
// pass's image; with 600 lights and maps (no rays) 2 draws of 512, where
// before only the first 512 lit it.
TEST(ForwardPass, ManyLightsAreDrawnInTheLightingsBatches) {
    auto render = [&](bool blend, int lights, bool rays) {
        Renderer r;
        set_world_color(r, 0.0f, 0.0f, 0.0f);
        add_plane(r, diffuse(0.75f, 0.375f, 0.25f), 10.0f);
        Material green = diffuse(0.25f, 0.75f, 0.375f);
        add_plane(r, blend ? blend_of(green, 1.0f) : green, 2.0f, 1, tools::translation(0, 0, 1.0), false);
        if (rays) {
            const tools::MeshArrays cloud = triangle_cloud(40000);
            const Mat4d I = identity_matrix();
            r.add_instances(r.add_mesh(cloud.view()), I.data(), 1, nullptr, {r.add_material(diffuse(0.5f, 0.5f, 0.5f))});
        }
        for (int k = 0; k < lights; ++k) {
            Light l;
            l.type = LightType::Point;
            l.cast_shadow = rays;
            l.matrix = tools::translation(-5.0 + 10.0 * ((k % 25) / 24.0), -5.0 + 10.0 * ((k / 25 % 25) / 24.0),
                                          8.0 + 0.5 * (k / 625));
            l.energy = 20.0f;
            r.add_light(l);
        }
        RenderSettings s;
        s.shadow_rays = rays;
        s.shadows = rays;
        s.width = s.height = kSize;
        s.samples = 1;
        s.filter_width = 0.01f;
        s.light_culling = false;
        return r.render(top_down_ortho(10.0, 6.0f), s);
    };
    for (auto [lights, rays, draws] : {std::tuple{160, true, 20u}, std::tuple{600, false, 2u}}) {
        const FrameResult opaque = render(false, lights, rays), forward = render(true, lights, rays);
        const PassImage& O = *opaque.find(Pass::Combined);
        const double worst = worst_inside(*forward.find(Pass::Combined), [&](int x, int y) { return pixel4(O, x, y); });
        std::printf("%d lights%s: %u forward draws, worst relative difference to the opaque pane %.2e (green %.4f)\n",
                    lights, rays ? " with shadow rays" : "", forward.timings.forward_batches, worst,
                    pixel4(O, 24, 24).y);
        EXPECT_EQ(forward.timings.forward_batches, draws);
        EXPECT_EQ(opaque.timings.forward_batches, 0u);
        EXPECT_GT(pixel4(O, 24, 24).y, 0.5);
        EXPECT_LT(worst, 1e-5);
        for (const std::string& w : forward.warnings) EXPECT_EQ(w.find("are lit by the first"), std::string::npos) << w;
    }
}

// A cancel stops a frame whose forward pass draws in batches (a cancel is
// checked before each later batch, and the pass restores the GL state it
// changed); the next frame equals the same frame rendered before it.
TEST(ForwardPass, ACancelledFrameOfManyBatchesLeavesTheNextFrameExact) {
    Renderer r;
    set_world_color(r, 0.1f, 0.1f, 0.1f);
    add_plane(r, diffuse(0.75f, 0.375f, 0.25f), 10.0f);
    add_plane(r, blend_of(diffuse(0.25f, 0.75f, 0.375f), 0.5f), 2.0f, 1, tools::translation(0, 0, 1.0), false);
    for (int k = 0; k < 600; ++k) {
        Light l;
        l.type = LightType::Point;
        l.matrix = tools::translation(-5.0 + 0.4 * (k % 25), -5.0 + 0.4 * (k / 25 % 25), 8.0);
        l.energy = 5.0f;
        r.add_light(l);
    }
    const Camera cam = top_down_ortho(10.0, 6.0f);
    RenderSettings plain;
    plain.width = plain.height = 32;
    plain.samples = 2;
    plain.shadows = false;
    plain.light_culling = false;
    plain.preview_interval_ms = 0;
    const FrameResult expected = r.render(cam, plain);
    ASSERT_EQ(expected.timings.forward_batches, 2u);
    PreviewImage before;
    ASSERT_TRUE(r.preview(0, before));
    RenderSettings busy = plain;
    busy.samples = 65536;  // far more than the cancel lets run
    EXPECT_TRUE(render_cancelled_once_begun(r, cam, busy, before.version));
    const FrameResult after = r.render(cam, plain);
    const PassImage& a = *after.find(Pass::Combined);
    const PassImage& e = *expected.find(Pass::Combined);
    ASSERT_EQ(a.pixels.size(), e.pixels.size());
    for (std::size_t i = 0; i < a.pixels.size(); ++i) ASSERT_EQ(a.pixels[i], e.pixels[i]) << i;
}

// Partly transparent planes as exact layers (layer_order.h,
// RenderSettings::exact_transparent_planes): a pane of alpha 0.4 that is
// not in Blend mode is composited by the forward pass at every sample in a
// Combined-only frame, so ONE sample is already 0.4 pane + 0.6 floor (the
// stochastic path shows pane or floor at each pixel and converges there,
// EqualsStochasticTransparencyConverged).
TEST(ExactLayers, APartlyTransparentPaneIsTheExactCompositeAtOneSample) {
    const Material green = diffuse(0.25f, 0.75f, 0.375f);
    Material pane = green;
    pane.alpha = 0.4f;
    const FrameResult floor_only = render_scene({}, 1), pane_opaque = render_scene({{green, 1.0}}, 1);
    const FrameResult exact = render_scene({{pane, 1.0}}, 1);
    const FrameResult stochastic = render_scene({{pane, 1.0}}, 1, false, true, 0.25f, false, false, true);
    const PassImage& F = *floor_only.find(Pass::Combined);
    const PassImage& P = *pane_opaque.find(Pass::Combined);
    auto composite = [&](int x, int y) { return 0.4 * pixel4(P, x, y) + 0.6 * pixel4(F, x, y); };
    const double worst = worst_inside(*exact.find(Pass::Combined), composite);
    const double worst_stochastic = worst_inside(*stochastic.find(Pass::Combined), composite);
    std::printf("exact layer, 1 sample: worst relative difference to 0.4 P + 0.6 F %.2e (stochastic %.2e)\n", worst,
                worst_stochastic);
    EXPECT_EQ(exact.timings.exact_layers, 1u);
    EXPECT_GT(exact.timings.forward_ms, 0.0);
    EXPECT_LT(worst, 1e-6);
    EXPECT_EQ(stochastic.timings.exact_layers, 0u);
    EXPECT_GT(worst_stochastic, 0.1);  // pane or floor, not the mix
    EXPECT_TRUE(exact.warnings.empty());
}

namespace {

// Column-major rotation about y by atan(slope) (z rises `slope` per x), then
// a lift to z = height.
Mat4d tilted(double slope, double height) {
    const double c = 1.0 / std::sqrt(1.0 + slope * slope), s = slope * c;
    Mat4d m = identity_matrix();
    m[0] = c;
    m[2] = s;
    m[8] = -s;
    m[10] = c;
    m[14] = height;
    return m;
}

struct LayerScene {
    Material big, small;        // the tilted pane's and the small pane's
    bool with_big = true, with_small = true, small_is_box = false;
    std::vector<Pass> passes;   // besides Combined
    double small_height = 1.2;  // the small pane's z (over x -2..-1)
};

// A floor, a big pane tilted through z = 1.5 (z = 1.5 + 0.5 x, half size
// 2), and a small one (half size 0.5) at x = -1.5, above the big pane's low
// end: nearer the eye there, though its centre is farther than the big
// pane's (the distance sort of Blend-mode layers would put it behind).
FrameResult render_layers(const LayerScene& l) {
    Renderer r;
    add_sun_and_floor(r, 0.25f);
    if (l.with_big) add_plane(r, l.big, 2.0f, 1, tilted(0.5, 1.5), false);
    if (l.with_small) {
        if (l.small_is_box) {
            const tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.05f);
            const std::uint32_t mesh = r.add_mesh(box.view());
            const std::uint32_t mat = r.add_material(l.small);
            const Mat4d at = tools::translation(-1.5, 0.0, l.small_height);
            r.add_instances(mesh, at.data(), 1, nullptr, {mat}, false);
        } else {
            add_plane(r, l.small, 0.5f, 1, tools::translation(-1.5, 0.0, l.small_height), false);
        }
    }
    RenderSettings s;
    s.width = s.height = kSize;
    s.samples = 1;
    s.filter_width = 0.01f;
    for (Pass p : l.passes) s.passes.insert(p);
    return r.render(top_down_ortho(10.0, 6.0f), s);
}

}  // namespace

TEST(ExactLayers, AreDrawnInThePlaneTestsOrder) {
    // Where the panes overlap (x -1.75..-1): small over big over floor,
    // a_s S + (1 - a_s)(a_b B + (1 - a_b) F), each surface lit as when it
    // is alone and opaque; the other order would give a_b B + (1 - a_b)
    // (a_s S + (1 - a_s) F), which differs by 0.25 |S - B| here.
    const Material red = diffuse(0.75f, 0.125f, 0.125f), blue = diffuse(0.125f, 0.125f, 0.75f);
    LayerScene l;
    l.big = blue;
    l.small = red;
    l.with_small = false;
    const FrameResult B = render_layers(l);
    l.with_small = true;
    l.with_big = false;
    const FrameResult S = render_layers(l);
    l.with_small = false;
    const FrameResult F = render_layers(l);
    l.with_big = l.with_small = true;
    l.big.alpha = 0.5f;
    l.small.alpha = 0.5f;
    const FrameResult both = render_layers(l);
    EXPECT_EQ(both.timings.exact_layers, 2u);
    double worst = 0.0, worst_other = 0.0;
    // Pixel (x + 3) * 8, (y + 3) * 8: x -1.6..-1.1, y -0.4..0.4.
    for (int y = 22; y <= 26; ++y)
        for (int x = 12; x <= 15; ++x) {
            const glm::dvec4 b = pixel4(*B.find(Pass::Combined), x, y), s = pixel4(*S.find(Pass::Combined), x, y),
                             f = pixel4(*F.find(Pass::Combined), x, y), got = pixel4(*both.find(Pass::Combined), x, y);
            const glm::dvec4 want = 0.5 * s + 0.5 * (0.5 * b + 0.5 * f), other = 0.5 * b + 0.5 * (0.5 * s + 0.5 * f);
            for (int c = 0; c < 3; ++c) {
                worst = std::max(worst, std::abs(got[c] - want[c]) / std::max(want[c], 0.05));
                worst_other = std::max(worst_other, std::abs(got[c] - other[c]) / std::max(other[c], 0.05));
            }
        }
    std::printf("tilted and small pane: worst relative difference %.2e to small-over-big, %.2e to the other order\n",
                worst, worst_other);
    EXPECT_LT(worst, 1e-5);
    EXPECT_GT(worst_other, 0.1);
}

TEST(ExactLayers, AreTakenOnlyWhereTheyAreExact) {
    // A small pane crossing the tilted one (each cuts the other's plane
    // where both are): one of them stays stochastic. Each of the other
    // frames keeps every partly transparent surface stochastic but the
    // tilted pane or all of them: a transparent box of six separate
    // faces instead of the pane (neither planar nor closed: a ray may meet
    // it twice, in no known order; a welded box is convex, the next
    // test), a colour pass (the forward layer reaches Combined only; data
    // passes keep the layers, the data G-buffer has them), a Blend-mode
    // material (the forward pass orders those by object).
    const Material red = diffuse(0.75f, 0.125f, 0.125f), blue = diffuse(0.125f, 0.125f, 0.75f);
    LayerScene base;
    base.big = blue;
    base.small = red;
    base.big.alpha = base.small.alpha = 0.5f;
    EXPECT_EQ(render_layers(base).timings.exact_layers, 2u);
    LayerScene crossing = base;
    crossing.small_height = 0.75;  // the big pane is at z 0.5..1 below x -2..-1
    EXPECT_EQ(render_layers(crossing).timings.exact_layers, 1u);
    LayerScene box = base;
    box.small_is_box = true;
    EXPECT_EQ(render_layers(box).timings.exact_layers, 1u);  // the tilted pane alone
    LayerScene opaque_box = box;
    opaque_box.small.alpha = 1.0f;
    EXPECT_EQ(render_layers(opaque_box).timings.exact_layers, 1u);
    LayerScene normal = base;
    normal.passes = {Pass::Normal, Pass::Depth};  // data passes: the data G-buffer has them
    EXPECT_EQ(render_layers(normal).timings.exact_layers, 2u);
    LayerScene colour = base;
    colour.passes = {Pass::Normal, Pass::DiffCol};
    EXPECT_EQ(render_layers(colour).timings.exact_layers, 0u);
    LayerScene blend = base;
    blend.small.blend = true;
    const FrameResult with_blend = render_layers(blend);
    EXPECT_EQ(with_blend.timings.exact_layers, 0u);
    EXPECT_GT(with_blend.timings.forward_ms, 0.0);  // the Blend pane is still drawn forward
}

namespace {

// A closed box (8 shared vertices, 12 triangles wound outwards): a convex
// solid (mesh_topology.h convex_mesh), unlike tools::make_box's separate faces.
tools::MeshArrays welded_box(float hx, float hy, float hz) {
    tools::MeshArrays m;
    for (int c = 0; c < 8; ++c)
        m.positions.insert(m.positions.end(), {c & 1 ? hx : -hx, c & 2 ? hy : -hy, c & 4 ? hz : -hz});
    // Each face's corners counter-clockwise seen from outside.
    const std::uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) m.indices.insert(m.indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
    return m;
}

}  // namespace

TEST(ExactLayers, AConvexSolidIsItsNearSideThenItsFarSide) {
    // A closed box over the floor, seen from above, its top red and its
    // other faces blue, all of alpha 0.5: every ray meets the top (from the
    // front), then the bottom (from behind). As an exact layer, drawn near
    // side then far side, ONE sample is 0.5 red + 0.25 blue + 0.25 floor
    // (the other order would be 0.5 blue + 0.25 red + 0.25 floor); it
    // equals stochastic coverage at 256 samples over the box (mean per
    // channel, within 4 of the mean's standard deviations, from one
    // stochastic sample's per-pixel spread).
    auto render = [](bool stochastic, int samples) {
        Renderer r;
        add_sun_and_floor(r, 0.0f);
        Material red = diffuse(0.75f, 0.125f, 0.125f), blue = diffuse(0.125f, 0.125f, 0.75f);
        red.alpha = blue.alpha = 0.5f;
        const tools::MeshArrays box = welded_box(2.0f, 2.0f, 0.25f);
        std::vector<std::int32_t> slots(box.indices.size() / 3, 1);
        slots[2] = slots[3] = 0;  // the +z face (faces[1])
        MeshData data = box.view();
        data.material_indices = slots.data();
        const std::uint32_t mesh = r.add_mesh(data);
        const std::uint32_t red_id = r.add_material(red), blue_id = r.add_material(blue);
        const Mat4d at = tools::translation(0.0, 0.0, 1.0);
        r.add_instances(mesh, at.data(), 1, nullptr, {red_id, blue_id}, false);
        RenderSettings s;
        s.width = s.height = kSize;
        s.samples = samples;
        s.filter_width = 0.01f;
        s.exact_transparent_planes = !stochastic;
        return r.render(top_down_ortho(10.0, 6.0f), s);
    };
    const FrameResult exact = render(false, 1), stochastic = render(true, 256), one = render(true, 1);
    EXPECT_EQ(exact.timings.exact_layers, 1u);
    EXPECT_EQ(stochastic.timings.exact_layers, 0u);
    glm::dvec4 mean_e(0), mean_s(0);
    for (int y = 16; y < 32; ++y)
        for (int x = 16; x < 32; ++x) {
            mean_e += pixel4(*exact.find(Pass::Combined), x, y) / 256.0;
            mean_s += pixel4(*stochastic.find(Pass::Combined), x, y) / 256.0;
        }
    double sd_one = 0.0, sd_exact = 0.0;
    for (int y = 16; y < 32; ++y)
        for (int x = 16; x < 32; ++x) {
            const glm::dvec3 d1 = glm::dvec3(pixel4(*one.find(Pass::Combined), x, y) - mean_s);
            const glm::dvec3 de = glm::dvec3(pixel4(*exact.find(Pass::Combined), x, y) - mean_s);
            sd_one += glm::dot(d1, d1) / 256.0;
            sd_exact += glm::dot(de, de) / 256.0;
        }
    sd_one = std::sqrt(sd_one);
    sd_exact = std::sqrt(sd_exact);
    std::printf("closed box: exact at 1 sample %.5f %.5f %.5f, stochastic x256 %.5f %.5f %.5f; per-pixel spread "
                "around it at 1 sample: stochastic %.4f, exact %.4f\n", mean_e.x, mean_e.y, mean_e.z, mean_s.x,
                mean_s.y, mean_s.z, sd_one, sd_exact);
    // 256 pixels x 256 samples: the mean's standard deviation is sd_one / 256.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean_e[c], mean_s[c], 4.0 * sd_one / 256.0 + 1e-6);
    EXPECT_GT(mean_e.x, mean_e.z + 0.05);  // red over blue: the near side first
    EXPECT_LT(sd_exact, 0.1 * sd_one);
}

TEST(ExactLayers, DataPassesKeepTheAlphaThreshold) {
    // With Depth and IndexOB asked, the pane is still an exact layer in
    // Combined (one sample: the composite of the opaque renders), and the
    // data passes come from the data G-buffer as with stochastic alpha: a
    // pane of alpha 0.6 reaches the Alpha Threshold (0.5) and is the depth
    // there, one of 0.4 is not (the floor's depth shows). Orthographic from
    // z = 10: the pane at z = 1 is at depth 9, the floor at 10. Through the
    // visibility buffer and the raster G-buffer.
    const Material green = diffuse(0.25f, 0.75f, 0.375f);
    for (bool visibility : {true, false}) {
        auto render = [&](float alpha, bool with_pane) {
            Renderer r;
            add_sun_and_floor(r, 0.25f);
            Material pane = green;
            pane.alpha = alpha;
            if (with_pane) add_plane(r, pane, 2.0f, 1, tools::translation(0, 0, 1.0), false);
            RenderSettings s;
            s.width = s.height = kSize;
            s.samples = 1;
            s.filter_width = 0.01f;
            s.passes.insert(Pass::Depth);
            s.passes.insert(Pass::IndexOB);
            s.visibility_buffer = visibility;
            return r.render(top_down_ortho(10.0, 6.0f), s);
        };
        const FrameResult floor_only = render(1.0f, false), opaque = render(1.0f, true);
        for (float alpha : {0.4f, 0.6f}) {
            const FrameResult f = render(alpha, true);
            EXPECT_EQ(f.timings.exact_layers, 1u);
            EXPECT_TRUE(f.warnings.empty()) << f.warnings.front();
            const PassImage& depth = *f.find(Pass::Depth);
            const double d = depth.pixels[(std::size_t(24) * depth.width + 24) * depth.channels];
            const double worst = worst_inside(*f.find(Pass::Combined), [&](int x, int y) {
                return double(alpha) * pixel4(*opaque.find(Pass::Combined), x, y) +
                       double(1.0f - alpha) * pixel4(*floor_only.find(Pass::Combined), x, y);
            });
            std::printf("%s, alpha %.1f with Depth and IndexOB: depth at the pane %.4f; Combined's worst relative "
                        "difference to the composite %.2e\n", visibility ? "visibility buffer" : "raster G-buffer", alpha,
                        d, worst);
            EXPECT_EQ(f.timings.visibility_buffer, visibility);
            EXPECT_NEAR(d, alpha >= 0.5f ? 9.0 : 10.0, 1e-3);
            EXPECT_LT(worst, 1e-5);
        }
    }
}
