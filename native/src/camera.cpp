#include "camera.h"

#include <deferred/renderer.h>

#include <cmath>
#include <limits>
#include <string>

namespace deferred {

glm::dmat4 to_glm(const Mat4d& m) {
    glm::dmat4 r;
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) r[c][row] = m[static_cast<std::size_t>(c * 4 + row)];
    return r;
}

namespace {
void require(bool ok, const std::string& what) {
    if (!ok) throw InvalidInput("camera: " + what);
}

// The GPU gets the projection and its inverse as float32: every entry must
// stay finite and, if not zero, a normal float (llvmpipe and most GPUs flush
// denormals to zero, which would collapse the depth range or the viewplane).
bool float_representable(const glm::dmat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            const double v = std::abs(m[c][r]);
            if (!std::isfinite(v) || v > double(std::numeric_limits<float>::max())) return false;
            if (v != 0.0 && v < double(std::numeric_limits<float>::min()) * 1024.0) return false;
        }
    return true;
}

// Largest |translation| of a camera (metres): the same bound as every other
// position of the scene (scene_store.h, InputLimits::kMaxCoordinate).
constexpr double kMaxCameraCoordinate = 1e15;
}  // namespace

CameraMatrices build_camera(const Camera& cam, int width, int height) {
    require(width > 0 && height > 0, "resolution must be positive");
    require(std::isfinite(cam.lens) && cam.lens > 0, "lens must be a positive finite number of mm");
    require(std::isfinite(cam.sensor_width) && cam.sensor_width > 0 && std::isfinite(cam.sensor_height) &&
                cam.sensor_height > 0, "sensor size must be positive");
    require(std::isfinite(cam.clip_start) && std::isfinite(cam.clip_end) && cam.clip_start > 0 &&
                cam.clip_end > cam.clip_start, "need 0 < clip_start < clip_end");
    require(std::isfinite(cam.ortho_scale) && cam.ortho_scale > 0, "ortho_scale must be positive");
    require(std::isfinite(cam.pixel_aspect_x) && std::isfinite(cam.pixel_aspect_y) && cam.pixel_aspect_x > 0 &&
                cam.pixel_aspect_y > 0, "pixel aspect must be a positive finite number");
    require(cam.clip_start >= 1e-6f, "clip_start must be at least 1e-6 m (Blender's minimum)");
    require(cam.type == CameraType::Perspective || cam.type == CameraType::Orthographic, "unknown camera type");
    require(std::isfinite(cam.shift_x) && std::isfinite(cam.shift_y), "shift must be finite");
    for (double v : cam.matrix) require(std::isfinite(v), "matrix has NaN/Inf");
    for (int i = 12; i < 15; ++i)
        require(std::abs(cam.matrix[std::size_t(i)]) <= kMaxCameraCoordinate,
                "position is farther than 1e15 m from the origin");

    CameraMatrices out;
    const glm::dmat4 m = to_glm(cam.matrix);
    out.position = glm::dvec3(m[3]);
    // Cycles: transform_clear_scale on the camera matrix.
    glm::dvec3 x(m[0]), y(m[1]), z(m[2]);
    require(glm::length(x) > 0 && glm::length(y) > 0 && glm::length(z) > 0, "matrix is degenerate");
    out.rotation = glm::dmat3(glm::normalize(x), glm::normalize(y), glm::normalize(z));
    require(std::abs(glm::determinant(out.rotation)) > 1e-6, "matrix is degenerate (its axes are parallel)");
    out.view = glm::dmat4(glm::transpose(out.rotation));
    out.orthographic = cam.type == CameraType::Orthographic;
    out.clip_start = cam.clip_start;
    out.clip_end = cam.clip_end;

    // blender_camera_viewplane (Cycles 3.4).
    const double xratio = double(width) * cam.pixel_aspect_x;
    const double yratio = double(height) * cam.pixel_aspect_y;
    bool horizontal_fit;
    double sensor_size;
    switch (cam.sensor_fit) {
        case SensorFit::Horizontal: horizontal_fit = true; sensor_size = cam.sensor_width; break;
        case SensorFit::Vertical: horizontal_fit = false; sensor_size = cam.sensor_height; break;
        default: horizontal_fit = xratio > yratio; sensor_size = cam.sensor_width; break;
    }
    double aspectratio, xaspect, yaspect;
    if (horizontal_fit) {
        aspectratio = xratio / yratio;
        xaspect = aspectratio;
        yaspect = 1.0;
    } else {
        aspectratio = yratio / xratio;
        xaspect = 1.0;
        yaspect = aspectratio;
    }
    // Perspective: screen units are scaled by tan(fov/2), with
    // fov = 2 atan(0.5 sensor / lens / aspectratio).
    double unit = 1.0;
    if (out.orthographic) {
        xaspect = xaspect * cam.ortho_scale / (aspectratio * 2.0);
        yaspect = yaspect * cam.ortho_scale / (aspectratio * 2.0);
        aspectratio = cam.ortho_scale / 2.0;
    } else {
        unit = (0.5 * sensor_size / cam.lens) / aspectratio;
    }
    const double dx = 2.0 * aspectratio * cam.shift_x;
    const double dy = 2.0 * aspectratio * cam.shift_y;
    double l = (-xaspect + dx) * unit, r = (xaspect + dx) * unit;
    double b = (-yaspect + dy) * unit, t = (yaspect + dy) * unit;
    if (cam.viewplane != std::array<float, 4>{0.0f, 0.0f, 0.0f, 0.0f}) {
        for (float v : cam.viewplane) require(std::isfinite(v), "viewplane has NaN/Inf");
        l = cam.viewplane[0];
        r = cam.viewplane[1];
        b = cam.viewplane[2];
        t = cam.viewplane[3];
    }
    out.viewplane = {l, r, b, t};

    const double n = cam.clip_start, f = cam.clip_end;
    glm::dmat4 p(0.0);  // p[col][row]
    if (out.orthographic) {
        p[0][0] = 2.0 / (r - l);
        p[3][0] = -(r + l) / (r - l);
        p[1][1] = 2.0 / (t - b);
        p[3][1] = -(t + b) / (t - b);
        // reversed Z: depth = (f - d) / (f - n), d = -z_view
        p[2][2] = 1.0 / (f - n);
        p[3][2] = f / (f - n);
        p[3][3] = 1.0;
    } else {
        // x_ndc = (2 x/d - (r + l)) / (r - l), d = -z_view
        p[0][0] = 2.0 / (r - l);
        p[2][0] = (r + l) / (r - l);
        p[1][1] = 2.0 / (t - b);
        p[2][1] = (t + b) / (t - b);
        // reversed Z: depth = n (f - d) / (d (f - n))
        p[2][2] = n / (f - n);
        p[3][2] = n * f / (f - n);
        p[2][3] = -1.0;
    }
    require(r > l && t > b, "the viewplane is empty (shift or lens out of range for float precision)");
    require(float_representable(p) && float_representable(glm::inverse(p)),
            "lens/sensor/shift/ortho_scale/clip range give a projection float32 cannot represent "
            "(clip " + std::to_string(n) + ".." + std::to_string(f) + ", viewplane " + std::to_string(r - l) + " x " +
                std::to_string(t - b) + ")");
    out.projection = p;
    return out;
}

}  // namespace deferred
