#include "film_module.h"

#include "parallel.h"

#include "../../shaders/shader_defines.h"

namespace deferred {

namespace {
Texture accumulation(int width, int height, const char* name, const float* value) {
    Texture t = make_texture_2d(GL_RGBA32F, width, height, name);
    glClearTexImage(t.get(), 0, GL_RGBA, GL_FLOAT, value);
    return t;
}
}  // namespace

void FilmModule::allocate(const Layout& layout) {
    release();
    layout_ = layout;
    const int w = layout.width, h = layout.height;
    const float zero[4] = {0, 0, 0, 0};
    film_ = accumulation(w, h, "film (Combined)", zero);
    if (layout.light_split) {
        diffuse_light_ = accumulation(w, h, "diffuse light", zero);
        glossy_light_ = accumulation(w, h, "glossy light", zero);
    }
    if (layout.shadow_pass) shadow_light_ = accumulation(w, h, "shadow light", zero);
    if (layout.catchers) {
        catcher_hit_ = accumulation(w, h, "shadow catcher light", zero);
        catcher_pass_ = accumulation(w, h, "shadow catcher light without the other objects", zero);
    }
    if (layout.light_groups > 0) {
        GLuint t = 0;
        glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &t);
        group_light_ = Texture(t);
        glTextureStorage3D(t, 1, GL_RGBA32F, w, h, layout.light_groups);
        glClearTexImage(t, 0, GL_RGBA, GL_FLOAT, zero);
        check_gl("allocating the light groups' layers");
    }
    // The Shadow Catcher pass is 1 where no catcher is seen (RESOLVE_CATCHER
    // writes the rest).
    const float one[4] = {1, 1, 1, 0};
    for (Pass p : layout.passes)
        if (p != Pass::Combined)
            pass_images_.emplace_back(p, accumulation(w, h, pass_info(p).name, p == Pass::ShadowCatcher ? one : zero));
}

void FilmModule::release() {
    film_.reset();
    diffuse_light_.reset();
    glossy_light_.reset();
    shadow_light_.reset();
    catcher_hit_.reset();
    catcher_pass_.reset();
    group_light_.reset();
    pass_images_.clear();
}

void FilmModule::bind_for_lighting() const {
    glBindImageTexture(IMG_FILM, film_.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (shadow_light_) glBindImageTexture(IMG_SHADOW, shadow_light_.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (catcher_hit_) {
        glBindImageTexture(IMG_CATCHER_HIT, catcher_hit_.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(IMG_CATCHER_PASS, catcher_pass_.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    }
    if (const GLuint ao = image(Pass::AO)) glBindImageTexture(IMG_AO, ao, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (group_light_)
        glBindImageTexture(IMG_LIGHT_GROUPS, group_light_.get(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
    if (diffuse_light_) {
        glBindImageTexture(IMG_DIFF_LIGHT, diffuse_light_.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glBindImageTexture(IMG_GLOSS_LIGHT, glossy_light_.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    }
}

GLuint FilmModule::image(Pass p) const {
    for (const auto& [pass, texture] : pass_images_)
        if (pass == p) return texture.get();
    return 0;
}

std::size_t FilmModule::bytes() const {
    const std::size_t pixels = std::size_t(layout_.width) * std::size_t(layout_.height);
    const std::size_t images = 1 + pass_images_.size() + (diffuse_light_ ? 2 : 0) + (shadow_light_ ? 1 : 0) +
                               (catcher_hit_ ? 2 : 0) + std::size_t(layout_.light_groups);
    return pixels * 16 * images;
}

std::vector<PassImage> FilmModule::read_passes() const {
    const std::size_t pixels = std::size_t(layout_.width) * std::size_t(layout_.height);
    std::vector<std::pair<Pass, GLuint>> reads{{Pass::Combined, film_.get()}};
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
        glGetTextureSubImage(group_light_.get(), 0, 0, 0, g, layout_.width, layout_.height, 1, GL_RGBA, GL_FLOAT,
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
