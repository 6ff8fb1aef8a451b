// Raster pipeline against compute on this GPU: the measurements behind the
// question "which of the frame's work should leave the raster pipeline?".
// NVIDIA's data-centre Hopper chips (H100, H200) run vertex and fragment
// shaders on a small part of the chip (the Hopper whitepaper: only a few of
// the TPCs are graphics-capable, with few ROPs), while compute shaders run
// on all SMs; the device's notes record one test whose arithmetic ran 30x
// slower in a fragment than in a compute shader there. The engine's
// G-buffer and shadow maps are raster passes, and the H200 check measured
// them at 64 % of a sample (bench/gpu/results). This probe puts numbers on
// each part, with GPU timer queries, median of 5 after a warm-up:
//   alu      the same arithmetic per pixel (an FMA chain of N steps) in a
//            fragment shader drawing a full-screen triangle and in a compute
//            shader, 1920x1080 (or the size given), one RGBA16F target;
//   texture  16 dependent fetches per pixel from a 512x512 RGBA8 texture,
//            fragment against compute;
//   fill     depth-only fill (a shadow map's work): 29 full-screen quads
//            into a 2048x2048 depth target, and colour fill into 1 and into
//            4 RGBA16F targets at the frame's size: pixels per second;
//   layouts  the engine's G-buffer targets written over the frame against
//            a visibility buffer's one or two 32-bit ids;
//   mesh     a 1M-triangle grid covering the frame, depth only and with 4
//            targets: triangles per second.
// Usage: deferred_bench_raster [width height]
#include "egl_context.h"
#include "gl_util.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using namespace deferred;

GLuint compile(GLenum stage, const std::string& src) {
    const GLuint s = glCreateShader(stage);
    const char* text = src.c_str();
    glShaderSource(s, 1, &text, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096];
        glGetShaderInfoLog(s, sizeof log, nullptr, log);
        throw std::runtime_error(std::string("compile: ") + log);
    }
    return s;
}

Program link(std::initializer_list<std::pair<GLenum, std::string>> stages) {
    const GLuint p = glCreateProgram();
    std::vector<GLuint> shaders;
    for (const auto& [stage, src] : stages) {
        shaders.push_back(compile(stage, src));
        glAttachShader(p, shaders.back());
    }
    glLinkProgram(p);
    for (GLuint s : shaders) glDeleteShader(s);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096];
        glGetProgramInfoLog(p, sizeof log, nullptr, log);
        throw std::runtime_error(std::string("link: ") + log);
    }
    return Program(p);
}

// Milliseconds of `draw`, the median of 5 after one warm-up: the GPU's
// timer query, or where that reads less than a microsecond (llvmpipe runs
// a dispatch outside the query's span) the wall time between glFinish calls.
template <class F>
double gpu_ms(F&& draw) {
    GLuint query = 0;
    glGenQueries(1, &query);
    std::vector<double> gpu, wall;
    for (int i = 0; i < 6; ++i) {
        glFinish();
        const auto t0 = std::chrono::steady_clock::now();
        glBeginQuery(GL_TIME_ELAPSED, query);
        draw();
        glEndQuery(GL_TIME_ELAPSED);
        glFinish();
        const auto t1 = std::chrono::steady_clock::now();
        GLuint64 ns = 0;
        glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
        if (i > 0) {
            gpu.push_back(double(ns) * 1e-6);
            wall.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        }
    }
    glDeleteQueries(1, &query);
    check_gl("timed draw");
    std::sort(gpu.begin(), gpu.end());
    std::sort(wall.begin(), wall.end());
    return gpu[gpu.size() / 2] >= 1e-3 ? gpu[gpu.size() / 2] : wall[wall.size() / 2];
}

const char* kHeader = "#version 450 core\n";

// The per-pixel arithmetic both stages run: a chain of dependent FMAs the
// compiler cannot fold (the step count is a uniform), four lanes wide.
const char* kAluBody = R"(
uniform int steps;
vec4 work(vec2 p) {
    vec4 x = vec4(p, p.yx * 0.5);
    for (int i = 0; i < steps; ++i) x = fract(x * 1.0009765625 + vec4(0.1, 0.2, 0.3, 0.4));
    return x;
}
)";

// 16 dependent fetches: each coordinate comes from the last texel read.
const char* kTextureBody = R"(
layout(binding = 0) uniform sampler2D image;
vec4 work(vec2 p) {
    vec4 x = vec4(0.0);
    vec2 uv = p * 0.001;
    for (int i = 0; i < 16; ++i) {
        x += texelFetch(image, ivec2(fract(uv) * 512.0), 0);
        uv += x.xy * 0.37 + 0.01;
    }
    return x;
}
)";

