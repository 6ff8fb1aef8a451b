#include "gl_util.h"

#include <deferred/renderer.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <thread>

namespace deferred {

const char* gl_error_name(GLenum error) {
    switch (error) {
        case GL_NO_ERROR: return "GL_NO_ERROR";
        case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
        case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
        case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
        case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
        case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
        case GL_STACK_UNDERFLOW: return "GL_STACK_UNDERFLOW";
        case GL_STACK_OVERFLOW: return "GL_STACK_OVERFLOW";
        default: return "unknown GL error";
    }
}

void check_gl(const char* step) {
    GLenum err = glGetError();
    if (err == GL_NO_ERROR) return;
    std::string names = gl_error_name(err);
    // Drain the queue so the next check starts clean.
    while ((err = glGetError()) != GL_NO_ERROR) names += std::string(", ") + gl_error_name(err);
    throw Error(std::string(step) + " failed: " + names);
}

void delete_buffer(GLuint id) { glDeleteBuffers(1, &id); }
void delete_texture(GLuint id) { glDeleteTextures(1, &id); }
void delete_framebuffer(GLuint id) { glDeleteFramebuffers(1, &id); }
void delete_program(GLuint id) { glDeleteProgram(id); }
void delete_vertex_array(GLuint id) { glDeleteVertexArrays(1, &id); }

Buffer make_storage_buffer(const void* data, std::size_t bytes, const char* what) {
    GLuint id = 0;
    glCreateBuffers(1, &id);
    Buffer buffer(id);
    const std::size_t size = std::max<std::size_t>(bytes, 16);
    if (data && bytes >= 16) {
        glNamedBufferStorage(id, static_cast<GLsizeiptr>(size), data, 0);
    } else {
        glNamedBufferStorage(id, static_cast<GLsizeiptr>(size), nullptr, GL_DYNAMIC_STORAGE_BIT);
        if (data && bytes) glNamedBufferSubData(id, 0, static_cast<GLsizeiptr>(bytes), data);
    }
    check_gl((std::string("allocating buffer '") + what + "'").c_str());
    return buffer;
}

Buffer make_readback_buffer(std::size_t bytes, const char* what) {
    GLuint id = 0;
    glCreateBuffers(1, &id);
    Buffer buffer(id);
    glNamedBufferStorage(id, static_cast<GLsizeiptr>(std::max<std::size_t>(bytes, 16)), nullptr,
                         GL_MAP_READ_BIT | GL_CLIENT_STORAGE_BIT);
    check_gl((std::string("allocating the readback buffer '") + what + "'").c_str());
    return buffer;
}

const void* map_for_reading(const Buffer& buffer, std::size_t bytes, const char* what) {
    const void* mapped = glMapNamedBufferRange(buffer.get(), 0, static_cast<GLsizeiptr>(bytes), GL_MAP_READ_BIT);
    check_gl((std::string("mapping the readback buffer '") + what + "'").c_str());
    if (!mapped) throw Error(std::string("mapping the readback buffer '") + what + "' failed");
    return mapped;
}

Texture make_texture_2d(GLenum internal_format, int width, int height, const char* what) {
    GLuint id = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &id);
    Texture tex(id);
    glTextureStorage2D(id, 1, internal_format, width, height);
    glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTextureParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    check_gl((std::string("allocating texture '") + what + "'").c_str());
    return tex;
}

std::size_t texel_bytes(GLenum f) {
    switch (f) {
        case GL_RGBA32F: case GL_RGBA32UI: return 16;
        case GL_RGBA16F: case GL_RG32F: case GL_RG32UI: return 8;
        case GL_R32F: case GL_R32UI: case GL_RG16: case GL_DEPTH_COMPONENT32F: case GL_RGBA8: return 4;
        default: return 16;
    }
}

