// Cost of each compositing output per film sample (issue 17's benchmark):
// the built-in showcase at WxH with S film samples, plus a node-material
// overlay on the floor that writes two shader AOVs and four point lights in
// four light groups, shadows off. Each row renders the frame with one output on and
// reports its time over the same frame without it, per film sample, and the
// frame targets it adds. Medians of R frames after a warm-up frame (shader
// compilation). Prints a markdown table.
// Usage: deferred_bench_outputs [width height] [samples] [repeats]
#include "builtin_scenes.h"
#include "cpu_profile.h"

#include <deferred/material_graph.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

using namespace deferred;

namespace {

// A Diffuse BSDF (grey, Lambert) whose AOV Output nodes write the position
// (colour AOV "position") and a constant (value AOV "mask").
MaterialGraph aov_graph() {
    auto constant = GraphArg::constant;
    auto shading = GraphArg::shading;
    auto slot = GraphArg::literal;
    MaterialGraph g;
    g.name = "aov overlay";
    g.constants = {0.5f, 0.5f, 0.5f, 0.0f, 1.0f};
    g.nodes.push_back({"node_bsdf_diffuse",
                       {constant(SocketType::Color, 0), constant(SocketType::Float, 3), shading("N")},
                       {SocketType::Closure}});
    g.nodes.push_back({"node_aov_output", {slot(0), shading("P"), constant(SocketType::Float, 4)}, {}});
    g.nodes.push_back({"node_aov_output", {slot(1), constant(SocketType::Color, 0), constant(SocketType::Float, 4)}, {}});
    g.surface_node = 0;
    g.aovs = {"position", "mask"};
    return g;
}

Camera build_scene(Renderer& r) {
    Camera cam = tools::build_showcase(r);
    // The overlay: a plane just above the floor, under the spheres.
    tools::MeshArrays plane = tools::make_plane(6.0f, 4);
    const std::uint32_t mesh = r.add_mesh(plane.view());
    const std::uint32_t mat = r.add_graph_material(Material{}, aov_graph());
    const Mat4d lifted = tools::translation(0.0, 0.0, 0.002);
    const std::uint32_t object_index = 3;
    r.add_instances(mesh, lifted.data(), 1, &object_index, {mat});
    for (std::uint32_t group = 1; group <= 4; ++group) {
        Light l;
        l.type = LightType::Point;
        l.matrix = tools::translation(-3.0 + 2.0 * group, 2.5, 1.5);
        l.energy = 60.0f;
        l.radius = 0.1f;
        l.light_group = group;
        r.add_light(l);
    }
    return cam;
}

struct Measure {
    double ms = 0;        // median total frame time
    double cpu_ms = 0;    // median CPU time of the process over the frame
    std::size_t bytes = 0;  // frame targets
};

}  // namespace

int main(int argc, char** argv) {
    const int width = argc > 2 ? std::atoi(argv[1]) : 1920;
    const int height = argc > 2 ? std::atoi(argv[2]) : 1080;
    const int samples = argc > 3 ? std::atoi(argv[3]) : 8;
    const int repeats = argc > 4 ? std::atoi(argv[4]) : 3;
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    try {
        Renderer renderer;
        const GLInfo& gl = renderer.gl_info();
        std::printf("GL: %s | %s | %s (%s)\n", gl.vendor.c_str(), gl.renderer.c_str(), gl.version.c_str(),
                    gl.display.c_str());
        const Camera cam = build_scene(renderer);
        RenderSettings base;
        base.width = width;
        base.height = height;
        base.samples = samples;
        // Shadows off: they cost the same with any output and would bury
        // the outputs' cost in their noise.
        base.shadows = false;
        auto measure = [&](const RenderSettings& s) {
            renderer.render(cam, s);  // warm-up: programs, targets
            std::vector<double> ms, cpu;
            Measure m;
            for (int i = 0; i < repeats; ++i) {
                const double cpu0 = deferred::bench::process_cpu_ms();
                const FrameResult f = renderer.render(cam, s);
                cpu.push_back(deferred::bench::process_cpu_ms() - cpu0);
                ms.push_back(f.timings.total_ms);
                m.bytes = f.timings.gbuffer_bytes;
            }
            std::sort(ms.begin(), ms.end());
            std::sort(cpu.begin(), cpu.end());
            m.ms = ms[ms.size() / 2];
            m.cpu_ms = cpu[cpu.size() / 2];
            return m;
        };
        // DEFERRED_BENCH_PROFILE=1: where the CPU time of a frame goes (cpu_profile.h).
        const bool profile = deferred::bench::profile_requested();
        std::string profiles;
        auto profile_frames = [&](const RenderSettings& s, const std::string& title) {
            if (!profile) return;
            deferred::bench::CpuProfile p;
            p.start();
            for (int i = 0; i < repeats; ++i) renderer.render(cam, s);
            p.stop();
            profiles += p.report_string(title.c_str());
        };
        std::printf("%dx%d, %d film samples, showcase + AOV overlay + 4 grouped lights, no shadows, median of %d "
                    "frames\n\n",
                    width, height, samples, repeats);
        const Measure none = measure(base);
        std::printf("Combined only: %.1f ms per frame, %.2f ms per sample (process CPU time %.1f ms per frame)\n\n",
                    none.ms, none.ms / samples, none.cpu_ms);
        profile_frames(base, "Combined only");
        std::printf("| output | frame ms | added per sample ms | added per sample %% | CPU ms per frame |\n");
        std::printf("|---|---:|---:|---:|---:|\n");
        struct Row { std::string name; std::function<void(RenderSettings&)> set; };
        const std::vector<Row> rows = {
            {"Depth + Normal + IndexOB (data passes)",
             [](RenderSettings& s) { s.passes = {Pass::Depth, Pass::Normal, Pass::IndexOB}; }},
            {"every light and colour pass (14)",
             [](RenderSettings& s) {
                 for (std::uint32_t i = 1; i < kPassCount; ++i)
                     if (Pass(i) != Pass::Vector) s.passes.insert(Pass(i));
             }},
            {"Vector", [](RenderSettings& s) { s.passes = {Pass::Vector}; }},
            {"Cryptomatte Object + Material + Asset, Levels 6",
             [](RenderSettings& s) {
                 s.cryptomatte = {CryptomatteKind::Object, CryptomatteKind::Material, CryptomatteKind::Asset};
             }},
            {"2 shader AOVs", [](RenderSettings& s) { s.aovs = {{"position", true}, {"mask", false}}; }},
            {"4 light groups", [](RenderSettings& s) { s.light_groups = 4; }},
        };
        for (const Row& row : rows) {
            RenderSettings s = base;
            row.set(s);
            const Measure m = measure(s);
            const double added = (m.ms - none.ms) / samples;
            std::printf("| %s | %.1f | %.2f | %.0f %% | %.1f |\n", row.name.c_str(), m.ms, added,
                        100.0 * added / (none.ms / samples), m.cpu_ms);
            if (!s.cryptomatte.empty() || s.light_groups > 0) profile_frames(s, row.name);
        }
        std::fputs(profiles.c_str(), stdout);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
