// Shadow maps (and shadow rays where named): no acne on lit planes at
// grazing angles, a penumbra as wide as geometry predicts, no light leaking
// under a resting cube, finite output with lights touching or inside
// geometry.
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace deferred;
using deferred::testing::pixel3;

namespace {

Material grey() {
    Material m;
    m.base_color = {0.5f, 0.5f, 0.5f};
    m.roughness = 0.5f;
    return m;
}

// A black emitter of radiance colour x strength (a mesh light).
Material emitter(float r, float g, float b, float strength) {
    Material m;
    m.base_color = {0.0f, 0.0f, 0.0f};
    m.specular = 0.0f;
    m.emission = {r, g, b};
    m.emission_strength = strength;
    return m;
}

// A grey floor (half size 6), a thin box of half size hx x hy at half a
// metre over the origin (a blocker) and a black world.
void add_floor_and_blocker(Renderer& r, float hx, float hy) {
    deferred::testing::add_plane(r, grey(), 6.0f);
    tools::MeshArrays blocker = tools::make_box(hx, hy, 0.02f);
    const std::uint32_t bm = r.add_mesh(blocker.view()), gm = r.add_material(grey());
    Mat4d bt = tools::translation(0.0, 0.0, 0.5);
    r.add_instances(bm, bt.data(), 1, nullptr, {gm});
    deferred::testing::set_world_color(r, 0, 0, 0);
}

// DEFERRED_MESH_LIGHT_RAYS set by a test, unset when it ends.
struct MeshLightRaysEnv {
    void set(const char* mode) { setenv("DEFERRED_MESH_LIGHT_RAYS", mode, 1); }
    ~MeshLightRaysEnv() { unsetenv("DEFERRED_MESH_LIGHT_RAYS"); }
};

// A 10 m floor with a 1 m grey cube resting on it at the origin.
void add_cube_on_floor(Renderer& r) {
    const std::uint32_t mat = deferred::testing::add_plane(r, grey(), 10.0f, 4);
    tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.5f);
    const std::uint32_t bm = r.add_mesh(box.view());
    Mat4d t = tools::translation(0, 0, 0.5);
    r.add_instances(bm, t.data(), 1, nullptr, {mat});
}

// Combined with and without shadows for the same scene.
std::pair<FrameResult, FrameResult> render_both(Renderer& r, const Camera& cam, int w, int h, int samples,
                                                bool rays = false) {
    RenderSettings s;
    s.shadow_rays = rays;
    s.width = w;
    s.height = h;
    s.samples = samples;
    s.filter_width = 0.01f;
    FrameResult with = r.render(cam, s);
    s.shadows = false;
    FrameResult without = r.render(cam, s);
    return {std::move(with), std::move(without)};
}

// Fraction of pixels (with light) darker with shadows than without by > 1 %.
double acne_fraction(const FrameResult& with, const FrameResult& without) {
    const PassImage& a = *with.find(Pass::Combined);
    const PassImage& b = *without.find(Pass::Combined);
    std::size_t lit = 0, dark = 0;
    for (int i = 0; i < a.width * a.height; ++i) {
        const double u = b.pixels[std::size_t(i) * 4];
        if (u <= 1e-6) continue;
        ++lit;
        if (a.pixels[std::size_t(i) * 4] < 0.99 * u) ++dark;
    }
    return lit ? double(dark) / double(lit) : 1.0;
}

Light light_of(LightType type, double angle_deg) {
    // Aimed at the origin from 4 m away, `angle` from the plane's normal.
    const double a = angle_deg * M_PI / 180.0;
    const double eye[3] = {4.0 * std::sin(a), 0.0, 4.0 * std::cos(a)}, target[3] = {0, 0, 0};
    Light l;
    l.type = type;
    l.matrix = tools::look_at(eye, target);
    l.energy = type == LightType::Sun ? 3.0f : 400.0f;
    l.radius = 0.1f;
    l.spot_size = float(M_PI / 2);
    l.shape = AreaShape::Square;
    l.size = 0.5f;
    return l;
}

// A floor, a blocker plane covering x < 0 at height h, and a point light of
// radius R at height H above the origin; black world.
void build_edge_scene(Renderer& r, double h, double H, double R) {
    tools::MeshArrays floor = tools::make_plane(8.0f);
    tools::MeshArrays blocker = tools::make_plane(2.0f);
    const std::uint32_t fm = r.add_mesh(floor.view()), bm = r.add_mesh(blocker.view());
    const std::uint32_t mat = r.add_material(grey());
    Mat4d I = identity_matrix();
    r.add_instances(fm, I.data(), 1, nullptr, {mat});
    Mat4d t = tools::translation(-2.0, 0.0, h);
    r.add_instances(bm, t.data(), 1, nullptr, {mat});
    Light l;
    l.type = LightType::Point;
    l.matrix = tools::translation(0, 0, H);
    l.radius = float(R);
    l.energy = 300.0f;
    r.add_light(l);
    World black;
    black.color = {0, 0, 0};
    r.set_world(black);
}

}  // namespace

TEST(Shadows, NoAcneOnLitPlanesAtGrazingAngles) {
    for (bool rays : {false, true})
    for (LightType type : {LightType::Point, LightType::Spot, LightType::Sun, LightType::Area}) {
        for (double angle : {0.0, 60.0, 80.0, 88.0}) {
            Renderer r;
            tools::MeshArrays plane = tools::make_plane(6.0f, 8);
            const std::uint32_t mesh = r.add_mesh(plane.view());
            Mat4d I = identity_matrix();
            r.add_instances(mesh, I.data(), 1, nullptr, {r.add_material(grey())});
            r.add_light(light_of(type, angle));
            World black;
            black.color = {0, 0, 0};
            r.set_world(black);
            Camera cam;
            const double eye[3] = {0, -5, 3}, target[3] = {0, 0, 0};
            cam.matrix = tools::look_at(eye, target);
            auto [with, without] = render_both(r, cam, 96, 64, 4, rays);
            EXPECT_EQ(with.timings.shadow_rays, rays);
            const double frac = acne_fraction(with, without);
            std::printf("%s, light type %d at %4.0f deg: %.4f %% of lit pixels darkened\n", rays ? "rays" : "maps",
                        int(type), angle, 100 * frac);
            EXPECT_LT(frac, 1e-3) << (rays ? "rays" : "maps") << " type " << int(type) << " angle " << angle;
        }
    }
}

