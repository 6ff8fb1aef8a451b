// Tiled light culling against brute force: the difference is bounded by what
// the culled lights can contribute (the threshold's prediction), on random
// scenes and on the edge cases of the issue.
#include "light_module.h"
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace deferred;
using deferred::testing::overview_camera;
using deferred::testing::pixel3;

namespace {

// Floor plus a few boxes, white Lambertian-bounded material (Burley with
// roughness 0 and no specular never exceeds Lambert), black world.
void build_geometry(Renderer& r) {
    Material white;
    white.base_color = {1.0f, 1.0f, 1.0f};
    white.roughness = 0.0f;
    white.specular = 0.0f;
    deferred::testing::add_floor_and_boxes(r, r.add_material(white));
}

std::vector<Light> random_point_lights(int n, std::uint32_t seed, float energy_max) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Light> lights;
    for (int i = 0; i < n; ++i) {
        Light l;
        l.type = LightType::Point;
        l.cast_shadow = false;  // culling under test, not shadows
        l.matrix = tools::translation(-28 + 56 * u(rng), -28 + 56 * u(rng), 0.1 + 3.0 * u(rng));
        l.energy = float(0.05 + energy_max * u(rng));
        l.radius = float(0.02 * u(rng));
        l.color = {float(u(rng)), float(u(rng)), float(u(rng))};
        lights.push_back(l);
    }
    return lights;
}

struct Comparison {
    double max_diff = 0, max_excess = 0;  // excess = diff beyond the predicted bound
    std::uint64_t pairs = 0;
    double culled_ms = 0, brute_ms = 0;
};

// Renders culled and brute force; the bound per pixel is the sum over the
// lights beyond their influence radius of S / (4 pi^2 d^2) (white Lambert).
Comparison compare(const std::vector<Light>& lights, const Camera& cam, int size, float threshold, int samples = 1) {
    Renderer r;
    build_geometry(r);
    for (const Light& l : lights) r.add_light(l);
    RenderSettings s;
    s.width = size;
    s.height = size;
    s.samples = samples;
    s.light_threshold = threshold;
    s.passes = {Pass::Position};
    FrameResult culled = r.render(cam, s);
    s.light_culling = false;
    FrameResult brute = r.render(cam, s);
    Comparison c;
    c.pairs = culled.timings.tile_light_pairs;
    c.culled_ms = culled.timings.culling_ms + culled.timings.lighting_ms;
    c.brute_ms = brute.timings.lighting_ms;
    const PassImage& a = *culled.find(Pass::Combined);
    const PassImage& b = *brute.find(Pass::Combined);
    const PassImage& pos = *culled.find(Pass::Position);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const glm::dvec3 P = pixel3(pos, x, y);
            double bound = 0;
            for (const Light& l : lights) {
                const double radius = influence_radius(l, threshold);
                const glm::dvec3 lp(l.matrix[12], l.matrix[13], l.matrix[14]);
                const double d = glm::length(P - lp);
                if (radius >= 0 && d > radius) {
                    const double S = std::abs(l.energy) * std::max({l.color[0], l.color[1], l.color[2]});
                    bound += S / (4.0 * M_PI * M_PI * std::max(d - l.radius, 1e-9) * std::max(d - l.radius, 1e-9));
                }
            }
            for (int k = 0; k < 3; ++k) {
                const double diff = std::abs(double(pixel3(a, x, y)[k]) - double(pixel3(b, x, y)[k]));
                c.max_diff = std::max(c.max_diff, diff);
                // float summation order differs between the two: 1e-5 relative slack
                const double excess = diff - bound - 1e-5 * std::abs(pixel3(b, x, y)[k]) - 1e-7;
                c.max_excess = std::max(c.max_excess, excess);
            }
        }
    return c;
}

}  // namespace

TEST(LightCulling, TenThousandRandomLightsMatchBruteForceWithinTheBound) {
    const auto lights = random_point_lights(10000, 2024, 2.0f);
    const Comparison c = compare(lights, overview_camera(), 64, 1e-3f);
    std::printf("10000 lights, threshold 1e-3: max |culled - brute| %.2e, beyond bound %.2e, %llu tile-light pairs "
                "(brute force would be %d), lighting %.0f ms culled vs %.0f ms brute\n",
                c.max_diff, c.max_excess, (unsigned long long)c.pairs, 16 * 10000, c.culled_ms, c.brute_ms);
    EXPECT_LE(c.max_excess, 0.0);
    EXPECT_LT(c.pairs, 16u * 10000u / 2);  // culling actually removes lights
}

TEST(LightCulling, JitteredSamplesStayExact) {
    // With 16 samples the jitter looks past tile borders and depth bounds:
    // the fallback keeps the result within the same bound.
    const auto lights = random_point_lights(2000, 7, 2.0f);
    const Comparison c = compare(lights, overview_camera(), 48, 1e-3f, 16);
    std::printf("2000 lights, 16 samples: max |culled - brute| %.2e, beyond bound %.2e\n", c.max_diff, c.max_excess);
    EXPECT_LE(c.max_excess, 0.0);
}

