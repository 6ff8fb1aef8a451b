// Passes: present only when requested, with their channels and Cycles'
// background values, and the values they carry on geometry.
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace deferred;
using deferred::testing::pixel3;

namespace {
struct Scene {
    Renderer r;
    Camera cam;
    Scene() {
        tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.5f);
        const std::uint32_t mesh = r.add_mesh(box.view());
        Material m;
        m.base_color = {0.75f, 0.5f, 0.25f};
        m.metallic = 0.25f;
        m.emission = {0.5f, 0.25f, 0.0f};
        m.emission_strength = 2.0f;
        m.pass_index = 7;
        const std::uint32_t mat = r.add_material(m);
        Mat4d t = tools::translation(0, 0, 0);
        const std::uint32_t ob = 42;
        r.add_instances(mesh, t.data(), 1, &ob, {mat});
        Light l;
        l.type = LightType::Point;
        l.matrix = tools::translation(1, -1, 3);
        l.energy = 100;
        l.radius = 0;
        r.add_light(l);
        World w;
        w.color = {0.1f, 0.2f, 0.3f};
        r.set_world(w);
        cam = deferred::testing::top_down_ortho(5.0, 4.0f);  // box covers the centre quarter
    }
};
}  // namespace

TEST(Passes, OnlyRequestedPassesAreProduced) {
    Scene s;
    RenderSettings settings;
    settings.width = 32;
    settings.height = 32;
    FrameResult only = s.r.render(s.cam, settings);
    ASSERT_EQ(only.passes.size(), 1u);
    EXPECT_EQ(only.passes[0].pass, Pass::Combined);
    EXPECT_EQ(only.passes[0].channels, 4);

    settings.passes.insert(Pass::Depth);
    settings.passes.insert(Pass::IndexOB);
    FrameResult two = s.r.render(s.cam, settings);
    ASSERT_EQ(two.passes.size(), 3u);
    EXPECT_NE(two.find(Pass::Depth), nullptr);
    EXPECT_NE(two.find(Pass::IndexOB), nullptr);
    EXPECT_EQ(two.find(Pass::Normal), nullptr);
}

TEST(Passes, ChannelsBackgroundsAndValues) {
    Scene s;
    RenderSettings settings;
    settings.width = 32;
    settings.height = 32;
    for (std::uint32_t i = 0; i < kPassCount; ++i) settings.passes.insert(Pass(i));
    FrameResult f = s.r.render(s.cam, settings);
    ASSERT_EQ(f.passes.size(), std::size_t(kPassCount));
    const int bx = 1, by = 1;   // background corner
    const int gx = 16, gy = 16; // box top face
    for (const PassImage& img : f.passes) {
        const PassInfo& info = pass_info(img.pass);
        EXPECT_EQ(img.channels, info.channels) << info.name;
        EXPECT_EQ(img.pixels.size(), std::size_t(32 * 32 * info.channels)) << info.name;
        if (img.pass == Pass::Combined || img.pass == Pass::Env) continue;
        for (int c = 0; c < img.channels; ++c)
            EXPECT_EQ(img.pixels[(std::size_t(by) * 32 + bx) * img.channels + c], info.background[c])
                << info.name << " background channel " << c;
    }
    // Combined: world colour behind, opaque.
    const PassImage& combined = *f.find(Pass::Combined);
    EXPECT_NEAR(combined.pixels[(by * 32 + bx) * 4 + 0], 0.1f, 1e-6);
    EXPECT_NEAR(combined.pixels[(by * 32 + bx) * 4 + 3], 1.0f, 1e-6);
    EXPECT_NEAR(combined.pixels[(gy * 32 + gx) * 4 + 3], 1.0f, 1e-6);
    // Env: the world where the background is seen, 0 on geometry.
    const PassImage& env = *f.find(Pass::Env);
    EXPECT_NEAR(pixel3(env, bx, by).z, 0.3, 1e-6);
    EXPECT_EQ(pixel3(env, gx, gy).x, 0.0);
    // Geometry values: top face at z = 0.5, seen from z = 5.
    EXPECT_NEAR(pixel3(*f.find(Pass::Depth), gx, gy).x, 4.5, 1e-5);
    EXPECT_NEAR(pixel3(*f.find(Pass::Position), gx, gy).z, 0.5, 1e-5);
    const glm::dvec3 n = pixel3(*f.find(Pass::Normal), gx, gy);
    EXPECT_NEAR(n.z, 1.0, 1e-5);
    EXPECT_NEAR(glm::length(n), 1.0, 1e-5);
    EXPECT_EQ(pixel3(*f.find(Pass::IndexOB), gx, gy).x, 42.0);
    EXPECT_EQ(pixel3(*f.find(Pass::IndexMA), gx, gy).x, 7.0);
    const glm::dvec3 uv = pixel3(*f.find(Pass::UV), gx, gy);
    EXPECT_EQ(uv.z, 1.0);  // UV alpha on geometry
    // DiffCol = base (1 - metallic); GlossCol = 1 (specular closure); Emit = emission x strength.
    const glm::dvec3 diffcol = pixel3(*f.find(Pass::DiffCol), gx, gy);
    EXPECT_NEAR(diffcol.x, 0.75 * 0.75, 1e-3);
    EXPECT_NEAR(diffcol.z, 0.25 * 0.75, 1e-3);
    EXPECT_NEAR(pixel3(*f.find(Pass::GlossCol), gx, gy).y, 1.0, 1e-6);
    const glm::dvec3 emit = pixel3(*f.find(Pass::Emit), gx, gy);
    EXPECT_NEAR(emit.x, 1.0, 1e-6);
    EXPECT_NEAR(emit.y, 0.5, 1e-6);
    // Combined = emission + DiffDir x DiffCol + GlossDir x GlossCol (no world
    // light here would be wrong: the world term is in the Dir passes too).
    const glm::dvec3 c = pixel3(combined, gx, gy);
    const glm::dvec3 rebuilt = emit + pixel3(*f.find(Pass::DiffDir), gx, gy) * diffcol +
                               pixel3(*f.find(Pass::GlossDir), gx, gy) * pixel3(*f.find(Pass::GlossCol), gx, gy);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(c[k], rebuilt[k], 1e-4 * std::max(1.0, c[k])) << "channel " << k;
    // Mist: distance 4.5 with start 5 -> 0.
    EXPECT_EQ(pixel3(*f.find(Pass::Mist), gx, gy).x, 0.0);
}

