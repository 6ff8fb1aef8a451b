// Emission samples (RenderSettings::emission_samples, emission_samples.h):
// directly seen emission estimated with K camera samples per film sample.
// The image must converge to the same filtered pixels as without them (an
// unbiased split of the pixel's integral), with less noise at equal film
// samples where small bright emitters are in view; the Emit pass carries
// the same estimate as Combined; frames that cannot use them do not take them.
#include "test_helpers.h"

#include "emission_samples.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

using namespace deferred;

namespace {

constexpr int kSize = 32;

// 24 emissive squares 0.06 m wide (about a third of a pixel's area each at
// 0.1 m a pixel) at z = 0.05, spread over the view off the pixel grid,
// casting no shadow; their radiance `radiance` (the largest channel).
void add_emitters(Renderer& r, float radiance) {
    Material emit;
    emit.base_color = {0.0f, 0.0f, 0.0f};
    emit.specular = 0.0f;
    emit.emission = {1.0f, 0.8f, 0.5f};
    emit.emission_strength = radiance;
    tools::MeshArrays square = tools::make_plane(0.03f);
    const std::uint32_t mesh = r.add_mesh(square.view());
    const std::uint32_t mat = r.add_material(emit);
    std::vector<double> matrices;
    for (int k = 0; k < 24; ++k) {
        const double x = -1.4 + 0.117 * k + 0.013 * (k % 5), y = -1.3 + 0.109 * ((k * 7) % 24);
        const Mat4d t = tools::translation(x, y, 0.05);
        matrices.insert(matrices.end(), t.begin(), t.end());
    }
    r.add_instances(mesh, matrices.data(), 24, nullptr, {mat}, false);
}

// A dark diffuse floor under a point light, seen from above (orthographic,
// 3.2 m across: 0.1 m a pixel), with the emitters a little above it.
// `lit_floor` false: a black floor (base colour and specular 0) and no
// light, so Combined is the emission alone.
void build_scene(Renderer& r, bool lit_floor, float radiance = 40.0f) {
    Material floor;
    floor.base_color = lit_floor ? Vec3{0.3f, 0.3f, 0.3f} : Vec3{0.0f, 0.0f, 0.0f};
    floor.specular = lit_floor ? 0.5f : 0.0f;
    floor.roughness = 0.5f;
    deferred::testing::add_plane(r, floor, 4.0f);
    add_emitters(r, radiance);
    if (lit_floor) {
        Light l;
        l.type = LightType::Point;
        l.matrix = tools::translation(0.5, -0.3, 2.0);
        l.energy = 200.0f;
        l.radius = 0.0f;
        r.add_light(l);
    }
    deferred::testing::set_world_color(r, 0.0f, 0.0f, 0.0f);
}

RenderSettings settings(int samples, int emission_samples) {
    RenderSettings s;
    s.width = kSize;
    s.height = kSize;
    s.samples = samples;
    s.emission_samples = emission_samples;
    s.shadows = false;
    return s;
}

std::vector<double> combined(const FrameResult& f) {
    const PassImage& img = *f.find(Pass::Combined);
    std::vector<double> out;
    for (std::size_t i = 0; i < img.pixels.size(); ++i)
        if (i % 4 != 3) out.push_back(img.pixels[i]);
    return out;
}

double rmse(const std::vector<double>& a, const std::vector<double>& b) {
    double s = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
    return std::sqrt(s / double(a.size()));
}

double sum(const std::vector<double>& a) {
    double s = 0.0;
    for (double v : a) s += v;
    return s;
}

}  // namespace

