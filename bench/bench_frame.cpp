// Frame-time benchmark: the built-in showcase at 1920x1080 with 4 + N point
// lights, timing each stage (on the GPU's clock) and reporting the
// render-target memory; then the GPU issue's frame targets on it: 64
// samples end to end with Combined read back, and one sample with the 16
// passes Combined..AO read back (wall time around render()), and the time
// a render of the unchanged scene spends before its first sample; each of
// those frames split into the engine's stages (GPU clock) beside the
// process's CPU time, which says whether a frame waits on the GPU or on the
// CPU issuing it, and each case's first render with its program compiles;
// then 64 samples with shadow rays, the same tables. Prints markdown tables. With DEFERRED_BENCH_PROFILE=1 in
// the environment, also a sampling CPU profile of each of those frames
// (cpu_profile.h): where a CPU-bound frame's time goes.
// Usage: deferred_bench_frame [width height] [repeats]
// (DEFERRED_BENCH_FRAME_BLOCKS=rays: the shadow-rays block alone)
#include "builtin_scenes.h"
#include "cpu_profile.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

int main(int argc, char** argv) {
    using namespace deferred;
    const int width = argc > 2 ? std::atoi(argv[1]) : 1920;
    const int height = argc > 2 ? std::atoi(argv[2]) : 1080;
    const int repeats = argc > 3 ? std::atoi(argv[3]) : 3;
    std::setvbuf(stdout, nullptr, _IOLBF, 0);  // rows appear as they are measured
    try {
        Renderer renderer;
        const GLInfo& gl = renderer.gl_info();
        std::printf("GL: %s | %s | %s (%s)\n", gl.vendor.c_str(), gl.renderer.c_str(), gl.version.c_str(),
                    gl.display.c_str());
        std::printf("%dx%d, Combined + Depth + Normal, 1 sample, median of %d frames (ms)\n\n", width, height,
                    repeats);
        std::printf("| lights | geometry | lighting | passes | readback | total | G-buffer MiB |\n");
        std::printf("|---:|---:|---:|---:|---:|---:|---:|\n");
        for (int extra : {0, 12, 60}) {
            renderer.clear_scene();
            Camera cam = tools::build_showcase(renderer, extra);
            RenderSettings s;
            s.width = width;
            s.height = height;
            s.passes.insert(Pass::Depth);
            s.passes.insert(Pass::Normal);
            renderer.render(cam, s);  // warm-up: shader compilation, allocation
            std::vector<FrameTimings> runs;
            for (int i = 0; i < repeats; ++i) runs.push_back(renderer.render(cam, s).timings);
            auto median = [&](double FrameTimings::*field) {
                std::vector<double> v;
                for (auto& t : runs) v.push_back(t.*field);
                std::sort(v.begin(), v.end());
                return v[v.size() / 2];
            };
            std::printf("| %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |\n", 4 + extra,
                        median(&FrameTimings::geometry_ms), median(&FrameTimings::lighting_ms),
                        median(&FrameTimings::passes_ms), median(&FrameTimings::readback_ms),
                        median(&FrameTimings::total_ms), double(runs[0].gbuffer_bytes) / (1 << 20));
        }
        renderer.clear_scene();
        const Camera cam = tools::build_showcase(renderer, 0);
        struct Case {
            const char* label;
            int samples;
            PassSet passes;
            bool rays = false;  // shadow rays instead of maps
            bool splat = true;  // the film's filter splatting (film.h)
            bool visibility = false;  // the G-buffer from the visibility buffer (visibility_module.h)
        };
        struct Split {  // one frame of a case: its timings, wall and CPU time
            const char* label;
            FrameTimings t;
            double wall = 0, cpu = 0;
        };
        const bool profile = deferred::bench::profile_requested();
        // One block of tables per call, printed when its cases are done, so a
        // later block that runs out of time loses only itself.
        auto run_cases = [&](const char* title, const std::vector<Case>& cases) {
            // "before the first sample": the frame's sync and programs
            // (upload_ms) in a render of the unchanged scene on the same
            // renderer (the GPU issue's warm-render target: under 50 ms on a GPU).
            std::printf("\nshowcase, 4 lights, %s: wall time around render(), median of %d frames (ms)\n\n", title,
                        repeats);
            std::printf("| frame | wall | per sample | readback | before the first sample |\n|---|---:|---:|---:|---:|\n");
            std::vector<Split> medians, warmups;  // warmups: each case's first render (programs compiled)
            std::string profiles;
            for (const Case& c : cases) {
                RenderSettings s;
                s.width = width;
                s.height = height;
                s.samples = c.samples;
                s.passes = c.passes;
                s.shadow_rays = c.rays;
                s.filter_splat = c.splat;
                s.visibility_buffer = c.visibility;
                auto timed = [&] {
                    Split x{c.label, {}, 0, 0};
                    const double cpu0 = deferred::bench::process_cpu_ms();
                    const auto t0 = std::chrono::steady_clock::now();
                    x.t = renderer.render(cam, s).timings;
                    x.wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
                    x.cpu = deferred::bench::process_cpu_ms() - cpu0;
                    return x;
                };
                // The first render also counts the shadow maps' fragments (a
                // query per layer, which may cost a GPU time: not in the
                // timed frames).
                s.count_shadow_fragments = true;
                warmups.push_back(timed());
                s.count_shadow_fragments = false;
                // At once: a first render that compiles for minutes (shadow
                // rays on an H200) still says so when the check stops it.
                std::printf("(first render of \"%s\": %.1f ms wall, %zu programs compiled in %.1f ms)\n", c.label,
                            warmups.back().wall, warmups.back().t.programs_compiled, warmups.back().t.compile_ms);
                std::vector<Split> runs;
                for (int i = 0; i < repeats; ++i) runs.push_back(timed());
                std::sort(runs.begin(), runs.end(), [](const Split& a, const Split& b) { return a.wall < b.wall; });
                const Split& m = runs[runs.size() / 2];  // the median frame by wall time
                std::vector<double> readback, before;
                for (const Split& x : runs) {
                    readback.push_back(x.t.readback_ms);
                    before.push_back(x.t.upload_ms);
                }
                std::sort(readback.begin(), readback.end());
                std::sort(before.begin(), before.end());
                std::printf("| %s | %.1f | %.2f | %.1f | %.1f |\n", c.label, m.wall, m.wall / c.samples,
                            readback[readback.size() / 2], before[before.size() / 2]);
                medians.push_back(m);
                if (profile) {
                    deferred::bench::CpuProfile p;
                    p.start();
                    for (int i = 0; i < repeats; ++i) renderer.render(cam, s);
                    p.stop();
                    profiles += p.report_string(c.label);
                }
            }
            // The median frames by stage (GPU clock: a stage's time also counts
            // the GPU waiting for the CPU to issue it) beside the process's CPU time.
            std::printf("\nthe median frames above by stage (ms; GPU timestamps) and the process's CPU time\n\n");
            std::printf("| frame | wall | CPU (all threads) | before the first sample | shadows | geometry | culling | "
                        "lighting | passes | forward | readback | total | shadow layers (Mtexels, M fragments) | instances drawn (camera, "
                        "shadows) |\n");
            std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
            for (std::size_t i = 0; i < medians.size(); ++i) {
                const Split& x = medians[i];
                std::printf("| %s | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %zu (%.1f, %.1f) | "
                            "%llu, %llu |\n",
                            x.label, x.wall, x.cpu, x.t.upload_ms, x.t.shadow_ms, x.t.geometry_ms, x.t.culling_ms,
                            x.t.lighting_ms, x.t.passes_ms, x.t.forward_ms, x.t.readback_ms, x.t.total_ms,
                            x.t.shadow_layers_rendered, 1e-6 * double(x.t.shadow_texels_rendered),
                            1e-6 * double(warmups[i].t.shadow_fragments),  // counted in the case's first render
                            static_cast<unsigned long long>(x.t.camera_instances_drawn),
                            static_cast<unsigned long long>(x.t.shadow_instances_drawn));
            }
            std::printf("\neach case's first render (its programs compiled or loaded from the disk cache)\n\n");
            std::printf("| frame | wall | CPU (all threads) | programs compiled | compile ms | programs loaded | load ms |\n");
            std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
            for (const Split& x : warmups)
                std::printf("| %s | %.1f | %.1f | %zu | %.1f | %zu | %.1f |\n", x.label, x.wall, x.cpu,
                            x.t.programs_compiled, x.t.compile_ms, x.t.programs_loaded, x.t.load_ms);
            std::fputs(profiles.c_str(), stdout);
            std::fflush(stdout);
        };
        PassSet sixteen;
        for (std::uint32_t p = 0; p <= static_cast<std::uint32_t>(Pass::AO); ++p) sixteen.insert(Pass(p));
        // DEFERRED_BENCH_FRAME_BLOCKS: "maps", "rays" or both (the default).
        const char* blocks_env = std::getenv("DEFERRED_BENCH_FRAME_BLOCKS");
        const std::string blocks = blocks_env ? blocks_env : "maps rays";
        if (blocks.find("maps") != std::string::npos)
            // The film's splat beside each pixel's own samples: its cost per
            // sample with one splatted image (Combined) and with ten (16 passes).
            // The visibility buffer's G-buffer (in compute) beside the raster's.
            run_cases("shadow maps", {Case{"64 samples, Combined read back", 64, PassSet{Pass::Combined}},
                                      Case{"64 samples, Combined, visibility buffer", 64, PassSet{Pass::Combined},
                                           false, true, true},
                                      Case{"64 samples, Combined, no filter splatting", 64, PassSet{Pass::Combined},
                                           false, false},
                                      Case{"1 sample, 16 passes (Combined..AO) read back", 1, sixteen},
                                      Case{"8 samples, 16 passes", 8, sixteen},
                                      Case{"8 samples, 16 passes, no filter splatting", 8, sixteen, false, false}});
        // Shadow rays apart and last: on an H200 tests with rays took minutes
        // where llvmpipe takes seconds (bench/gpu/results/nvidia_h200_2026-11-26);
        // one sample first, so its cost per sample shows before 64 of them.
        if (blocks.find("rays") != std::string::npos)
            run_cases("shadow rays", {Case{"1 sample, shadow rays, Combined read back", 1, PassSet{Pass::Combined}, true},
                                      Case{"64 samples, shadow rays, Combined read back", 64, PassSet{Pass::Combined}, true}});
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
