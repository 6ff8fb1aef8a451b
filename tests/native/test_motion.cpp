// The Vector pass (motion_module.h): Cycles' primitive_motion_vector, xy =
// raster(previous) - raster(now), zw = raster(now) - raster(next), in
// pixels with y up, averaged over the samples that see a surface.
#include "camera.h"
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

using namespace deferred;

namespace {
constexpr int kSize = 32;  // pixels; the orthographic cameras cover 4 m: 8 px per metre

std::array<double, 32> motion_of(const Mat4d& previous, const Mat4d& next) {
    std::array<double, 32> m{};
    std::copy(previous.begin(), previous.end(), m.begin());
    std::copy(next.begin(), next.end(), m.begin() + 16);
    return m;
}

glm::dvec4 vector_at(const PassImage& v, int x, int y) {
    const float* p = &v.pixels[(std::size_t(y) * v.width + x) * 4];
    return {p[0], p[1], p[2], p[3]};
}

RenderSettings vector_settings(int samples) {
    RenderSettings s;
    s.width = kSize;
    s.height = kSize;
    s.samples = samples;
    s.shadows = false;
    s.passes = {Pass::Vector, Pass::Position};
    return s;
}

// A box moved by its instance's motion: previous at (-0.25, 0.25), next at
// (0.5, -0.125) around the origin.
struct MovingBox {
    Renderer r;
    Camera cam = deferred::testing::top_down_ortho(5.0, 4.0f);
    MovingBox(bool holdout = false) {
        tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.5f);
        const std::uint32_t mesh = r.add_mesh(box.view());
        const std::uint32_t mat = r.add_material(Material{});
        const Mat4d now = tools::translation(0, 0, 0);
        const std::array<double, 32> motion =
            motion_of(tools::translation(-0.25, 0.25, 0), tools::translation(0.5, -0.125, 0));
        r.add_instances(mesh, now.data(), 1, nullptr, {mat}, true, nullptr, nullptr, nullptr, holdout, 0, nullptr,
                        motion.data());
        deferred::testing::set_world_color(r, 0.1f, 0.1f, 0.1f);
    }
};
}  // namespace

TEST(VectorPass, TranslatedObjectMovesByItsOffsetInPixelsWithYUp) {
    MovingBox s;
    // 16 samples: every pixel a surface covers, edges too, carries the box's
    // motion exactly (divided by the samples that saw it, not by all).
    const FrameResult f = s.r.render(s.cam, vector_settings(16));
    const PassImage& v = *f.find(Pass::Vector);
    ASSERT_EQ(v.channels, 4);
    const glm::dvec4 expected(-0.25 * 8, 0.25 * 8, -0.5 * 8, 0.125 * 8);
    int covered = 0, background = 0;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const glm::dvec4 m = vector_at(v, x, y);
            if (m == glm::dvec4(0.0)) {
                ++background;
                continue;
            }
            ++covered;
            for (int c = 0; c < 4; ++c) ASSERT_NEAR(m[c], expected[c], 1e-4) << x << ", " << y << " channel " << c;
        }
    EXPECT_GE(covered, 8 * 8);        // the box's 1 m top face is 8 x 8 pixels
    EXPECT_LE(covered, 10 * 10);      // and its edges reach at most a pixel further
    EXPECT_GT(background, 32 * 32 - 100);
    // The background stays exactly 0 (Cycles writes no motion there).
    EXPECT_EQ(vector_at(v, 1, 1), glm::dvec4(0.0));
}

TEST(VectorPass, NoMotionGivenIsZero) {
    Renderer r;
    tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.5f);
    const std::uint32_t mesh = r.add_mesh(box.view());
    const std::uint32_t mat = r.add_material(Material{});
    const Mat4d now = tools::translation(0, 0, 0);
    r.add_instances(mesh, now.data(), 1, nullptr, {mat});
    const FrameResult f = r.render(deferred::testing::top_down_ortho(5.0, 4.0f), vector_settings(4));
    for (float value : f.find(Pass::Vector)->pixels) ASSERT_EQ(value, 0.0f);
}

