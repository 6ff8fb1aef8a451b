// Many-lights benchmark: frame time against light count with tiled culling
// and with brute force (every light at every pixel), same build, same scene:
// a floor with boxes and N small random point lights (energy 0.05..0.55 W,
// radius <= 2 cm, seed 99), one sample, Combined only. Also culled with
// stochastic light selection (RenderSettings::light_samples = M, 16): its time,
// and the one sample's error against every light's (its noise, which the
// film's samples average out; the mean stays every light's).
// Usage: deferred_bench_lights [width height] [brute_max_lights] [csv_path]
// (DEFERRED_BENCH_MAX_LIGHTS=N: only the rows up to N lights;
// DEFERRED_BENCH_LIGHT_SAMPLES=M: a budget other than 16)
// Prints a markdown table; rows with more lights than brute_max skip brute
// force (llvmpipe would take minutes per frame).
#include "builtin_scenes.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

using namespace deferred;

namespace {
void build(Renderer& r, int light_count) {
    tools::MeshArrays floor = tools::make_plane(30.0f);
    tools::MeshArrays box = tools::make_box(1.0f, 1.0f, 1.0f);
    Material m;
    m.base_color = {0.8f, 0.8f, 0.8f};
    const std::uint32_t mat = r.add_material(m);
    const std::uint32_t floor_mesh = r.add_mesh(floor.view()), box_mesh = r.add_mesh(box.view());
    Mat4d I = identity_matrix();
    r.add_instances(floor_mesh, I.data(), 1, nullptr, {mat});
    for (int i = 0; i < 8; ++i) {
        Mat4d t = tools::translation(-14.0 + 4.0 * i, 3.0 * (i % 3) - 3.0, 1.0);
        r.add_instances(box_mesh, t.data(), 1, nullptr, {mat});
    }
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < light_count; ++i) {
        Light l;
        l.type = LightType::Point;
        l.cast_shadow = false;
        l.matrix = tools::translation(-28 + 56 * u(rng), -28 + 56 * u(rng), 0.1 + 3.0 * u(rng));
        l.energy = float(0.05 + 0.5 * u(rng));
        l.radius = float(0.02 * u(rng));
        l.color = {float(u(rng)), float(u(rng)), float(u(rng))};
        r.add_light(l);
    }
}
}  // namespace

int main(int argc, char** argv) {
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    const int width = argc > 2 ? std::atoi(argv[1]) : 1920;
    const int height = argc > 2 ? std::atoi(argv[2]) : 1080;
    const int brute_max = argc > 3 ? std::atoi(argv[3]) : 128;
    const char* csv_path = argc > 4 ? argv[4] : nullptr;
    FILE* csv = csv_path ? std::fopen(csv_path, "w") : nullptr;
    if (csv) std::fprintf(csv, "lights,culled_ms,culling_ms,shading_ms,tile_light_pairs,brute_ms\n");
    // DEFERRED_BENCH_LIGHT_SAMPLES: the selection's budget M (16).
    const char* samples_env = std::getenv("DEFERRED_BENCH_LIGHT_SAMPLES");
    const int light_samples = samples_env ? std::atoi(samples_env) : 16;
    try {
        Renderer r;
        std::printf("GL: %s | %s\n%dx%d, 1 sample, light threshold 1e-3, M = %d light samples (ms, one frame after a "
                    "warm-up)\n\n",
                    r.gl_info().renderer.c_str(), r.gl_info().version.c_str(), width, height, light_samples);
        std::printf("| lights | culled total | culling | shading | tile-light pairs | brute force | brute/culled | "
                    "M light samples: total | shading | per-pixel rms | mean ratio |\n");
        std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        Camera cam;
        const double eye[3] = {0, -22, 12}, target[3] = {0, 0, 0};
        cam.matrix = tools::look_at(eye, target);
        cam.lens = 30.0f;
        cam.clip_end = 200.0f;
        double one_light_ms = 0;
        // DEFERRED_BENCH_MAX_LIGHTS: stop after the rows up to that many lights.
        const char* max_env = std::getenv("DEFERRED_BENCH_MAX_LIGHTS");
        const int max_lights = max_env ? std::atoi(max_env) : 1 << 30;
        for (int n : {1, 16, 128, 1000, 10000, 65536}) {
            if (n > max_lights) break;
            r.clear_scene();
            build(r, n);
            RenderSettings s;
            s.width = width;
            s.height = height;
            r.render(cam, s);  // warm-up: compile, allocate
            const FrameResult culled_frame = r.render(cam, s);
            const FrameTimings culled = culled_frame.timings;
            // Stochastic selection of M lights per pixel (where more reach it).
            s.light_samples = light_samples;
            r.render(cam, s);
            const FrameResult sampled = r.render(cam, s);
            s.light_samples = 0;
            double err2 = 0, sum_a = 0, sum_b = 0;
            int lit = 0;
            const PassImage& a = *sampled.find(Pass::Combined);
            const PassImage& b = *culled_frame.find(Pass::Combined);
            for (std::size_t i = 0; i < b.pixels.size(); i += 4) {
                const double la = 0.2126 * a.pixels[i] + 0.7152 * a.pixels[i + 1] + 0.0722 * a.pixels[i + 2];
                const double lb = 0.2126 * b.pixels[i] + 0.7152 * b.pixels[i + 1] + 0.0722 * b.pixels[i + 2];
                sum_a += la;
                sum_b += lb;
                if (lb > 1e-3) {
                    err2 += (la - lb) * (la - lb) / (lb * lb);
                    ++lit;
                }
            }
            const double rms = std::sqrt(err2 / std::max(lit, 1));
            double brute_ms = -1;
            if (n <= brute_max) {
                s.light_culling = false;
                r.render(cam, s);
                brute_ms = r.render(cam, s).timings.total_ms;
            }
            if (n == 1) one_light_ms = culled.total_ms;
            std::printf("| %d | %.0f (%.2fx one light) | %.0f | %.0f | %llu | %s | %s | %.0f | %.0f | %.3f | %.4f |\n", n,
                        culled.total_ms, culled.total_ms / one_light_ms, culled.culling_ms, culled.lighting_ms,
                        (unsigned long long)culled.tile_light_pairs,
                        brute_ms < 0 ? "skipped" : std::to_string(int(brute_ms)).c_str(),
                        brute_ms < 0 ? "-" : std::to_string(brute_ms / culled.total_ms).substr(0, 5).c_str(),
                        sampled.timings.total_ms, sampled.timings.lighting_ms, rms, sum_a / sum_b);
            if (csv)
                std::fprintf(csv, "%d,%.2f,%.2f,%.2f,%llu,%.2f\n", n, culled.total_ms, culled.culling_ms,
                             culled.lighting_ms, (unsigned long long)culled.tile_light_pairs, brute_ms);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    if (csv) std::fclose(csv);
    return 0;
}
