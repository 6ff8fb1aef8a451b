// Small scene helpers shared by the rendering tests.
#pragma once

#include "builtin_scenes.h"

#include <deferred/renderer.h>

#include <glm/glm.hpp>

#include <thread>

namespace deferred::testing {

// The many-lights tests' view: from (0, -22, 12) at the origin, a 30 mm lens.
inline Camera overview_camera() {
    Camera cam;
    const double eye[3] = {0, -22, 12}, target[3] = {0, 0, 0};
    cam.matrix = tools::look_at(eye, target);
    cam.lens = 30.0f;
    cam.clip_start = 0.05f;
    cam.clip_end = 200.0f;
    return cam;
}

// The many-lights tests' scene: a 30 m floor and four unit boxes along x,
// all with material `mat`, under a black world (the lights are the test's).
inline void add_floor_and_boxes(Renderer& r, std::uint32_t mat) {
    tools::MeshArrays floor = tools::make_plane(30.0f);
    tools::MeshArrays box = tools::make_box(1.0f, 1.0f, 1.0f);
    const std::uint32_t floor_mesh = r.add_mesh(floor.view()), box_mesh = r.add_mesh(box.view());
    Mat4d I = identity_matrix();
    r.add_instances(floor_mesh, I.data(), 1, nullptr, {mat});
    for (int i = 0; i < 4; ++i) {
        Mat4d t = tools::translation(-6.0 + 4.0 * i, 2.0 * (i % 2), 1.0);
        r.add_instances(box_mesh, t.data(), 1, nullptr, {mat});
    }
    World black;
    black.color = {0, 0, 0};
    r.set_world(black);
}

// Orthographic camera at height `h` above the origin looking straight down,
// covering `extent` metres across.
inline Camera top_down_ortho(double h, float extent) {
    Camera cam;
    cam.type = CameraType::Orthographic;
    cam.matrix = tools::translation(0, 0, h);
    cam.ortho_scale = extent;
    cam.clip_start = 0.01f;
    cam.clip_end = float(h * 10);
    return cam;
}

// One instance of a z = 0 plane (half size `half`, `subdivisions` per side)
// with material `m` at `matrix` (identity: the floor); returns the material id.
inline std::uint32_t add_plane(Renderer& r, const Material& m, float half = 20.0f, int subdivisions = 1,
                               const Mat4d& matrix = identity_matrix(), bool cast_shadow = true) {
    tools::MeshArrays plane = tools::make_plane(half, subdivisions);
    const std::uint32_t mesh = r.add_mesh(plane.view());
    const std::uint32_t mat = r.add_material(m);
    r.add_instances(mesh, matrix.data(), 1, nullptr, {mat}, cast_shadow);
    return mat;
}

// A constant world colour.
inline void set_world_color(Renderer& r, float red, float green, float blue) {
    World w;
    w.color = {red, green, blue};
    r.set_world(w);
}

inline glm::dvec3 pixel3(const PassImage& img, int x, int y) {
    const float* p = &img.pixels[(std::size_t(y) * img.width + x) * img.channels];
    return {p[0], img.channels > 1 ? p[1] : p[0], img.channels > 2 ? p[2] : p[0]};
}

// Renders `busy` and cancels it from another thread once the frame has
// begun (a preview past `before_version` is out); true when the render threw
// Cancelled.
inline bool render_cancelled_once_begun(Renderer& r, const Camera& cam, const RenderSettings& busy,
                                        decltype(PreviewImage{}.version) before_version) {
    std::thread canceller([&] {
        PreviewImage image;
        while (!r.preview(before_version, image)) std::this_thread::yield();
        r.cancel();
    });
    bool cancelled = false;
    try {
        r.render(cam, busy);
    } catch (const Cancelled&) {
        cancelled = true;
    }
    canceller.join();
    return cancelled;
}

}  // namespace deferred::testing
