// The converging film: Blackman-Harris pixel filter importance sampling
// (Cycles' filter_table), anti-aliased edges, sample-0 passes, and error
// against the oracle falling as samples double.
#include "film.h"
#include "test_helpers.h"

#include "cycles_oracle.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

using namespace deferred;
using deferred::testing::pixel3;

namespace {
// CDF of Cycles' filter (Blackman-Harris, width doubled) at x pixels.
double bh_cdf(double x, double filter_width) {
    const double w = 2.0 * filter_width;
    const int n = 20000;
    double total = 0, below = 0;
    for (int i = 0; i < n; ++i) {
        const double v = -0.5 * w + w * (i + 0.5) / n;
        const double f = blackman_harris(v, w);
        total += f;
        if (v < x) below += f;
    }
    return below / total;
}
}  // namespace

TEST(Film, FilterOffsetsFollowBlackmanHarris) {
    for (float width : {1.5f, 0.75f, 3.0f}) {
        PixelFilter filter(width);
        EXPECT_NEAR(filter.offset(0.5f), 0.0f, 1e-4f);
        EXPECT_FLOAT_EQ(filter.support(), width);
        // Kolmogorov-Smirnov distance between the offsets of a uniform grid of
        // u and the filter's CDF.
        const int n = 4000;
        std::vector<double> offsets;
        for (int i = 0; i < n; ++i) offsets.push_back(filter.offset((i + 0.5f) / n));
        double ks = 0;
        for (int i = 0; i < n; i += 20) {
            const double x = offsets[std::size_t(i)];
            EXPECT_LE(std::abs(x), width + 1e-5);
            ks = std::max(ks, std::abs(bh_cdf(x, width) - (i + 0.5) / n));
        }
        std::printf("filter width %.2f: KS distance %.2e\n", width, ks);
        EXPECT_LT(ks, 2e-3);
    }
}

TEST(Film, EdgeCoverageMatchesFilterIntegral) {
    // A plane covering x > x_edge, seen from above with a transparent film:
    // alpha of pixel i = P(x_centre + offset > x_edge) under the filter.
    Renderer r;
    tools::MeshArrays plane = tools::make_plane(10.0f);
    const std::uint32_t mesh = r.add_mesh(plane.view());
    const std::uint32_t mat = r.add_material(Material{});
    // In pixels from the left of a 32 px image; a multiple of 1/256 px so the
    // rasteriser's sub-pixel snapping (8 bits on llvmpipe) does not move it.
    const double x_edge_px = 16.25;
    const double metres_per_px = 4.0 / 32.0;
    Mat4d t = tools::translation(-2.0 + x_edge_px * metres_per_px + 10.0, 0, 0);
    r.add_instances(mesh, t.data(), 1, nullptr, {mat});
    RenderSettings s;
    s.width = 32;
    s.height = 8;
    s.samples = 1024;
    s.film_transparent = true;
    Camera cam = deferred::testing::top_down_ortho(5.0, 4.0f);
    // Both estimators: each pixel's own sample, and the film's splat
    // (film.h), which must converge to the same coverage.
    for (bool splat : {false, true}) {
        s.filter_splat = splat;
        FrameResult f = r.render(cam, s);
        const PassImage& c = *f.find(Pass::Combined);
        double worst = 0;
        for (int x = 10; x < 23; ++x) {
            const double alpha = c.pixels[(std::size_t(4) * 32 + x) * 4 + 3];
            const double expect = 1.0 - bh_cdf(x_edge_px - (x + 0.5), 1.5);
            worst = std::max(worst, std::abs(alpha - expect));
        }
        std::printf("edge coverage vs Blackman-Harris integral (%s): max error %.2e (1024 samples)\n",
                    splat ? "splatted" : "own sample", worst);
        EXPECT_LT(worst, 5e-3) << splat;
    }
}

