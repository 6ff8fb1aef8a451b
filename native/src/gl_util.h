// Small OpenGL helpers: error names, RAII handles, timing.
#pragma once

#include <epoxy/gl.h>

#include <string>
#include <utility>

namespace deferred {

const char* gl_error_name(GLenum error);
// Throws deferred::Error("<step> failed: GL_OUT_OF_MEMORY") if glGetError is set.
void check_gl(const char* step);

// Owning handle for a GL object name; Deleter is e.g. glDeleteBuffers.
template <void (*Delete)(GLuint)>
class GLHandle {
public:
    GLHandle() = default;
    explicit GLHandle(GLuint id) : id_(id) {}
    ~GLHandle() { reset(); }
    GLHandle(GLHandle&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
    GLHandle& operator=(GLHandle&& o) noexcept {
        if (this != &o) { reset(); id_ = std::exchange(o.id_, 0); }
        return *this;
    }
    GLHandle(const GLHandle&) = delete;
    GLHandle& operator=(const GLHandle&) = delete;
    GLuint get() const { return id_; }
    explicit operator bool() const { return id_ != 0; }
    void reset() { if (id_) Delete(id_); id_ = 0; }

private:
    GLuint id_ = 0;
};

void delete_buffer(GLuint id);
void delete_texture(GLuint id);
void delete_framebuffer(GLuint id);
void delete_program(GLuint id);
void delete_vertex_array(GLuint id);

using Buffer = GLHandle<delete_buffer>;
using Texture = GLHandle<delete_texture>;
using Framebuffer = GLHandle<delete_framebuffer>;
using Program = GLHandle<delete_program>;
using VertexArray = GLHandle<delete_vertex_array>;

// Immutable storage buffer holding `bytes` (at least 16 so empty arrays bind).
Buffer make_storage_buffer(const void* data, std::size_t bytes, const char* what);
Texture make_texture_2d(GLenum internal_format, int width, int height, const char* what);

// Bytes per texel of the internal formats this library allocates.
std::size_t texel_bytes(GLenum internal_format);

// Wall-clock milliseconds since construction, after glFinish, so the GPU
// work issued in between is counted (llvmpipe and GPUs alike).
class StageTimer {
public:
    StageTimer();
    double lap_ms();  // glFinish, time since the previous lap

private:
    double last_;
};

}  // namespace deferred