TEST(Shadows, PenumbraWidthMatchesGeometry) {
    // A sphere light of radius R at height H above an occluding half-plane
    // edge at height h: on the floor the penumbra spans x in
    // [-R (h / (H - h)), +R (h / (H - h))] around the edge's shadow line.
    const double H = 2.0, h = 0.5;
    for (double R : {0.2, 0.4}) {
        Renderer r;
        build_edge_scene(r, h, H, R);
        // Looking down from between the blocker (behind the camera) and the floor.
        Camera cam = deferred::testing::top_down_ortho(0.3, 1.6f);
        RenderSettings s;
        s.width = 400;
        s.height = 8;
        s.samples = 256;
        s.filter_width = 0.01f;
        s.passes = {Pass::Position};
        FrameResult with = r.render(cam, s);
        s.shadows = false;
        FrameResult without = r.render(cam, s);
        const PassImage& a = *with.find(Pass::Combined);
        const PassImage& b = *without.find(Pass::Combined);
        const PassImage& pos = *with.find(Pass::Position);
        // Visibility ratio along the middle row; penumbra = where it is in (0.05, 0.95).
        const int y = 4;
        double x_lo = 1e9, x_hi = -1e9;
        for (int x = 0; x < s.width; ++x) {
            const double v = pixel3(a, x, y).x / std::max(pixel3(b, x, y).x, 1e-12);
            if (v > 0.05 && v < 0.95) {
                x_lo = std::min(x_lo, pixel3(pos, x, y).x);
                x_hi = std::max(x_hi, pixel3(pos, x, y).x);
            }
        }
        // Between 5 % and 95 % visibility of a uniformly bright disk seen
        // edge-on: the visible fraction of a disk cut by a chord; solve for
        // the chord offsets giving 5 % and 95 %.
        auto disk_fraction = [](double t) {  // fraction of unit disk with x < t
            t = std::clamp(t, -1.0, 1.0);
            return (std::acos(-t) - (-t) * std::sqrt(1 - t * t)) / M_PI;
        };
        auto solve = [&](double f) {
            double lo = -1, hi = 1;
            for (int i = 0; i < 60; ++i) {
                const double m = 0.5 * (lo + hi);
                (disk_fraction(m) < f ? lo : hi) = m;
            }
            return 0.5 * (lo + hi);
        };
        const double scale = R * h / (H - h);  // disk radius projected to the floor
        const double predicted = (solve(0.95) - solve(0.05)) * scale;
        const double measured = x_hi - x_lo;
        std::printf("sphere light R %.1f: penumbra (5-95 %%) measured %.4f m, predicted %.4f m (%.1f %%)\n", R,
                    measured, predicted, 100 * (measured / predicted - 1));
        EXPECT_NEAR(measured, predicted, 0.1 * predicted);
    }
}

TEST(Shadows, RaysPenumbraConvergesPerPixel) {
    // Shadow rays under a sphere light (R 0.4 at H 2, the blocker's edge at
    // h 0.5: a penumbra 0.27 m wide, 66 px here). Each pixel's shadowed
    // light is D + p (U - F) (sized_light_shadowed): unbiased only when the
    // probe p is independent of the traced point. Drawn from the same
    // sequence shifted per pixel, every pixel kept a bias of its own that
    // more samples did not remove (box_room's penumbra left of the tall box:
    // relMSE 2.2e-3 at 64 samples, 8.0e-4 at 256; independent: 3.8e-4; here
    // the noise fell 3.7x from 64 to 1024 samples, 10.7x since).
    // Measured here as the penumbra's roughness from pixel to pixel (the
    // second difference along x of the Shadow pass, whose true profile is
    // smooth at this resolution) at 64 and 1024 samples, and against the
    // visible fraction of the light's disk.
    const double H = 2.0, h = 0.5, R = 0.4, scale = R * h / (H - h);
    Renderer r;
    build_edge_scene(r, h, H, R);
    RenderSettings s;
    s.width = 400;
    s.height = 8;
    s.filter_width = 0.01f;
    s.shadow_rays = true;
    s.passes = {Pass::Shadow, Pass::Position};
    auto measure = [&](int samples, double* fraction_error) {
        s.samples = samples;
        FrameResult f = r.render(deferred::testing::top_down_ortho(0.3, 1.6f), s);
        const PassImage& sh = *f.find(Pass::Shadow);
        const PassImage& pos = *f.find(Pass::Position);
        double rough2 = 0.0, err2 = 0.0;
        int n = 0, m = 0;
        for (int y = 0; y < s.height; ++y)
            for (int x = 1; x + 1 < s.width; ++x) {
                const double px = pixel3(pos, x, y).x;
                if (std::abs(px) > 0.9 * scale) continue;  // the penumbra
                const double d2 = pixel3(sh, x - 1, y).x - 2.0 * pixel3(sh, x, y).x + pixel3(sh, x + 1, y).x;
                rough2 += d2 * d2;
                ++n;
                // The visible fraction of a uniform disk cut by the edge's
                // line (the disk's light weighted by cos / d^2 varies 2 %
                // across it: the bound below allows for that).
                const double t = std::clamp(px / scale, -1.0, 1.0);
                const double visible = (std::acos(-t) + t * std::sqrt(1 - t * t)) / M_PI;
                err2 += std::pow(pixel3(sh, x, y).x - visible, 2);
                ++m;
            }
        EXPECT_GT(n, 400);
        *fraction_error = std::sqrt(err2 / std::max(m, 1));
        return std::sqrt(rough2 / std::max(n, 1) / 6.0);  // per-pixel noise: var(d2) = 6 var
    };
    double e64 = 0, e1024 = 0;
    const double n64 = measure(64, &e64), n1024 = measure(1024, &e1024);
    std::printf("penumbra per-pixel noise: %.5f at 64 samples, %.5f at 1024 (%.1fx less); rms against the disk's "
                "visible fraction %.5f, %.5f\n",
                n64, n1024, n64 / n1024, e64, e1024);
    EXPECT_LT(n1024, 0.15 * n64);  // LD points: 10.7x less noise from 16x the samples (the correlated probe: 3.7x)
    EXPECT_LT(n1024, 2e-3);
    EXPECT_LT(e1024, 0.01);
}

