// Directly seen emission with more camera samples than the lighting
// (RenderSettings::emission_samples).
//
// A small, bright emitter seen by the camera (a string of fairy lights, a
// lamp's bulb a few pixels wide) is the noise of its pixels: each film
// sample sees it or misses it, and its radiance is tens of times the
// surfaces' around it. That noise comes from the pixel filter's integral
// over the pixel alone, so it falls with more camera samples, not with more
// light samples; the emitters report scene lost 99.5 % of its squared error
// there (bench/report/error_split.py). The pixel's value is a sum of two
// integrals over the filter,
//     I = int f(x) (L(x) - E(x)) dx + int f(x) E(x) dx,
// E the emission of the surface seen at x (not a holdout's or a shadow
// catcher's, which keep their own paths); each may be estimated with its own
// samples. With K emission samples, film sample s adds, at its own jitter,
// L - E (1 - 1/K) (the lighting pass scales the emission it adds by 1/K,
// frame.jitter.w), and K - 1 more G-buffer passes at their own jitters add
// E / K each, splatted with the filter's taps for their offset: the second
// integral gets N K samples, at the cost of K - 1 geometry passes (no
// shadows, no lighting) per film sample. The sub-samples' offsets continue
// the film's pixel-filter sequence (film.h sample_point) past its N
// samples, so all N K offsets are one low-discrepancy set; the sub-samples
// share their film sample's shutter time and random numbers otherwise. With
// the visibility buffer a sub-sample resolves only the materials that may
// emit (the raster still draws every surface: they hide emitters), about
// half of its cost on llvmpipe.
//
// A frame takes them only where they can change its image: more than one
// film sample (a one-sample render is the pixel centre), an emissive mesh in
// view (EmitterModule's lights; with motion blur any emissive mesh), no
// Blend-mode layer over the G-buffer (the lighting pass shows what is
// behind it through the layer's transmittance) and no light groups (the
// emission would also go to its instance's group).
//
// Automatic (RenderSettings::emission_samples 0): kAutoEmissionSamples where
// an emissive mesh in view has a radiance above kAutoEmissionRadiance, none
// otherwise. An edge pixel's coverage noise grows with the emitter's
// radiance over what is behind it; at 320x180, 4 samples, the emitters
// scene's fairy lights (radiance 60) gave 99.5 % of its squared error and
// 4 emission samples cut its RMSE 1.80 -> 0.71, while the showcase's
// glowing torus (radiance 3) gave its edge pixels the same error with them
// as without (the error there is not coverage noise) for ~10 % more time a
// sample. 8 is above both panels of that scene (4 and 6: lit-surface
// brightness) and far below lamps and bulbs seen directly.
#pragma once

#include "shader_library.h"

#include <deferred/scene.h>

#include <array>
#include <vector>

namespace deferred {

constexpr int kAutoEmissionSamples = 4;
constexpr double kAutoEmissionRadiance = 8.0;

class FilmModule;
class GBuffer;

class EmissionSamples {
public:
    // The frame's count K (1: none) and, for K > 1, its program (Combined,
    // and the Emission pass when `film` has it).
    void prepare(ShaderLibrary& shaders, const ShaderVariant& base, const FilmModule& film,
                 const std::vector<Material>& materials, int count, int width, int height);
    int count() const { return count_; }
    // The share of a directly seen emission the film sample's own pixel adds.
    float own_share() const { return 1.0f / float(count_); }
    // Film point (pixel-filter dimensions, in [0,1)^2) of sub-sample k
    // (1..K-1) of film sample `sample` among `samples`.
    std::array<float, 2> point(int sample, int samples, int k) const;
    // Per material id: whether its surfaces may emit (a constant emission
    // not 0, a graph that may emit, or either in its stochastic mix chain).
    // The sub-samples' visibility buffer resolves only these: the others'
    // pixels keep the cleared G-buffer, whose emission adds nothing.
    const std::vector<bool>& emitting_materials() const { return emitting_; }
    // Adds the bound G-buffer's directly seen emission, 1/(samples K) of
    // it, to the film sample's Combined (and Emission) targets.
    void add(const GBuffer& gbuffer) const;

private:
    ShaderLibrary* shaders_ = nullptr;
    const FilmModule* film_ = nullptr;
    ShaderVariant variant_;
    std::vector<bool> emitting_;
    int count_ = 1;
    unsigned groups_x_ = 0, groups_y_ = 0;
};

}  // namespace deferred