static double now_ms() {
    using namespace std::chrono;
    return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

StageTimer::StageTimer() : last_(now_ms()) {}

double StageTimer::lap_ms() {
    glFinish();
    const double t = now_ms();
    const double d = t - last_;
    last_ = t;
    return d;
}

double StageTimer::lap_cpu_ms() {
    const double t = now_ms();
    const double d = t - last_;
    last_ = t;
    return d;
}

void StageTimer::restart() { last_ = now_ms(); }

UniformRing::UniformRing(std::size_t block_bytes, int slots, GLuint binding, const char* what)
    : block_bytes_(block_bytes), binding_(binding), fences_(std::size_t(std::max(slots, 1)), nullptr) {
    GLint align = 256;
    glGetIntegerv(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT, &align);
    align = std::max(align, 1);
    stride_ = (block_bytes + std::size_t(align) - 1) / std::size_t(align) * std::size_t(align);
    GLuint id = 0;
    glCreateBuffers(1, &id);
    buffer_ = Buffer(id);
    const GLbitfield flags = GL_MAP_WRITE_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
    const GLsizeiptr size = GLsizeiptr(stride_ * fences_.size());
    glNamedBufferStorage(id, size, nullptr, flags);
    mapped_ = static_cast<unsigned char*>(glMapNamedBufferRange(id, 0, size, flags));
    check_gl((std::string("allocating the ring buffer '") + what + "'").c_str());
    if (!mapped_) throw Error(std::string("mapping the ring buffer '") + what + "' failed");
}

UniformRing::~UniformRing() {
    for (GLsync f : fences_)
        if (f) glDeleteSync(f);
    if (buffer_) glUnmapNamedBuffer(buffer_.get());
}

void UniformRing::push(const void* block) {
    // The commands issued since the last push read the current slot: fence them.
    if (pushed_) {
        GLsync& done = fences_[current_];
        if (done) glDeleteSync(done);
        done = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    }
    pushed_ = true;
    current_ = next_;
    next_ = (next_ + 1) % fences_.size();
    if (GLsync& f = fences_[current_]) {  // the GPU may still read this slot
        // Polled with short sleeps rather than one long wait: NVIDIA's driver
        // spins in a waiting glClientWaitSync (an H200 frame spent 93-96 % of
        // its CPU time there, on clock_gettime; its __GL_YIELD setting is the
        // driver's own switch), which takes a core from the other renders and
        // exports a GPU server runs beside this one. The GPU then has 3
        // samples queued; a sleep (50 us, more with timer slack) is nothing
        // beside a sample. Flushed first: a zero-timeout wait need not flush.
        glFlush();
        GLenum state = glClientWaitSync(f, 0, 0);
        while (state == GL_TIMEOUT_EXPIRED) {
            std::this_thread::sleep_for(std::chrono::microseconds(50));
            state = glClientWaitSync(f, 0, 0);
        }
        glDeleteSync(f);
        f = nullptr;
    }
    std::memcpy(mapped_ + current_ * stride_, block, block_bytes_);
    glBindBufferRange(GL_UNIFORM_BUFFER, binding_, buffer_.get(), GLintptr(current_ * stride_),
                      GLsizeiptr(block_bytes_));
}

GpuStageTimer::GpuStageTimer() {
    const GLuint q = acquire();
    glQueryCounter(q, GL_TIMESTAMP);
    pending_.push_back({q, nullptr});
}

GpuStageTimer::~GpuStageTimer() {
    if (!all_.empty()) glDeleteQueries(GLsizei(all_.size()), all_.data());
}

GLuint GpuStageTimer::acquire() {
    if (free_.empty()) {
        GLuint q = 0;
        glGenQueries(1, &q);
        all_.push_back(q);
        return q;
    }
    const GLuint q = free_.back();
    free_.pop_back();
    return q;
}

void GpuStageTimer::lap(double& into_ms) {
    const GLuint q = acquire();
    glQueryCounter(q, GL_TIMESTAMP);
    pending_.push_back({q, &into_ms});
    // Read what has finished now and then; the GPU runs a few samples
    // behind at most, so the oldest queries are done and reading them waits
    // for nothing. Far behind (thousands of laps), wait for the oldest.
    if (pending_.size() > 64) collect(false);
    while (pending_.size() > 4096) {
        GLuint64 t = 0;
        glGetQueryObjectui64v(pending_.front().query, GL_QUERY_RESULT, &t);
        collect(false);
    }
}

void GpuStageTimer::collect(bool wait) {
    while (!pending_.empty()) {
        const Pending p = pending_.front();
        if (!wait) {
            GLint available = 0;
            glGetQueryObjectiv(p.query, GL_QUERY_RESULT_AVAILABLE, &available);
            if (!available) break;
        }
        GLuint64 t = 0;
        glGetQueryObjectui64v(p.query, GL_QUERY_RESULT, &t);
        if (have_last_ && p.into_ms) *p.into_ms += double(t - std::min(t, last_)) * 1e-6;
        last_ = t;
        have_last_ = true;
        free_.push_back(p.query);
        pending_.pop_front();
    }
}

}  // namespace deferred
