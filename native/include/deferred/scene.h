// Scene description handed to the native renderer: plain data, no GL.
//
// Everything here mirrors a Blender 3.4 data-block closely enough that the
// add-on's exporter is a field-by-field copy. Units are Blender's: metres,
// Watts (sun: W/m^2), radians, millimetres for the lens and sensor.
#pragma once

#include <deferred/material_graph.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace deferred {

using Vec3 = std::array<float, 3>;
// Column-major 4x4 matrix (m[col][row]), the layout numpy's `M.T` gives for a
// Blender Matrix; doubles so that world matrices far from the origin keep
// their precision until the camera position has been subtracted.
using Mat4d = std::array<double, 16>;

Mat4d identity_matrix();

// A triangle mesh. Positions are indexed by `indices`; per-corner data
// (normals, uvs) are given per triangle corner, in the order of `indices`
// (corner c of triangle t is element 3*t + c), because Blender's split
// normals and UVs live on loops, not vertices.
struct MeshData {
    const float* positions = nullptr;        // [vertex_count][3]
    std::size_t vertex_count = 0;
    const std::uint32_t* indices = nullptr;  // [triangle_count][3]
    std::size_t triangle_count = 0;
    const float* corner_normals = nullptr;   // [triangle_count*3][3], optional (flat if null)
    const float* corner_uvs = nullptr;       // [triangle_count*3][2], optional
    const std::int32_t* material_indices = nullptr;  // [triangle_count], optional (slot 0)
    // A deforming mesh's vertices at the previous and the next frame (the
    // Vector pass), object space, in the order of `positions`: [2][vertex_count][3],
    // optional (null: the vertices do not move within the object).
    const float* motion_positions = nullptr;
    // Named per-corner attributes node materials read (UV maps, tangents,
    // colour attributes); only those some material uses are exported.
    std::vector<CornerAttribute> attributes;
    // Texture space (Blender's texspace_location / texspace_size): generated
    // coordinates are (P - (location - size)) / (2 size).
    Vec3 texspace_location{0.0f, 0.0f, 0.0f};
    Vec3 texspace_size{1.0f, 1.0f, 1.0f};
};

// Principled BSDF parameter set of Blender 3.4 (constants per material).
struct Material {
    Vec3 base_color{0.8f, 0.8f, 0.8f};
    float metallic = 0.0f;
    float roughness = 0.5f;
    float specular = 0.5f;
    float specular_tint = 0.0f;
    float sheen = 0.0f;
    float sheen_tint = 0.5f;
    float clearcoat = 0.0f;
    float clearcoat_roughness = 0.03f;
    Vec3 emission{0.0f, 0.0f, 0.0f};
    float emission_strength = 1.0f;
    float alpha = 1.0f;
    // The diffuse lobe: < 0 the Principled BSDF's (Burley, with `roughness`);
    // >= 0 a Diffuse BSDF: Oren-Nayar with this sigma (0 = Lambert), as
    // Cycles' svm_node_closure_bsdf chooses (values above 1 act as 1).
    float diffuse_roughness = -1.0f;
    // The specular lobe: 0 the Principled BSDF's (GGX with its Fresnel);
    // 1 a Glossy BSDF with GGX, 2 with Beckmann: weight `base_color`, no
    // Fresnel, with metallic 1 (no diffuse lobe). With metallic 0 the sum
    // of a Lambert Diffuse BSDF and a grey Glossy BSDF (a Mix or Add of the
    // two, as Cycles sums their closures): diffuse weight `base_color`,
    // glossy weight `specular_tint` (grey).
    int glossy_model = 0;
    std::uint32_t pass_index = 0;  // IndexMA
    // Stochastic mix (a Mix Shader of BSDFs that one parameter set cannot
    // represent): each film sample shades a pixel with this material with
    // probability 1 - mix_probability, or with material `mix_with` (an
    // earlier id, itself possibly mixed: a chain of at most kMaxMixChain)
    // with probability mix_probability, so the accumulated image is the
    // weighted sum of the two, as Cycles' closure weights make it.
    std::int32_t mix_with = -1;
    float mix_probability = 0.0f;
    // A node material: index of its graph (Renderer::add_graph_material sets
    // it); -1 for a constant parameter set.
    std::int32_t graph = -1;
    // A node material whose emission varies over the surface (a texture, an
    // attribute, a procedural): its emitting triangles are baked with the
    // graph to light other surfaces (emitter_module.h). Off: `emission` holds
    // the constant radiance a graph emits (0: none).
    bool emission_varies = false;
    // A node material whose graph may emit for camera rays (an Emission node
    // or a Principled BSDF's emission that is linked or not 0): the emission
    // samples resolve only such materials' surfaces (emission_samples.h).
    // False only when the caller knows the graph emits nothing.
    bool graph_may_emit = true;
    // Blend mode (EEVEE's Blend): drawn after the opaque surfaces by the
    // forward pass (forward_module.h), lit where it is drawn and composited
    // over what is behind with its alpha, back to front per object: exact
    // for one layer at any sample count. Off: alpha is stochastic coverage
    // (Cycles' behaviour, converging over samples).
    bool blend = false;
    // Cryptomatte: MurmurHash3_32 of the material's name (the caller's).
    std::uint32_t crypto = 0;
    // A Holdout shader (Cycles' holdout closure, the whole surface): a hole
    // in the image, black with alpha 0, with no light and no colour passes.
    bool holdout = false;
};
constexpr int kMaxMixChain = 16;

