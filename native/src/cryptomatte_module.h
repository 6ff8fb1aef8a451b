// Cryptomatte (Object, Material, Asset layers) as Cycles writes it: per
// pixel, the ids of what the film samples saw with their coverage, most
// coverage first, `levels` of them (the view layer's Levels). The ids are
// the caller's MurmurHash3_32 of the names (the add-on hashes them as
// Blender does, export/cryptomatte.py); they reach the image as floats by
// Cycles' conversion (cryptomatte_hash_to_float), and the manifest is the
// add-on's too.
//
// Per sample the geometry pass writes each pixel's instance and material id
// into the ids target (GBUF_INSTANCE_IDS makes it RGBA32UI), and
// shaders/cryptomatte_comp.glsl adds the sample's coverage to the pixel's
// slots; the slots are read back once, sorted on the CPU. Nothing exists
// when no layer is asked for.
#pragma once

#include "gl_util.h"

#include <deferred/renderer.h>

#include <cstdint>
#include <vector>

namespace deferred {

class ShaderLibrary;

// Cycles' util_hash_to_float: the hash's bits as a float, the exponent
// clamped to 1..254 so that the value is a normal number.
float cryptomatte_hash_to_float(std::uint32_t hash);

class CryptomatteModule {
public:
    static constexpr int kMaxLevels = 16;

    // Bytes of the per-pixel slots for these settings (0 when none asked).
    static std::size_t bytes(const RenderSettings& settings);
    // Prepares a frame: the slots cleared, the hash buffers uploaded
    // (two per instance in GpuInstance order: object, asset; one per material).
    void begin(const RenderSettings& settings, const std::vector<std::uint32_t>& instance_hashes,
               const std::vector<std::uint32_t>& material_hashes);
    bool active() const { return !kinds_.empty(); }
    // One film sample's coverage from the bound G-buffer (depth, ids).
    void accumulate(ShaderLibrary& shaders, int samples, unsigned groups_x, unsigned groups_y);
    // The layers, ranked per pixel; releases the frame's buffers.
    std::vector<CryptomatteImage> finish();
    void release();

private:
    std::vector<CryptomatteKind> kinds_;
    int levels_ = 0, width_ = 0, height_ = 0;
    Buffer slots_, instances_, materials_;
};

}  // namespace deferred
