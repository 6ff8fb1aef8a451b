// The visibility buffer (visibility_module.h) against the raster path: the
// same scene rendered both ways gives the same passes. The varyings come
// from the pixel's ray met on the triangle's plane instead of the
// rasteriser's interpolation, so the two agree to rounding (bounds below,
// with what llvmpipe measures). Node materials through real Blender files:
// tests/blender/test_visibility_buffer.py.
#include "builtin_scenes.h"
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

using namespace deferred;
using namespace deferred::testing;

namespace {

// The rasteriser's interpolation is the visibility buffer's only up to where
// it puts the vertices: GL snaps window positions to its subpixel grid (GL
// 4.5 section 14.5, GL_SUBPIXEL_BITS, 8 on llvmpipe and NVIDIA), each
// corner by up to 1/512 pixel per axis. An attribute interpolated over the
// snapped corners moves by at most its screen gradient times that shift
// (the weights' change is -sum_j b_j grad(b) . e_j): for a linear attribute,
// at most 0.7 of its largest difference to a neighbour over 256. A pixel's
// Normal or UV may differ by that difference over 64 (a 1/64-pixel shift):
// an H200 differed by 2.3e-3 in Normal and 4.2e-4 in UV on the showcase at
// 96x64, where its 24x12 sphere's triangles are two or three pixels wide,
// at most 2.02/256 of the neighbour difference (by the silhouette, where
// the normal is far from linear). llvmpipe interpolates from the unsnapped
// positions: every pass within 7.4e-5 without the allowance. A resolve off
// by 0.05 pixel exceeds it everywhere (Normal 0.12; measured by hand).
constexpr double kSnapSlopeFactor = 4.0 / 256.0;

bool interpolated(Pass p) { return p == Pass::Normal || p == Pass::UV; }
// Passes shaded from that normal: a sharp highlight narrower than a pixel
// moves by more than the image's neighbour differences tell, so these must
// agree at all but 1 % of their pixels to the same allowance, and on
// average to the bound.
bool shaded(Pass p) {
    return p == Pass::Combined || p == Pass::DiffDir || p == Pass::GlossDir || p == Pass::Shadow || p == Pass::AO ||
           p == Pass::ShadowCatcher;
}

// Per pass: the largest difference between the two renders beyond what the
// rasteriser's snapping allows (above), relative to the pass's range
// (Depth, Position are metres). The other passes (Depth, Position, the
// indices, the colour passes: what surface a pixel sees, not where on it)
// must agree to the bound at every pixel.
void expect_same_passes(const FrameResult& raster, const FrameResult& vis, double bound, const std::string& what) {
    ASSERT_EQ(raster.passes.size(), vis.passes.size());
    for (const PassImage& a : raster.passes) {
        const PassImage* b = vis.find(a.pass);
        ASSERT_NE(b, nullptr);
        ASSERT_EQ(a.pixels.size(), b->pixels.size());
        double scale = 1;
        for (float v : a.pixels)
            if (std::isfinite(v) && std::abs(v) < 1e9f) scale = std::max(scale, double(std::abs(v)));
        const bool snapped = interpolated(a.pass) || shaded(a.pass);
        const std::size_t ch = std::size_t(a.channels), w = std::size_t(a.width), h = std::size_t(a.height);
        double worst = 0, worst_excess = 0, sum = 0;
        std::size_t beyond = 0, counted = 0, worst_at = 0;
        for (std::size_t i = 0; i < a.pixels.size(); ++i) {
            ASSERT_TRUE(std::isfinite(b->pixels[i]) || !std::isfinite(a.pixels[i])) << what;
            if (std::abs(a.pixels[i]) >= 1e9f) continue;  // the background's depth
            const double d = std::abs(double(a.pixels[i]) - double(b->pixels[i]));
            double slope = 0;  // the raster pixel's largest difference to a neighbour
            if (snapped) {
                const std::size_t px = i / ch, x = px % w, y = px / w;
                for (const auto& [dx, dy] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
                    const long nx = long(x) + dx, ny = long(y) + dy;
                    if (nx < 0 || ny < 0 || nx >= long(w) || ny >= long(h)) continue;
                    const float n = a.pixels[(std::size_t(ny) * w + std::size_t(nx)) * ch + i % ch];
                    if (std::abs(n) < 1e9f) slope = std::max(slope, std::abs(double(n) - double(a.pixels[i])));
                }
            }
            const double excess = d - slope * kSnapSlopeFactor;
            if (excess > bound * scale) ++beyond;
            if (excess > worst_excess) worst_excess = excess, worst_at = i;
            worst = std::max(worst, d);
            sum += d;
            ++counted;
        }
        const double mean = counted ? sum / double(counted) : 0.0;
        const std::size_t px = worst_at / ch;
        std::printf("%s: %s differs by %.3g (of %.3g), mean %.3g; beyond the snapping allowance %.3g at %zu of %zu "
                    "values (worst at pixel %zu, %zu)\n",
                    what.c_str(), pass_info(a.pass).name, worst, scale, mean, worst_excess, beyond, counted, px % w,
                    px / w);
        if (shaded(a.pass)) {
            EXPECT_LE(double(beyond), 0.01 * double(counted)) << what << ": " << pass_info(a.pass).name;
            EXPECT_LE(mean, bound * scale) << what << ": " << pass_info(a.pass).name << " differs on average";
        } else {
            EXPECT_LE(worst_excess, bound * scale) << what << ": " << pass_info(a.pass).name << " differs by " << worst;
        }
    }
}

FrameResult render(Renderer& r, const Camera& cam, RenderSettings s, bool visibility) {
    s.visibility_buffer = visibility;
    FrameResult f = r.render(cam, s);
    EXPECT_EQ(f.timings.visibility_buffer, visibility);
    return f;
}

RenderSettings every_pass(int w, int h, int samples) {
    RenderSettings s;
    s.width = w;
    s.height = h;
    s.samples = samples;
    for (std::uint32_t p = 0; p < kPassCount; ++p) s.passes.insert(Pass(p));
    return s;
}

}  // namespace

