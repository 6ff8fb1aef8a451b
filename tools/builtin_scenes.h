// Procedural meshes and built-in scenes for the render tool, the benchmark
// and the tests (no Blender needed).
#pragma once

#include <deferred/renderer.h>

#include <cstdint>
#include <vector>

namespace deferred::tools {

struct MeshArrays {
    std::vector<float> positions;       // [V][3]
    std::vector<std::uint32_t> indices; // [T][3]
    std::vector<float> normals;         // [3T][3] per corner
    std::vector<float> uvs;             // [3T][2] per corner
    MeshData view() const;
};

MeshArrays make_plane(float half_size, int subdivisions = 1);  // z = 0, normal +Z
MeshArrays make_uv_sphere(float radius, int segments, int rings);
MeshArrays make_box(float half_x, float half_y, float half_z);

Mat4d translation(double x, double y, double z);
Mat4d scale_translation(double s, double x, double y, double z);
// World matrix of a camera (or light) at `eye` looking at `target` (-Z forward, +Y up).
Mat4d look_at(const double eye[3], const double target[3], const double up[3] = nullptr);

// The showcase: a floor, a 5x5 grid of spheres sweeping roughness (x) and
// metallic (y), one light of each type plus `extra_point_lights` small point
// lights scattered above the floor. Returns the camera. `offset` moves
// everything (camera and lights too): the far-from-origin hard cases.
Camera build_showcase(Renderer& renderer, int extra_point_lights = 0, const double offset[3] = nullptr);

}  // namespace deferred::tools
