// Tiled light culling (shaders/light_cull_comp.glsl): per-tile light lists
// in an index buffer that grows with the scene (two passes: count and
// reserve with one global atomic, read the total back, then write).
#pragma once

#include "gl_util.h"
#include "shader_library.h"

#include <cstdint>

namespace deferred {

class LightCulling {
public:
    // Builds the lists for the current G-buffer depth (sample 0). The frame
    // UBO, lights SSBO and depth texture must be bound.
    void build(ShaderLibrary& shaders, std::uint32_t tiles_x, std::uint32_t tiles_y);
    void bind() const;
    std::uint64_t last_index_count() const { return last_count_; }

private:
    Buffer tiles_, indices_, counter_;
    std::size_t tile_capacity_ = 0;
    std::uint32_t index_capacity_ = 0;
    std::uint64_t last_count_ = 0;
};

}  // namespace deferred
