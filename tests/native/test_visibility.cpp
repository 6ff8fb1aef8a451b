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

// Largest absolute difference between the two renders' passes, per pass.
void expect_same_passes(const FrameResult& raster, const FrameResult& vis, double bound, const std::string& what) {
    ASSERT_EQ(raster.passes.size(), vis.passes.size());
    for (const PassImage& a : raster.passes) {
        const PassImage* b = vis.find(a.pass);
        ASSERT_NE(b, nullptr);
        ASSERT_EQ(a.pixels.size(), b->pixels.size());
        double worst = 0, scale = 1;
        for (float v : a.pixels)
            if (std::isfinite(v) && std::abs(v) < 1e9f) scale = std::max(scale, double(std::abs(v)));
        for (std::size_t i = 0; i < a.pixels.size(); ++i) {
            ASSERT_TRUE(std::isfinite(b->pixels[i]) || !std::isfinite(a.pixels[i])) << what;
            if (std::abs(a.pixels[i]) >= 1e9f) continue;  // the background's depth
            worst = std::max(worst, std::abs(double(a.pixels[i]) - double(b->pixels[i])));
        }
        std::printf("%s: %s differs by %.3g (of %.3g)\n", what.c_str(), pass_info(a.pass).name, worst, scale);
        // Relative to the pass's range (Depth, Position are metres).
        EXPECT_LE(worst, bound * scale) << what << ": " << pass_info(a.pass).name << " differs by " << worst;
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
