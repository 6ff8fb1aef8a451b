// The lighting pass's two forms of its light loop (lighting_comp.glsl
// LIGHT_KIND_LOOPS): one loop per light kind, each holding only that kind's
// code (on llvmpipe, which runs every branch of a loop body, in frames that
// are not culled), and one loop over every kind's code (GPUs). They shade the same entries in the same
// order, so their images are equal; DEFERRED_LIGHT_KIND_LOOPS picks the
// form, so both run on one driver.
#include "builtin_scenes.h"
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

using namespace deferred;
using namespace deferred::testing;

namespace {

FrameResult render_with_kind_loops(Renderer& r, const Camera& cam, const RenderSettings& s, bool kind_loops) {
    const char* before = std::getenv("DEFERRED_LIGHT_KIND_LOOPS");
    const std::string saved = before ? before : "";
    setenv("DEFERRED_LIGHT_KIND_LOOPS", kind_loops ? "on" : "off", 1);
    FrameResult f = r.render(cam, s);
    if (before) setenv("DEFERRED_LIGHT_KIND_LOOPS", saved.c_str(), 1);
    else unsetenv("DEFERRED_LIGHT_KIND_LOOPS");
    return f;
}

}  // namespace

TEST(LightKinds, LoopsPerKindEqualTheOneLoop) {
    // The showcase's point, spot, sun and area lights with 2 more point
    // lights added after them (6: one sequence, which LightModule packs
    // kind by kind; a culled frame, 8 lights or more, keeps the one loop),
    // every light and then 2 light samples a pixel (the chosen lights' short
    // list). Every pass the light loop adds to: Combined, the light split,
    // Shadow.
    for (const int light_samples : {0, 2}) {
        const int extra = 2;
        Renderer r;
        const Camera cam = tools::build_showcase(r, extra);
        RenderSettings s;
        s.width = 96;
        s.height = 64;
        s.samples = 2;
        s.light_samples = light_samples;
        s.passes = PassSet{Pass::Combined, Pass::DiffDir, Pass::GlossDir, Pass::Shadow};
        const FrameResult one = render_with_kind_loops(r, cam, s, false);
        const FrameResult kinds = render_with_kind_loops(r, cam, s, true);
        for (const PassImage& a : one.passes) {
            const PassImage& b = *kinds.find(a.pass);
            double worst = 0, scale = 1e-30;
            for (std::size_t i = 0; i < a.pixels.size(); ++i) {
                scale = std::max(scale, double(std::abs(a.pixels[i])));
                worst = std::max(worst, std::abs(double(a.pixels[i]) - double(b.pixels[i])));
            }
            std::printf("%d light samples: %s differs by %.3g (of %.3g)\n", light_samples, pass_info(a.pass).name,
                        worst, scale);
            EXPECT_LE(worst, 1e-6 * scale) << light_samples << " light samples, " << pass_info(a.pass).name;
            EXPECT_GT(scale, 1e-3) << "the pass should hold light";
        }
    }
}
