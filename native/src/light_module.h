// Lights -> GpuLight array (camera-relative), plus the shader defines for the
// light types present (only those get code in the lighting shader).
#pragma once

#include "camera.h"
#include "gl_util.h"
#include "shader_library.h"

#include "../../shaders/shader_shared.h"

#include <deferred/scene.h>

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

class LightModule {
public:
    // `shadows` (optional) gives each kept light its shadow index (params.w).
    void sync(const std::vector<Light>& lights, const glm::dvec3& camera_position, double threshold,
              class ShadowModule* shadows = nullptr);
    void add_defines(ShaderVariant& variant) const;
    void bind() const;
    std::uint32_t count() const { return count_; }

private:
    Buffer buffer_;
    std::uint32_t count_ = 0;
    bool has_type_[4] = {false, false, false, false};
};

}  // namespace deferred
