// Lights -> GpuLight array (camera-relative), plus the shader defines for the
// light types present (only those get code in the lighting shader).
#pragma once

#include "camera.h"
#include "gl_util.h"
#include "shader_library.h"

#include "../../shaders/shader_shared.h"

#include <deferred/scene.h>

#include <array>
#include <vector>

namespace deferred {

// One Blender light as the lighting shader reads it (see shader_shared.h),
// with Cycles 3.4's conventions applied: spot cone from spot_size/blend, area
// extents scaled by the object's X/Y scale, ellipse area pi/4 u v.
gpu::GpuLight pack_light(const Light& light, const glm::dvec3& camera_position, double threshold);

// Distance beyond which `light` cannot make a white Lambertian surface
// reflect `threshold` or more (radiance), or -1 for "everywhere" (sun, or a
// threshold of 0). Bounds, from Cycles' light units:
//   point/spot (radius R): E <= S / (4 pi d^2) at distance d from the sphere,
//     so L_o = E/pi < T beyond d = R + sqrt(S / (4 pi^2 T));
//   area (radiance S/(4A), extent e = half diagonal): E <= (S/(4A)) A / (d-e)^2,
//     so beyond d = e + sqrt(S / (4 pi T)).
// S is the largest colour channel x energy. Negative energies count by magnitude.
double influence_radius(const Light& light, double threshold);

class EmitterModule;

class LightModule {
public:
    // `shadows` (optional) gives each kept light its shadow index (params.w);
    // `emitters` (optional): emissive meshes, packed after the lights as LIGHT_MESH.
    void sync(const std::vector<Light>& lights, const glm::dvec3& camera_position, double threshold,
              class ShadowModule* shadows = nullptr, const EmitterModule* emitters = nullptr);
    // Per film sample: each emissive mesh light's shared point for `u`, in
    // the light buffer and (if it has maps) in the shadow module's entry.
    void update_mesh_points(const EmitterModule& emitters, const std::array<float, 2>& u,
                            class ShadowModule* shadows);
    void add_defines(ShaderVariant& variant) const;
    bool has_mesh_lights() const { return has_type_[LIGHT_MESH]; }
    void bind() const;
    std::uint32_t count() const { return count_; }
    // Each packed light's light group (0 none), for the light-group passes;
    // bound at SSBO_LIGHT_GROUPS by bind_groups().
    const std::vector<std::uint32_t>& groups() const { return groups_; }
    void bind_groups() const;

private:
    Buffer buffer_;
    std::uint32_t count_ = 0;
    bool has_type_[5] = {false, false, false, false, false};
    std::vector<gpu::GpuLight> packed_;
    std::vector<std::uint32_t> groups_;
    Buffer groups_buffer_;
    std::size_t first_mesh_ = 0;  // packed index of the first mesh light
    bool emission_texels_ = false;  // some mesh light is baked (HAS_EMISSION_TEXELS)
};

}  // namespace deferred