TEST(VectorPass, HoldoutsWriteNoMotion) {
    MovingBox s(true);
    const FrameResult f = s.r.render(s.cam, vector_settings(4));
    for (float value : f.find(Pass::Vector)->pixels) ASSERT_EQ(value, 0.0f);
}

TEST(VectorPass, DeformingMeshMovesByItsVertices) {
    // A plane whose vertices were 0.5 m further along -x at the previous
    // frame and will be 0.25 m along +y at the next (object space, the
    // instance itself scaled by 2: the motion is scaled with it).
    Renderer r;
    tools::MeshArrays plane = tools::make_plane(0.5f);
    std::vector<float> motion_positions;
    for (int step = 0; step < 2; ++step)
        for (std::size_t v = 0; v < plane.positions.size() / 3; ++v) {
            motion_positions.push_back(plane.positions[3 * v] + (step == 0 ? -0.5f : 0.0f));
            motion_positions.push_back(plane.positions[3 * v + 1] + (step == 1 ? 0.25f : 0.0f));
            motion_positions.push_back(plane.positions[3 * v + 2]);
        }
    MeshData data = plane.view();
    data.motion_positions = motion_positions.data();
    const std::uint32_t mesh = r.add_mesh(data);
    const std::uint32_t mat = r.add_material(Material{});
    const Mat4d now = tools::scale_translation(2.0, 0, 0, 0);
    r.add_instances(mesh, now.data(), 1, nullptr, {mat});
    const FrameResult f = r.render(deferred::testing::top_down_ortho(5.0, 4.0f), vector_settings(1));
    const glm::dvec4 m = vector_at(*f.find(Pass::Vector), 16, 16);
    EXPECT_NEAR(m.x, -0.5 * 2 * 8, 1e-4);
    EXPECT_NEAR(m.y, 0.0, 1e-4);
    EXPECT_NEAR(m.z, 0.0, 1e-4);
    EXPECT_NEAR(m.w, -0.25 * 2 * 8, 1e-4);
}

TEST(VectorPass, MovingPerspectiveCameraMatchesTheProjectedPositions) {
    // A static floor seen by a perspective camera that turns and moves: each
    // pixel's motion is its Position-pass point projected through the
    // previous and next cameras (this frame's lens), minus / from its
    // projection now, computed here in double.
    Renderer r;
    deferred::testing::add_plane(r, Material{}, 20.0f, 4);
    Camera cam;
    const double eye[3] = {0.0, -6.0, 4.0}, target[3] = {0.0, 0.0, 0.0};
    const double eye_prev[3] = {-0.3, -6.2, 4.1}, target_prev[3] = {0.2, 0.1, 0.0};
    const double eye_next[3] = {0.4, -5.7, 3.9}, target_next[3] = {-0.1, 0.3, 0.0};
    cam.matrix = tools::look_at(eye, target);
    cam.has_motion = true;
    cam.matrix_previous = tools::look_at(eye_prev, target_prev);
    cam.matrix_next = tools::look_at(eye_next, target_next);
    const FrameResult f = r.render(cam, vector_settings(1));
    const PassImage& v = *f.find(Pass::Vector);
    const PassImage& position = *f.find(Pass::Position);
    auto raster = [&](const Mat4d& matrix, const glm::dvec3& p) {
        Camera c = cam;
        c.matrix = matrix;
        const CameraMatrices m = build_camera(c, kSize, kSize);
        const glm::dvec4 clip = m.projection * m.view * glm::dvec4(p - m.position, 1.0);
        return (glm::dvec2(clip) / clip.w * 0.5 + 0.5) * double(kSize);
    };
    int checked = 0;
    double largest = 0.0;
    for (int y = 0; y < kSize; y += 3)
        for (int x = 0; x < kSize; x += 3) {
            const glm::dvec3 p = deferred::testing::pixel3(position, x, y);
            if (p == glm::dvec3(0.0)) continue;  // background
            const glm::dvec2 now = raster(cam.matrix, p);
            const glm::dvec2 pre = raster(cam.matrix_previous, p) - now;
            const glm::dvec2 post = now - raster(cam.matrix_next, p);
            const glm::dvec4 m = vector_at(v, x, y);
            for (int c = 0; c < 2; ++c) {
                EXPECT_NEAR(m[c], pre[c], 2e-3) << x << ", " << y;
                EXPECT_NEAR(m[c + 2], post[c], 2e-3) << x << ", " << y;
            }
            largest = std::max({largest, std::abs(pre.x), std::abs(post.y)});
            ++checked;
        }
    EXPECT_GT(checked, 40);
    EXPECT_GT(largest, 1.0);  // the camera's motion is pixels, not a rounding error
}

