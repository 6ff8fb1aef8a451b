// Blender camera parameters -> view and projection matrices that put every
// pixel where Cycles puts it (intern/cycles/blender/camera.cpp,
// blender_camera_viewplane, Blender 3.4).
#pragma once

#include <deferred/scene.h>

#include <glm/glm.hpp>

namespace deferred {

struct CameraMatrices {
    glm::dvec3 position;        // world position (subtracted from everything in double)
    glm::dmat3 rotation;        // camera -> world rotation (scale removed, as Cycles does)
    glm::dmat4 view;            // camera-relative world -> view (rotation only)
    glm::dmat4 projection;      // view -> clip, reversed Z in [0, 1] (near -> 1, far -> 0)
    glm::dvec4 viewplane;       // left, right, bottom, top (tan units for perspective, metres for ortho)
    bool orthographic = false;
    double clip_start = 0.1, clip_end = 100.0;
};

// Throws InvalidInput for non-finite or impossible parameters (lens <= 0,
// clip_end <= clip_start, non-positive sensor, ...).
CameraMatrices build_camera(const Camera& camera, int width, int height);

glm::dmat4 to_glm(const Mat4d& m);

}  // namespace deferred
