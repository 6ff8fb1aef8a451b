// Small scene helpers shared by the rendering tests.
#pragma once

#include "builtin_scenes.h"

#include <deferred/renderer.h>

#include <glm/glm.hpp>

namespace deferred::testing {

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

inline glm::dvec3 pixel3(const PassImage& img, int x, int y) {
    const float* p = &img.pixels[(std::size_t(y) * img.width + x) * img.channels];
    return {p[0], img.channels > 1 ? p[1] : p[0], img.channels > 2 ? p[2] : p[0]};
}

}  // namespace deferred::testing