const char* kFullscreenVert = R"(
uniform float depth;
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    gl_Position = vec4(p * 2.0 - 1.0, depth, 1.0);
}
)";

std::string fragment_of(const char* body, int targets) {
    std::string s = std::string(kHeader) + body;
    for (int i = 0; i < targets; ++i)
        s += "layout(location = " + std::to_string(i) + ") out vec4 out" + std::to_string(i) + ";\n";
    s += "void main() {\n    vec4 v = work(gl_FragCoord.xy);\n";
    for (int i = 0; i < targets; ++i) s += "    out" + std::to_string(i) + " = v + " + std::to_string(i) + ".0;\n";
    return s + "}\n";
}

std::string compute_of(const char* body) {
    return std::string(kHeader) + "layout(local_size_x = 8, local_size_y = 8) in;\n" +
           "layout(binding = 0, rgba16f) uniform writeonly image2D target;\n" + body +
           "void main() {\n    ivec2 p = ivec2(gl_GlobalInvocationID.xy);\n"
           "    if (any(greaterThanEqual(p, imageSize(target)))) return;\n"
           "    imageStore(target, p, work(vec2(p) + 0.5));\n}\n";
}

struct Targets {
    std::vector<Texture> colour;
    Texture depth;
    Framebuffer fbo;
};

Targets make_targets(int w, int h, const std::vector<GLenum>& formats, GLenum depth_format) {
    Targets t;
    GLuint fbo = 0;
    glCreateFramebuffers(1, &fbo);
    t.fbo = Framebuffer(fbo);
    std::vector<GLenum> draw;
    for (std::size_t i = 0; i < formats.size(); ++i) {
        t.colour.push_back(make_texture_2d(formats[i], w, h, "probe colour"));
        glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0 + i, t.colour.back().get(), 0);
        draw.push_back(GL_COLOR_ATTACHMENT0 + i);
    }
    if (depth_format) {
        t.depth = make_texture_2d(depth_format, w, h, "probe depth");
        glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, t.depth.get(), 0);
    }
    if (draw.empty()) glNamedFramebufferDrawBuffer(fbo, GL_NONE);
    else glNamedFramebufferDrawBuffers(fbo, GLsizei(draw.size()), draw.data());
    if (glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw std::runtime_error("probe framebuffer incomplete");
    return t;
}

Targets make_targets(int w, int h, int colours, GLenum depth_format) {
    return make_targets(w, h, std::vector<GLenum>(std::size_t(colours), GL_RGBA16F), depth_format);
}

// A fragment shader writing a constant to each target, typed by its format.
std::string constant_writer(const std::vector<GLenum>& formats) {
    std::string decl, body;
    for (std::size_t i = 0; i < formats.size(); ++i) {
        const std::string n = std::to_string(i);
        const GLenum f = formats[i];
        const char* type = f == GL_R32UI ? "uint" : f == GL_RG32UI ? "uvec2" : f == GL_RGBA32UI ? "uvec4" : "vec4";
        const char* value = f == GL_R32UI ? "uint(gl_FragCoord.x)" : f == GL_RG32UI ? "uvec2(gl_FragCoord.xy)"
                          : f == GL_RGBA32UI ? "uvec4(gl_FragCoord.xyxy)" : "vec4(gl_FragCoord.xy, 0.5, 1.0)";
        decl += "layout(location = " + n + ") out " + type + " out" + n + ";\n";
        body += "    out" + n + " = " + value + ";\n";
    }
    return std::string(kHeader) + decl + "void main() {\n" + body + "}\n";
}

}  // namespace

