#include "film_module.h"

#include "parallel.h"

#include <algorithm>
#include <string>

#include "../../shaders/shader_defines.h"

namespace deferred {

static_assert(kMaxSplatTaps == SPLAT_MAX_TAPS, "film.h's taps and film_splat_comp.glsl's uniform arrays");

FilmModule::Accumulation FilmModule::accumulation(const char* name, const float* value, bool splat,
                                                  int layers) const {
    const int w = layout_.width, h = layout_.height;
    const float zero[4] = {0, 0, 0, 0};
    auto make = [&](const char* what, const float* clear) {
        Texture t;
        if (layers > 0) {
            GLuint id = 0;
            glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &id);
            t = Texture(id);
            glTextureStorage3D(id, 1, GL_RGBA32F, w, h, layers);
            check_gl(what);
        } else {
            t = make_texture_2d(GL_RGBA32F, w, h, what);
        }
        glClearTexImage(t.get(), 0, GL_RGBA, GL_FLOAT, clear);
        return t;
    };
    Accumulation a;
    a.total = make(name, value);
    if (splat && layout_.splat_margin > 0) a.sample = make((std::string(name) + " (this sample)").c_str(), zero);
    return a;
}

bool FilmModule::splatted(Pass p) {
    // The passes Combined is made of: Emission and Environment, where a
    // small bright feature makes the filter tail's fireflies, and the
    // colours DiffDir/GlossDir divide the splatted light by (their images
    // accumulate the colour until the resolve). Splatted like the light, a
    // pixel whose own samples all saw the background but whose neighbours'
    // saw a surface has that surface's colour as well as its light, so
    // DiffDir x DiffCol is exactly the light there too and the passes add
    // up to Combined. (Combined, the light split, Shadow's and the
    // catchers' sums and the light groups are the film's own
    // accumulations, all splatted.) Data passes (Normal, UV, Mist, AO, the
    // sample-0 ones, Vector) keep each pixel's own samples: splatting them
    // would only cost (on llvmpipe a 9-tap gather per image and sample).
    return p == Pass::Emit || p == Pass::Env || p == Pass::DiffCol || p == Pass::GlossCol || p == Pass::DiffDir ||
           p == Pass::GlossDir;
}

void FilmModule::allocate(const Layout& layout) {
    release();
    layout_ = layout;
    const float zero[4] = {0, 0, 0, 0};
    film_ = accumulation("film (Combined)", zero, true);
    if (layout.light_split) {
        diffuse_light_ = accumulation("diffuse light", zero, true);
        glossy_light_ = accumulation("glossy light", zero, true);
    }
    if (layout.shadow_pass) shadow_light_ = accumulation("shadow light", zero, true);
    if (layout.catchers) {
        catcher_hit_ = accumulation("shadow catcher light", zero, true);
        catcher_pass_ = accumulation("shadow catcher light without the other objects", zero, true);
    }
    if (layout.light_groups > 0)
        group_light_ = accumulation("light groups", zero, true, layout.light_groups);
    // The Shadow Catcher pass is 1 where no catcher is seen (RESOLVE_CATCHER
    // writes the rest).
    const float one[4] = {1, 1, 1, 0};
    for (Pass p : layout.passes)
        if (p != Pass::Combined) {
            Accumulation a = accumulation(pass_info(p).name, p == Pass::ShadowCatcher ? one : zero, splatted(p));
            pass_images_.emplace_back(p, std::move(a.total));
            pass_samples_.push_back(std::move(a.sample));
        }
}

void FilmModule::release() {
    for (Accumulation* a : {&film_, &diffuse_light_, &glossy_light_, &shadow_light_, &catcher_hit_, &catcher_pass_,
                            &group_light_}) {
        a->total.reset();
        a->sample.reset();
    }
    pass_images_.clear();
    pass_samples_.clear();
}