// --- Motion blur --------------------------------------------------------

#include "motion_module.h"

#include <glm/gtc/matrix_transform.hpp>

TEST(MotionBlur, InterpolationIsCyclesDecompositionBetweenTheSteps) {
    auto rot_z = [](double degrees, double scale, glm::dvec3 t) {
        glm::dmat4 m = glm::translate(glm::dmat4(1.0), t);
        m = glm::rotate(m, glm::radians(degrees), glm::dvec3(0, 0, 1));
        return glm::scale(m, glm::dvec3(scale, scale, 1.0));
    };
    const glm::dmat4 a = rot_z(0, 1, {0, 0, 0}), b = rot_z(45, 2, {1, 0, 0}), c = rot_z(90, 3, {1, 2, 0});
    for (auto [r, expected] : {std::pair{-1.0, a}, std::pair{0.0, b}, std::pair{1.0, c}}) {
        const glm::dmat4 m = interpolate_motion(a, b, c, r);
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) ASSERT_NEAR(m[i][j], expected[i][j], 1e-9) << "r " << r;
    }
    // Halfway between the middle and the last step: rotation 67.5 degrees
    // (slerp), scale 2.5 and translation (1, 1, 0) (linear).
    const glm::dmat4 half = interpolate_motion(a, b, c, 0.5);
    const glm::dmat4 expected = rot_z(67.5, 2.5, {1, 1, 0});
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_NEAR(half[i][j], expected[i][j], 1e-9);
    // A mirrored step keeps its mirroring in the stretch, not the rotation.
    const glm::dmat4 mirrored = glm::scale(b, glm::dvec3(-1.0, 1.0, 1.0));
    const glm::dmat4 back = compose_transform(decompose_transform(mirrored));
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_NEAR(back[i][j], mirrored[i][j], 1e-9);
}

TEST(MotionBlur, ShutterTimesAreStratifiedFromTheMiddle) {
    EXPECT_EQ(shutter_time(0), 0.5);
    std::vector<int> ninths(9, 0);
    for (int s = 0; s < 9; ++s) {
        const double t = shutter_time(s);
        ASSERT_GE(t, 0.0);
        ASSERT_LT(t, 1.0);
        ++ninths[std::size_t(t * 9.0)];
    }
    for (int n : ninths) EXPECT_EQ(n, 1);
}

