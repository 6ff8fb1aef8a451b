// The film a frame's samples add to, as one module that owns it: the
// Combined accumulation, the light split (DiffDir/GlossDir's light), the
// Shadow pass's shadowed and unshadowed sums, the shadow catchers' two
// lights, one layer per light group and one accumulation per other pass
// asked for (all RGBA32F, cleared at allocation); their binding for the
// lighting pass; and the readback of the resolved passes, every one queued
// into one pixel pack buffer in its final layout and mapped once (a read
// into client memory waits for each pass in turn). The resolves that
// divide the accumulations stay with the frame (they need its programs).
//
// Filter splatting (film.h PixelFilter::splat_taps): with a margin, every
// accumulation Combined is made of (Combined, the light split, Shadow's and
// the catchers' sums, the light groups, Emission, Environment and the
// colours the light split is divided by; splatted()) has a scratch image
// of the sample's values: the sample's shaders add to it
// (sample_target, bind_for_lighting) as they would to the accumulation,
// and splat() adds it to the accumulation, each pixel from its neighbours
// with the filter's weights for the sample's jitter.
#pragma once

#include "film.h"
#include "gl_util.h"
#include "shader_library.h"

#include <deferred/passes.h>
#include <deferred/renderer.h>

#include <cstddef>
#include <utility>
#include <vector>

namespace deferred {

class FilmModule {
public:
    struct Layout {
        int width = 0, height = 0;
        std::vector<Pass> passes;  // besides Combined, in output order
        bool light_split = false;  // DiffDir / GlossDir
        bool shadow_pass = false;
        bool catchers = false;
        int light_groups = 0;
        int splat_margin = 0;  // PixelFilter::splat_margin(); 0: each pixel its own sample
    };
    // New, cleared accumulations for `layout` (the previous ones released).
    void allocate(const Layout& layout);
    void release();

    // The lighting pass's images (lighting_comp.glsl's IMG_* bindings):
    // this sample's targets.
    void bind_for_lighting() const;

    // Whether each sample is splatted (the layout has a margin).
    bool splatting() const { return layout_.splat_margin > 0; }
    // Starts the splat program's compile (ShaderLibrary::prefetch_compute).
    void prefetch(ShaderLibrary& shaders) const;
    // Before a sample's first write: its scratch images cleared
    // (`emission_only`: Combined's and the Emit pass's, all an emission
    // sub-sample writes, emission_samples.h).
    void begin_sample(bool emission_only = false) const;
    // After its last write: the scratch images added to the accumulations
    // with the taps for the sample's jitter on x and y (`emission_only`: as
    // begin_sample).
    void splat(ShaderLibrary& shaders, const SplatTaps& x, const SplatTaps& y, bool emission_only = false) const;

    // The accumulations (the resolves, the preview and the readback read these).
    GLuint combined() const { return film_.total.get(); }
    // Where this sample's shaders add to Combined: its scratch image when
    // splatted, else the accumulation.
    GLuint combined_target() const { return film_.target(); }
    GLuint diffuse_light() const { return diffuse_light_.total.get(); }
    GLuint glossy_light() const { return glossy_light_.total.get(); }
    GLuint shadow_light() const { return shadow_light_.total.get(); }
    GLuint catcher_hit() const { return catcher_hit_.total.get(); }
    GLuint catcher_pass() const { return catcher_pass_.total.get(); }
    GLuint group_layers() const { return group_light_.total.get(); }
    // The other passes' accumulations, in output order.
    const std::vector<std::pair<Pass, Texture>>& pass_images() const { return pass_images_; }
    // 0 when the pass was not asked for.
    GLuint image(Pass p) const;
    // Where this sample's shaders add pass p (0 when not asked for): its
    // scratch image when splatted, else its image.
    GLuint sample_target(Pass p) const;
    // Whether pass p's image (one of pass_images(), so never Combined,
    // whose film is splatted whenever the layout splats) goes through the
    // splat: the passes Combined is made of.
    static bool splatted(Pass p);

    // Bytes of the accumulations (the frame's memory estimate counts them).
    std::size_t bytes() const;

    // Combined, then the other passes, resolved (call after the resolves).
    std::vector<PassImage> read_passes() const;
    // One RGBA image per light group.
    std::vector<std::vector<float>> read_light_groups() const;

private:
    // An accumulation and, when splatted, this sample's scratch image.
    struct Accumulation {
        Texture total, sample;
        GLuint target() const { return sample ? sample.get() : total.get(); }
        explicit operator bool() const { return bool(total); }
    };
    Accumulation accumulation(const char* name, const float* value, bool splat, int layers = 0) const;
    template <typename F> void for_each_splatted(F&& f) const;
    template <typename F> void for_each_emission_splatted(F&& f) const;

    Layout layout_;
    Accumulation film_, diffuse_light_, glossy_light_, shadow_light_, catcher_hit_, catcher_pass_, group_light_;
    std::vector<std::pair<Pass, Texture>> pass_images_;
    std::vector<Texture> pass_samples_;  // pass_images_'s scratch images (empty Texture: not splatted)
};

}  // namespace deferred