enum class LightType : std::uint32_t { Point = 0, Spot = 1, Sun = 2, Area = 3 };
enum class AreaShape : std::uint32_t { Square = 0, Rectangle = 1, Disk = 2, Ellipse = 3 };

// A Blender light. `matrix` is the object's world matrix: position from its
// translation, the light's -Z axis is its direction (spot, sun, area) and,
// for area lights, the X/Y axes scale `size`/`size_y` (Cycles 3.4).
struct Light {
    LightType type = LightType::Point;
    Mat4d matrix = identity_matrix();
    Vec3 color{1.0f, 1.0f, 1.0f};
    float energy = 10.0f;           // W (sun: W/m^2)
    float radius = 0.25f;           // shadow_soft_size, m (point/spot)
    float spot_size = 0.785398f;    // full cone angle, rad
    float spot_blend = 0.15f;
    float angle = 0.00918043f;      // sun angular diameter, rad (0.526 deg)
    AreaShape shape = AreaShape::Square;
    float size = 0.25f;             // area X size, m
    float size_y = 0.25f;           // area Y size (RECTANGLE/ELLIPSE), m
    bool cast_shadow = true;
    // Light group (the view layer's light groups): 0 none, k the k-th group.
    std::uint32_t light_group = 0;
};

enum class CameraType : std::uint32_t { Perspective = 0, Orthographic = 1 };
enum class SensorFit : std::uint32_t { Auto = 0, Horizontal = 1, Vertical = 2 };

// Blender camera parameters; see camera.cpp for how they become a projection
// identical to Cycles' (blender/intern/cycles/blender/camera.cpp).
struct Camera {
    CameraType type = CameraType::Perspective;
    Mat4d matrix = identity_matrix();  // camera object's world matrix (looks down -Z)
    float lens = 50.0f;                // mm
    float sensor_width = 36.0f;        // mm
    float sensor_height = 24.0f;       // mm
    SensorFit sensor_fit = SensorFit::Auto;
    float shift_x = 0.0f;
    float shift_y = 0.0f;
    float clip_start = 0.1f;
    float clip_end = 100.0f;
    float ortho_scale = 6.0f;
    float pixel_aspect_x = 1.0f;
    float pixel_aspect_y = 1.0f;
    // An explicit viewplane (left, right, bottom, top at unit distance for a
    // perspective camera, in metres for an orthographic one) replaces the one
    // lens, sensor, shift and ortho_scale give: the 3D viewport's projection
    // (region_data.window_matrix), whose zoom and offset in camera view a
    // physical camera cannot express. Off (all zero): the camera's own.
    std::array<float, 4> viewplane{0.0f, 0.0f, 0.0f, 0.0f};
    // The camera's world matrices at the previous and the next frame (the
    // Vector pass; with this frame's lens, as Cycles 3.4's motion pass).
    // Off: the camera does not move.
    bool has_motion = false;
    Mat4d matrix_previous = identity_matrix();
    Mat4d matrix_next = identity_matrix();
};

struct World {
    Vec3 color{0.05f, 0.05f, 0.05f};  // Background colour x strength
    std::uint32_t light_group = 0;     // its light group (background and world light), 0 none
};

// Blender's mist settings (World > Mist Pass).
enum class MistFalloff : std::uint32_t { Quadratic = 0, Linear = 1, InverseQuadratic = 2 };
struct Mist {
    float start = 5.0f;
    float depth = 25.0f;
    MistFalloff falloff = MistFalloff::Quadratic;
};

}  // namespace deferred