TEST(Shadows, LightsTouchingOrInsideGeometryStayFinite) {
    Renderer r;
    tools::MeshArrays floor = tools::make_plane(5.0f);
    tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.5f);
    const std::uint32_t fm = r.add_mesh(floor.view()), bm = r.add_mesh(box.view());
    const std::uint32_t mat = r.add_material(grey());
    Mat4d I = identity_matrix();
    r.add_instances(fm, I.data(), 1, nullptr, {mat});
    Mat4d t = tools::translation(0, 0, 0.5);  // resting on the floor: occluder touching the receiver
    r.add_instances(bm, t.data(), 1, nullptr, {mat});
    Light inside;  // inside the closed box: must light nothing outside it
    inside.type = LightType::Point;
    inside.matrix = tools::translation(0, 0, 0.5);
    inside.energy = 1000.0f;
    inside.radius = 0.1f;
    r.add_light(inside);
    Light touching;  // on the floor's surface
    touching.type = LightType::Point;
    touching.matrix = tools::translation(2.0, 2.0, 0.0);
    touching.energy = 10.0f;
    touching.radius = 0.0f;
    r.add_light(touching);
    World black;
    black.color = {0, 0, 0};
    r.set_world(black);
    Camera cam = deferred::testing::top_down_ortho(6.0, 6.0f);
    RenderSettings s;
    s.width = 64;
    s.height = 64;
    s.samples = 8;
    FrameResult f = r.render(cam, s);
    const PassImage& c = *f.find(Pass::Combined);
    double leak = 0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            for (int k = 0; k < 4; ++k) ASSERT_TRUE(std::isfinite(c.pixels[(std::size_t(y) * 64 + x) * 4 + k]));
            // Floor pixels near the box but far from the touching light (x < 0):
            const double wx = -3.0 + (x + 0.5) * 6.0 / 64, wy = -3.0 + (y + 0.5) * 6.0 / 64;
            if (wx < -0.7 && wx > -2.5 && std::abs(wy) < 1.0) leak = std::max(leak, pixel3(c, x, y).x);
        }
    // The light inside the box would put ~1000/(4 pi^2 1^2) ~ 25 on the floor
    // beside the box without shadows; what gets out is the documented tolerance.
    std::printf("light inside a closed box: max floor radiance beside it %.3e\n", leak);
    EXPECT_LT(leak, 1e-3);
}

TEST(Shadows, CubeRestingOnThePlaneCastsAnAttachedShadow) {
    // A 1 m cube on the floor, lit at 45 degrees from -X by a spot and by a
    // sun; a 1920x1080 view of the cube. On the floor behind the cube
    // (x just beyond its +X face, |y| < 0.4) the shadow must start at the
    // face: the lit gap is measured in pixels along each image row.
    for (bool rays : {false, true})
    for (LightType type : {LightType::Spot, LightType::Sun}) {
        Renderer r;
        add_cube_on_floor(r);
        Light l;
        l.type = type;
        const double eye[3] = {-3.0, 0.0, 3.0}, target[3] = {0.0, 0.0, 0.0};
        l.matrix = tools::look_at(eye, target);
        l.energy = type == LightType::Sun ? 3.0f : 500.0f;
        l.radius = 0.0f;
        l.angle = 0.0f;
        l.spot_size = float(M_PI / 2);
        r.add_light(l);
        World black;
        black.color = {0, 0, 0};
        r.set_world(black);
        Camera cam;
        const double ceye[3] = {3.0, -3.0, 3.0}, ctarget[3] = {0.6, 0.0, 0.2};
        cam.matrix = tools::look_at(ceye, ctarget);
        RenderSettings s;
        s.width = 1920;
        s.height = 1080;
        s.filter_width = 0.01f;
        s.passes = {Pass::Position};
        s.shadow_rays = rays;
        FrameResult f = r.render(cam, s);
        const PassImage& c = *f.find(Pass::Combined);
        const PassImage& pos = *f.find(Pass::Position);
        // Per row: floor pixels (z ~ 0) with 0.5 < x < 1.3, |y| < 0.4 must be
        // dark; count the lit ones next to the face.
        int worst_gap = 0;
        for (int y = 0; y < s.height; ++y) {
            int gap = 0;
            for (int x = 0; x < s.width; ++x) {
                const glm::dvec3 P = pixel3(pos, x, y);
                if (std::abs(P.z) > 1e-4 || P.x <= 0.5 || P.x > 1.3 || std::abs(P.y) > 0.4) continue;
                if (pixel3(c, x, y).x > 1e-4) ++gap;
            }
            worst_gap = std::max(worst_gap, gap);
        }
        std::printf("cube on plane (%s), light type %d: lit pixels in the attached shadow, worst row %d\n",
                    rays ? "rays" : "maps", int(type), worst_gap);
        // Rays: the exact geometry, no pixel lit.
        EXPECT_LE(worst_gap, rays ? 0 : 1) << "light type " << int(type);
    }
}

