// The visibility buffer: the G-buffer written in compute instead of by the
// raster pipeline's fragment stage (RenderSettings::visibility_buffer).
//
// On the data-centre GPUs this engine's users render on, fragment shading
// runs on a small part of the chip: the same arithmetic measured 32x slower
// in a fragment shader than in a compute shader on an H200, and a textured
// node material's geometry pass 4.1x its constant material's
// (bench/gpu/results/nvidia_h200_2026-11-26). So the raster only decides
// visibility here, and everything per pixel runs in compute:
//
//   raster     depth + (instance, triangle, slot key + 1) per pixel, one
//              program for every material (geometry_vert.glsl VISIBILITY_PASS,
//              visibility_frag.glsl)
//   classify   the 8 x 8 tiles listed by the slot keys they see (a key: a
//              mesh batch's material slot, one mesh and one material):
//              counts, an exclusive scan with each key's indirect dispatch,
//              a scatter (visibility_classify_comp.glsl); one atomic per
//              tile and key, not per pixel
//   resolve    per key, one indirect dispatch with the mesh's buffers and the
//              material's program, a workgroup per tile: geometry_frag.glsl's
//              own surface code in compute (gbuffer_resolve_comp.glsl) for
//              the tile's pixels of that key, into the G-buffer's images
//
// The G-buffer it writes is the raster path's up to floating-point rounding
// (interpolation from the pixel's ray rather than the rasteriser's plane
// equations; exact screen derivatives rather than a quad's differences):
// tests/native/test_visibility.cpp holds the two paths against each other.
// Stochastic transparency needs the material's alpha where the fragment is
// discarded: a partly transparent constant material's and every node
// material that drives alpha are drawn into the visibility buffer by their
// own programs (geometry_frag.glsl VISIBILITY_PASS: the alpha test, then the
// ids), the others by one program for all.
#pragma once

#include "gbuffer.h"
#include "frame_scene.h"
#include "shader_library.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace deferred {

class MaterialModule;

class VisibilityBuffer {
public:
    // Bytes per pixel it adds to a frame at most (the ids target, and the
    // tile list: at most one (tile, key) pair per pixel).
    static constexpr std::size_t kBytesPerPixel = 16 + 4;

    // Why a frame cannot take this path ("" if it can).
    static std::string unsupported(int width, int height);

    // A node material drawn with its graph: its id and graph, and whether
    // the graph drives alpha (its own raster program).
    struct GraphMaterial {
        std::uint32_t id, graph;
        bool alpha;
    };
    // The raster programs (the shared one; SCENE_ALPHA's for the constant
    // materials `partly_transparent` marks, per material id), the
    // classification's, the constant-material resolve and each node
    // material's (`graphs`; the materials not listed resolve as constant
    // ones). A node material whose programs do not compile takes the
    // default surface, warned (as the raster path's); throws Error if one of
    // the frame's own programs does not compile.
    void prepare(ShaderLibrary& shaders, MaterialModule& materials, const ShaderVariant& base,
                 const std::vector<GraphMaterial>& graphs, const std::vector<bool>& partly_transparent,
                 std::vector<std::string>& warnings);
    // Distinct node-material resolve programs (FrameTimings::material_programs).
    std::size_t distinct_graph_programs() const;
    // Stochastic coverage (false) or the Alpha Threshold's (true, the data
    // G-buffer), as GeometryStage::set_alpha_mode.
    void set_alpha_mode(bool data, float threshold) const;
    // The targets for a frame (reallocated only when the size or the slot
    // table grows); `depth` is the G-buffer's depth texture.
    void ensure(int width, int height, std::size_t slot_count, GLuint depth);
    std::size_t bytes() const { return bytes_; }

    // Draws the kept instances' surfaces (the last cull of `scene`; slots
    // whose material is in `skip` are left out: the forward pass draws
    // them) into the visibility buffer, over the G-buffer's depth, then
    // classifies and resolves them into `gbuffer`, already cleared.
    // `resolve_only` (not null): only the materials it marks are resolved,
    // the others keep the cleared G-buffer under their depth (an emission
    // sample's pass needs only the emitters' emission, emission_samples.h).
    void draw(const FrameScene& scene, const MaterialModule& materials, const GBuffer& gbuffer,
              const std::vector<bool>& skip, const std::vector<bool>* resolve_only = nullptr) const;

private:
    GLuint resolve_for(std::uint32_t material) const;
    GLuint raster_for(std::uint32_t material) const;  // 0: the shared raster program

    bool transparent(std::uint32_t material) const {
        return alpha_raster_ != 0 && material < partly_transparent_.size() && partly_transparent_[material];
    }

    GLuint raster_ = 0, count_ = 0, scan_ = 0, scatter_ = 0, resolve_ = 0;
    // The partly transparent constant materials' raster program (SCENE_ALPHA,
    // by corner: the alpha test needs each corner's triangle), 0 without
    // them; alpha_test_ the program with the alpha test (its mode uniform).
    GLuint alpha_raster_ = 0, alpha_test_ = 0;
    std::vector<bool> partly_transparent_;
    // How the shared raster program draws: by vertex (with
    // DEFERRED_ALPHA_APART=off and a partly transparent constant material,
    // by corner: it is then SCENE_ALPHA's). Both sides: leaving out closed meshes' back faces changed
    // 159 of the showcase's 172 800 colour values at 320x180 (up to 0.097):
    // a sliver facing the camera by a sphere's silhouette turns over when
    // the rasteriser snaps its corners, and culled it lets the floor show
    // where the resolve's exact ray meets the sphere; it saved 11 % of the
    // instancing capture's geometry pass.
    DrawStyle one_program_style_;
    std::vector<std::pair<std::uint32_t, GLuint>> graph_resolves_, graph_rasters_;  // material id -> program
    std::vector<std::uint32_t> graph_of_;                                            // material id -> graph, or ~0u
    int width_ = 0, height_ = 0;
    std::size_t slot_capacity_ = 0, bytes_ = 0;
    Texture ids_;
    Framebuffer fbo_;
    int tiles_x_ = 0, tiles_y_ = 0;
    std::size_t tile_capacity_ = 0;
    Buffer keys_, tiles_;
};

}  // namespace deferred