int main(int argc, char** argv) {
    const int width = argc > 2 ? std::atoi(argv[1]) : 1920;
    const int height = argc > 2 ? std::atoi(argv[2]) : 1080;
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    try {
        EglContext context(-1);
        std::printf("GL: %s | %s | %s (%s)\n", reinterpret_cast<const char*>(glGetString(GL_VENDOR)),
                    reinterpret_cast<const char*>(glGetString(GL_RENDERER)),
                    reinterpret_cast<const char*>(glGetString(GL_VERSION)),
                    context.display_description().c_str());
        GLuint vao = 0;
        glCreateVertexArrays(1, &vao);
        VertexArray empty_vao(vao);
        glBindVertexArray(vao);
        const double pixels = double(width) * height;
        const int gx = (width + 7) / 8, gy = (height + 7) / 8;

        // alu and texture: fragment against compute.
        Targets one = make_targets(width, height, 1, 0);
        std::vector<unsigned char> noise(512 * 512 * 4);
        unsigned state = 12345;
        for (auto& b : noise) b = (unsigned char)((state = state * 1664525u + 1013904223u) >> 24);
        Texture image = make_texture_2d(GL_RGBA8, 512, 512, "probe image");
        glTextureSubImage2D(image.get(), 0, 0, 0, 512, 512, GL_RGBA, GL_UNSIGNED_BYTE, noise.data());
        glBindTextureUnit(0, image.get());
        std::printf("\n%dx%d, GPU ms (median of 5)\n\n", width, height);
        std::printf("| per-pixel work | fragment | compute | fragment / compute |\n|---|---:|---:|---:|\n");
        struct Work { const char* name; const char* body; int steps; };
        for (const Work& w : {Work{"nothing (write only)", kAluBody, 0}, Work{"64 FMA steps", kAluBody, 64},
                              Work{"512 FMA steps", kAluBody, 512},
                              Work{"16 dependent texel fetches", kTextureBody, 0}}) {
            Program frag = link({{GL_VERTEX_SHADER, std::string(kHeader) + kFullscreenVert},
                                 {GL_FRAGMENT_SHADER, fragment_of(w.body, 1)}});
            Program comp = link({{GL_COMPUTE_SHADER, compute_of(w.body)}});
            glBindFramebuffer(GL_FRAMEBUFFER, one.fbo.get());
            glViewport(0, 0, width, height);
            glUseProgram(frag.get());
            glUniform1i(glGetUniformLocation(frag.get(), "steps"), w.steps);
            const double f = gpu_ms([] { glDrawArrays(GL_TRIANGLES, 0, 3); });
            glUseProgram(comp.get());
            glUniform1i(glGetUniformLocation(comp.get(), "steps"), w.steps);
            glBindImageTexture(0, one.colour[0].get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA16F);
            const double c = gpu_ms([&] { glDispatchCompute(gx, gy, 1); });
            std::printf("| %s | %.3f | %.3f | %.1f |\n", w.name, f, c, f / c);
        }

        // fill: depth only into a shadow-map-sized target, colour at the frame's size.
        std::printf("\n| fill | ms | Gpixel/s |\n|---|---:|---:|\n");
        Program depth_only = link({{GL_VERTEX_SHADER, std::string(kHeader) + kFullscreenVert},
                                   {GL_FRAGMENT_SHADER, std::string(kHeader) + "void main() {}\n"}});
        Program constant_out1 = link({{GL_VERTEX_SHADER, std::string(kHeader) + kFullscreenVert},
                                      {GL_FRAGMENT_SHADER, fragment_of("vec4 work(vec2 p) { return vec4(0.5); }\n", 1)}});
        Program constant_out4 = link({{GL_VERTEX_SHADER, std::string(kHeader) + kFullscreenVert},
                                      {GL_FRAGMENT_SHADER, fragment_of("vec4 work(vec2 p) { return vec4(0.5); }\n", 4)}});
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_ALWAYS);  // every layer's every pixel is written, as the nearest caster's would be
        {
            const int size = 2048, layers = 29;
            Targets shadow = make_targets(size, size, 0, GL_DEPTH_COMPONENT32F);
            glBindFramebuffer(GL_FRAMEBUFFER, shadow.fbo.get());
            glViewport(0, 0, size, size);
            glUseProgram(depth_only.get());
            const GLint depth_at = glGetUniformLocation(depth_only.get(), "depth");
            const double ms = gpu_ms([&] {
                for (int l = 0; l < layers; ++l) {
                    glUniform1f(depth_at, 0.9f - 0.01f * l);
                    glDrawArrays(GL_TRIANGLES, 0, 3);
                }
            });
            std::printf("| depth only, %d x %d^2 (shadow maps) | %.3f | %.1f |\n", layers, size, ms,
                        double(layers) * size * size / ms * 1e-6);
        }
        glDisable(GL_DEPTH_TEST);
        for (int targets : {1, 4}) {
            Targets t = make_targets(width, height, targets, 0);
            glBindFramebuffer(GL_FRAMEBUFFER, t.fbo.get());
            glViewport(0, 0, width, height);
            const Program& p = targets == 1 ? constant_out1 : constant_out4;
            glUseProgram(p.get());
            const double ms = gpu_ms([] { for (int i = 0; i < 8; ++i) glDrawArrays(GL_TRIANGLES, 0, 3); });
            std::printf("| %d RGBA16F target%s, 8 full-screen layers | %.3f | %.1f |\n", targets,
                        targets > 1 ? "s" : "", ms, 8.0 * pixels / ms * 1e-6);
        }

        // G-buffer layouts: what the raster writes per pixel today against a
        // visibility buffer's one or two 32-bit ids (its materials would be
        // evaluated in compute).
        {
            struct Layout { const char* name; std::vector<GLenum> formats; };
            const std::vector<Layout> layouts = {
                {"visibility: R32UI (4 B)", {GL_R32UI}},
                {"visibility: RG32UI (8 B)", {GL_RG32UI}},
                {"the G-buffer: emission RGBA32F, base and params0 RGBA16F, normal R32UI (36 B)",
                 {GL_RGBA32F, GL_RGBA16F, GL_RGBA16F, GL_R32UI}},
                {"the same + params1 RGBA16F, geometry RGBA32UI (60 B)",
                 {GL_RGBA32F, GL_RGBA16F, GL_RGBA16F, GL_R32UI, GL_RGBA16F, GL_RGBA32UI}},
            };
            std::printf("\n| targets written, 8 full-screen layers at %dx%d | ms per layer | Gpixel/s |\n|---|---:|---:|\n",
                        width, height);
            for (const Layout& l : layouts) {
                Targets t = make_targets(width, height, l.formats, 0);
                Program p = link({{GL_VERTEX_SHADER, std::string(kHeader) + kFullscreenVert},
                                  {GL_FRAGMENT_SHADER, constant_writer(l.formats)}});
                glBindFramebuffer(GL_FRAMEBUFFER, t.fbo.get());
                glViewport(0, 0, width, height);
                glUseProgram(p.get());
                const double ms = gpu_ms([] { for (int i = 0; i < 8; ++i) glDrawArrays(GL_TRIANGLES, 0, 3); });
                std::printf("| %s | %.3f | %.1f |\n", l.name, ms / 8.0, 8.0 * pixels / ms * 1e-6);
            }
        }

        // mesh: a grid of 1M triangles over the frame.
        {
            const int n = 707;  // 707^2 * 2 = 1.0M triangles
            std::vector<float> vertices;
            for (int y = 0; y <= n; ++y)
                for (int x = 0; x <= n; ++x) vertices.insert(vertices.end(), {2.0f * x / n - 1, 2.0f * y / n - 1, 0.5f});
            std::vector<unsigned> indices;
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const unsigned a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
                    indices.insert(indices.end(), {a, b, d, a, d, c});
                }
            GLuint buffers[2];
            glCreateBuffers(2, buffers);
            Buffer vb(buffers[0]), ib(buffers[1]);
            glNamedBufferStorage(buffers[0], GLsizeiptr(vertices.size() * 4), vertices.data(), 0);
            glNamedBufferStorage(buffers[1], GLsizeiptr(indices.size() * 4), indices.data(), 0);
            GLuint mesh_vao = 0;
            glCreateVertexArrays(1, &mesh_vao);
            VertexArray mesh(mesh_vao);
            glVertexArrayVertexBuffer(mesh_vao, 0, buffers[0], 0, 12);
            glVertexArrayElementBuffer(mesh_vao, buffers[1]);
            glEnableVertexArrayAttrib(mesh_vao, 0);
            glVertexArrayAttribFormat(mesh_vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
            glVertexArrayAttribBinding(mesh_vao, 0, 0);
            glBindVertexArray(mesh_vao);
            const std::string vert = std::string(kHeader) + "layout(location = 0) in vec3 p;\nvoid main() { gl_Position = vec4(p, 1.0); }\n";
            Program mesh_depth = link({{GL_VERTEX_SHADER, vert}, {GL_FRAGMENT_SHADER, std::string(kHeader) + "void main() {}\n"}});
            Program mesh_out4 = link({{GL_VERTEX_SHADER, vert},
                                      {GL_FRAGMENT_SHADER, fragment_of("vec4 work(vec2 p) { return vec4(p, 0.5, 1.0); }\n", 4)}});
            const GLsizei count = GLsizei(indices.size());
            std::printf("\n| 1.0M-triangle grid over %dx%d | ms | Mtriangles/s |\n|---|---:|---:|\n", width, height);
            glEnable(GL_DEPTH_TEST);
            glDepthFunc(GL_LESS);
            for (int targets : {0, 4}) {
                Targets t = make_targets(width, height, targets, GL_DEPTH_COMPONENT32F);
                glBindFramebuffer(GL_FRAMEBUFFER, t.fbo.get());
                glViewport(0, 0, width, height);
                glUseProgram(targets ? mesh_out4.get() : mesh_depth.get());
                const double ms = gpu_ms([&] {
                    glClear(GL_DEPTH_BUFFER_BIT);
                    glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
                });
                std::printf("| %s | %.3f | %.0f |\n", targets ? "depth + 4 RGBA16F targets" : "depth only", ms,
                            count / 3.0 / ms * 1e-3);
            }
            glBindVertexArray(vao);
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "deferred_bench_raster: %s\n", e.what());
        return 1;
    }
}