TEST(Shadows, ShadowPassIsShadowedOverUnshadowedLight) {
    // A floor half covered by a blocker at 0.5 m, lit by a small sphere light
    // from above; looking down from between blocker and floor.
    Renderer r;
    build_edge_scene(r, 0.5, 2.0, 0.0);
    RenderSettings s;
    s.width = 64;
    s.height = 8;
    s.passes = {Pass::Shadow};
    FrameResult f = r.render(deferred::testing::top_down_ortho(0.3, 1.6f), s);
    const PassImage& sh = *f.find(Pass::Shadow);
    EXPECT_NEAR(pixel3(sh, 4, 4).x, 0.0, 1e-6);   // under the blocker (x ~ -0.7)
    EXPECT_NEAR(pixel3(sh, 60, 4).x, 1.0, 1e-6);  // in the open (x ~ +0.7)
    // Shadow rays with a sized light (radius 0.1: penumbra +-0.033 m around
    // the edge), whose shadowed light comes back from the lighting already
    // shadowed: the pass still divides by the unshadowed light.
    Renderer rr;
    build_edge_scene(rr, 0.5, 2.0, 0.1);
    s.shadow_rays = true;
    s.samples = 4;
    FrameResult fr = rr.render(deferred::testing::top_down_ortho(0.3, 1.6f), s);
    EXPECT_TRUE(fr.timings.shadow_rays);
    const PassImage& shr = *fr.find(Pass::Shadow);
    EXPECT_NEAR(pixel3(shr, 4, 4).x, 0.0, 1e-6);
    EXPECT_NEAR(pixel3(shr, 60, 4).x, 1.0, 1e-5);
}

namespace {
// A floor with a cube under a point light (radius 0 or 0.2) and a sun; the
// camera looks down at the cube from 3 m.
FrameTimings footprint_frame(int width, float quality, float radius, int samples = 1) {
    Renderer r;
    add_cube_on_floor(r);
    Light point;
    point.type = LightType::Point;
    point.matrix = tools::translation(1.0, 0.5, 2.5);
    point.energy = 500.0f;
    point.radius = radius;
    r.add_light(point);
    Light sun;
    sun.type = LightType::Sun;
    const double eye[3] = {-3.0, 0.0, 3.0}, target[3] = {0.0, 0.0, 0.0};
    sun.matrix = tools::look_at(eye, target);
    sun.energy = 3.0f;
    sun.angle = radius > 0 ? 0.05f : 0.0f;
    r.add_light(sun);
    deferred::testing::set_world_color(r, 0, 0, 0);  // no world occlusion map
    Camera cam;
    const double ceye[3] = {2.0, -2.0, 2.5}, ctarget[3] = {0.0, 0.0, 0.3};
    cam.matrix = tools::look_at(ceye, ctarget);
    cam.clip_end = 20.0f;
    RenderSettings s;
    s.width = width;
    s.height = width * 9 / 16;
    s.samples = samples;
    s.shadow_quality = quality;
    s.shadow_resolution = 8192;
    return r.render(cam, s).timings;
}
}  // namespace

TEST(Shadows, ResolutionFollowsTheProjectedFootprint) {
    // Four times the pixels across: four times the texels (within the
    // rounding to 32); twice the quality: twice the texels.
    const FrameTimings small = footprint_frame(240, 1.0f, 0.0f);
    const FrameTimings large = footprint_frame(960, 1.0f, 0.0f);
    const FrameTimings fine = footprint_frame(240, 2.0f, 0.0f);
    ASSERT_EQ(small.shadow_resolutions.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        std::printf("light %zu: %d texels at 240 px, %d at 960 px, %d at 240 px quality 2\n", i,
                    small.shadow_resolutions[i], large.shadow_resolutions[i], fine.shadow_resolutions[i]);
        EXPECT_NEAR(double(large.shadow_resolutions[i]) / small.shadow_resolutions[i], 4.0, 4.0 * 32 / small.shadow_resolutions[i] + 0.01);
        EXPECT_NEAR(double(fine.shadow_resolutions[i]) / small.shadow_resolutions[i], 2.0, 2.0 * 32 / small.shadow_resolutions[i] + 0.01);
        EXPECT_LT(small.shadow_resolutions[i], 1024);  // the old fixed size was 1024 for any image
    }
}

TEST(Shadows, LightsWithoutSizeRenderTheirMapsOnce) {
    // 8 samples: a radius-0 point light (6 faces) and a sun of angle 0 (4
    // cascades) draw 10 layers in all; with size, 10 per sample.
    const FrameTimings hard = footprint_frame(160, 1.0f, 0.0f, 8);
    const FrameTimings soft = footprint_frame(160, 1.0f, 0.2f, 8);
    EXPECT_EQ(hard.shadow_layers_rendered, 10u);
    EXPECT_EQ(soft.shadow_layers_rendered, 80u);
}

TEST(Shadows, InstancesThatCastNoShadowBlockNothing) {
    // A plate between a point light (and the world) and the floor, seen from
    // between them: with cast_shadow off (Blender's ray visibility "Shadow")
    // the floor is lit as if the plate were not there; with it on, shadowed.
    auto floor_light = [](bool plate, bool plate_casts) {
        Renderer r;
        deferred::testing::add_plane(r, grey(), 10.0f, 4);
        if (plate) deferred::testing::add_plane(r, grey(), 1.0f, 1, tools::translation(0, 0, 1.0), plate_casts);
        Light l;
        l.type = LightType::Point;
        l.matrix = tools::translation(0.0, 0.0, 3.0);
        l.energy = 300.0f;
        l.radius = 0.0f;
        r.add_light(l);
        deferred::testing::set_world_color(r, 0.2f, 0.2f, 0.2f);
        RenderSettings s;
        s.width = 16;
        s.height = 16;
        s.samples = 4;
        return r.render(deferred::testing::top_down_ortho(0.5, 1.0f), s);
    };
    const FrameResult none = floor_light(false, false), ghost = floor_light(true, false),
                      solid = floor_light(true, true);
    double worst = 0, darkest = 1e9;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            const double open = pixel3(*none.find(Pass::Combined), x, y).x;
            worst = std::max(worst, std::abs(pixel3(*ghost.find(Pass::Combined), x, y).x - open) / open);
            darkest = std::min(darkest, open - pixel3(*solid.find(Pass::Combined), x, y).x);
        }
    std::printf("plate that casts no shadow: max relative change %.2e; casting: darker by >= %.3f\n", worst, darkest);
    EXPECT_LT(worst, 1e-6);
    EXPECT_GT(darkest, 0.1);
}