TEST(Passes, FilmTransparentMakesBackgroundAlphaZero) {
    Scene s;
    RenderSettings settings;
    settings.width = 16;
    settings.height = 16;
    settings.film_transparent = true;
    FrameResult f = s.r.render(s.cam, settings);
    const PassImage& combined = *f.find(Pass::Combined);
    for (int c = 0; c < 4; ++c) EXPECT_EQ(combined.pixels[c], 0.0f);  // corner pixel
    EXPECT_NEAR(combined.pixels[(8 * 16 + 8) * 4 + 3], 1.0f, 1e-6);
}

TEST(Passes, AddUpToCombinedAtEveryPixelWhenSplatted) {
    // Filter splatting (film_module.h): the passes Combined is made of are
    // splatted with it, colours too, so at every pixel, edges included
    // (where a pixel's own samples may all see the background and its
    // neighbours' the box), Combined = Emit + Env + DiffDir x DiffCol +
    // GlossDir x GlossCol, as with each pixel's own samples.
    Scene s;
    RenderSettings settings;
    settings.width = 32;
    settings.height = 32;
    settings.samples = 16;
    settings.passes = {Pass::Combined, Pass::Emit, Pass::Env, Pass::DiffDir, Pass::DiffCol, Pass::GlossDir,
                       Pass::GlossCol};
    for (bool splat : {true, false}) {
        settings.filter_splat = splat;
        FrameResult f = s.r.render(s.cam, settings);
        double worst = 0;
        int edge_pixels = 0;
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                const glm::dvec3 c = pixel3(*f.find(Pass::Combined), x, y);
                const glm::dvec3 rebuilt =
                    pixel3(*f.find(Pass::Emit), x, y) + pixel3(*f.find(Pass::Env), x, y) +
                    pixel3(*f.find(Pass::DiffDir), x, y) * pixel3(*f.find(Pass::DiffCol), x, y) +
                    pixel3(*f.find(Pass::GlossDir), x, y) * pixel3(*f.find(Pass::GlossCol), x, y);
                const double env = pixel3(*f.find(Pass::Env), x, y).z;
                if (env > 0.0 && env < 0.3 - 1e-4) ++edge_pixels;  // partly background
                for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(c[k] - rebuilt[k]) / std::max(1.0, c[k]));
            }
        std::printf("%s: the passes rebuild Combined to %.2e over %d pixels partly background\n",
                    splat ? "splatted" : "own samples", worst, edge_pixels);
        EXPECT_GT(edge_pixels, 20);
        EXPECT_LT(worst, 1e-4) << splat;
    }
}