TEST(LightCulling, LightOnTileBoundaryAndThroughNearPlane) {
    Camera cam = deferred::testing::top_down_ortho(10.0, 8.0f);
    std::vector<Light> lights;
    // 64 px over 8 m: tile borders (16 px) every 2 m; a light right above one,
    // one above a tile corner, a light at the camera (through the near plane).
    // Five more far lights so the scene has enough lights to be culled.
    for (auto [x, y, z] : {std::tuple{0.0, 1.3, 0.5}, std::tuple{2.0, 2.0, 0.3}, std::tuple{0.0, 0.0, 10.0},
                           std::tuple{25.0, 25.0, 1.0}, std::tuple{-25.0, 25.0, 1.0}, std::tuple{25.0, -25.0, 1.0},
                           std::tuple{-25.0, -25.0, 1.0}, std::tuple{0.0, 28.0, 1.0}}) {
        Light l;
        l.type = LightType::Point;
        l.cast_shadow = false;  // culling under test, not shadows
        l.matrix = tools::translation(x, y, z);
        l.energy = 5.0f;
        l.radius = 0.0f;
        lights.push_back(l);
    }
    const Comparison c = compare(lights, cam, 64, 1e-3f);
    std::printf("boundary/near-plane lights: max |culled - brute| %.2e, beyond bound %.2e\n", c.max_diff, c.max_excess);
    EXPECT_GT(c.pairs, 0u);  // the lists were built
    EXPECT_LE(c.max_excess, 0.0);
}

TEST(LightCulling, TileWithMoreLightsThanAWorkgroup) {
    // 3000 lights over one small area: one tile holds ~3000 > 256 threads.
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Light> lights;
    for (int i = 0; i < 3000; ++i) {
        Light l;
        l.type = LightType::Point;
        l.cast_shadow = false;  // culling under test, not shadows
        l.matrix = tools::translation(0.3 * u(rng), 0.3 * u(rng), 0.5 + 0.5 * u(rng));
        l.energy = 0.2f;
        l.radius = 0.0f;
        lights.push_back(l);
    }
    Camera cam = deferred::testing::top_down_ortho(10.0, 8.0f);
    const Comparison c = compare(lights, cam, 32, 1e-3f);
    std::printf("3000 lights over one tile: %llu tile-light pairs, beyond bound %.2e\n", (unsigned long long)c.pairs,
                c.max_excess);
    EXPECT_GE(c.pairs, 3000u);
    EXPECT_LE(c.max_excess, 0.0);
}

TEST(LightCulling, ZeroLights) {
    Renderer r;
    build_geometry(r);
    RenderSettings s;
    s.width = 16;
    s.height = 16;
    FrameResult f = r.render(overview_camera(), s);
    EXPECT_EQ(f.find(Pass::Combined)->pixels[0], 0.0f);
}

TEST(LightCulling, SixtyFiveThousandLights) {
    const auto lights = random_point_lights(65536, 99, 0.5f);
    const Comparison c = compare(lights, overview_camera(), 32, 1e-3f);
    std::printf("65536 lights: max |culled - brute| %.2e, beyond bound %.2e, %llu pairs, %.0f ms culled vs %.0f ms brute\n",
                c.max_diff, c.max_excess, (unsigned long long)c.pairs, c.culled_ms, c.brute_ms);
    EXPECT_LE(c.max_excess, 0.0);
}

// Lights add linearly (no selection; salts per shadowed light, not per
// light index): the image of `lights` rendered at once equals the sum of
// renders of its consecutive parts of `part` lights each. Returns the
// worst relative difference; `whole` gets the full render's timings.
double parts_difference(const std::vector<Light>& lights, std::size_t part, const RenderSettings& s,
                        FrameTimings& whole_timings, int& geometry_pixels) {
    Renderer r;
    build_geometry(r);
    for (const Light& l : lights) r.add_light(l);
    const FrameResult whole = r.render(overview_camera(), s);
    whole_timings = whole.timings;
    std::vector<double> sum(std::size_t(s.width) * s.height * 4, 0.0);
    for (std::size_t begin = 0; begin < lights.size(); begin += part) {
        Renderer p;
        build_geometry(p);
        for (std::size_t i = begin; i < std::min(lights.size(), begin + part); ++i) p.add_light(lights[i]);
        const FrameResult f = p.render(overview_camera(), s);
        const std::vector<float>& px = f.find(Pass::Combined)->pixels;
        for (std::size_t i = 0; i < px.size(); ++i) sum[i] += px[i];
    }
    const std::vector<float>& a = whole.find(Pass::Combined)->pixels;
    const PassImage& depth = *whole.find(Pass::Depth);
    double worst = 0;
    geometry_pixels = 0;
    for (std::size_t i = 0; i < a.size(); i += 4) {
        if (depth.pixels[(i / 4) * std::size_t(depth.channels)] < 1e9f) ++geometry_pixels;
        for (int k = 0; k < 3; ++k)
            worst = std::max(worst, std::abs(a[i + k] - sum[i + k]) / std::max(std::abs(sum[i + k]), 1e-3));
    }
    return worst;
}