TEST(Shadows, CullingInstancesPerMapAndViewChangesNothing) {
    // 64 boxes on a floor around a point light and under a soft sun and the
    // world: drawn as 64 instances (each map draws only the instances whose
    // bounding sphere reaches it) or as one merged mesh (nothing to cull).
    // The images must agree (measured 2.3e-6); the instances drawn must be
    // well below 64 x the maps (measured 51 %: each cube face sees about a
    // sixth of the boxes, the cascades and the world's map most of them).
    tools::MeshArrays box = tools::make_box(0.3f, 0.3f, 0.6f), merged;
    std::vector<Mat4d> placements;
    for (int i = 0; i < 64; ++i) {
        const double x = -7.0 + 2.0 * (i % 8), y = -7.0 + 2.0 * (i / 8);
        placements.push_back(tools::translation(x, y, 0.6));
        const std::uint32_t base = std::uint32_t(merged.positions.size() / 3);
        for (std::size_t v = 0; v < box.positions.size(); v += 3) {
            merged.positions.push_back(box.positions[v] + float(x));
            merged.positions.push_back(box.positions[v + 1] + float(y));
            merged.positions.push_back(box.positions[v + 2] + 0.6f);
        }
        for (std::uint32_t index : box.indices) merged.indices.push_back(base + index);
        merged.normals.insert(merged.normals.end(), box.normals.begin(), box.normals.end());
    }
    auto render = [&](bool instanced) {
        Renderer r;
        const std::uint32_t mat = deferred::testing::add_plane(r, grey(), 10.0f, 4);
        if (instanced) {
            const std::uint32_t bm = r.add_mesh(box.view());
            for (const Mat4d& m : placements) r.add_instances(bm, m.data(), 1, nullptr, {mat});
        } else {
            const std::uint32_t mm = r.add_mesh(merged.view());
            Mat4d I = identity_matrix();
            r.add_instances(mm, I.data(), 1, nullptr, {mat});
        }
        Light point;
        point.type = LightType::Point;
        point.matrix = tools::translation(0.5, 0.5, 2.0);
        point.energy = 400.0f;
        point.radius = 0.1f;
        r.add_light(point);
        Light sun;
        sun.type = LightType::Sun;
        const double eye[3] = {-3.0, 1.0, 3.0}, target[3] = {0.0, 0.0, 0.0};
        sun.matrix = tools::look_at(eye, target);
        sun.energy = 2.0f;
        sun.angle = 0.05f;
        r.add_light(sun);
        deferred::testing::set_world_color(r, 0.1f, 0.1f, 0.1f);
        Camera cam;
        const double ceye[3] = {1.0, -6.0, 5.0}, ctarget[3] = {0.0, 0.0, 0.0};
        cam.matrix = tools::look_at(ceye, ctarget);
        RenderSettings s;
        s.width = 96;
        s.height = 64;
        s.samples = 4;
        return r.render(cam, s);
    };
    const FrameResult inst = render(true), one = render(false);
    double worst = 0;
    const PassImage& a = *inst.find(Pass::Combined);
    const PassImage& b = *one.find(Pass::Combined);
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        worst = std::max(worst, double(std::abs(a.pixels[i] - b.pixels[i])) / std::max(1e-3, double(std::abs(b.pixels[i]))));
    const std::size_t maps = inst.timings.shadow_layers_rendered;
    std::printf("instances drawn into %zu maps: %llu of %zu (%.0f %%); image vs merged mesh: max relative difference %.2e\n",
                maps, static_cast<unsigned long long>(inst.timings.shadow_instances_drawn), maps * 64,
                100.0 * double(inst.timings.shadow_instances_drawn) / double(maps * 64), worst);
    EXPECT_LT(double(inst.timings.shadow_instances_drawn), 0.6 * double(maps * 64));
    // The geometry pass keeps the boxes in the camera's frustum.
    std::printf("instances drawn by the camera: %llu of %d\n",
                static_cast<unsigned long long>(inst.timings.camera_instances_drawn), 64 * 4);
    EXPECT_LT(inst.timings.camera_instances_drawn, 64u * 4u);
    EXPECT_GT(inst.timings.camera_instances_drawn, 0u);
    EXPECT_LT(worst, 1e-4);
}

TEST(Shadows, RaysDoNotOccludeAnEmitterByItsOwnSurface) {
    // An emissive panel (a subdivided plane 1 m above the floor) lights the
    // floor: with shadow rays its own triangles, which every ray ends on,
    // must not block it, also at grazing angles (a ray that kept its
    // direction from the lifted origin crossed the panel's plane up to
    // eps / cos before its end: 4.4 % of the light lost). Reference: the
    // same panel casting no shadow.
    auto floor_mean = [](bool cast) {
        Renderer r;
        deferred::testing::add_plane(r, grey(), 6.0f);
        deferred::testing::add_plane(r, emitter(1.0f, 1.0f, 1.0f, 5.0f), 0.75f, 6, tools::translation(0, 0, 1.0), cast);
        deferred::testing::set_world_color(r, 0, 0, 0);
        RenderSettings s;
        s.width = 96;
        s.height = 96;
        s.samples = 16;
        s.shadow_rays = true;
        FrameResult f = r.render(deferred::testing::top_down_ortho(0.5, 5.0f), s);
        const PassImage& c = *f.find(Pass::Combined);
        double sum = 0.0;
        for (int i = 0; i < c.width * c.height; ++i) sum += c.pixels[std::size_t(i) * 4];
        EXPECT_EQ(f.timings.shadow_rays, cast);  // a floor with a non-casting emitter: nothing to shadow
        return sum / double(c.width * c.height);
    };
    const double shadowed = floor_mean(true), reference = floor_mean(false);
    std::printf("emitter over a floor, shadow rays: %.6f with its own shadow, %.6f without (ratio %.5f)\n", shadowed,
                reference, shadowed / reference);
    EXPECT_NEAR(shadowed / reference, 1.0, 1e-3);
}

