// The pass stage: the render passes besides Combined and the light the
// lighting pass accumulates (shaders/passes_comp.glsl, one compute program
// per pass), added to the film's accumulations each sample, and the
// resolves after the last sample that divide one accumulation by another
// (DiffDir/GlossDir: light over colour; Shadow: shadowed over unshadowed
// light; Vector: summed motion over its count; the shadow catchers' pass).
//
// Data passes (Depth, Position, Normal, UV, indices, Vector) follow the
// Alpha Threshold, not the stochastic coverage: with transparency in the
// scene they come from a G-buffer of their own, drawn before the sample's
// (data_gbuffer()).
#pragma once

#include "shader_library.h"

#include <deferred/passes.h>

namespace deferred {

class FilmModule;
class GBuffer;
class MotionModule;
class WorldModule;

// Passes Cycles takes from the first sample, unfiltered; the others are
// averaged over the film's samples like Combined.
bool pass_from_first_sample(Pass p);

class PassStage {
public:
    // `base`: the G-buffer's variant (which targets exist);
    // `stochastic_alpha`: something in the scene can be partly transparent.
    void prepare(ShaderLibrary& shaders, const ShaderVariant& base, const FilmModule& film,
                 const WorldModule& world, bool stochastic_alpha, int width, int height);
    // The data passes need their own G-buffer: at sample 0, and every
    // sample when one of them (Normal, UV) is averaged.
    bool data_gbuffer() const { return data_gbuffer_; }
    bool data_every_sample() const { return data_every_sample_; }
    // Adds this sample's share to the passes read from the bound G-buffer
    // (`data`: the data G-buffer's passes; without one, every pass).
    void run(int sample, bool data, const GBuffer& gbuffer) const;
    // After the last sample: the shadow catchers' matte (into the Shadow
    // Catcher pass, or without it into Combined: returns true then), then
    // the light split, Shadow and Vector resolves.
    bool resolve(bool catchers, const MotionModule& motion) const;

private:
    // Whether run() writes the pass each sample (or at sample 0), and with
    // which mode (ACCUMULATE, or none for sample 0's data passes).
    static bool written_per_sample(Pass p);
    static const char* sample_mode(Pass p);
    ShaderVariant variant(Pass p, const char* mode) const;
    GLuint program(Pass p, const char* mode) const;

    ShaderLibrary* shaders_ = nullptr;
    ShaderVariant base_;
    const FilmModule* film_ = nullptr;
    const WorldModule* world_ = nullptr;
    bool data_gbuffer_ = false, data_every_sample_ = false;
    unsigned groups_x_ = 0, groups_y_ = 0;
};

}  // namespace deferred
