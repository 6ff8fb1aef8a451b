// Shader AOVs (the view layer's AOVs, written by AOV Output nodes of node
// materials), as Cycles fills them: per film sample, the value the surface
// the camera sees writes, averaged over the samples; 0 where nothing writes
// it (background, materials without that AOV).
//
// After each sample's geometry pass, every graph material that writes an
// AOV is drawn again with its AOV_PASS program (geometry_frag.glsl) into
// that AOV's accumulation, against the G-buffer's depth with an EQUAL test
// (gl_Position is invariant across the programs), blended with the constant
// 1/samples. Nothing exists when no AOV is asked for.
#pragma once

#include "gl_util.h"

#include <deferred/renderer.h>

#include <string>
#include <vector>

namespace deferred {

class AovModule {
public:
    // Allocates one RGBA32F accumulation per AOV (cleared), each with a
    // framebuffer that shares the G-buffer's depth.
    void begin(const std::vector<AovRequest>& aovs, int width, int height, GLuint gbuffer_depth);
    bool active() const { return !aovs_.empty(); }
    std::size_t count() const { return aovs_.size(); }
    const std::string& name(std::size_t k) const { return aovs_[k].name; }
    // Binds AOV k's framebuffer with the state the AOV draws need.
    void bind(std::size_t k, int samples) const;
    void end_draws() const;
    // The AOVs' images (rows bottom-up); releases the frame's targets.
    std::vector<AovImage> finish();
    void release();
    static std::size_t bytes(const RenderSettings& s) {
        return std::size_t(s.width) * std::size_t(s.height) * 16 * s.aovs.size();
    }

private:
    std::vector<AovRequest> aovs_;
    std::vector<Texture> images_;
    std::vector<Framebuffer> fbos_;
    int width_ = 0, height_ = 0;
};

}  // namespace deferred