TEST(LightCulling, LaterBatchesReachEveryPixelThatNeedsThem) {
    // The lighting shades 512 lights a dispatch (8 with shadow rays); the
    // dispatches after the first run only over the pixels the first listed
    // (an indirect dispatch). 1100 lights make three batches: the image
    // must equal the sum of renders of 512, 512 and 76 of them, one batch
    // each, over two samples (the list is rebuilt each sample).
    std::vector<Light> lights = random_point_lights(500, 5, 1.0f);
    {
        // 600 more lights crowded over one corner of the floor: only the
        // tiles there hold more than a batch.
        std::vector<Light> crowd = random_point_lights(600, 6, 1.0f);
        for (Light& l : crowd) {
            l.matrix[12] = -12.0 + 0.1 * l.matrix[12];
            l.matrix[13] = -6.0 + 0.1 * l.matrix[13];
        }
        lights.insert(lights.end(), crowd.begin(), crowd.end());
    }
    RenderSettings s;
    s.width = 64;
    s.height = 48;
    s.samples = 2;
    s.passes = {Pass::Combined, Pass::Depth};
    for (bool culled : {true, false}) {
        s.light_culling = culled;
        FrameTimings t;
        int geometry = 0;
        const double worst = parts_difference(lights, 512, s, t, geometry);
        std::printf("%s: %d of %d pixels see a surface, %llu pixel-samples in the later batches, worst relative "
                    "difference to the parts' sum %.2e\n",
                    culled ? "culled" : "brute force", geometry, s.width * s.height,
                    (unsigned long long)t.lighting_later_pixels, worst);
        EXPECT_GT(geometry, s.width * s.height / 2);
        EXPECT_LT(geometry, s.width * s.height);  // some background, never listed
        if (culled) {
            // Some pixels' lists go past a batch, most do not.
            EXPECT_GT(t.lighting_later_pixels, 0u);
            EXPECT_LT(t.lighting_later_pixels, std::uint64_t(geometry) * s.samples * 8 / 10);
        } else {
            // Every pixel that sees a surface, each sample (a silhouette
            // pixel's samples may see it or not).
            EXPECT_GE(t.lighting_later_pixels, std::uint64_t(geometry) * s.samples * 95 / 100);
            EXPECT_LE(t.lighting_later_pixels, std::uint64_t(s.width) * s.height * s.samples);
        }
        EXPECT_LT(worst, 1e-4);
    }
    {
        // More than 1024 groups of 64 listed pixels: the indirect dispatch's
        // second row of groups (lighting_comp.glsl LATER_GROUPS_PER_ROW).
        RenderSettings big;
        big.width = 384;
        big.height = 256;
        big.passes = {Pass::Combined, Pass::Depth};
        big.light_culling = false;
        FrameTimings t;
        int geometry = 0;
        const double worst = parts_difference(random_point_lights(513, 9, 1.0f), 512, big, t, geometry);
        std::printf("384x256, 513 lights: %llu pixels in the later batch (%llu groups), worst relative difference "
                    "%.2e\n",
                    (unsigned long long)t.lighting_later_pixels, (unsigned long long)(t.lighting_later_pixels + 63) / 64,
                    worst);
        EXPECT_GT(t.lighting_later_pixels, 1024u * 64u);
        EXPECT_LT(worst, 1e-4);
    }

    // With shadow rays (8 lights a dispatch), sized lights draw their
    // points per pixel: four shadowed lights after eight faint unshadowed
    // ones (the second batch) must light as the four alone do (the first),
    // so a later batch's invocation knows its pixel.
    std::vector<Light> rays = random_point_lights(12, 8, 1.0f);
    for (std::size_t i = 0; i < rays.size(); ++i) {
        rays[i].cast_shadow = i >= 8;
        rays[i].radius = i >= 8 ? 0.5f : 0.0f;
        if (i < 8) rays[i].energy = 1e-9f;
    }
    std::vector<Light> four(rays.begin() + 8, rays.end());
    RenderSettings r = s;
    r.shadow_rays = true;
    r.light_culling = false;
    Renderer a, b;
    build_geometry(a);
    build_geometry(b);
    for (const Light& l : rays) a.add_light(l);
    for (const Light& l : four) b.add_light(l);
    const FrameResult with = a.render(overview_camera(), r);
    const FrameResult alone = b.render(overview_camera(), r);
    const std::vector<float>& x = with.find(Pass::Combined)->pixels;
    const std::vector<float>& y = alone.find(Pass::Combined)->pixels;
    double worst = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
        if (i % 4 != 3) worst = std::max(worst, double(std::abs(x[i] - y[i])) / std::max(double(std::abs(y[i])), 1e-3));
    std::printf("shadow rays: %llu pixel-samples in the later batches, worst relative difference %.2e\n",
                (unsigned long long)with.timings.lighting_later_pixels, worst);
    EXPECT_TRUE(with.timings.shadow_rays);
    EXPECT_GT(with.timings.lighting_later_pixels, 0u);
    EXPECT_LT(worst, 1e-3);
}