TEST(EmissionSamples, SmallEmittersConvergeToTheSameImageWithLessNoise) {
    Renderer r;
    build_scene(r, true);
    const Camera cam = deferred::testing::top_down_ortho(3.0, 3.2f);
    // The converged image: 1024 film samples without emission samples.
    const std::vector<double> reference = combined(r.render(cam, settings(1024, 1)));
    const FrameResult plain = r.render(cam, settings(16, 1));
    const FrameResult more = r.render(cam, settings(16, 4));
    EXPECT_EQ(plain.timings.emission_samples, 1);
    EXPECT_EQ(more.timings.emission_samples, 4);
    const double e_plain = rmse(combined(plain), reference), e_more = rmse(combined(more), reference);
    // Four times the emission's samples: about half the error where the
    // emitters' coverage is the noise (measured 0.48x here).
    EXPECT_LT(e_more, 0.6 * e_plain) << "16 samples: " << e_plain << " without, " << e_more << " with 4 emission samples";
    // No bias: 256 film samples with 4 emission samples each against the
    // reference, in total energy (measured 1.0002) and per pixel (measured
    // 0.01 of the 16-sample error: the jitter is one low-discrepancy
    // sequence for the whole image).
    const std::vector<double> converged = combined(r.render(cam, settings(256, 4)));
    std::printf("16 samples: RMSE %.4f without emission samples, %.4f with 4 (%.2fx); 256 x 4: energy %.5f, RMSE "
                "%.4f of the 16-sample error\n", e_plain, e_more, e_more / e_plain, sum(converged) / sum(reference),
                rmse(converged, reference) / e_plain);
    EXPECT_NEAR(sum(converged) / sum(reference), 1.0, 0.01);
    EXPECT_LT(rmse(converged, reference), 0.1 * e_plain);
    // The lit floor apart from the emitters: the same light either way (the
    // lighting pass's own samples, untouched by the emission samples).
    const PassImage& a = *plain.find(Pass::Combined);
    const PassImage& b = *more.find(Pass::Combined);
    double floor_a = 0.0, floor_b = 0.0;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const glm::dvec3 pa = deferred::testing::pixel3(a, x, y), pb = deferred::testing::pixel3(b, x, y);
            floor_a += std::min(pa.x, 1.0);
            floor_b += std::min(pb.x, 1.0);
        }
    EXPECT_NEAR(floor_b / floor_a, 1.0, 0.05);
}

TEST(EmissionSamples, EmitPassCarriesTheSameEstimateAsCombined) {
    Renderer r;
    build_scene(r, false);  // nothing lit: Combined is the emission alone
    const Camera cam = deferred::testing::top_down_ortho(3.0, 3.2f);
    RenderSettings s = settings(8, 4);
    s.passes.insert(Pass::Emit);
    const FrameResult f = r.render(cam, s);
    ASSERT_EQ(f.timings.emission_samples, 4);
    const PassImage& c = *f.find(Pass::Combined);
    const PassImage& e = *f.find(Pass::Emit);
    double total = 0.0;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const glm::dvec3 pc = deferred::testing::pixel3(c, x, y), pe = deferred::testing::pixel3(e, x, y);
            for (int i = 0; i < 3; ++i) EXPECT_NEAR(pc[i], pe[i], 1e-5 * (1.0 + pc[i])) << x << ", " << y;
            total += pe.x;
        }
    EXPECT_GT(total, 0.0);  // the emitters are seen
}

TEST(EmissionSamples, TakenOnlyWhereTheyCanChangeTheImage) {
    Renderer r;
    build_scene(r, true);
    const Camera cam = deferred::testing::top_down_ortho(3.0, 3.2f);
    EXPECT_EQ(r.render(cam, settings(4, 4)).timings.emission_samples, 4);
    // One film sample: the pixel centre, as without them.
    EXPECT_EQ(r.render(cam, settings(1, 4)).timings.emission_samples, 1);
    // No emitter in view: the camera looks at a corner of the floor away from them.
    Camera away = cam;
    away.matrix = tools::translation(3.3, 3.3, 3.0);
    away.ortho_scale = 1.0f;
    EXPECT_EQ(r.render(away, settings(4, 4)).timings.emission_samples, 1);
    // ... unless motion blur may move one into view over the shutter.
    RenderSettings blurred = settings(4, 4);
    blurred.motion_blur = true;
    EXPECT_EQ(r.render(away, blurred).timings.emission_samples, 4);
    // Automatic (0): these emitters' radiance, 40, is above
    // kAutoEmissionRadiance: kAutoEmissionSamples.
    EXPECT_EQ(r.render(cam, settings(4, 0)).timings.emission_samples, kAutoEmissionSamples);
    // Out of range: an error, not a clamp.
    EXPECT_THROW(r.render(cam, settings(4, -1)), InvalidInput);
    EXPECT_THROW(r.render(cam, settings(4, 65)), InvalidInput);
    // Automatic with dim emitters (radiance 4): none; asked for, taken.
    Renderer dim;
    build_scene(dim, true, 4.0f);
    EXPECT_EQ(dim.render(cam, settings(4, 0)).timings.emission_samples, 1);
    EXPECT_EQ(dim.render(cam, settings(4, 3)).timings.emission_samples, 3);
    // Light groups: the emission would also go to its instance's group.
    Renderer g;
    build_scene(g, true);
    RenderSettings grouped = settings(4, 4);
    grouped.light_groups = 1;
    EXPECT_EQ(g.render(cam, grouped).timings.emission_samples, 1);
}

