#include "emission_samples.h"

#include "film.h"
#include "film_module.h"
#include "gbuffer.h"

#include "../../shaders/shader_defines.h"

namespace deferred {

namespace {
// A material's own emission, for the camera: a constant's colour x strength
// not 0, or a graph that may emit; a holdout shows none.
bool may_emit(const Material& m) {
    if (m.holdout) return false;
    if (m.graph >= 0) return m.graph_may_emit;
    return m.emission_strength != 0.0f && (m.emission[0] != 0.0f || m.emission[1] != 0.0f || m.emission[2] != 0.0f);
}
}  // namespace

void EmissionSamples::prepare(ShaderLibrary& shaders, const ShaderVariant& base, const FilmModule& film,
                              const std::vector<Material>& materials, int count, int width, int height) {
    shaders_ = &shaders;
    film_ = &film;
    count_ = std::max(count, 1);
    groups_x_ = unsigned((width + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    groups_y_ = unsigned((height + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    emitting_.assign(materials.size(), false);
    if (count_ == 1) return;
    for (std::size_t i = 0; i < materials.size(); ++i) {
        // The chain of stochastic mixes a pixel of material i may be shaded
        // with (each partner an earlier id, at most kMaxMixChain of them).
        bool emits = false;
        std::int64_t id = std::int64_t(i);
        for (int step = 0; id >= 0 && std::size_t(id) < materials.size() && step <= kMaxMixChain; ++step) {
            emits = emits || may_emit(materials[std::size_t(id)]);
            id = materials[std::size_t(id)].mix_with;
        }
        emitting_[i] = emits;
    }
    variant_ = base;
    if (film.image(Pass::Emit)) variant_.defines.push_back("OUT_EMIT");
    shaders.prefetch_compute("emission_samples_comp.glsl", variant_);
}

std::array<float, 2> EmissionSamples::point(int sample, int samples, int k) const {
    // The film's pixel-filter sequence continued past its `samples` points:
    // film sample s's sub-samples are points samples + s (K - 1) + k - 1.
    const std::array<float, 4> u = sample_point(samples + sample * (count_ - 1) + (k - 1));
    return {u[0], u[1]};
}

void EmissionSamples::add(const GBuffer& gbuffer) const {
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    glUseProgram(shaders_->compute_program("emission_samples_comp.glsl", variant_));
    gbuffer.bind_textures();
    glBindImageTexture(IMG_FILM, film_->combined_target(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (const GLuint emit = film_->sample_target(Pass::Emit))
        glBindImageTexture(IMG_PASS_OUT, emit, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    glDispatchCompute(groups_x_, groups_y_, 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
}

}  // namespace deferred
