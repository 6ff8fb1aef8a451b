#include "aov_module.h"

#include "parallel.h"

#include <string>

namespace deferred {

void AovModule::begin(const std::vector<AovRequest>& aovs, int width, int height, GLuint gbuffer_depth) {
    release();
    if (aovs.size() > 64) throw InvalidInput("at most 64 AOVs, got " + std::to_string(aovs.size()));
    aovs_ = aovs;
    width_ = width;
    height_ = height;
    const float zero[4] = {0, 0, 0, 0};
    for (const AovRequest& a : aovs_) {
        Texture t = make_texture_2d(GL_RGBA32F, width, height, ("AOV " + a.name).c_str());
        glClearTexImage(t.get(), 0, GL_RGBA, GL_FLOAT, zero);
        GLuint fbo = 0;
        glCreateFramebuffers(1, &fbo);
        glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, t.get(), 0);
        glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, gbuffer_depth, 0);
        glNamedFramebufferDrawBuffer(fbo, GL_COLOR_ATTACHMENT0);
        const GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
        fbos_.emplace_back(fbo);
        if (status != GL_FRAMEBUFFER_COMPLETE)
            throw Error("AOV framebuffer incomplete (status 0x" + std::to_string(status) + ")");
        images_.push_back(std::move(t));
    }
    check_gl("AOV targets");
}

void AovModule::bind(std::size_t k, int samples) const {
    glBindFramebuffer(GL_FRAMEBUFFER, fbos_[k].get());
    glViewport(0, 0, width_, height_);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_EQUAL);  // the surface this sample's G-buffer holds
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendColor(0.0f, 0.0f, 0.0f, 1.0f / float(samples));
    glBlendFunc(GL_CONSTANT_ALPHA, GL_ONE);  // accumulation += value / samples
}

void AovModule::end_draws() const {
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_GREATER);  // reversed Z, the renderer's default
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

std::vector<AovImage> AovModule::finish() {
    // As the passes' readback (FilmModule::read_passes): every AOV into one
    // pack buffer, then each copied out of the mapping on its own thread
    // (a value AOV keeps the alpha channel: the accumulated value).
    const std::size_t pixels = std::size_t(width_) * std::size_t(height_);
    const std::size_t image_bytes = pixels * 4 * sizeof(float);
    std::vector<AovImage> out(aovs_.size());
    if (!aovs_.empty()) {
        const Buffer pack = make_readback_buffer(image_bytes * aovs_.size(), "AOVs");
        glBindBuffer(GL_PIXEL_PACK_BUFFER, pack.get());
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        for (std::size_t k = 0; k < aovs_.size(); ++k)
            glGetTextureImage(images_[k].get(), 0, GL_RGBA, GL_FLOAT, GLsizei(image_bytes),
                              reinterpret_cast<void*>(image_bytes * k));
        glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
        check_gl("reading the AOVs");
        const auto* mapped =
            static_cast<const float*>(map_for_reading(pack, image_bytes * aovs_.size(), "AOVs"));
        parallel_for(aovs_.size(), [&](std::size_t k) {
            AovImage& img = out[k];
            img.name = aovs_[k].name;
            img.color = aovs_[k].color;
            img.width = width_;
            img.height = height_;
            const float* rgba = mapped + pixels * 4 * k;
            if (img.color) {
                img.pixels.assign(rgba, rgba + pixels * 4);  // rgb, and in a the share of samples that wrote it
            } else {
                img.pixels.resize(pixels);
                for (std::size_t i = 0; i < pixels; ++i) img.pixels[i] = rgba[i * 4 + 3];
            }
        });
        glUnmapNamedBuffer(pack.get());
    }
    release();
    return out;
}

void AovModule::release() {
    fbos_.clear();
    images_.clear();
    aovs_.clear();
}

}  // namespace deferred
