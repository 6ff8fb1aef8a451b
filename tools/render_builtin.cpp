// Renders the built-in showcase scene headless to OUT.exr (all passes,
// Blender's multilayer naming) and OUT.png (Standard view transform).
// Usage: deferred_render_builtin OUT_PREFIX [width height]
#include "builtin_scenes.h"
#include "image_io.h"

#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
    using namespace deferred;
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s OUT_PREFIX [width height]\n", argv[0]);
        return 2;
    }
    const std::string out = argv[1];
    const int width = argc > 3 ? std::atoi(argv[2]) : 960;
    const int height = argc > 3 ? std::atoi(argv[3]) : 540;
    try {
        Renderer renderer;
        const GLInfo& gl = renderer.gl_info();
        std::printf("GL: %s | %s | %s (%s)\n", gl.vendor.c_str(), gl.renderer.c_str(), gl.version.c_str(),
                    gl.display.c_str());
        Camera cam = tools::build_showcase(renderer);
        RenderSettings settings;
        settings.width = width;
        settings.height = height;
        for (std::uint32_t i = 0; i < kPassCount; ++i) settings.passes.insert(Pass(i));
        settings.samples = 16;
        FrameResult frame = renderer.render(cam, settings);
        tools::write_multilayer_exr(out + ".exr", frame);
        tools::write_png_preview(out + ".png", *frame.find(Pass::Combined));
        const FrameTimings& t = frame.timings;
        std::printf("%dx%d, %zu passes: geometry %.1f ms, lighting %.1f ms, passes %.1f ms, readback %.1f ms\n",
                    width, height, frame.passes.size(), t.geometry_ms, t.lighting_ms, t.passes_ms, t.readback_ms);
        std::printf("wrote %s.exr and %s.png\n", out.c_str(), out.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