void FilmModule::bind_for_lighting() const {
    glBindImageTexture(IMG_FILM, film_.target(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (shadow_light_) glBindImageTexture(IMG_SHADOW, shadow_light_.target(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (catcher_hit_) {
        glBindImageTexture(IMG_CATCHER_HIT, catcher_hit_.target(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(IMG_CATCHER_PASS, catcher_pass_.target(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    }
    if (const GLuint ao = sample_target(Pass::AO)) glBindImageTexture(IMG_AO, ao, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (group_light_)
        glBindImageTexture(IMG_LIGHT_GROUPS, group_light_.target(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (diffuse_light_) {
        glBindImageTexture(IMG_DIFF_LIGHT, diffuse_light_.target(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(IMG_GLOSS_LIGHT, glossy_light_.target(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    }
}

GLuint FilmModule::image(Pass p) const {
    for (const auto& [pass, texture] : pass_images_)
        if (pass == p) return texture.get();
    return 0;
}

GLuint FilmModule::sample_target(Pass p) const {
    for (std::size_t k = 0; k < pass_images_.size(); ++k)
        if (pass_images_[k].first == p)
            return pass_samples_[k] ? pass_samples_[k].get() : pass_images_[k].second.get();
    return 0;
}

// f(sample, total, layers) for each splatted accumulation.
template <typename F> void FilmModule::for_each_splatted(F&& f) const {
    for (const Accumulation* a : {&film_, &diffuse_light_, &glossy_light_, &shadow_light_, &catcher_hit_,
                                  &catcher_pass_})
        if (a->sample) f(a->sample.get(), a->total.get(), 0);
    if (group_light_.sample) f(group_light_.sample.get(), group_light_.total.get(), layout_.light_groups);
    for (std::size_t k = 0; k < pass_images_.size(); ++k)
        if (pass_samples_[k]) f(pass_samples_[k].get(), pass_images_[k].second.get(), 0);
}

void FilmModule::prefetch(ShaderLibrary& shaders) const {
    if (!splatting()) return;
    shaders.prefetch_compute("film_splat_comp.glsl", ShaderVariant{});
    if (group_light_.sample) shaders.prefetch_compute("film_splat_comp.glsl", ShaderVariant{{"SPLAT_LAYERS"}});
}

// f(sample, total, layers) for Combined and the Emit pass: what an
// emission sub-sample writes (emission_samples.h).
template <typename F> void FilmModule::for_each_emission_splatted(F&& f) const {
    if (film_.sample) f(film_.sample.get(), film_.total.get(), 0);
    for (std::size_t k = 0; k < pass_images_.size(); ++k)
        if (pass_images_[k].first == Pass::Emit && pass_samples_[k])
            f(pass_samples_[k].get(), pass_images_[k].second.get(), 0);
}

void FilmModule::begin_sample(bool emission_only) const {
    if (!splatting()) return;
    // The last splat's reads of these images come first.
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    const float zero[4] = {0, 0, 0, 0};
    auto clear = [&](GLuint sample, GLuint, int) { glClearTexImage(sample, 0, GL_RGBA, GL_FLOAT, zero); };
    if (emission_only) for_each_emission_splatted(clear);
    else for_each_splatted(clear);
}

void FilmModule::splat(ShaderLibrary& shaders, const SplatTaps& x, const SplatTaps& y, bool emission_only) const {
    if (!splatting()) return;
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    const unsigned groups_x = unsigned((layout_.width + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    const unsigned groups_y = unsigned((layout_.height + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    GLuint programs[2] = {0, 0};  // 2D, layers
    auto add = [&](GLuint sample, GLuint total, int layers) {
        GLuint& program = programs[layers > 0 ? 1 : 0];
        if (!program) {
            program = shaders.compute_program("film_splat_comp.glsl",
                                              layers > 0 ? ShaderVariant{{"SPLAT_LAYERS"}} : ShaderVariant{});
            glProgramUniform4i(program, LOC_SPLAT_TAPS, x.first, y.first, x.count, y.count);
            glProgramUniform1i(program, LOC_SPLAT_MARGIN, layout_.splat_margin);
            glProgramUniform1fv(program, LOC_SPLAT_WEIGHTS_X, SPLAT_MAX_TAPS, x.weight.data());
            glProgramUniform1fv(program, LOC_SPLAT_WEIGHTS_Y, SPLAT_MAX_TAPS, y.weight.data());
            glUseProgram(program);
        } else {
            glUseProgram(program);
        }
        const GLboolean layered = layers > 0 ? GL_TRUE : GL_FALSE;
        glBindImageTexture(IMG_SPLAT_SAMPLE, sample, 0, layered, 0, GL_READ_ONLY, GL_RGBA32F);
        glBindImageTexture(IMG_SPLAT_FILM, total, 0, layered, 0, GL_READ_WRITE, GL_RGBA32F);
        glDispatchCompute(groups_x, groups_y, unsigned(std::max(layers, 1)));
    };
    if (emission_only) for_each_emission_splatted(add);
    else for_each_splatted(add);
    check_gl("film splat");
    // The preview, the next sample's writes, the resolves and the readback
    // read the accumulations.
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT |
                    GL_PIXEL_BUFFER_BARRIER_BIT);
}

std::size_t FilmModule::bytes() const {
    const std::size_t pixels = std::size_t(layout_.width) * std::size_t(layout_.height);
    std::size_t images = 1 + pass_images_.size() + (diffuse_light_ ? 2 : 0) + (shadow_light_ ? 1 : 0) +
                         (catcher_hit_ ? 2 : 0) + std::size_t(layout_.light_groups);
    for_each_splatted([&](GLuint, GLuint, int layers) { images += std::size_t(std::max(layers, 1)); });
    return pixels * 16 * images;
}

std::vector<PassImage> FilmModule::read_passes() const {
    const std::size_t pixels = std::size_t(layout_.width) * std::size_t(layout_.height);
    std::vector<std::pair<Pass, GLuint>> reads{{Pass::Combined, film_.total.get()}};
    for (const auto& [p, image] : pass_images_) reads.emplace_back(p, image.get());
    std::vector<std::size_t> offsets;
    std::size_t bytes = 0;
    for (const auto& [p, texture] : reads) {
        offsets.push_back(bytes);
        bytes += pixels * std::size_t(pass_info(p).channels) * sizeof(float);
    }
    // On an H200 the copy out of this mapping was 70 % of a 16-pass frame's
    // CPU time with GL_CLIENT_STORAGE_BIT and without (readback 100-204 ms
    // on three machines, bench/gpu/results/nvidia_h200_2026-11-26): the
    // copy's cost is the new images' first-touch page faults, hence the
    // parallel copy below.
    const Buffer pack = make_readback_buffer(bytes, "passes");
    const GLuint id = pack.get();
    glBindBuffer(GL_PIXEL_PACK_BUFFER, id);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    for (std::size_t k = 0; k < reads.size(); ++k) {
        const int channels = pass_info(reads[k].first).channels;
        const GLenum format = channels == 1 ? GL_RED : channels == 3 ? GL_RGB : GL_RGBA;
        glGetTextureImage(reads[k].second, 0, format, GL_FLOAT, GLsizei(pixels * std::size_t(channels) * sizeof(float)),
                          reinterpret_cast<void*>(offsets[k]));
    }
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    const auto* mapped = static_cast<const float*>(map_for_reading(pack, bytes, "passes"));
    // The copies into new images in parallel: their cost is mostly the
    // first-touch page faults of the new memory (parallel.h).
    std::vector<PassImage> out(reads.size());
    parallel_for(reads.size(), [&](std::size_t k) {
        PassImage& img = out[k];
        img.pass = reads[k].first;
        img.width = layout_.width;
        img.height = layout_.height;
        img.channels = pass_info(img.pass).channels;
        const float* from = mapped + offsets[k] / sizeof(float);
        img.pixels.assign(from, from + pixels * std::size_t(img.channels));
    });
    glUnmapNamedBuffer(id);
    return out;
}

std::vector<std::vector<float>> FilmModule::read_light_groups() const {
    std::vector<std::vector<float>> out;
    if (!group_light_) return out;
    const std::size_t layer = std::size_t(layout_.width) * std::size_t(layout_.height) * 4;
    const std::size_t bytes = layer * std::size_t(layout_.light_groups) * sizeof(float);
    // As read_passes: one pack buffer, each group copied out in parallel
    // (an H200 spent 69 % of a 4-group frame's CPU time in the old path's
    // read into one vector and its copy into the groups').
    const Buffer pack = make_readback_buffer(bytes, "light groups");
    const GLuint id = pack.get();
    glBindBuffer(GL_PIXEL_PACK_BUFFER, id);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    // One layer per call: the call's size is a GLsizei, which all groups
    // together outgrow at 4K from 17 groups (2 GiB).
    const std::size_t layer_bytes = layer * sizeof(float);
    for (int g = 0; g < layout_.light_groups; ++g)
        glGetTextureSubImage(group_light_.total.get(), 0, 0, 0, g, layout_.width, layout_.height, 1, GL_RGBA, GL_FLOAT,
                             GLsizei(layer_bytes), reinterpret_cast<void*>(layer_bytes * std::size_t(g)));
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    check_gl("reading the light groups");
    const auto* mapped = static_cast<const float*>(map_for_reading(pack, bytes, "light groups"));
    out.resize(std::size_t(layout_.light_groups));
    parallel_for(out.size(), [&](std::size_t g) { out[g].assign(mapped + layer * g, mapped + layer * (g + 1)); });
    glUnmapNamedBuffer(id);
    return out;
}

}  // namespace deferred