TEST(VisibilityBuffer, TheShowcaseMatchesTheRasterPathInEveryPass) {
    // Principled materials, several lights with shadow maps, and three
    // more objects: a mirrored sphere (negative determinant: the facing the
    // resolve derives must be the rasteriser's), a box under non-uniform
    // scale, and a Blend-mode pane the forward pass draws (left out of the
    // visibility buffer). Measured on llvmpipe: every pass within 7.4e-5
    // absolute (Combined 5e-5 where it reaches 12.9; Depth, Position, the
    // indices and the colour passes exactly equal); a wrong facing would
    // turn the mirrored sphere's normals over (a difference of ~2).
    Renderer r;
    Camera cam = tools::build_showcase(r);
    tools::MeshArrays sphere = tools::make_uv_sphere(0.6f, 24, 12);
    tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.5f);
    Material red;
    red.base_color = {0.8f, 0.1f, 0.1f};
    red.roughness = 0.3f;
    Material pane;
    pane.base_color = {0.1f, 0.3f, 0.9f};
    pane.blend = true;
    const std::uint32_t sphere_mesh = r.add_mesh(sphere.view()), box_mesh = r.add_mesh(box.view());
    const std::uint32_t red_id = r.add_material(red), pane_id = r.add_material(pane);
    Mat4d mirrored = tools::translation(-1.5, -1.0, 0.8);
    mirrored[0] = -1.0;
    r.add_instances(sphere_mesh, mirrored.data(), 1, nullptr, {red_id});
    Mat4d stretched = tools::translation(1.5, -1.5, 0.5);
    stretched[0] = 2.0;
    stretched[5] = 0.5;
    r.add_instances(box_mesh, stretched.data(), 1, nullptr, {red_id});
    Mat4d in_front = tools::translation(0.0, -2.5, 0.6);
    r.add_instances(box_mesh, in_front.data(), 1, nullptr, {pane_id});
    const RenderSettings s = every_pass(96, 64, 4);
    const FrameResult raster = render(r, cam, s, false), vis = render(r, cam, s, true);
    expect_same_passes(raster, vis, 1e-4, "showcase");
    // The Cryptomatte ids come from the resolve too (the instance ids target).
    RenderSettings c = s;
    c.passes = PassSet();
    c.cryptomatte = {CryptomatteKind::Object, CryptomatteKind::Material};
    const FrameResult craster = render(r, cam, c, false), cvis = render(r, cam, c, true);
    ASSERT_EQ(craster.cryptomatte.size(), cvis.cryptomatte.size());
    for (std::size_t k = 0; k < craster.cryptomatte.size(); ++k)
        EXPECT_EQ(craster.cryptomatte[k].pixels, cvis.cryptomatte[k].pixels) << "Cryptomatte layer " << k;
}