TEST(Shadows, RaysToAMeshLightTraceOnePickedPointPerSample) {
    // Shadow rays towards an emissive mesh trace one ray per pixel and
    // sample (DEFERRED_MESH_LIGHT_RAYS=light: per light), to a candidate
    // (one of the light's points or the glossy lobe's hits) picked by its
    // unshadowed light, weighted W / w_j (light_lib.glsl,
    // MeshLightReservoir): unbiased for the sum over every candidate's own
    // ray (DEFERRED_MESH_LIGHT_RAYS=every, the reference).
    // A panel (32 triangles, 1 m up, coloured) over a glossy floor (alpha^2
    // 0.008: its lobe's directions are candidates too) with a blocker at
    // half height covering x < 0: the floor is wholly lit for x > 0.75,
    // wholly blocked for x < -0.75, a penumbra between. Where every ray is
    // free or every ray blocked, the pick gives the sum itself (its
    // candidates' light has one colour: c_j W / w_j = sum_k c_k); in the
    // penumbra it adds noise, and many samples agree.
    MeshLightRaysEnv env;
    Renderer r;
    Material floor = grey();
    floor.roughness = 0.3f;
    deferred::testing::add_plane(r, floor, 6.0f);
    deferred::testing::add_plane(r, emitter(1.0f, 0.6f, 0.3f, 8.0f), 0.75f, 4, tools::translation(0, 0, 1.0));
    deferred::testing::add_plane(r, grey(), 2.0f, 1, tools::translation(-2.0, 0, 0.5));
    deferred::testing::set_world_color(r, 0, 0, 0);
    Camera cam;
    const double eye[3] = {0.0, -3.0, 0.45}, target[3] = {0.0, 0.3, 0.0};
    cam.matrix = tools::look_at(eye, target);
    cam.lens = 18.0f;
    RenderSettings s;
    s.width = 160;
    s.height = 96;
    s.filter_width = 0.01f;
    s.shadow_rays = true;
    s.passes = {Pass::Combined, Pass::Position};
    auto render = [&](const char* mode, int samples) {
        env.set(mode);
        s.samples = samples;
        FrameResult f = r.render(cam, s);
        EXPECT_TRUE(f.timings.shadow_rays);
        return f;
    };
    const FrameResult pick4 = render("light", 4), every4 = render("every", 4);
    const FrameResult pick64 = render("light", 64), every64 = render("every", 64);
    // The default, one ray per pixel for all mesh lights: with one light the
    // same estimator (its own numbers).
    const FrameResult pool64 = render("pixel", 64);
    const PassImage& pos = *pick4.find(Pass::Position);
    double lit_diff = 0.0, lit_max = 0.0, umbra_max = 0.0, pen_diff2 = 0.0, pen_pick = 0.0, pen_every = 0.0,
           pen_pool = 0.0;
    int lit = 0, umbra = 0, penumbra = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const glm::dvec3 P = pixel3(pos, x, y);
            // The floor (the background's Position is 0).
            if (P == glm::dvec3(0.0) || std::abs(P.z) > 1e-3 || std::abs(P.y) > 1.5 || std::abs(P.x) > 3.0) continue;
            const double a = pixel3(*pick4.find(Pass::Combined), x, y).x;
            const double b = pixel3(*every4.find(Pass::Combined), x, y).x;
            if (P.x > 0.8) {
                lit_diff = std::max(lit_diff, std::abs(a - b));
                lit_max = std::max(lit_max, b);
                ++lit;
            } else if (P.x < -0.8) {
                umbra_max = std::max({umbra_max, std::abs(a), std::abs(b)});
                ++umbra;
            } else if (std::abs(P.x) < 0.7) {
                pen_diff2 += (a - b) * (a - b);
                pen_pick += pixel3(*pick64.find(Pass::Combined), x, y).x;
                pen_every += pixel3(*every64.find(Pass::Combined), x, y).x;
                pen_pool += pixel3(*pool64.find(Pass::Combined), x, y).x;
                ++penumbra;
            }
        }
    ASSERT_GT(lit, 500);
    ASSERT_GT(umbra, 500);
    ASSERT_GT(penumbra, 500);
    const double pen_rms = std::sqrt(pen_diff2 / penumbra);
    std::printf("mesh light, one picked ray: lit %d px, max |pick - every| %.2e of %.3f; umbra %d px, max %.2e; "
                "penumbra %d px: rms difference %.4f at 4 samples, means at 64 %.5f and %.5f (ratio %.5f; one ray a "
                "pixel %.5f)\n",
                lit, lit_diff, lit_max, umbra, umbra_max, penumbra, pen_rms, pen_pick / penumbra,
                pen_every / penumbra, pen_pick / pen_every, pen_pool / pen_every);
    EXPECT_GT(lit_max, 0.05);
    EXPECT_LT(lit_diff, 1e-4 * lit_max);
    EXPECT_LT(umbra_max, 1e-6);
    EXPECT_GT(pen_rms, 1e-3 * lit_max);  // the pick ran (and is noisier there)
    EXPECT_NEAR(pen_pick / pen_every, 1.0, 0.01);
    EXPECT_NEAR(pen_pool / pen_every, 1.0, 0.01);
}

