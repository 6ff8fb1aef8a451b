// Small OpenGL helpers: error names, RAII handles, timing.
#pragma once

#include <epoxy/gl.h>

#include <atomic>
#include <deque>
#include <string>
#include <utility>
#include <vector>

namespace deferred {

const char* gl_error_name(GLenum error);
// Throws deferred::Error("<step> failed: GL_OUT_OF_MEMORY") if glGetError is set.
void check_gl(const char* step);

// Owning handle for a GL object name; Deleter is e.g. glDeleteBuffers.
template <void (*Delete)(GLuint)>
class GLHandle {
public:
    GLHandle() = default;
    explicit GLHandle(GLuint id) : id_(id) {
        if (id_) live_.fetch_add(1, std::memory_order_relaxed);
    }
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
    void reset() {
        if (id_) {
            Delete(id_);
            live_.fetch_sub(1, std::memory_order_relaxed);
        }
        id_ = 0;
    }
    // Objects of this kind the process holds through handles (the tests:
    // what a release leaves).
    static long live() { return live_.load(std::memory_order_relaxed); }

private:
    GLuint id_ = 0;
    static inline std::atomic<long> live_{0};
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
// A buffer for results the CPU reads back (a pixel pack buffer, or the target
// of a buffer copy), GL_CLIENT_STORAGE_BIT: a hint for system memory the CPU
// reads through its cache. map_for_reading() maps it whole, or throws.
Buffer make_readback_buffer(std::size_t bytes, const char* what);
const void* map_for_reading(const Buffer& buffer, std::size_t bytes, const char* what);
Texture make_texture_2d(GLenum internal_format, int width, int height, const char* what);

// Bytes per texel of the internal formats this library allocates.
std::size_t texel_bytes(GLenum internal_format);

// Wall-clock milliseconds since construction, after glFinish, so the GPU
// work issued in between is counted (llvmpipe and GPUs alike). For the CPU
// stages around the frame (upload, compile, readback): it waits for the GPU.
class StageTimer {
public:
    StageTimer();
    double lap_ms();      // glFinish, time since the previous lap
    double lap_cpu_ms();  // the same without glFinish (CPU work only)
    void restart();       // the next lap counts from now

private:
    double last_;
};

// Per-sample constants without a CPU-GPU sync: a ring of slots in one
// persistently mapped, coherent buffer. push() fences the commands issued
// with the current slot, then takes the next one, waiting only for the
// fence of its use `slots` pushes ago (long done unless the GPU is that far
// behind), copies the block in and binds that slot's range as the uniform
// block.
class UniformRing {
public:
    UniformRing(std::size_t block_bytes, int slots, GLuint binding, const char* what);
    ~UniformRing();
    UniformRing(const UniformRing&) = delete;
    UniformRing& operator=(const UniformRing&) = delete;
    void push(const void* block);

private:
    Buffer buffer_;
    unsigned char* mapped_ = nullptr;
    std::size_t block_bytes_, stride_;
    GLuint binding_;
    std::vector<GLsync> fences_;
    std::size_t next_ = 0, current_ = 0;
    bool pushed_ = false;
};

// The frame's stages timed on the GPU's own clock without waiting for it:
// each lap() writes a timestamp query (glQueryCounter) and names the
// accumulator the time since the previous lap goes to; collect() reads the
// queries the GPU has finished (never stalling unless asked to wait), so
// the sample loop issues no glFinish. The accumulators must outlive the
// last collect(true). A GPU timestamp advances while the GPU waits for the
// CPU too, so a lap also counts CPU work issued between its queries.
class GpuStageTimer {
public:
    GpuStageTimer();
    ~GpuStageTimer();
    GpuStageTimer(const GpuStageTimer&) = delete;
    GpuStageTimer& operator=(const GpuStageTimer&) = delete;
    void lap(double& into_ms);
    // Adds every finished lap; wait: every lap, waiting for the GPU.
    void collect(bool wait);

private:
    struct Pending {
        GLuint query;
        double* into_ms;  // null: the first timestamp
    };
    GLuint acquire();
    std::deque<Pending> pending_;
    std::vector<GLuint> free_;
    std::vector<GLuint> all_;
    GLuint64 last_ = 0;
    bool have_last_ = false;
};

}  // namespace deferred