TEST(VisibilityBuffer, OrthographicViewsAndDeformingMeshesUnderMotionBlur) {
    // An orthographic camera (the pixel's ray keeps its direction and moves
    // its origin) over a plane whose vertices move over the shutter (the
    // resolve fetches them at the sample's time, as the vertex stage) and a
    // sphere moving as an instance.
    Renderer r;
    tools::MeshArrays plane = tools::make_plane(1.0f, 4);
    std::vector<float> motion_positions;
    for (int step = 0; step < 2; ++step)
        for (std::size_t v = 0; v < plane.positions.size() / 3; ++v) {
            motion_positions.push_back(plane.positions[3 * v] + (step == 0 ? -0.5f : 0.5f));
            motion_positions.push_back(plane.positions[3 * v + 1]);
            motion_positions.push_back(plane.positions[3 * v + 2] + (step == 0 ? 0.0f : 0.3f));
        }
    MeshData data = plane.view();
    data.motion_positions = motion_positions.data();
    Material grey;
    grey.base_color = {0.5f, 0.5f, 0.5f};
    const std::uint32_t grey_id = r.add_material(grey);
    r.add_instances(r.add_mesh(data), identity_matrix().data(), 1, nullptr, {grey_id});
    tools::MeshArrays sphere = tools::make_uv_sphere(0.4f, 16, 8);
    const Mat4d now = tools::translation(0.5, 0.5, 0.5);
    // Its previous and next matrices (Renderer::add_instances' `motion`).
    const Mat4d previous = tools::translation(0.2, 0.5, 0.5), next = tools::translation(0.8, 0.6, 0.5);
    double steps[32];
    std::copy(previous.begin(), previous.end(), steps);
    std::copy(next.begin(), next.end(), steps + 16);
    r.add_instances(r.add_mesh(sphere.view()), now.data(), 1, nullptr, {grey_id}, true, nullptr, nullptr, nullptr,
                    false, 0, nullptr, steps);
    Light sun;
    sun.type = LightType::Sun;
    sun.energy = 2.0f;
    r.add_light(sun);
    set_world_color(r, 0.05f, 0.05f, 0.05f);
    RenderSettings s = every_pass(64, 48, 8);
    s.motion_blur = true;
    const Camera cam = top_down_ortho(5.0, 3.0f);
    expect_same_passes(render(r, cam, s, false), render(r, cam, s, true), 1e-4, "orthographic, motion blur");
}

TEST(VisibilityBuffer, PartlyTransparentMaterialsCoverTheSamePixels) {
    // Stochastic transparency: a pane of alpha 0.5 and one mixing alpha 0.3
    // with an opaque component over a floor. The visibility pass tests the
    // same numbers for the same (pixel, instance, triangle, sample) as the
    // raster G-buffer, and the resolve picks the same mix component, so the
    // covered pixels are the same ones; the data passes' Alpha Threshold
    // G-buffer too (Depth, Normal, the indices from the first surface whose
    // alpha reaches it).
    Renderer r;
    Material floor;
    floor.base_color = {0.7f, 0.7f, 0.7f};
    add_plane(r, floor, 3.0f);
    Material half;
    half.base_color = {0.9f, 0.2f, 0.1f};
    half.alpha = 0.5f;
    add_plane(r, half, 1.0f, 1, tools::translation(-0.8, 0.0, 0.5));
    Material solid;
    solid.base_color = {0.1f, 0.9f, 0.2f};
    const std::uint32_t solid_id = r.add_material(solid);
    Material mixed;  // alpha 0.3, or the opaque one with probability 0.5
    mixed.base_color = {0.1f, 0.2f, 0.9f};
    mixed.alpha = 0.3f;
    mixed.mix_with = std::int32_t(solid_id);
    mixed.mix_probability = 0.5f;
    const std::uint32_t mixed_id = r.add_material(mixed);
    tools::MeshArrays pane = tools::make_plane(0.6f);
    r.add_instances(r.add_mesh(pane.view()), tools::translation(0.8, 0.3, 0.8).data(), 1, nullptr, {mixed_id});
    Light sun;
    sun.type = LightType::Sun;
    sun.energy = 3.0f;
    r.add_light(sun);
    set_world_color(r, 0.1f, 0.1f, 0.1f);
    RenderSettings s = every_pass(48, 32, 8);
    s.film_transparent = true;
    const Camera cam = top_down_ortho(5.0, 3.0f);
    expect_same_passes(render(r, cam, s, false), render(r, cam, s, true), 1e-4, "partly transparent");
}

