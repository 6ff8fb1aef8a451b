// The frame's stage timings: taken on the GPU's clock inside the sample loop
// (GpuStageTimer: timestamp queries read after the frame, no glFinish per
// stage), they still account for the frame: every stage that ran has time,
// and their sum is the render's own time, within it.
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <chrono>

using namespace deferred;

TEST(StageTimings, GpuTimedStagesAccountForTheFrame) {
    Renderer r;
    Material m;
    m.base_color = {0.6f, 0.6f, 0.6f};
    deferred::testing::add_plane(r, m, 5.0f);
    Light l;
    l.type = LightType::Point;
    l.matrix = tools::translation(0.0, 0.0, 2.0);
    l.energy = 100.0f;
    r.add_light(l);
    RenderSettings s;
    s.width = 160;
    s.height = 90;
    s.samples = 12;
    const Camera cam = deferred::testing::top_down_ortho(3.0, 4.0f);
    r.render(cam, s);  // compile
    const auto t0 = std::chrono::steady_clock::now();
    const FrameResult f = r.render(cam, s);
    const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const FrameTimings& t = f.timings;
    std::printf("wall %.1f ms; total %.1f = upload %.1f + geometry %.1f + shadow %.1f + lighting %.1f + passes %.1f + "
                "readback %.1f\n",
                wall, t.total_ms, t.upload_ms, t.geometry_ms, t.shadow_ms, t.lighting_ms, t.passes_ms, t.readback_ms);
    EXPECT_GT(t.geometry_ms, 0.0);
    EXPECT_GT(t.shadow_ms, 0.0);
    EXPECT_GT(t.lighting_ms, 0.0);
    EXPECT_GT(t.readback_ms, 0.0);
    EXPECT_LE(t.total_ms, wall + 1.0);  // the stages lie within the render
    EXPECT_GE(t.total_ms, 0.5 * wall);  // and make up most of it
}
