// Depth and Position of a plane from 0.1 m to 10 km, and camera-relative
// rendering far from the origin.
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace deferred;
using deferred::testing::pixel3;

namespace {
FrameResult render_plane(double distance, double offset_x, double offset_y, int size = 32) {
    Renderer r;
    tools::MeshArrays plane = tools::make_plane(float(distance * 2));
    const std::uint32_t mesh = r.add_mesh(plane.view());
    const std::uint32_t mat = r.add_material(Material{});
    Mat4d m = tools::translation(offset_x, offset_y, 0);
    r.add_instances(mesh, m.data(), 1, nullptr, {mat});
    Light sun;
    sun.type = LightType::Sun;
    r.add_light(sun);
    Camera cam;
    cam.matrix = tools::translation(offset_x, offset_y, distance);
    cam.lens = 50;
    cam.clip_start = 0.01f;
    cam.clip_end = 1e5f;
    RenderSettings s;
    s.width = size;
    s.height = size;
    s.passes.insert(Pass::Depth);
    s.passes.insert(Pass::Position);
    return r.render(cam, s);
}
}  // namespace

TEST(DepthPosition, PlaneFromTenCentimetresToTenKilometres) {
    for (double d : {0.1, 1.0, 10.0, 100.0, 1000.0, 10000.0}) {
        FrameResult f = render_plane(d, 0, 0);
        const PassImage& depth = *f.find(Pass::Depth);
        const PassImage& pos = *f.find(Pass::Position);
        // Perspective camera, 50 mm lens on a 36 mm sensor, square image:
        // pixel centre (i + 0.5) maps to x/d = (2 (i + 0.5)/W - 1) * 18/50.
        double worst_depth = 0, worst_pos = 0;
        for (int y = 0; y < depth.height; ++y)
            for (int x = 0; x < depth.width; ++x) {
                const double z = depth.pixels[std::size_t(y) * depth.width + x];
                worst_depth = std::max(worst_depth, std::abs(z - d) / d);
                const double ex = (2.0 * (x + 0.5) / depth.width - 1.0) * 18.0 / 50.0 * d;
                const double ey = (2.0 * (y + 0.5) / depth.height - 1.0) * 18.0 / 50.0 * d;
                const glm::dvec3 p = pixel3(pos, x, y);
                const double err = glm::length(p - glm::dvec3(ex, ey, 0.0)) / d;
                worst_pos = std::max(worst_pos, err);
            }
        std::printf("plane at %8.1f m: depth rel. error %.2e, position rel. error %.2e\n", d, worst_depth, worst_pos);
        EXPECT_LT(worst_depth, 1e-5) << "distance " << d;
        EXPECT_LT(worst_pos, 1e-5) << "distance " << d;
    }
}

TEST(DepthPosition, CameraFarFromOriginGivesTheSameImage) {
    // Scene and camera moved together by 1e5 m: camera-relative rendering
    // keeps the image (float32 world positions would misplace pixels).
    FrameResult a = render_plane(10.0, 0, 0, 64);
    FrameResult b = render_plane(10.0, 1e5, -1e5, 64);
    const PassImage& ca = *a.find(Pass::Combined);
    const PassImage& cb = *b.find(Pass::Combined);
    const PassImage& da = *a.find(Pass::Depth);
    const PassImage& db = *b.find(Pass::Depth);
    double worst_color = 0, worst_depth = 0;
    for (std::size_t i = 0; i < ca.pixels.size(); ++i)
        worst_color = std::max(worst_color, double(std::abs(ca.pixels[i] - cb.pixels[i])));
    for (std::size_t i = 0; i < da.pixels.size(); ++i)
        worst_depth = std::max(worst_depth, double(std::abs(da.pixels[i] - db.pixels[i])) / 10.0);
    std::printf("camera at 1e5 m: max colour difference %.2e, depth rel. difference %.2e\n", worst_color, worst_depth);
    EXPECT_LT(worst_color, 1e-5);
    EXPECT_LT(worst_depth, 1e-6);
}
