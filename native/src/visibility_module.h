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
//   classify   the covered pixels grouped by slot key (a mesh batch's
//              material slot: one mesh, one material): counts, an exclusive
//              scan with each key's indirect dispatch, a scatter
//              (visibility_classify_comp.glsl)
//   resolve    per key, one indirect dispatch with the mesh's buffers and the
//              material's program: geometry_frag.glsl's own surface code in
//              compute (gbuffer_resolve_comp.glsl), into the G-buffer's images
//
// The G-buffer it writes is the raster path's up to floating-point rounding
// (interpolation from the pixel's ray rather than the rasteriser's plane
// equations; exact screen derivatives rather than a quad's differences):
// tests/native/test_visibility.cpp holds the two paths against each other.
// Stochastic transparency (a partly transparent constant material, a node
// material that drives alpha) needs the material in the raster, where the
// fragment is discarded: such frames take the raster path, said in a
// warning when the setting asked for this one.
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
    // Bytes per pixel it adds to a frame (the ids target and the pixel list).
    static constexpr std::size_t kBytesPerPixel = 16 + 4;

    // Why a frame cannot take this path ("" if it can).
    static std::string unsupported(bool stochastic_alpha, int width, int height);

    // The raster, classification and constant-material resolve programs, and
    // each node material's resolve program (`graphs`: material id -> graph,
    // for the materials drawn with their graph; the others resolve as
    // constant materials). Throws Error if one does not compile.
    void prepare(ShaderLibrary& shaders, MaterialModule& materials, const ShaderVariant& base,
                 const std::vector<std::pair<std::uint32_t, std::uint32_t>>& graphs);
    // The targets for a frame (reallocated only when the size or the slot
    // table grows); `depth` is the G-buffer's depth texture.
    void ensure(int width, int height, std::size_t slot_count, GLuint depth);
    std::size_t bytes() const { return bytes_; }

    // Draws the kept instances' surfaces (the last cull of `scene`; slots
    // whose material is in `skip` are left out: the forward pass draws
    // them) into the visibility buffer, over the G-buffer's depth, then
    // classifies and resolves them into `gbuffer`, already cleared.
    void draw(const FrameScene& scene, const MaterialModule& materials, const GBuffer& gbuffer,
              const std::vector<bool>& skip) const;

private:
    GLuint program_for(std::uint32_t material) const;

    GLuint raster_ = 0, count_ = 0, scan_ = 0, scatter_ = 0, resolve_ = 0;
    std::vector<std::pair<std::uint32_t, GLuint>> graph_resolves_;  // material id -> program
    std::vector<std::uint32_t> graph_of_;                            // material id -> graph, or ~0u
    int width_ = 0, height_ = 0;
    std::size_t slot_capacity_ = 0, bytes_ = 0;
    Texture ids_;
    Framebuffer fbo_;
    Buffer keys_, pixels_;
};

}  // namespace deferred
