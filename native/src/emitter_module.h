// Emissive meshes as lights (Cycles' mesh lights): every mesh instance whose
// material slots emit becomes one light (LIGHT_MESH) over its emitting
// triangles, in world space (camera-relative), with a CDF that picks a
// triangle by its power (area x luminance of its radiance) and a point
// uniform on it (the sample's shared point; the lighting's own points take a
// direction uniform in the triangle's solid angle where it is near, and
// glossy lobes trace their directions against the triangles of small
// lights). The lighting (shaders/light_lib.glsl) integrates it like
// the world: per pixel, points of its own (unoccluded light), minus the
// light blocked at the sample's shared point, whose cube shadow map the
// shadow module draws (a control variate: unbiased, no noise where nothing
// occludes).
//
// Emission is two-sided (Cycles' emissive_simple_eval: |N.I|), constant per
// material slot: colour x strength x alpha of a constant material,
// averaged over its stochastic mix chain. Node materials' emission is not
// known here (their graph runs in the geometry pass): they light nothing
// (the add-on warns).
#pragma once

#include "gl_util.h"
#include "scene_store.h"

#include "../../shaders/shader_shared.h"

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace deferred {

struct MeshLight {
    std::uint32_t first = 0, count = 0;  // its triangles in the emitter buffer
    glm::dvec3 center{0.0};              // bounding sphere (camera-relative)
    double radius = 0.0;
    double area = 0.0;                   // total emitting area, m^2 (one side)
    double power = 0.0;                  // sum of area x luminance of the radiance
    double max_radiance = 0.0;           // largest radiance channel
    bool cast_shadow = true;
    std::uint32_t light_group = 0;       // the instance's light group
    // Which side emits: 0 both (an open mesh, as Cycles' emission); +1 or -1
    // the side the triangles' winding normal points to, for a closed mesh,
    // whose other side faces its own inside (lighting nothing but adding
    // noise: half of its points would be drawn to be blocked).
    int side = 0;
};

// The sample's shared point of a mesh light: where its cube map looks from,
// the radiance there, the triangle's unit normal and the point's density
// (area measure) under the light's CDF.
struct MeshLightPoint {
    glm::dvec3 position{0.0};
    glm::dvec3 normal{0.0, 0.0, 1.0};
    glm::dvec3 radiance{0.0};
    double pdf = 0.0;
};

class EmitterModule {
public:
    // Finds the emitting triangles of the scene's instances (reading back
    // only the meshes that emit) and uploads them. Returns the triangles found.
    std::size_t sync(const SceneStore& scene, const glm::dvec3& camera_position);
    void release() { *this = EmitterModule(); }

    const std::vector<MeshLight>& lights() const { return lights_; }
    // The point of light `k` for a film sample's point u in [0, 1)^2.
    MeshLightPoint sample_point(std::size_t k, const std::array<float, 2>& u) const;
    void bind() const;

private:
    std::vector<MeshLight> lights_;
    std::vector<gpu::GpuEmitterTriangle> triangles_;
    Buffer buffer_;
};

}  // namespace deferred
