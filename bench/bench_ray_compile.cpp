// Shadow rays' cost to the driver's compiler, against the number of places a
// program calls the traversal (shaders/bench_ray_compile_comp.glsl), inlined
// as GLSL compilers do, or called through a subroutine uniform as the
// engine's programs do (RAY_SUBROUTINE, ray_lib.glsl). On an H200
// the native tests with shadow rays took 20-60 s each where llvmpipe takes
// seconds, on images of at most 96 x 64 pixels; the lighting program calls
// the traversal from up to ten places (light_lib.glsl). This says whether
// compile time grows with the copies, and what a subroutine call saves
// there and costs per ray.
// For each variant: compile + link ms (no disk cache), then the GPU time of
// one dispatch of 1M random rays (the best of 3) against 4 instances of a 131k-triangle
// bumpy grid (each ray crosses the sites' branches as its index's bits say).
// On an H200 (run 5, bench/gpu/results) it stopped with GL_INVALID_VALUE
// before its first row, where llvmpipe runs it: each step is now checked by
// name, so the next GPU check says which call it was.
// Usage: deferred_bench_ray_compile [max sites: 1, 2, 4, 8 or 16] [rays, 1M]
#include "egl_context.h"
#include "gl_util.h"
#include "ray_scene.h"
#include "shader_library.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

int main(int argc, char** argv) {
    using namespace deferred;
    const int max_sites = argc > 1 ? std::atoi(argv[1]) : 16;
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    setenv("DEFERRED_SHADER_CACHE", "off", 1);  // every variant compiled, none loaded
    try {
        EglContext context(-1);
        check_gl("creating the context");
        std::printf("GL: %s | %s | %s\n\n", reinterpret_cast<const char*>(glGetString(GL_VENDOR)),
                    reinterpret_cast<const char*>(glGetString(GL_RENDERER)),
                    reinterpret_cast<const char*>(glGetString(GL_VERSION)));
        // The scene: a 256 x 256 grid of bumpy quads, 4 instances side by side.
        const int n = 256;
        std::vector<float> corners;
        auto height = [](int x, int y) { return 0.05f * std::sin(0.37f * x) * std::cos(0.23f * y); };
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const float x0 = float(x) / n, x1 = float(x + 1) / n, y0 = float(y) / n, y1 = float(y + 1) / n;
                const float h00 = height(x, y), h10 = height(x + 1, y), h01 = height(x, y + 1), h11 = height(x + 1, y + 1);
                corners.insert(corners.end(), {x0, y0, h00, x1, y0, h10, x1, y1, h11});
                corners.insert(corners.end(), {x0, y0, h00, x1, y1, h11, x0, y1, h01});
            }
        auto bvh = std::make_shared<const MeshBvh>(build_mesh_bvh(corners.data(), nullptr, corners.size() / 9));
        std::vector<RayScene::Instance> instances;
        for (int k = 0; k < 4; ++k) {
            glm::dmat4 m(1.0);
            m[3] = glm::dvec4(double(k % 2), double(k / 2), 0.0, 1.0);
            instances.push_back({bvh, m, {}});
        }
        RayScene scene;
        scene.build(instances);
        scene.upload();
        check_gl("uploading the ray scene");
        // Rays from above the grid towards random points below it or beside it.
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        const std::size_t ray_count = argc > 2 ? std::size_t(std::atol(argv[2])) / 64 * 64 + 64 : std::size_t(1) << 20;
        std::vector<float> packed;
        packed.reserve(ray_count * 8);
        for (std::size_t i = 0; i < ray_count; ++i) {
            const glm::vec3 o(2.0f * u(rng), 2.0f * u(rng), 0.2f + u(rng));
            const glm::vec3 t(2.0f * u(rng), 2.0f * u(rng), -0.2f + 0.3f * u(rng));
            const glm::vec3 d = glm::normalize(t - o);
            packed.insert(packed.end(), {o.x, o.y, o.z, 10.0f, d.x, d.y, d.z, 0.0f});
        }
        Buffer rays = make_storage_buffer(packed.data(), packed.size() * sizeof(float), "rays");
        Buffer out = make_storage_buffer(nullptr, ray_count * sizeof(float), "transmittance");
        std::printf("%zu triangles in %zu instances, %zu rays\n\n", scene.triangles(), scene.instances(), ray_count);
        std::printf("| call sites | call | compile + link ms | dispatch ms (GPU) | result checksum |\n");
        std::printf("|---:|---|---:|---:|---:|\n");
        GLuint query = 0;
        glGenQueries(1, &query);
        for (int sites = 1; sites <= max_sites; sites *= 2) {
            for (bool subroutine : {false, true}) {
                ShaderLibrary library;
                ShaderVariant variant;
                variant.defines.push_back("RAY_SITES " + std::to_string(sites));
                if (subroutine) variant.defines.push_back("RAY_SUBROUTINE");
                const auto t0 = std::chrono::steady_clock::now();
                const GLuint program = library.compute_program("bench_ray_compile_comp.glsl", variant);
                glFinish();
                check_gl("compiling the program");
                const double compile_ms =
                    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
                glUseProgram(program);
                use_ray_traversal(program, GL_COMPUTE_SHADER);  // the engine's call, as the lighting pass makes it
                check_gl("using the program");
                scene.bind();
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, rays.get());
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out.get());
                check_gl("binding the buffers");
                double best = 1e30;
                for (int rep = 0; rep < 3; ++rep) {
                    glBeginQuery(GL_TIME_ELAPSED, query);
                    glDispatchCompute(GLuint(ray_count / 64), 1, 1);
                    glEndQuery(GL_TIME_ELAPSED);
                    GLuint64 ns = 0;
                    glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
                    best = std::min(best, double(ns) * 1e-6);
                }
                check_gl("the timed dispatches");
                glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
                std::vector<float> T(ray_count);
                glGetNamedBufferSubData(out.get(), 0, GLsizeiptr(T.size() * sizeof(float)), T.data());
                check_gl("reading the result back");
                double sum = 0.0;
                for (float t : T) sum += t;
                std::printf("| %d | %s | %.0f | %.2f | %.1f |\n", sites, subroutine ? "subroutine" : "inlined",
                            compile_ms, best, sum);
            }
        }
        glDeleteQueries(1, &query);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "deferred_bench_ray_compile: %s\n", e.what());
        return 1;
    }
}