namespace {
// A white emitter box of 1 m moving along x from -1 to +1 over the shutter
// (or standing while the camera moves the other way), seen from above on a
// black world: the fraction of the shutter a point x is covered is the
// length of {c in [-1, 1] : |x - c| <= 0.5} over 2.
double coverage(double x) {
    const double lo = std::max(-1.0, x - 0.5), hi = std::min(1.0, x + 0.5);
    return std::max(0.0, hi - lo) / 2.0;
}

const PassImage& blurred_box(Renderer& r, FrameResult& f, bool camera_moves, bool motion_blur = true) {
    tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.5f);
    const std::uint32_t mesh = r.add_mesh(box.view());
    Material m;
    m.base_color = {0.0f, 0.0f, 0.0f};
    m.specular = 0.0f;
    m.emission = {1.0f, 1.0f, 1.0f};
    const std::uint32_t mat = r.add_material(m);
    const Mat4d now = tools::translation(0, 0, 0);
    Camera cam = deferred::testing::top_down_ortho(5.0, 4.0f);
    if (camera_moves) {
        cam.has_motion = true;
        cam.matrix_previous = tools::translation(1.0, 0, 5.0);
        cam.matrix_next = tools::translation(-1.0, 0, 5.0);
        r.add_instances(mesh, now.data(), 1, nullptr, {mat});
    } else {
        const std::array<double, 32> motion = motion_of(tools::translation(-1, 0, 0), tools::translation(1, 0, 0));
        r.add_instances(mesh, now.data(), 1, nullptr, {mat}, true, nullptr, nullptr, nullptr, false, 0, nullptr,
                        motion.data());
    }
    deferred::testing::set_world_color(r, 0.0f, 0.0f, 0.0f);
    RenderSettings s;
    s.width = 64;
    s.height = 16;
    s.samples = 81;
    s.motion_blur = motion_blur;
    s.passes = {Pass::Vector};
    cam.ortho_scale = 4.0f;  // 16 px per metre across
    f = r.render(cam, s);
    return *f.find(Pass::Combined);
}

double red_at(const PassImage& img, double x) {
    const int px = int(std::floor((x + 2.0) * 16.0));
    return img.pixels[(std::size_t(img.height / 2) * img.width + std::size_t(px)) * 4];
}
}  // namespace

TEST(MotionBlur, MovingObjectIsSmearedOverTheShutter) {
    Renderer r;
    FrameResult f;
    const PassImage& img = blurred_box(r, f, false);
    for (double x : {-1.47, -1.22, -0.97, -0.72, -0.47, 0.03, 0.53, 0.78, 1.03, 1.28, 1.53, 1.72})
        EXPECT_NEAR(red_at(img, x), coverage(x), 0.03) << "x " << x;
    // With motion blur Cycles writes no Vector pass: 0.
    for (float v : f.find(Pass::Vector)->pixels) ASSERT_EQ(v, 0.0f);
}

TEST(MotionBlur, MovingCameraSmearsAsTheObjectMovingTheOtherWay) {
    Renderer r;
    FrameResult f;
    const PassImage& img = blurred_box(r, f, true);
    for (double x : {-1.47, -1.22, -0.97, -0.72, -0.47, 0.03, 0.53, 0.78, 1.03, 1.28, 1.53, 1.72})
        EXPECT_NEAR(red_at(img, x), coverage(x), 0.03) << "x " << x;
}

TEST(MotionBlur, OffRendersTheMiddleOfTheShutter) {
    Renderer r;
    FrameResult f;
    const PassImage& img = blurred_box(r, f, false, false);
    EXPECT_NEAR(red_at(img, 0.03), 1.0, 1e-5);
    EXPECT_NEAR(red_at(img, 0.78), 0.0, 1e-5);
}

TEST(MotionBlur, DeformingMeshIsSmearedOverTheShutter) {
    // A 1 m plane whose vertices move from x - 1 to x + 1 over the shutter:
    // the same profile as the moving box.
    Renderer r;
    tools::MeshArrays plane = tools::make_plane(0.5f);
    std::vector<float> motion_positions;
    for (int step = 0; step < 2; ++step)
        for (std::size_t v = 0; v < plane.positions.size() / 3; ++v) {
            motion_positions.push_back(plane.positions[3 * v] + (step == 0 ? -1.0f : 1.0f));
            motion_positions.push_back(plane.positions[3 * v + 1]);
            motion_positions.push_back(plane.positions[3 * v + 2]);
        }
    MeshData data = plane.view();
    data.motion_positions = motion_positions.data();
    const std::uint32_t mesh = r.add_mesh(data);
    Material m;
    m.base_color = {0.0f, 0.0f, 0.0f};
    m.specular = 0.0f;
    m.emission = {1.0f, 1.0f, 1.0f};
    const std::uint32_t mat = r.add_material(m);
    const Mat4d now = tools::translation(0, 0, 0);
    r.add_instances(mesh, now.data(), 1, nullptr, {mat});
    deferred::testing::set_world_color(r, 0.0f, 0.0f, 0.0f);
    RenderSettings s;
    s.width = 64;
    s.height = 16;
    s.samples = 81;
    s.motion_blur = true;
    const FrameResult f = r.render(deferred::testing::top_down_ortho(5.0, 4.0f), s);
    const PassImage& img = *f.find(Pass::Combined);
    for (double x : {-1.47, -1.22, -0.97, -0.47, 0.03, 0.53, 1.03, 1.28, 1.53})
        EXPECT_NEAR(red_at(img, x), coverage(x), 0.03) << "x " << x;
}

