#include "gbuffer.h"

#include "../../shaders/shader_defines.h"

#include <deferred/renderer.h>

#include <vector>

namespace deferred {

void GBuffer::ensure(int width, int height, const GBufferFeatures& f) {
    if (allocated_ && width == width_ && height == height_ && f == features_) return;
    *this = GBuffer();
    width_ = width;
    height_ = height;
    features_ = f;
    auto make = [&](Texture& t, GLenum format, const char* name) {
        t = make_texture_2d(format, width, height, name);
        bytes_ += texel_bytes(format) * std::size_t(width) * std::size_t(height);
    };
    make(depth_, GL_DEPTH_COMPONENT32F, "gbuffer depth");
    make(emission_, GL_RGBA32F, "gbuffer emission");
    make(base_, GL_RGBA16F, "gbuffer base");
    make(params0_, GL_RGBA16F, "gbuffer params0");
    // The octahedral normal as packUnorm2x16's bits in an integer target, not
    // an RG16 unorm one: the GL spec lets a driver convert a float written to
    // a unorm target to either of the two nearest integers (NVIDIA's choice
    // differs from packUnorm2x16's rounding), and the forward pass quantises
    // its normals with packUnorm2x16 to light them as this pass does.
    make(normal_, GL_R32UI, "gbuffer normal");
    if (f.params1) make(params1_, GL_RGBA16F, "gbuffer params1");
    if (f.ids || f.instance_ids) make(ids_, f.instance_ids ? GL_RGBA32UI : GL_RG32UI, "gbuffer ids");
    if (f.uv) make(uv_, GL_RG32F, "gbuffer uv");
    if (f.geometry) make(geometry_, GL_RGBA32UI, "gbuffer geometry");

    GLuint fbo = 0;
    glCreateFramebuffers(1, &fbo);
    fbo_ = Framebuffer(fbo);
    glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth_.get(), 0);
    std::vector<GLenum> draw(8, GL_NONE);
    auto attach = [&](const Texture& t, int slot) {
        if (!t) return;
        glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0 + slot, t.get(), 0);
        draw[static_cast<std::size_t>(slot)] = GL_COLOR_ATTACHMENT0 + slot;
    };
    attach(emission_, OUT_EMISSION);
    attach(base_, OUT_BASE);
    attach(params0_, OUT_PARAMS0);
    attach(normal_, OUT_NORMAL);
    attach(params1_, OUT_PARAMS1);
    attach(ids_, OUT_IDS);
    attach(uv_, OUT_UV);
    attach(geometry_, OUT_GEOMETRY);
    glNamedFramebufferDrawBuffers(fbo, static_cast<GLsizei>(draw.size()), draw.data());
    GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        throw Error("G-buffer framebuffer incomplete (status 0x" + std::to_string(status) + ")");
    check_gl("allocating the G-buffer");
    allocated_ = true;
}

void GBuffer::bind_for_geometry() const {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    glViewport(0, 0, width_, height_);
    const float zero[4] = {0, 0, 0, 0};
    const GLuint uzero[4] = {0, 0, 0, 0};
    const float depth_far = 0.0f;  // reversed Z: far plane is 0
    glClearNamedFramebufferfv(fbo_.get(), GL_DEPTH, 0, &depth_far);
    for (int slot : {OUT_EMISSION, OUT_BASE, OUT_PARAMS0, OUT_PARAMS1, OUT_UV})
        glClearNamedFramebufferfv(fbo_.get(), GL_COLOR, slot, zero);
    glClearNamedFramebufferuiv(fbo_.get(), GL_COLOR, OUT_NORMAL, uzero);
    if (ids_) glClearNamedFramebufferuiv(fbo_.get(), GL_COLOR, OUT_IDS, uzero);
    if (geometry_) glClearNamedFramebufferuiv(fbo_.get(), GL_COLOR, OUT_GEOMETRY, uzero);
}

void GBuffer::bind_textures() const {
    glBindTextureUnit(TEX_DEPTH, depth_.get());
    glBindTextureUnit(TEX_GBUF_EMISSION, emission_.get());
    glBindTextureUnit(TEX_GBUF_BASE, base_.get());
    glBindTextureUnit(TEX_GBUF_PARAMS0, params0_.get());
    glBindTextureUnit(TEX_GBUF_NORMAL, normal_.get());
    if (params1_) glBindTextureUnit(TEX_GBUF_PARAMS1, params1_.get());
    if (ids_) glBindTextureUnit(TEX_GBUF_IDS, ids_.get());
    if (uv_) glBindTextureUnit(TEX_GBUF_UV, uv_.get());
    if (geometry_) glBindTextureUnit(TEX_GBUF_GEOMETRY, geometry_.get());
}

void GBuffer::bind_images() const {
    auto bind = [](const Texture& t, int unit, GLenum format) {
        if (t) glBindImageTexture(GLuint(unit), t.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, format);
    };
    bind(emission_, OUT_EMISSION, GL_RGBA32F);
    bind(base_, OUT_BASE, GL_RGBA16F);
    bind(params0_, OUT_PARAMS0, GL_RGBA16F);
    bind(normal_, OUT_NORMAL, GL_R32UI);
    bind(params1_, OUT_PARAMS1, GL_RGBA16F);
    bind(ids_, OUT_IDS, features_.instance_ids ? GL_RGBA32UI : GL_RG32UI);
    bind(uv_, OUT_UV, GL_RG32F);
    bind(geometry_, OUT_GEOMETRY, GL_RGBA32UI);
}

}  // namespace deferred