TEST(Shadows, RaysToMeshLightsPoolTheirCandidatesAndKeepEachLightsGroup) {
    // One ray per pixel and sample for all the mesh lights (the default):
    // the pick runs over the union of their candidates, so a pixel that one
    // light reaches and a blocker hides from the other gets either all of
    // it or nothing, and the picked light's group gets it. Two panels (one
    // colour, light groups 1 and 2) at x = -1.2 and x = +1.2, 1 m up, a
    // blocker over -0.3 < x < 0.3 at half height: against every candidate's
    // own ray, each group's mean and the whole image's agree at 64 samples,
    // and per pixel the groups add up to Combined.
    MeshLightRaysEnv env;
    Renderer r;
    add_floor_and_blocker(r, 0.3f, 1.5f);
    tools::MeshArrays panel = tools::make_plane(0.5f, 2);
    const std::uint32_t pm = r.add_mesh(panel.view()), em = r.add_material(emitter(1.0f, 0.8f, 0.6f, 6.0f));
    for (int k = 0; k < 2; ++k) {
        Mat4d t = tools::translation(k == 0 ? -1.2 : 1.2, 0.0, 1.0);
        r.add_instances(pm, t.data(), 1, nullptr, {em}, true, nullptr, nullptr, nullptr, false, std::uint32_t(k + 1));
    }
    RenderSettings s;
    s.width = 128;
    s.height = 64;
    s.filter_width = 0.01f;
    s.shadow_rays = true;
    s.light_groups = 2;
    const Camera cam = deferred::testing::top_down_ortho(0.2, 4.0f);  // under the panels and the blocker
    auto render = [&](const char* mode, int samples) {
        env.set(mode);
        s.samples = samples;
        FrameResult f = r.render(cam, s);
        EXPECT_EQ(f.light_groups.size(), 2u);
        return f;
    };
    const FrameResult pool = render("pixel", 64), every = render("every", 64), pool4 = render("pixel", 4);
    auto mean = [](const std::vector<float>& px) {
        double sum = 0.0;
        for (std::size_t i = 0; i < px.size(); i += 4) sum += px[i] + px[i + 1] + px[i + 2];
        return sum / double(px.size() / 4);
    };
    const double g1 = mean(pool.light_groups[0]) / mean(every.light_groups[0]);
    const double g2 = mean(pool.light_groups[1]) / mean(every.light_groups[1]);
    const double all = mean(pool.find(Pass::Combined)->pixels) / mean(every.find(Pass::Combined)->pixels);
    double split = 0.0, peak = 0.0;
    const PassImage& c4 = *pool4.find(Pass::Combined);
    for (std::size_t i = 0; i < std::size_t(c4.width * c4.height) * 4; i += 4)
        for (int c = 0; c < 3; ++c) {
            split = std::max(split, std::abs(double(pool4.light_groups[0][i + c]) + pool4.light_groups[1][i + c] -
                                             c4.pixels[i + c]));
            peak = std::max(peak, double(c4.pixels[i + c]));
        }
    std::printf("two mesh lights, one ray a pixel, 64 samples against every candidate's ray: group 1 %.5f, group 2 "
                "%.5f, Combined %.5f; at 4 samples max |group 1 + group 2 - Combined| %.2e of %.3f\n",
                g1, g2, all, split, peak);
    EXPECT_GT(mean(every.light_groups[0]), 0.05);
    EXPECT_GT(mean(every.light_groups[1]), 0.05);
    EXPECT_NEAR(g1, 1.0, 0.01);
    EXPECT_NEAR(g2, 1.0, 0.01);
    EXPECT_NEAR(all, 1.0, 0.01);
    EXPECT_LT(split, 1e-5 * peak);
}

TEST(Shadows, RaysToMeshLightsPoolPerLightingBatch) {
    // More mesh lights than one lighting dispatch takes with rays
    // (kRayLightBatch): each dispatch pools its own lights' candidates and
    // traces their one ray. Twelve small panels in a ring 1 m up, a blocker
    // over the middle at half height: the image's mean at 64 samples
    // against every candidate's own ray.
    MeshLightRaysEnv env;
    Renderer r;
    add_floor_and_blocker(r, 0.6f, 0.6f);
    tools::MeshArrays panel = tools::make_plane(0.2f, 1);
    const std::uint32_t pm = r.add_mesh(panel.view()), em = r.add_material(emitter(1.0f, 0.9f, 0.7f, 20.0f));
    for (int k = 0; k < 12; ++k) {
        const double a = 2.0 * M_PI * k / 12.0;
        Mat4d t = tools::translation(1.5 * std::cos(a), 1.5 * std::sin(a), 1.0);
        r.add_instances(pm, t.data(), 1, nullptr, {em});
    }
    RenderSettings s;
    s.width = 96;
    s.height = 96;
    s.samples = 64;
    s.filter_width = 0.01f;
    s.shadow_rays = true;
    const Camera cam = deferred::testing::top_down_ortho(0.2, 5.0f);  // under the panels and the blocker
    auto mean = [&](const char* mode) {
        env.set(mode);
        const FrameResult f = r.render(cam, s);
        EXPECT_TRUE(f.timings.shadow_rays);
        EXPECT_GT(f.timings.lighting_later_pixels, 0u);  // a second dispatch of lights
        const PassImage& c = *f.find(Pass::Combined);
        double sum = 0.0;
        for (int i = 0; i < c.width * c.height; ++i) sum += c.pixels[std::size_t(i) * 4];
        return sum / double(c.width * c.height);
    };
    const double pool = mean("pixel"), every = mean("every");
    std::printf("twelve mesh lights, one ray a pixel and dispatch: mean %.5f against every candidate's ray %.5f "
                "(ratio %.5f)\n", pool, every, pool / every);
    EXPECT_GT(every, 0.05);
    EXPECT_NEAR(pool / every, 1.0, 0.01);
}

