// Shadow maps, rendered once per film sample from that sample's point on
// each shadow-casting light (shaders/shadow_frag.glsl, lookups in
// shaders/shadow_lib.glsl).
//
//  point, spot, area : a cube of 6 R32F layers storing the distance from the
//                      light point (90 degree faces, reversed-Z depth test);
//                      sphere lights use, per face, the point of the disk
//                      perpendicular to the face's axis
//  sun               : 4 orthographic cascades over the view frustum
//                      (practical split scheme, lambda 0.75) storing depth
//                      along the sun's direction
// All maps are layers of one 2D array texture, so the number of shadowed
// lights is not limited by texture units. Only lights that cast shadows,
// have energy, and whose influence sphere reaches the view frustum get maps.
#pragma once

#include "camera.h"
#include "gl_util.h"
#include "shader_library.h"

#include "../../shaders/shader_shared.h"

#include <deferred/scene.h>

#include <array>
#include <functional>
#include <vector>

namespace deferred {

class ShadowModule {
public:
    // Per frame: forget last frame's selection.
    void begin_frame(const CameraMatrices& camera, int resolution, std::size_t memory_budget);
    // Offers a light; returns false if it cannot shadow anything visible.
    bool offer(std::size_t light_index, const Light& light, const gpu::GpuLight& packed);
    // Keeps as many offered lights as the array layers and the memory budget
    // allow (suns first, then by power over squared distance to the camera),
    // allocates their maps and returns light_index -> shadow index (-1: none).
    std::vector<int> allocate(std::size_t light_count);
    std::size_t dropped() const { return dropped_; }  // offered but over the limits
    // Renders every assigned light's maps for one film sample; `draw` issues
    // the scene's draw calls with the currently bound program.
    void render_sample(ShaderLibrary& shaders, const std::array<float, 2>& u,
                       const std::function<void()>& bind_and_draw_scene);
    void bind() const;
    bool empty() const { return entries_.empty(); }
    std::size_t count() const { return entries_.size(); }
    std::size_t map_bytes() const { return bytes_; }
    int resolution() const { return resolution_; }

private:
    struct Entry {
        gpu::GpuLight light;
        bool sun = false;
        int first_layer = 0;
        std::size_t light_index = 0;
        double priority = 0;
    };
    std::size_t dropped_ = 0;
    CameraMatrices camera_{};
    int resolution_ = 1024;
    std::size_t budget_ = 0, bytes_ = 0;
    std::vector<Entry> entries_;
    int layers_ = 0;
    Texture maps_, depth_;
    Framebuffer fbo_;
    Buffer shadow_buffer_;
    int allocated_layers_ = 0, allocated_resolution_ = 0;
};

}  // namespace deferred
