#include "pass_stage.h"

#include "film_module.h"
#include "gbuffer.h"
#include "motion_module.h"
#include "world_module.h"

#include "../../shaders/shader_defines.h"

#include <string>

namespace deferred {

bool pass_from_first_sample(Pass p) {
    return p == Pass::Depth || p == Pass::Position || p == Pass::IndexOB || p == Pass::IndexMA;
}

namespace {
bool is_data_pass(Pass p) {
    return p == Pass::Depth || p == Pass::Position || p == Pass::Normal || p == Pass::UV || p == Pass::IndexOB ||
           p == Pass::IndexMA || p == Pass::Vector;
}
}  // namespace

void PassStage::prepare(ShaderLibrary& shaders, const ShaderVariant& base, const FilmModule& film,
                        const WorldModule& world, bool stochastic_alpha, int width, int height) {
    shaders_ = &shaders;
    base_ = base;
    film_ = &film;
    world_ = &world;
    groups_x_ = unsigned((width + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    groups_y_ = unsigned((height + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    data_gbuffer_ = data_every_sample_ = false;
    if (stochastic_alpha)
        for (auto& [p, image] : film.pass_images())
            if (is_data_pass(p)) {
                data_gbuffer_ = true;
                // Depth, Position and the indices come from sample 0 only;
                // Normal and UV are averaged over the samples.
                if (!pass_from_first_sample(p)) data_every_sample_ = true;
            }
    // Each pass's program starts compiling now, on the driver's threads where
    // it has them (ShaderLibrary::prefetch_compute), while sample 0 draws;
    // run() asks for it after sample 0's lighting.
    for (auto& [p, image] : film.pass_images())
        if (written_per_sample(p)) shaders.prefetch_compute("passes_comp.glsl", variant(p, sample_mode(p)));
}

bool PassStage::written_per_sample(Pass p) {
    // Shadow: resolved after the samples; AO: accumulated by the lighting
    // pass; Vector: drawn by the motion module; Shadow Catcher: resolved
    // after the samples.
    return p != Pass::Shadow && p != Pass::AO && p != Pass::Vector && p != Pass::ShadowCatcher;
}

const char* PassStage::sample_mode(Pass p) { return pass_from_first_sample(p) ? nullptr : "ACCUMULATE"; }

ShaderVariant PassStage::variant(Pass p, const char* mode) const {
    ShaderVariant v = base_;
    v.defines.push_back("PASS_ID " + std::to_string(static_cast<int>(p)));
    if (mode) v.defines.push_back(mode);
    if (p == Pass::Env) world_->add_defines(v);
    return v;
}

GLuint PassStage::program(Pass p, const char* mode) const {
    return shaders_->compute_program("passes_comp.glsl", variant(p, mode));
}

void PassStage::run(int sample, bool data, const GBuffer& gbuffer) const {
    // Filtered passes every sample, the rest at sample 0.
    for (auto& [p, image] : film_->pass_images()) {
        const bool first_only = pass_from_first_sample(p);
        if ((first_only && sample > 0) || !written_per_sample(p)) continue;
        if (data_gbuffer_ && is_data_pass(p) != data) continue;
        glUseProgram(program(p, sample_mode(p)));
        gbuffer.bind_textures();
        if (p == Pass::Env) world_->bind();
        // The sample's scratch image where the film splats it (film_module.h).
        glBindImageTexture(IMG_PASS_OUT, film_->sample_target(p), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glDispatchCompute(groups_x_, groups_y_, 1);
    }
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
}

bool PassStage::resolve(bool catchers, const MotionModule& motion) const {
    // Shadow catchers: the Shadow Catcher pass from the catchers' light and
    // the matte's alpha, or without it Combined carries their shadow.
    bool matte_in_combined = false;
    if (catchers) {
        glBindTextureUnit(TEX_CATCHER_HIT, film_->catcher_hit());
        glBindTextureUnit(TEX_CATCHER_PASS, film_->catcher_pass());
        glBindTextureUnit(TEX_CATCHER_FILM, film_->combined());
        if (const GLuint image = film_->image(Pass::ShadowCatcher)) {
            glUseProgram(program(Pass::ShadowCatcher, "RESOLVE_CATCHER"));
            glBindImageTexture(IMG_PASS_OUT, image, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
            glDispatchCompute(groups_x_, groups_y_, 1);
        } else {
            ShaderVariant v = base_;
            v.defines.push_back("PASS_ID " + std::to_string(int(Pass::ShadowCatcher)));
            v.defines.push_back("RESOLVE_CATCHER_COMBINED");
            world_->add_defines(v);
            glUseProgram(shaders_->compute_program("passes_comp.glsl", v));
            world_->bind();
            glBindImageTexture(IMG_PASS_OUT, film_->combined(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
            glDispatchCompute(groups_x_, groups_y_, 1);
            matte_in_combined = true;
        }
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    for (auto& [p, image] : film_->pass_images()) {
        if (p == Pass::Vector) {
            glUseProgram(program(p, "RESOLVE_MOTION"));
            motion.bind_resolve();
            glBindImageTexture(IMG_PASS_OUT, image.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
            glDispatchCompute(groups_x_, groups_y_, 1);
            continue;
        }
        if (p != Pass::DiffDir && p != Pass::GlossDir && p != Pass::Shadow) continue;
        glUseProgram(program(p, p == Pass::Shadow ? "RESOLVE_SHADOW" : "RESOLVE_LIGHT"));
        glBindTextureUnit(TEX_DIFF_LIGHT, film_->diffuse_light());
        glBindTextureUnit(TEX_GLOSS_LIGHT, film_->glossy_light());
        glBindTextureUnit(TEX_SHADOW_LIGHT, film_->shadow_light());
        glBindImageTexture(IMG_PASS_OUT, image.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glDispatchCompute(groups_x_, groups_y_, 1);
    }
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_PIXEL_BUFFER_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    return matte_in_combined;
}

}  // namespace deferred
