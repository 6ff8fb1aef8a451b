// G-buffer targets and their framebuffer (layout: shaders/gbuffer_lib.glsl).
// Only the targets a frame needs are allocated: params1 when a material uses
// sheen or clearcoat, ids for IndexOB/IndexMA, uv for UV, geometry (smooth and
// true normals, shadow terminator offset) when shadow maps are drawn or a node
// material bends its closures' normal (Bump, Normal Map). The G-buffer holds
// one film sample; the accumulations live in the Film's targets.
#pragma once

#include "gl_util.h"

#include <cstddef>

namespace deferred {

struct GBufferFeatures {
    bool params1 = false, ids = false, uv = false, geometry = false;
    bool instance_ids = false;  // ids also hold the instance and material ids (RGBA32UI; Cryptomatte, light groups)
    bool operator==(const GBufferFeatures& o) const {
        return params1 == o.params1 && ids == o.ids && uv == o.uv && geometry == o.geometry &&
               instance_ids == o.instance_ids;
    }
};

class GBuffer {
public:
    // Reallocates only when size or features change.
    void ensure(int width, int height, const GBufferFeatures& features);
    void bind_for_geometry() const;   // binds the FBO, clears (depth 0 = far, reversed Z)
    void bind_textures() const;       // binds every target to its TEX_* unit
    // Binds every colour target to image unit OUT_* (write only): the
    // visibility buffer's resolve (gbuffer_resolve_comp.glsl) stores there.
    void bind_images() const;

    std::size_t bytes() const { return bytes_; }
    GLuint depth_texture() const { return depth_.get(); }
    int width() const { return width_; }
    int height() const { return height_; }
    const GBufferFeatures& features() const { return features_; }

private:
    int width_ = 0, height_ = 0;
    GBufferFeatures features_;
    bool allocated_ = false;
    std::size_t bytes_ = 0;
    Texture depth_, emission_, base_, params0_, normal_, params1_, ids_, uv_, geometry_;
    Framebuffer fbo_;
};

}  // namespace deferred
