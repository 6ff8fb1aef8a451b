// World light with occlusion: a constant world colour lights an open floor
// exactly (no false occlusion from the world's shadow maps), and the AO pass
// under a square plate converges to the plate's cosine-weighted form factor.
#include "test_helpers.h"

#include "cycles_oracle.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace deferred;
using deferred::testing::pixel3;

namespace {

// Form factor from a differential area (normal towards the rectangle) to a
// parallel rectangle with one corner straight above it: X = width/h,
// Y = length/h (Howell's catalogue, configuration B-3).
double corner_form_factor(double X, double Y) {
    const double sx = std::sqrt(1.0 + X * X), sy = std::sqrt(1.0 + Y * Y);
    return (X / sx * std::atan(Y / sx) + Y / sy * std::atan(X / sy)) / (2.0 * M_PI);
}

// Cosine-weighted fraction of the hemisphere of (px, py, 0) blocked by the
// square |x|, |y| <= a at height h.
double plate_blocked_fraction(double px, double py, double a, double h) {
    double f = 0;
    for (double w : {a - px, a + px})
        for (double l : {a - py, a + py}) f += corner_form_factor(w / h, l / h);
    return f;
}

// An open floor (nothing above it) under a constant world, seen in
// perspective from `eye`, with Position and Depth.
FrameResult open_floor(const Material& m, const glm::vec3& world, const double eye[3], const double target[3],
                       int width, int height, int samples, PassSet passes = {}) {
    Renderer r;
    deferred::testing::add_plane(r, m, 50.0f, 8);
    deferred::testing::set_world_color(r, world.x, world.y, world.z);
    Camera cam;
    cam.matrix = tools::look_at(eye, target);
    RenderSettings s;
    s.width = width;
    s.height = height;
    s.samples = samples;
    s.filter_width = 0.01f;
    s.passes = passes;
    s.passes.insert(Pass::Position);
    s.passes.insert(Pass::Depth);
    return r.render(cam, s);
}

// Largest relative error of Combined against world x the oracle's
// directional albedo (every lobe) over every `stride`-th floor pixel.
double max_error_against_albedo(const FrameResult& f, const Material& m, const glm::vec3& world, const double eye[3],
                                int stride, int quadrature) {
    const PassImage& c = *f.find(Pass::Combined);
    const PassImage& pos = *f.find(Pass::Position);
    const PassImage& depth = *f.find(Pass::Depth);
    double worst = 0;
    for (int y = 0; y < c.height; ++y)
        for (int x = 0; x < c.width; ++x) {
            if ((x + y * c.width) % stride != 0 || pixel3(depth, x, y).x > 1e9) continue;
            const glm::dvec3 V = glm::normalize(glm::dvec3(eye[0], eye[1], eye[2]) - pixel3(pos, x, y));
            const oracle::Lobes a = oracle::hemisphere_albedo(m, glm::dvec3(0, 0, 1), V, quadrature);
            const glm::dvec3 expect = (a.diffuse + a.sheen + a.specular + a.clearcoat) * glm::dvec3(world);
            const glm::dvec3 got = pixel3(c, x, y);
            for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(got[k] - expect[k]) / expect[k]);
        }
    return worst;
}

Material white_floor() {
    Material m;
    m.base_color = {0.75f, 0.75f, 0.75f};
    m.roughness = 0.5f;
    m.specular = 0.0f;
    return m;
}

}  // namespace

TEST(WorldLight, OpenFloorIsLitExactlyByTheWorld) {
    // No occluder: the control variate subtracts nothing, every pixel is
    // Lw x the Burley lobe's directional albedo (the oracle's quadrature)
    // whatever the sample's world direction (a false occlusion in any of the
    // 16 maps would darken pixels). Perspective at a grazing view so the
    // floor spans many depths and view angles.
    const glm::vec3 world(1.0f, 0.5f, 0.25f);
    const double eye[3] = {0.0, -6.0, 1.0}, target[3] = {0.0, 10.0, 0.0};
    const FrameResult f = open_floor(white_floor(), world, eye, target, 96, 64, 16, {Pass::AO});
    const PassImage& ao = *f.find(Pass::AO);
    const PassImage& depth = *f.find(Pass::Depth);
    double worst_ao = 0;
    int floor_pixels = 0;
    for (int y = 0; y < ao.height; ++y)
        for (int x = 0; x < ao.width; ++x) {
            if (pixel3(depth, x, y).x > 1e9) continue;
            ++floor_pixels;
            worst_ao = std::max(worst_ao, std::abs(pixel3(ao, x, y).x - 1.0));
        }
    // The quadrature is slow: every 7th pixel.
    const double worst = max_error_against_albedo(f, white_floor(), world, eye, 7, 64);
    std::printf("open floor under the world: %d pixels, max relative error %.2e, max |AO - 1| %.2e\n",
                floor_pixels, worst, worst_ao);
    EXPECT_GT(floor_pixels, 1000);
    EXPECT_LT(worst, 1e-3);
    EXPECT_LT(worst_ao, 1e-6);
}

