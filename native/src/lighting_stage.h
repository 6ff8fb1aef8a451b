// The lighting stage: one compute pass per film sample
// (shaders/lighting_comp.glsl) that shades the G-buffer with the scene's
// lights, in dispatches of a batch of lights each, and adds the sample's
// share to the film (Combined, and the light split, Shadow, AO, catcher and
// light-group accumulations the frame asks for). Its variant says what the
// scene holds: light types, culled tile lists, shadows (maps or rays), the
// world's occlusion, stochastic light selection, a forward layer.
#pragma once

#include "gl_util.h"
#include "shader_library.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace deferred {

class FilmModule;
class LightCulling;
class LightModule;
class WorldModule;

// Points per light shape (a 4x4 grid) per sample for the Monte Carlo parts
// of disk and area lights (shaders/light_lib.glsl).
constexpr std::uint32_t kLightShapePoints = 16;
// Lights per lighting dispatch. A light runs at most ~40 loop iterations
// (quadrature + light points); llvmpipe ends all loops of an invocation after
// 65535 iterations in total, so 512 lights per dispatch stay well inside.
constexpr std::uint32_t kLightBatch = 512;
// ... with shadow rays, whose traversal loops count too (a ray visits tens
// of nodes, at most RAY_MAX_STEPS; a mesh light traces up to 10 per pixel).
constexpr std::uint32_t kRayLightBatch = 8;
// ... with mesh lights of more than MESH_LIGHT_CHUNK triangles: each can take
// MESH_LIGHT_CHUNK + MESH_LIGHT_TRACED_TRIANGLES iterations (chunk tests and
// the triangles of the chunks a ray meets) besides its points: 12 stay
// inside 65535, 4 with shadow rays (whose traversals count too).
constexpr std::uint32_t kChunkedMeshLightBatch = 12;
constexpr std::uint32_t kChunkedMeshLightRayBatch = 4;

class LightingStage {
public:
    struct Config {
        bool light_split = false;  // DiffDir / GlossDir
        bool culled = false;       // tile light lists (light_culling.h)
        int light_samples = 0;     // the budget of stochastic light selection, 0: every light
        bool shadow_maps = false;  // some light or the world casts shadows
        bool shadow_rays = false;  // ... answered by rays (ray_scene.h)
        bool world_occlusion = false;
        bool ao = false;
        int light_groups = 0;
        bool shadow_pass = false;
        bool catchers = false;
        bool forward_layer = false;
        // One light loop per light kind, each holding only its kind's code
        // (lighting_comp.glsl LIGHT_KIND_LOOPS): for drivers that run every
        // branch of a loop body (llvmpipe), where it took the showcase's
        // lighting from 760 to 450 ms at 320x180; an H200 ran many point
        // lights 30-57 % slower with it (a culled list mixes kinds, so a
        // warp's lanes sit in different loops), so GPUs keep the one loop.
        bool kind_loops = false;
        // Some mesh light has more than MESH_LIGHT_CHUNK triangles: a sharp
        // lobe's rays walk its chunks (light_lib.glsl), up to ~4 200 loop
        // iterations a light, so a dispatch takes fewer lights
        // (kChunkedMeshLightBatch).
        bool chunked_mesh_lights = false;
    };
    // Compiles the program for `config` over the G-buffer's `base` variant.
    // A light budget no dispatch can use is warned (every light is shaded).
    void prepare(ShaderLibrary& shaders, const ShaderVariant& base, const LightModule& lights,
                 const WorldModule& world, const Config& config, std::vector<std::string>& warnings);
    // Starts compiling prepare()'s program for `config` on the driver's
    // threads (ShaderLibrary::prefetch_compute), so that it overlaps the
    // frame's other compiles (the lighting program is the largest: 11.7 s
    // with shadow rays on an H200). Never throws.
    static void prefetch(ShaderLibrary& shaders, const ShaderVariant& base, const LightModule& lights,
                         const WorldModule& world, const Config& config);
    // Shades one sample: every batch of lights into the film (bound here).
    // `instance_groups`: each instance's light group (0: no light groups),
    // `world_group` the world's; `between_batches` runs before each batch
    // after the first (a cancel).
    // Batches after the first run over the pixels the first one listed
    // (an indirect dispatch), not the whole image, where the list fits a
    // storage block.
    void run(const LightModule& lights, const LightCulling* culling, const FilmModule& film, GLuint instance_groups,
             std::uint32_t world_group, int width, int height, const std::function<void()>& between_batches);
    bool light_sampling() const { return light_sampling_; }
    // Lights per dispatch for `config` (kLightBatch and the smaller ones):
    // as many as one invocation's loops can take on llvmpipe. The forward
    // pass draws its lights in batches of this size too.
    static std::uint32_t batch_size(const Config& config);
    // Pixels the batches after the first ran over, summed over this
    // frame's samples (reads the GPU's count: after the frame).
    std::uint64_t later_pixels() const;

private:
    // The program's variant; `light_sampling`: whether stochastic light
    // selection is on (a budget below the dispatch's batch and the lights).
    static ShaderVariant variant(const ShaderVariant& base, const LightModule& lights, const WorldModule& world,
                                 const Config& config, bool& light_sampling);
    GLuint program_ = 0;
    std::uint32_t batch_ = kLightBatch;
    bool light_sampling_ = false;
    static constexpr std::size_t kLaterHeader = 32;  // dispatch arguments, count; totals
    Buffer later_;  // SSBO_LIGHTING_LATER: header and pixels
    std::size_t later_pixels_ = 0;
};

}  // namespace deferred