namespace {

// A floor with boxes around and under the lights of `config`, 4 samples:
// 0: an area light facing straight down; 1: a spot without radius facing
// down (40 degrees); 2: an area light tilted 35 degrees and a spot with a
// radius tilted the other way, with boxes in front of, beside and behind
// both (behind the area light's plane, outside the spot's cone).
FrameResult lit_region_frame(int config, bool count_fragments = true) {
    Renderer r;
    const std::uint32_t mat = deferred::testing::add_plane(r, grey(), 10.0f, 4);
    tools::MeshArrays box = tools::make_box(0.3f, 0.3f, 0.3f);
    const std::uint32_t bm = r.add_mesh(box.view());
    const double spots[][3] = {{0.0, 0.0, 0.3}, {1.5, 0.5, 0.3}, {-1.5, -0.5, 0.8}, {0.5, -1.5, 2.6},
                               {-0.6, 0.4, 3.4}, {2.5, 2.0, 1.2}, {-2.5, 1.5, 0.3}};
    for (const auto& p : spots) {
        Mat4d t = tools::translation(p[0], p[1], p[2]);
        r.add_instances(bm, t.data(), 1, nullptr, {mat});
    }
    auto aimed = [](LightType type, double x, double y, double z, double tx, double ty) {
        Light l;
        l.type = type;
        const double eye[3] = {x, y, z}, target[3] = {tx, ty, 0.0};
        l.matrix = tools::look_at(eye, target);
        l.energy = 300.0f;
        return l;
    };
    if (config == 0) {
        Light l = aimed(LightType::Area, 0.0, 0.0, 3.0, 0.0, 0.0);
        l.matrix = tools::translation(0.0, 0.0, 3.0);  // facing -Z exactly
        l.size = 0.8f;
        r.add_light(l);
    } else if (config == 1) {
        Light l = aimed(LightType::Spot, 0.0, 0.0, 3.0, 0.0, 0.0);
        l.matrix = tools::translation(0.0, 0.0, 3.0);
        l.radius = 0.0f;
        l.spot_size = float(40.0 * M_PI / 180.0);
        r.add_light(l);
    } else {
        Light area = aimed(LightType::Area, -1.2, 0.3, 3.0, 0.9, -0.4);
        area.shape = AreaShape::Rectangle;
        area.size = 1.0f;
        area.size_y = 0.4f;
        r.add_light(area);
        Light spot = aimed(LightType::Spot, 1.5, -0.8, 2.8, -0.8, 0.6);
        spot.radius = 0.3f;
        spot.spot_size = float(70.0 * M_PI / 180.0);
        spot.spot_blend = 0.3f;
        r.add_light(spot);
    }
    deferred::testing::set_world_color(r, 0, 0, 0);  // no world occlusion map
    Camera cam;
    const double ceye[3] = {5.0, -6.0, 6.0}, ctarget[3] = {0.0, 0.0, 0.8};
    cam.matrix = tools::look_at(ceye, ctarget);
    RenderSettings s;
    s.width = 96;
    s.height = 64;
    s.samples = 4;
    s.passes = {Pass::Combined, Pass::DiffDir, Pass::GlossDir, Pass::Shadow};
    s.count_shadow_fragments = count_fragments;
    return r.render(cam, s);
}

}  // namespace

TEST(Shadows, CubeMapsAreDrawnOnlyWhereTheLightShines) {
    // A spot lights only its cone and an area light only what lies in front
    // of its plane: the faces and parts of their cube maps that no lit
    // receiver looks up are not drawn (scissors), and casters outside are
    // clipped. The image must be the one with every face drawn whole
    // (DEFERRED_SHADOW_LIT_REGION=off): measured equal to the bit.
    const char* names[] = {"area light facing down", "spot without radius", "tilted area light, spot with radius"};
    struct EnvGuard {  // unset again whatever happens
        ~EnvGuard() { unsetenv("DEFERRED_SHADOW_LIT_REGION"); }
    } guard;
    for (int config = 0; config < 3; ++config) {
        unsetenv("DEFERRED_SHADOW_LIT_REGION");
        const FrameResult lit = lit_region_frame(config);
        setenv("DEFERRED_SHADOW_LIT_REGION", "off", 1);
        const FrameResult whole = lit_region_frame(config);
        unsetenv("DEFERRED_SHADOW_LIT_REGION");
        double worst = 0;
        for (Pass pass : {Pass::Combined, Pass::DiffDir, Pass::GlossDir, Pass::Shadow}) {
            const PassImage& a = *lit.find(pass);
            const PassImage& b = *whole.find(pass);
            for (std::size_t i = 0; i < a.pixels.size(); ++i)
                worst = std::max(worst, double(std::abs(a.pixels[i] - b.pixels[i])) /
                                            std::max(1e-3, double(std::abs(b.pixels[i]))));
        }
        const double ratio = double(lit.timings.shadow_texels_rendered) / double(whole.timings.shadow_texels_rendered);
        const double fill = double(lit.timings.shadow_fragments) / double(std::max<std::uint64_t>(whole.timings.shadow_fragments, 1));
        std::printf("%s: %zu of %zu layers, %.3f of the texels, %.3f of the fragments (%llu); largest relative "
                    "difference %.2e\n", names[config], lit.timings.shadow_layers_rendered,
                    whole.timings.shadow_layers_rendered, ratio, fill,
                    static_cast<unsigned long long>(whole.timings.shadow_fragments), worst);
        EXPECT_LT(worst, 1e-5) << names[config];
        // Less fill (llvmpipe counts fragment shader invocations; a driver
        // without them reports 0). With the tilted lights the scissors leave
        // most texels, and the clip planes take out the casters behind the
        // area light and outside the spot's cone: less fill than texels.
        if (whole.timings.shadow_fragments > 0) {
            EXPECT_LT(fill, 0.9) << names[config];
            if (config == 2) {
                EXPECT_LT(fill, ratio) << names[config];
            }
        }
        if (config == 0) {
            // The face looking up sees nothing lit; the four side faces half
            // of it (and the margin: 0.52 at this image's resolution).
            EXPECT_EQ(lit.timings.shadow_layers_rendered, 5u * 4u);
            EXPECT_EQ(whole.timings.shadow_layers_rendered, 6u * 4u);
            EXPECT_LT(ratio, 0.6);
            EXPECT_GT(ratio, 0.5);
        } else if (config == 1) {
            // Drawn once (no size): one face, the cone's square within it.
            EXPECT_EQ(lit.timings.shadow_layers_rendered, 1u);
            EXPECT_EQ(whole.timings.shadow_layers_rendered, 6u);
            EXPECT_LT(ratio, 0.05);
        } else {
            EXPECT_LE(lit.timings.shadow_layers_rendered, whole.timings.shadow_layers_rendered);
            EXPECT_LT(ratio, 1.0);
        }
    }
    // Fragments are counted only when asked (RenderSettings::
    // count_shadow_fragments): no queries in a render's layers otherwise.
    const FrameResult uncounted = lit_region_frame(1, false);
    EXPECT_EQ(uncounted.timings.shadow_layers_rendered, 1u);
    EXPECT_EQ(uncounted.timings.shadow_fragments, 0u);
}