TEST(Film, DepthPositionAndIndexComeFromTheFirstSample) {
    // A tilted plane: jittered samples see other depths, but Depth must be
    // the pixel centre's, the same at 1 and 16 samples.
    Renderer r;
    tools::MeshArrays plane = tools::make_plane(10.0f);
    const std::uint32_t mesh = r.add_mesh(plane.view());
    const std::uint32_t mat = r.add_material(Material{});
    Mat4d m = identity_matrix();
    m[5] = std::cos(0.6); m[6] = std::sin(0.6); m[9] = -std::sin(0.6); m[10] = std::cos(0.6);
    const std::uint32_t ob = 5;
    r.add_instances(mesh, m.data(), 1, &ob, {mat});
    RenderSettings s;
    s.width = 24;
    s.height = 24;
    s.passes = {Pass::Depth, Pass::Position, Pass::IndexOB};
    Camera cam;
    cam.matrix = tools::translation(0, 0, 6);
    FrameResult one = r.render(cam, s);
    s.samples = 16;
    FrameResult many = r.render(cam, s);
    for (Pass p : {Pass::Depth, Pass::Position, Pass::IndexOB}) {
        const PassImage& a = *one.find(p);
        const PassImage& b = *many.find(p);
        double worst = 0;
        for (std::size_t i = 0; i < a.pixels.size(); ++i)
            worst = std::max(worst, double(std::abs(a.pixels[i] - b.pixels[i])));
        EXPECT_EQ(worst, 0.0) << pass_info(p).name;
    }
}

TEST(Film, DoublingSamplesLowersErrorUnderAnAreaLight) {
    // Unoccluded glossy plane under a square light: RMSE against the oracle
    // (point-sampled pixel centres) for 2, 4, ..., 64 samples.
    Renderer r;
    tools::MeshArrays plane = tools::make_plane(20.0f);
    const std::uint32_t mesh = r.add_mesh(plane.view());
    Material mat;
    mat.base_color = {0.5f, 0.5f, 0.5f};
    mat.roughness = 0.25f;
    mat.specular = 0.5f;
    const std::uint32_t mid = r.add_material(mat);
    Mat4d I = identity_matrix();
    r.add_instances(mesh, I.data(), 1, nullptr, {mid});
    Light light;
    light.type = LightType::Area;
    light.matrix = tools::translation(0.2, 0.0, 1.0);
    light.size = 1.0f;
    light.energy = 200.0f;
    r.add_light(light);
    World black;
    black.color = {0, 0, 0};
    r.set_world(black);
    Camera cam;
    cam.matrix = tools::translation(0, -1.0, 4.0);
    RenderSettings s;
    s.width = 24;
    s.height = 24;
    s.filter_width = 0.01f;
    s.passes = {Pass::Position, Pass::Normal};
    std::vector<double> reference;
    std::vector<double> errors;
    for (int samples : {2, 4, 8, 16, 32, 64}) {
        s.samples = samples;
        FrameResult f = r.render(cam, s);
        const PassImage& c = *f.find(Pass::Combined);
        if (reference.empty()) {
            const PassImage& pos = *f.find(Pass::Position);
            const PassImage& nrm = *f.find(Pass::Normal);
            for (int y = 0; y < s.height; y += 2)
                for (int x = 0; x < s.width; x += 2) {
                    const glm::dvec3 P = pixel3(pos, x, y);
                    const glm::dvec3 V = glm::normalize(glm::dvec3(0, -1, 4) - P);
                    const oracle::Shade o = oracle::shade(light, mat, P, glm::normalize(pixel3(nrm, x, y)), V, 128);
                    reference.push_back((o.diffuse + o.glossy).x);
                }
        }
        double se = 0;
        std::size_t k = 0;
        for (int y = 0; y < s.height; y += 2)
            for (int x = 0; x < s.width; x += 2, ++k) {
                const double d = pixel3(c, x, y).x - reference[k];
                se += d * d;
            }
        errors.push_back(std::sqrt(se / double(k)));
        std::printf("area light, %2d samples: RMSE %.3e\n", samples, errors.back());
    }
    for (std::size_t i = 1; i < errors.size(); ++i) EXPECT_LT(errors[i], errors[i - 1]) << "step " << i;
}