// Holdouts and shadow catchers keep their own paths: a holdout plane over the
// left third of the emitters (a hole: black) and the floor a shadow catcher
// that emits a little (Combined, the matte, shows no catcher; emission
// samples that added a catcher's emission would put 3/4 of it there: energy
// 1.57x, measured with that mistake made on purpose). With 4 emission samples the image converges to the one without them: the
// hole stays black (exactly) with the same alpha, the whole image's energy
// and alpha agree within the noise.
TEST(EmissionSamples, HoldoutsAndShadowCatchersKeepTheirPaths) {
    auto render = [](int emission_samples) {
        Renderer r;
        Material floor;
        floor.base_color = {0.3f, 0.3f, 0.3f};
        floor.emission = {0.2f, 0.2f, 0.2f};  // a catcher's own emission stays on its path (whole)
        tools::MeshArrays plane = tools::make_plane(4.0f);
        const Mat4d I = identity_matrix();
        r.add_instances(r.add_mesh(plane.view()), I.data(), 1, nullptr, {r.add_material(floor)}, true, nullptr,
                        nullptr, nullptr, false, 0, nullptr, nullptr, /*shadow_catcher=*/true);
        add_emitters(r, 40.0f);
        // The holdout: x in [-1.6, -0.6], above the emitters.
        tools::MeshArrays hole = tools::make_plane(0.5f);
        const Mat4d h = tools::translation(-1.1, 0.0, 0.5);
        Material any;
        r.add_instances(r.add_mesh(hole.view()), h.data(), 1, nullptr, {r.add_material(any)}, false, nullptr,
                        nullptr, nullptr, /*holdout=*/true);
        Light l;
        l.type = LightType::Point;
        l.matrix = tools::translation(0.5, -0.3, 2.0);
        l.energy = 200.0f;
        r.add_light(l);
        deferred::testing::set_world_color(r, 0.0f, 0.0f, 0.0f);
        RenderSettings s = settings(128, emission_samples);
        s.shadows = true;
        return r.render(deferred::testing::top_down_ortho(3.0, 3.2f), s);
    };
    const FrameResult plain = render(1), more = render(4);
    ASSERT_EQ(more.timings.emission_samples, 4);
    const PassImage& a = *plain.find(Pass::Combined);
    const PassImage& b = *more.find(Pass::Combined);
    double energy_a = 0.0, energy_b = 0.0, alpha_a = 0.0, alpha_b = 0.0;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const float* pa = &a.pixels[(std::size_t(y) * kSize + x) * 4];
            const float* pb = &b.pixels[(std::size_t(y) * kSize + x) * 4];
            energy_a += pa[0] + pa[1] + pa[2];
            energy_b += pb[0] + pb[1] + pb[2];
            alpha_a += pa[3];
            alpha_b += pb[3];
            // Pixels well inside the hole (0.1 m a pixel: x -1.5..-0.7, y -0.4..0.4).
            if (x >= 2 && x <= 8 && y >= 12 && y <= 19) {
                for (int c = 0; c < 3; ++c) EXPECT_EQ(pb[c], 0.0f) << x << ", " << y;
                EXPECT_EQ(pb[3], pa[3]) << x << ", " << y;  // (1: opaque film, the catchers' matte resolve)
            }
        }
    std::printf("energy %.5f, alpha %.5f (4 emission samples over none)\n", energy_b / energy_a, alpha_b / alpha_a);
    EXPECT_NEAR(energy_b / energy_a, 1.0, 0.02);
    EXPECT_NEAR(alpha_b / alpha_a, 1.0, 1e-3);
}
