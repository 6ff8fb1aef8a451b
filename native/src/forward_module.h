// The forward pass over the deferred frame: materials in Blend mode
// (Material::blend) are drawn after the opaque G-buffer, each fragment lit
// where it is drawn by the lighting pass's own code (shaders/lighting_lib.glsl
// through geometry_frag.glsl's FORWARD_PASS variant) and composited front to
// back into this module's layer: rgb the layers' light, premultiplied by
// alpha, a the transmittance left for what is behind them. The lighting pass
// then shows the opaque surface or background through it (FORWARD_LAYER):
// value * T + layer. One layer is exact at every sample count; several are
// composited in object order, which is right when objects do not overlap in
// depth (per-object sorting, as EEVEE's Blend mode).
//
// The lights come in the lighting pass's batches (LightingStage::batch_size):
// llvmpipe ends all loops of an invocation after 65 535 iterations in total,
// so one fragment looping over 256 lights with shadow rays through a dense
// scene kept a third of their light. Each batch is a draw of the sorted
// surfaces. Front to back with the "under" operator (C += T a L, T *= 1 - a)
// the batches add up in one layer: before each later batch T is reset to 1
// (its colour kept), and each batch multiplies the same T again.
//
// The opaque depth is read as a texture and tested by hand, so a pane behind
// an opaque surface is hidden exactly; Blend surfaces write no depth and no
// data pass (as in EEVEE); their shadows are the stochastic ones every
// partly transparent caster has.
#pragma once

#include "frame_scene.h"
#include "gl_util.h"
#include "layer_order.h"
#include "shader_library.h"

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace deferred {

class GeometryStage;
class MaterialModule;

class ForwardModule {
public:
    // The forward program (`variant`: the lighting's defines and
    // FORWARD_PASS) of every Blend-mode material: its graph's, or
    // geometry_frag.glsl's for a constant one. One that does not compile
    // stays in the stochastic path, warned. Returns, per material id,
    // whether the forward pass draws it.
    // `light_count` lights are drawn `lights_per_draw` at a time.
    // `exact`: the frame's exact layers (layer_order.h), drawn too, in
    // their rank's order instead of by distance (a frame has them only
    // without Blend-mode materials).
    std::vector<bool> prepare(ShaderLibrary& shaders, MaterialModule& materials, const FrameScene& scene,
                              const GeometryStage& geometry, const ShaderVariant& variant,
                              std::uint32_t light_count, std::uint32_t lights_per_draw, const ExactLayers& exact,
                              std::vector<std::string>& warnings);
    bool active() const { return !programs_.empty(); }
    // Forgets the frame's programs and draws (they point into the frame).
    void end_frame();
    // One sample's forward pass: the instances `view` keeps that have
    // Blend-mode slots, one draw each, nearest first (by the bounding
    // sphere's centre, or the exact layers' rank), into a cleared layer;
    // once per batch of lights.
    // `between_batches` runs before each batch after the first (a cancel).
    // Returns the instances kept.
    std::uint64_t draw(FrameScene& scene, const ViewVolume& view, const std::function<void()>& between_batches);
    // Draws of the surfaces per sample: one per batch of lights.
    std::uint32_t batches() const;
    // Allocates the layer for the frame size (reallocated only when it changes).
    void ensure(int width, int height);
    // Binds the layer's framebuffer, clears it to (0, 0, 0, T = 1) and sets
    // the blending and depth state the forward pass draws with.
    void begin_sample() const;
    // Before a later batch of lights: T back to 1, the colour kept.
    void begin_later_batch() const;
    // Restores the state begin_sample changed.
    void end_sample() const;
    // The layer at TEX_FORWARD_LAYER, for the lighting pass.
    void bind_layer() const;
    void release();
    std::size_t bytes() const { return std::size_t(width_) * std::size_t(height_) * 16; }

private:
    struct Sorted {
        double depth;
        FrameScene::Culled one;
    };
    const MaterialModule* materials_ = nullptr;
    const GeometryStage* geometry_ = nullptr;
    std::map<std::uint32_t, GLuint> programs_;  // material id -> its forward program
    std::vector<std::uint32_t> rank_;           // per instance: the exact layers' order (empty: by distance)
    std::vector<Sorted> sorted_;
    std::uint32_t light_count_ = 0, lights_per_draw_ = 1;
    int width_ = 0, height_ = 0;
    Texture layer_;
    Framebuffer fbo_;
};

}  // namespace deferred
