#include "forward_module.h"

#include <deferred/renderer.h>

#include "../../shaders/shader_defines.h"

#include <string>

namespace deferred {

void ForwardModule::ensure(int width, int height) {
    if (layer_ && width == width_ && height == height_) return;
    release();
    // Float: the layer carries lit radiance (any range) and the
    // transmittance multiplied over many layers.
    layer_ = make_texture_2d(GL_RGBA32F, width, height, "forward layer");
    GLuint fbo = 0;
    glCreateFramebuffers(1, &fbo);
    fbo_ = Framebuffer(fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, layer_.get(), 0);
    glNamedFramebufferDrawBuffer(fbo, GL_COLOR_ATTACHMENT0);
    const GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        throw Error("forward layer framebuffer incomplete (status 0x" + std::to_string(status) + ")");
    width_ = width;
    height_ = height;
    check_gl("allocating the forward layer");
}

void ForwardModule::begin_sample() const {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    glViewport(0, 0, width_, height_);
    const float empty[4] = {0.0f, 0.0f, 0.0f, 1.0f};  // no light, everything behind shows
    glClearNamedFramebufferfv(fbo_.get(), GL_COLOR, 0, empty);
    glDisable(GL_DEPTH_TEST);  // tested against the opaque depth in the shader
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);   // two-sided, as Cycles
    // Back to front "over" with premultiplied colour: c = src + (1 - a) c;
    // the alpha channel keeps the transmittance, T = (1 - a) T.
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ZERO, GL_ONE_MINUS_SRC_ALPHA);
}

void ForwardModule::end_sample() const {
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
    glEnable(GL_DEPTH_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void ForwardModule::bind_layer() const { glBindTextureUnit(TEX_FORWARD_LAYER, layer_.get()); }

void ForwardModule::release() {
    fbo_.reset();
    layer_.reset();
    width_ = height_ = 0;
}

}  // namespace deferred