TEST(MotionBlur, ShadowRaysFollowTheMovingCasterAsTheMapsDo) {
    // A box (1 x 1 m, z from 0.75 to 1.25) moving from x = -1 to +1 over the
    // shutter above a floor, a sun 45 degrees from +x: at the box's centre c
    // its shadow covers the floor's x in [c - 1.75, c - 0.25], the box itself
    // hides [c - 0.5, c + 0.5] from the camera above, and the box's top and
    // the lit floor look alike (both at 45 degrees to the sun). So a floor
    // pixel at x is dark for the share of the shutter with c in
    // [x + 0.5, x + 1.75]. Shadow rays (the instances' hierarchy rebuilt each
    // sample) and maps (drawn each sample) must both give that.
    auto render = [](bool rays, std::vector<std::string>& warnings) {
        Renderer r;
        tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.25f), floor = tools::make_plane(6.0f);
        Material white;
        white.base_color = {1.0f, 1.0f, 1.0f};
        white.specular = 0.0f;
        white.diffuse_roughness = 0.0f;
        const std::uint32_t mat = r.add_material(white);
        const Mat4d now = tools::translation(0, 0, 1.0), at_origin = tools::translation(0, 0, 0);
        const std::array<double, 32> motion = motion_of(tools::translation(-1, 0, 1.0), tools::translation(1, 0, 1.0));
        r.add_instances(r.add_mesh(box.view()), now.data(), 1, nullptr, {mat}, true, nullptr, nullptr, nullptr,
                        false, 0, nullptr, motion.data());
        r.add_instances(r.add_mesh(floor.view()), at_origin.data(), 1, nullptr, {mat});
        Light sun;
        sun.type = LightType::Sun;
        const double from[3] = {3.0, 0.0, 3.0}, to[3] = {0.0, 0.0, 0.0};
        sun.matrix = tools::look_at(from, to);
        sun.energy = 3.0f;
        sun.angle = 0.0f;
        r.add_light(sun);
        deferred::testing::set_world_color(r, 0.0f, 0.0f, 0.0f);
        RenderSettings s;
        s.width = 64;
        s.height = 16;
        s.samples = 81;
        s.motion_blur = true;
        s.shadow_rays = rays;
        s.shadow_quality = 4.0f;
        const FrameResult f = r.render(deferred::testing::top_down_ortho(5.0, 4.0f), s);
        warnings = f.warnings;
        return *f.find(Pass::Combined);
    };
    std::vector<std::string> maps_warnings, rays_warnings;
    const PassImage maps = render(false, maps_warnings), rays = render(true, rays_warnings);
    for (const std::string& w : rays_warnings) EXPECT_EQ(w.find("shadow maps"), std::string::npos) << w;
    const double lit = 3.0 * std::sqrt(0.5) / M_PI;
    auto dark_share = [](double x) {
        const double lo = std::max(x + 0.5, -1.0), hi = std::min(x + 1.75, 1.0);
        return std::max(0.0, hi - lo) / 2.0;
    };
    for (double x : {-1.83, -1.53, -1.28, -1.03, -0.78, -0.53, -0.28, 0.53, 1.03}) {
        const double expected = lit * (1.0 - dark_share(x));
        EXPECT_NEAR(red_at(rays, x), expected, 0.03 * lit) << "rays, x " << x;
        EXPECT_NEAR(red_at(maps, x), expected, 0.05 * lit) << "maps, x " << x;
    }
}
