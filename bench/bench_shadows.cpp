// Shadow-map benchmark: the cost of shadows per light type and its share of
// the frame, and how it grows with the number of shadow-casting lights.
// Scene: a floor with 16 boxes, a black world (the world's occlusion map is
// its own row: a grey world and no light); one sample; each light's map
// size follows its footprint (shadow_quality 1, at most 1024).
// Shadow rays (settings.shadow_rays) beside the maps, per light type, and
// the ray hierarchy's build for a mesh of ~1M triangles (first render: the
// mesh's own hierarchy; second: the instances' only). The casters no
// shadow lookup reads, left out or not (DEFERRED_SHADOW_RECEIVER_CULLING).
// Usage: deferred_bench_shadows [width height]
#include "builtin_scenes.h"

#include <cstdio>
#include <cstdlib>
#include <vector>

using namespace deferred;

namespace {
void build_geometry(Renderer& r) {
    tools::MeshArrays floor = tools::make_plane(20.0f);
    tools::MeshArrays box = tools::make_box(0.5f, 0.5f, 0.5f);
    Material m;
    const std::uint32_t mat = r.add_material(m);
    const std::uint32_t fm = r.add_mesh(floor.view()), bm = r.add_mesh(box.view());
    Mat4d I = identity_matrix();
    r.add_instances(fm, I.data(), 1, nullptr, {mat});
    for (int i = 0; i < 16; ++i) {
        Mat4d t = tools::translation(-6.0 + 4.0 * (i % 4), -6.0 + 4.0 * (i / 4), 0.5);
        r.add_instances(bm, t.data(), 1, nullptr, {mat});
    }
    World black;
    black.color = {0, 0, 0};
    r.set_world(black);
}

Light make(LightType type, double x, double y) {
    Light l;
    l.type = type;
    const double eye[3] = {x, y, 4.0}, target[3] = {x * 0.5, y * 0.5, 0.0};
    l.matrix = tools::look_at(eye, target);
    l.energy = type == LightType::Sun ? 2.0f : 300.0f;
    l.spot_size = 1.2f;
    l.size = 1.0f;
    return l;
}

FrameTimings frame(Renderer& r, const Camera& cam, int w, int h, bool shadows, bool rays = false) {
    RenderSettings s;
    s.width = w;
    s.height = h;
    s.shadows = shadows;
    s.shadow_rays = rays;
    r.render(cam, s);  // warm-up
    return r.render(cam, s).timings;
}
}  // namespace