TEST(Film, SplatWeightsAreUnbiasedForTheJitterDensity) {
    // film.h PixelFilter::splat_taps: a pixel's expected weight on the point
    // x pixels from its centre, summed over the neighbours d whose sample
    // lands there (jitter o = d - x, density f), must be the filter's
    // density f(x): K(x) = sum_d f(d - x) a_d(d - x) = f(x).
    for (float width : {1.5f, 0.75f, 1.0f, 2.3f, 4.0f}) {
        const PixelFilter filter(width);
        const double h = filter.support();
        ASSERT_GT(filter.splat_margin(), 0) << width;
        const double norm = 0.35875 * 2.0 * h;  // the cosine terms integrate to 0 over the support
        auto f = [&](double x) { return std::abs(x) < h ? blackman_harris(x, 2.0 * h) / norm : 0.0; };
        double worst = 0;
        for (int i = 0; i <= 400; ++i) {
            const double x = -h + 2.0 * h * i / 400.0;
            double k = 0;
            for (int d = -filter.splat_margin(); d <= filter.splat_margin(); ++d) {
                const double o = double(d) - x;
                if (std::abs(o) >= h) continue;
                const SplatTaps taps = filter.splat_taps(float(o));
                double sum = 0;
                for (int t = 0; t < taps.count; ++t) sum += taps.weight[std::size_t(t)];
                EXPECT_NEAR(sum, 1.0, 1e-6);
                EXPECT_LE(std::abs(taps.first), filter.splat_margin());
                EXPECT_LE(std::abs(taps.first + taps.count - 1), filter.splat_margin());
                const int t = d - taps.first;
                if (t >= 0 && t < taps.count) k += f(o) * taps.weight[std::size_t(t)];
            }
            worst = std::max(worst, std::abs(k - f(x)));
        }
        std::printf("filter width %.2f: margin %d, max |K - f| %.2e (f(0) %.3f)\n", width, filter.splat_margin(), worst,
                    f(0.0));
        EXPECT_LT(worst, 1e-5);
    }
    // Below half a pixel there is nothing to splat; above the taps' reach,
    // the pixel's own sample.
    EXPECT_EQ(PixelFilter(0.4f).splat_margin(), 0);
    EXPECT_EQ(PixelFilter(5.0f).splat_margin(), 0);
    EXPECT_EQ(PixelFilter(5.0f).splat_taps(1.3f).count, 1);
}

TEST(Film, SplattingTamesASmallBrightFeatureInTheFilterTail) {
    // An emitter an eighth of a pixel wide (radiance 1000): a pixel sees it
    // when its jittered sample lands on it, with probability
    // P = int_square f, so its filtered value is 1000 P. The pixels one
    // away see it only with the filter's tail: each pixel's own sample
    // (Cycles' estimator) hits it rarely and then counts fully; splatting
    // weighs each neighbour's hit by the tail. Same expectation, much less
    // error at equal samples.
    Renderer r;
    // Edges on multiples of 1/256 px (llvmpipe's sub-pixel grid): 16 px over
    // 4 m, the square 0.125 px wide centred at (8.25, 8.0) px.
    const double px = 4.0 / 16.0, cx = 8.25, cy = 8.0, half = 0.0625;
    tools::MeshArrays square = tools::make_plane(float(half * px));
    const std::uint32_t mesh = r.add_mesh(square.view());
    Material m;
    m.base_color = {0, 0, 0};
    m.emission = {1, 1, 1};
    m.emission_strength = 1000.0f;
    const std::uint32_t mat = r.add_material(m);
    Mat4d t = tools::translation(-2.0 + cx * px, -2.0 + cy * px, 0);
    r.add_instances(mesh, t.data(), 1, nullptr, {mat});
    World black;
    black.color = {0, 0, 0};
    r.set_world(black);
    RenderSettings s;
    s.width = s.height = 16;
    const Camera cam = deferred::testing::top_down_ortho(5.0, 4.0f);
    // The filtered value: P(the sample point lies on the square), per axis
    // (the filter is symmetric, so the jitter's sign does not matter).
    auto p_axis = [](double pixel_centre, double lo, double hi) {
        return bh_cdf(hi - pixel_centre, 1.5) - bh_cdf(lo - pixel_centre, 1.5);
    };
    // RMSE over the pixels whose filter reaches the square only with its
    // tail (filtered value under a tenth of the brightest pixel's), and over
    // the rest (the pixels the square sits in or beside).
    struct Errors {
        double tail = 0, core = 0;
    };
    auto errors = [&](const FrameResult& f) {
        const PassImage& c = *f.find(Pass::Combined);
        std::vector<double> expect(256), got(256);
        double brightest = 0;
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x) {
                const std::size_t i = std::size_t(y) * 16 + std::size_t(x);
                expect[i] = 1000.0 * p_axis(x + 0.5, cx - half, cx + half) * p_axis(y + 0.5, cy - half, cy + half);
                got[i] = c.pixels[i * 4];
                brightest = std::max(brightest, expect[i]);
            }
        double se_tail = 0, se_core = 0;
        int n_tail = 0, n_core = 0;
        for (std::size_t i = 0; i < expect.size(); ++i) {
            if (expect[i] <= 0.0) continue;
            const double d = (got[i] - expect[i]) * (got[i] - expect[i]);
            if (expect[i] < 0.1 * brightest) se_tail += d, ++n_tail;
            else se_core += d, ++n_core;
        }
        return Errors{std::sqrt(se_tail / std::max(n_tail, 1)), std::sqrt(se_core / std::max(n_core, 1))};
    };
    for (int samples : {64, 1024}) {
        s.samples = samples;
        s.filter_splat = false;
        const Errors own = errors(r.render(cam, s));
        s.filter_splat = true;
        const Errors splat = errors(r.render(cam, s));
        std::printf("%4d samples: RMSE in the filter's tail: own sample %.3e, splatted %.3e; nearer: %.3e, %.3e\n",
                    samples, own.tail, splat.tail, own.core, splat.core);
        EXPECT_LT(splat.tail, 0.25 * own.tail) << samples;
        EXPECT_LT(splat.core, own.core) << samples;
    }
}