TEST(VisibilityBuffer, TheResolveMeetsThePixelsRayAsExactlyAsDoublesAllow) {
    // A plane seen obliquely (perspective: the weights are not affine in
    // the window) whose corners, and the camera's position, are exact in
    // float, so the only error left is the resolve's own: its UV against the
    // UV where each pixel centre's ray (1 sample: unjittered) meets the
    // plane, computed here in double. llvmpipe: the resolve in double errs
    // 1.1e-7, in float 5.3e-7 (the ray's origin and the corner are ~9 m
    // apart while the weights resolve millimetres), the rasteriser 2.7e-7.
    Renderer r;
    Material m;
    m.base_color = {0.5f, 0.5f, 0.5f};
    const float half = 2.0f;
    add_plane(r, m, half, 4);
    set_world_color(r, 0.1f, 0.1f, 0.1f);
    Camera cam;
    const double eye[3] = {0.25, -4.5, 6.5}, target[3] = {0.125, 0.25, 0.0};
    cam.matrix = tools::look_at(eye, target);
    RenderSettings s;
    s.width = 160;
    s.height = 120;
    s.samples = 1;
    s.passes = PassSet{Pass::Combined, Pass::UV};
    const FrameResult vis = render(r, cam, s, true), raster = render(r, cam, s, false);
    // The pixel centre's ray (the camera looks down its -Z; sensor fit Auto,
    // so the width spans the sensor's 36 mm at the 50 mm lens).
    const double tan_x = 0.5 * double(cam.sensor_width) / double(cam.lens);
    const double tan_y = tan_x * double(s.height) / double(s.width);
    const Mat4d& M = cam.matrix;
    double worst_vis = 0, worst_raster = 0;
    int counted = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const double lx = (2.0 * (x + 0.5) / s.width - 1.0) * tan_x, ly = (2.0 * (y + 0.5) / s.height - 1.0) * tan_y;
            const glm::dvec3 dir(M[0] * lx + M[4] * ly - M[8], M[1] * lx + M[5] * ly - M[9], M[2] * lx + M[6] * ly - M[10]);
            const glm::dvec3 origin(M[12], M[13], M[14]);
            const double t = -origin.z / dir.z;
            const glm::dvec3 hit = origin + t * dir;
            // Pixels a whole pixel inside the plane's edges.
            if (!(t > 0) || std::abs(hit.x) > half - 0.1 || std::abs(hit.y) > half - 0.1) continue;
            const glm::dvec2 uv(0.5 + hit.x / (2.0 * half), 0.5 + hit.y / (2.0 * half));
            const glm::dvec3 got = pixel3(*vis.find(Pass::UV), x, y), raster_uv = pixel3(*raster.find(Pass::UV), x, y);
            ASSERT_EQ(got.z, 1.0) << "pixel " << x << ", " << y << " should see the plane";
            worst_vis = std::max({worst_vis, std::abs(got.x - uv.x), std::abs(got.y - uv.y)});
            worst_raster = std::max({worst_raster, std::abs(raster_uv.x - uv.x), std::abs(raster_uv.y - uv.y)});
            ++counted;
        }
    std::printf("%d pixels: UV against the ray's exact hit: visibility buffer %.3g, raster %.3g\n", counted, worst_vis,
                worst_raster);
    EXPECT_GT(counted, 5000);
    // UV is stored as float (half an ulp at 1: 6e-8); the weights as float.
    EXPECT_LT(worst_vis, 3e-7);
}