int main(int argc, char** argv) {
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    const int w = argc > 2 ? std::atoi(argv[1]) : 1920, h = argc > 2 ? std::atoi(argv[2]) : 1080;
    try {
        Renderer r;
        Camera cam;
        const double eye[3] = {0, -14, 10}, target[3] = {0, 0, 0};
        cam.matrix = tools::look_at(eye, target);
        cam.lens = 30.0f;
        std::printf("GL: %s, %dx%d, 1 sample (ms, one frame after a warm-up)\n\n", r.gl_info().renderer.c_str(), w,
                    h);
        std::printf("| light | frame without shadows | frame with shadows | shadow maps | share of frame | texels | map MiB | frame with shadow rays | rays / maps |\n");
        std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        const char* names[] = {"point", "spot", "sun", "area"};
        for (LightType type : {LightType::Point, LightType::Spot, LightType::Sun, LightType::Area}) {
            r.clear_scene();
            build_geometry(r);
            r.add_light(make(type, 2.0, -3.0));
            const FrameTimings off = frame(r, cam, w, h, false), on = frame(r, cam, w, h, true);
            const FrameTimings rays = frame(r, cam, w, h, true, true);
            std::printf("| %s | %.0f | %.0f | %.0f | %.0f %% | %d | %.0f | %.0f | %.2f |\n", names[int(type)],
                        off.total_ms, on.total_ms, on.shadow_ms, 100.0 * on.shadow_ms / on.total_ms,
                        on.shadow_resolutions.empty() ? 0 : on.shadow_resolutions[0],
                        double(on.shadow_map_bytes) / (1 << 20), rays.total_ms, rays.total_ms / on.total_ms);
        }
        {
            // The world's occlusion map alone: a grey world, no light.
            r.clear_scene();
            build_geometry(r);
            World grey;
            grey.color = {0.5f, 0.5f, 0.5f};
            r.set_world(grey);
            const FrameTimings off = frame(r, cam, w, h, false), on = frame(r, cam, w, h, true);
            const FrameTimings rays = frame(r, cam, w, h, true, true);
            std::printf("| world (occlusion map) | %.0f | %.0f | %.0f | %.0f %% | - | %.0f | %.0f | %.2f |\n",
                        off.total_ms, on.total_ms, on.shadow_ms, 100.0 * on.shadow_ms / on.total_ms,
                        double(on.shadow_map_bytes) / (1 << 20), rays.total_ms, rays.total_ms / on.total_ms);
        }
        std::printf("\n| shadowed point lights | frame | shadow maps | per light |\n|---:|---:|---:|---:|\n");
        for (int n : {1, 2, 4, 8}) {
            r.clear_scene();
            build_geometry(r);
            for (int i = 0; i < n; ++i) r.add_light(make(LightType::Point, -6.0 + 12.0 * i / 8, 3.0));
            const FrameTimings on = frame(r, cam, w, h, true);
            std::printf("| %d | %.0f | %.0f | %.0f |\n", n, on.total_ms, on.shadow_ms, on.shadow_ms / n);
        }
        {
            // Casters no lookup reads, left out (shadow_module.cpp
            // slice_casters, cone_casters): 10 000 small spheres over a
            // 100 m field of which the view sees a part, under a sun with an
            // angle and a sphere light behind the camera; 4 samples (the
            // maps drawn every sample). The same images either way.
            r.clear_scene();
            build_geometry(r);
            tools::MeshArrays pebble = tools::make_uv_sphere(0.3f, 12, 8);
            Material m;
            const std::uint32_t mat = r.add_material(m), pm = r.add_mesh(pebble.view());
            std::vector<double> at;
            for (int i = 0; i < 100; ++i)
                for (int j = 0; j < 100; ++j) {
                    const Mat4d t = tools::translation(-50.0 + i + 0.5 * (j % 2), -50.0 + j, 0.3);
                    at.insert(at.end(), t.begin(), t.end());
                }
            r.add_instances(pm, at.data(), at.size() / 16, nullptr, {mat});
            Light sun = make(LightType::Sun, 2.0, -3.0);
            sun.angle = 0.05f;
            r.add_light(sun);
            Light lamp = make(LightType::Point, -4.0, -20.0);
            lamp.radius = 0.2f;
            lamp.energy = 3000.0f;
            r.add_light(lamp);
            RenderSettings s;
            s.width = w;
            s.height = h;
            s.samples = 4;
            std::printf("\n| 10 000 spheres, a sun and a light out of view, 4 samples | frame | shadow maps | instances "
                        "drawn into the maps |\n|---|---:|---:|---:|\n");
            for (const char* culling : {"off", "on"}) {
                setenv("DEFERRED_SHADOW_RECEIVER_CULLING", culling, 1);
                r.render(cam, s);
                const FrameTimings t = r.render(cam, s).timings;
                std::printf("| DEFERRED_SHADOW_RECEIVER_CULLING=%s | %.0f | %.0f | %llu |\n", culling, t.total_ms,
                            t.shadow_ms, static_cast<unsigned long long>(t.shadow_instances_drawn));
            }
            unsetenv("DEFERRED_SHADOW_RECEIVER_CULLING");
        }
        {
            // The ray hierarchy of ~1M triangles (a 708 x 708 grid, 1 002 528
            // triangles, 4 instances): the first render builds the mesh's
            // hierarchy, the next ones only the instances'.
            r.clear_scene();
            build_geometry(r);
            tools::MeshArrays grid = tools::make_plane(4.0f, 708);
            Material m;
            const std::uint32_t mat = r.add_material(m), gm = r.add_mesh(grid.view());
            for (int i = 0; i < 4; ++i) {
                Mat4d t = tools::translation(-4.0 + 8.0 * (i % 2), -4.0 + 8.0 * (i / 2), 2.0);
                r.add_instances(gm, t.data(), 1, nullptr, {mat});
            }
            r.add_light(make(LightType::Sun, 2.0, -3.0));
            RenderSettings s;
            s.width = w;
            s.height = h;
            s.shadow_rays = true;
            const FrameTimings first = r.render(cam, s).timings, second = r.render(cam, s).timings;
            s.shadow_rays = false;
            r.render(cam, s);
            const FrameTimings maps = r.render(cam, s).timings;
            std::printf("\n| ray hierarchy, %zu triangles over the instances | first render: build ms | next render: build ms | "
                        "buffer MiB | frame with rays | frame with maps |\n|---|---:|---:|---:|---:|---:|\n",
                        first.ray_triangles);
            std::printf("| 4 x 1 002 528-triangle grid + 17 boxes | %.0f | %.1f | %.0f | %.0f | %.0f |\n",
                        first.ray_build_ms, second.ray_build_ms, double(second.ray_scene_bytes) / (1 << 20),
                        second.total_ms, maps.total_ms);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
