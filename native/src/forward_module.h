// The forward pass over the deferred frame: materials in Blend mode
// (Material::blend) are drawn after the opaque G-buffer, each fragment lit
// where it is drawn by the lighting pass's own code (shaders/lighting_lib.glsl
// through geometry_frag.glsl's FORWARD_PASS variant) and composited back to
// front into this module's layer: rgb the layers' light, premultiplied by
// alpha, a the transmittance left for what is behind them. The lighting pass
// then shows the opaque surface or background through it (FORWARD_LAYER):
// value * T + layer. One layer is exact at every sample count; several are
// composited in object order, which is right when objects do not overlap in
// depth (per-object sorting, as EEVEE's Blend mode).
//
// The opaque depth is read as a texture and tested by hand, so a pane behind
// an opaque surface is hidden exactly; Blend surfaces write no depth and no
// data pass (as in EEVEE); their shadows are the stochastic ones every
// partly transparent caster has.
#pragma once

#include "gl_util.h"

namespace deferred {

class ForwardModule {
public:
    // Allocates the layer for the frame size (reallocated only when it changes).
    void ensure(int width, int height);
    // Binds the layer's framebuffer, clears it to (0, 0, 0, T = 1) and sets
    // the blending and depth state the forward pass draws with.
    void begin_sample() const;
    // Restores the state begin_sample changed.
    void end_sample() const;
    // The layer at TEX_FORWARD_LAYER, for the lighting pass.
    void bind_layer() const;
    void release();
    std::size_t bytes() const { return std::size_t(width_) * std::size_t(height_) * 16; }

private:
    int width_ = 0, height_ = 0;
    Texture layer_;
    Framebuffer fbo_;
};

}  // namespace deferred
