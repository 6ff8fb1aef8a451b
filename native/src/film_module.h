// The film a frame's samples add to, as one module that owns it: the
// Combined accumulation, the light split (DiffDir/GlossDir's light), the
// Shadow pass's shadowed and unshadowed sums, the shadow catchers' two
// lights, one layer per light group and one accumulation per other pass
// asked for (all RGBA32F, cleared at allocation); their binding for the
// lighting pass; and the readback of the resolved passes, every one queued
// into one pixel pack buffer in its final layout and mapped once (a read
// into client memory waits for each pass in turn). The resolves that
// divide the accumulations stay with the frame (they need its programs).
#pragma once

#include "gl_util.h"

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
    };
    // New, cleared accumulations for `layout` (the previous ones released).
    void allocate(const Layout& layout);
    void release();

    // The lighting pass's images (lighting_comp.glsl's IMG_* bindings).
    void bind_for_lighting() const;

    GLuint combined() const { return film_.get(); }
    GLuint diffuse_light() const { return diffuse_light_.get(); }
    GLuint glossy_light() const { return glossy_light_.get(); }
    GLuint shadow_light() const { return shadow_light_.get(); }
    GLuint catcher_hit() const { return catcher_hit_.get(); }
    GLuint catcher_pass() const { return catcher_pass_.get(); }
    GLuint group_layers() const { return group_light_.get(); }
    // The other passes' accumulations, in output order.
    const std::vector<std::pair<Pass, Texture>>& pass_images() const { return pass_images_; }
    // 0 when the pass was not asked for.
    GLuint image(Pass p) const;

    // Bytes of the accumulations (the frame's memory estimate counts them).
    std::size_t bytes() const;

    // Combined, then the other passes, resolved (call after the resolves).
    std::vector<PassImage> read_passes() const;
    // One RGBA image per light group.
    std::vector<std::vector<float>> read_light_groups() const;

private:
    Layout layout_;
    Texture film_, diffuse_light_, glossy_light_, shadow_light_, catcher_hit_, catcher_pass_, group_light_;
    std::vector<std::pair<Pass, Texture>> pass_images_;
};

}  // namespace deferred