TEST(WorldLight, DiffuseBsdfFloorIsLitByItsOwnAlbedo) {
    // A Diffuse BSDF (Oren-Nayar; sigma 0 is Lambert, albedo exactly 1)
    // under a uniform world: the closed-form directional albedo of
    // bsdf_lib.glsl against the oracle's quadrature of Cycles' eval, over
    // the grazing-to-steep view angles of the perspective floor.
    const glm::vec3 world(1.0f, 0.5f, 0.25f);
    const double eye[3] = {0.0, -6.0, 1.0}, target[3] = {0.0, 10.0, 0.0};
    for (float sigma : {0.0f, 0.5f, 1.0f}) {
        Material m = white_floor();
        m.diffuse_roughness = sigma;
        const FrameResult f = open_floor(m, world, eye, target, 96, 64, 4, {});
        const double worst = max_error_against_albedo(f, m, world, eye, 11, 96);
        std::printf("Diffuse BSDF floor, sigma %.1f: max relative error against the albedo %.2e\n", sigma, worst);
        EXPECT_LT(worst, 1e-3) << "sigma " << sigma;
    }
}

TEST(WorldLight, AmbientOcclusionUnderAPlateConvergesToItsFormFactor) {
    // A 2 m square plate 1 m above the floor; the camera looks down from
    // between them at the 1 m around the centre. AO there is 1 minus the
    // plate's form factor (0.554 blocked at the centre).
    Renderer r;
    deferred::testing::add_plane(r, white_floor(), 20.0f, 4);
    deferred::testing::add_plane(r, white_floor(), 1.0f, 1, tools::translation(0, 0, 1.0));
    deferred::testing::set_world_color(r, 1.0f, 1.0f, 1.0f);
    const double centre = 1.0 - plate_blocked_fraction(0, 0, 1, 1);
    // The world's map has 4 x quality texels per pixel of the receivers; the
    // plate's edges land within a texel, a small over-occlusion that a finer
    // map shrinks (measured at 1024 samples: max error 0.0143 at quality 1,
    // 0.0115 at quality 4; 0.021 when the map had 1 x quality; RMSE at 16
    // samples 0.065, 0.39 before one map answered for both directions).
    for (float quality : {1.0f, 4.0f}) {
        RenderSettings s;
        s.width = 32;
        s.height = 32;
        s.filter_width = 0.01f;
        s.passes = {Pass::AO, Pass::Position};
        s.shadow_quality = quality;
        double previous = 1e9;
        for (int samples : {16, 256, 1024}) {
            s.samples = samples;
            FrameResult f = r.render(deferred::testing::top_down_ortho(0.5, 1.0f), s);
            const PassImage& ao = *f.find(Pass::AO);
            const PassImage& pos = *f.find(Pass::Position);
            double se = 0, worst = 0;
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) {
                    const glm::dvec3 P = pixel3(pos, x, y);
                    const double d = pixel3(ao, x, y).x - (1.0 - plate_blocked_fraction(P.x, P.y, 1.0, 1.0));
                    se += d * d;
                    worst = std::max(worst, std::abs(d));
                }
            const double rmse = std::sqrt(se / (s.width * s.height));
            std::printf("AO under a plate, quality %.0f, %4d samples: centre %.4f (expects %.4f), RMSE %.4f, max "
                        "error %.4f\n", quality, samples, pixel3(ao, 16, 16).x, centre, rmse, worst);
            EXPECT_LT(rmse, previous);
            previous = rmse;
            if (samples == 1024) {
                EXPECT_LT(worst, quality > 1.0f ? 0.015 : 0.02);
            }
        }
    }
}

TEST(WorldLight, SpecularAndSheenAlbedoConvergeToTheOracle) {
    // An open floor, metallic (specular only) and a sheen-coated diffuse
    // one: the world's glossy / sheen light is sampled per film sample
    // (GGX visible normals, cosine directions) and converges to the oracle's
    // hemisphere quadrature.
    Material metal;
    metal.base_color = {0.9f, 0.6f, 0.3f};
    metal.metallic = 1.0f;
    metal.roughness = 0.4f;
    Material cloth = white_floor();
    cloth.sheen = 1.0f;
    cloth.sheen_tint = 0.0f;
    const glm::vec3 white(1.0f);
    const double eye[3] = {0.0, -4.0, 2.0}, target[3] = {0.0, 2.0, 0.0};
    for (const Material& m : {metal, cloth}) {
        const FrameResult f = open_floor(m, white, eye, target, 48, 32, 64);
        const double worst = max_error_against_albedo(f, m, white, eye, 3, 128);
        std::printf("world on an open floor, %s: max relative error %.2e at 64 samples\n",
                    m.metallic > 0 ? "metal roughness 0.4" : "diffuse + sheen", worst);
        EXPECT_LT(worst, 0.01);
    }
}