TEST(Film, SplattingStepsAsideWhereItsImagesWouldExceedTheMemoryBudget) {
    // 512x512, Combined: ~22 MiB of targets (G-buffer, the accumulation,
    // the CPU copy: 88 bytes a pixel) and 4 MiB of splat scratch. A 24 MiB
    // budget holds the frame but not the scratch: the frame renders each pixel's own samples,
    // warned, exactly as with the setting off.
    const char* before = std::getenv("DEFERRED_MEMORY_BUDGET_MB");
    const std::string user = before ? before : "";
    Renderer r;
    Material m;
    m.base_color = {0.5f, 0.5f, 0.5f};
    deferred::testing::add_plane(r, m);
    Light lamp;
    lamp.type = LightType::Point;
    lamp.matrix = tools::translation(0.3, 0.2, 2.0);
    lamp.radius = 0.2f;
    lamp.energy = 400.0f;
    r.add_light(lamp);
    RenderSettings s;
    s.width = s.height = 512;
    s.samples = 2;
    const Camera cam = deferred::testing::top_down_ortho(5.0, 4.0f);
    auto mentions_splat = [](const FrameResult& f) {
        for (const std::string& w : f.warnings)
            if (w.find("Filter Splatting is off") != std::string::npos) return true;
        return false;
    };
    setenv("DEFERRED_MEMORY_BUDGET_MB", "24", 1);
    const FrameResult dropped = r.render(cam, s);
    s.filter_splat = false;
    const FrameResult off = r.render(cam, s);
    setenv("DEFERRED_MEMORY_BUDGET_MB", "128", 1);
    s.filter_splat = true;
    const FrameResult on = r.render(cam, s);
    if (before) setenv("DEFERRED_MEMORY_BUDGET_MB", user.c_str(), 1);
    else unsetenv("DEFERRED_MEMORY_BUDGET_MB");
    EXPECT_TRUE(mentions_splat(dropped));
    EXPECT_FALSE(mentions_splat(off));
    EXPECT_FALSE(mentions_splat(on));
    EXPECT_EQ(dropped.find(Pass::Combined)->pixels, off.find(Pass::Combined)->pixels);
    EXPECT_GT(on.timings.gbuffer_bytes, dropped.timings.gbuffer_bytes);
}
