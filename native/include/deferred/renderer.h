// Public entry point of the native deferred renderer.
//
// A Renderer owns a headless EGL context on a render thread of its own; every
// method forwards its work to that thread and waits for it, so callers never
// need (and never disturb) a current GL context. The scene is synced EEVEE
// style: clear_scene(), then add_mesh()/add_material()/add_instances()/
// add_light()/set_world(), then render() any number of times.
#pragma once

#include <deferred/passes.h>
#include <deferred/scene.h>

#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace deferred {

// Every failure of the library is one of these, with a message that names the
// step that failed and, where there is one, the EGL/GL error by name.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};
// Bad input from the caller (shape, range, NaN): maps to Python's ValueError.
class InvalidInput : public Error {
public:
    using Error::Error;
};
// render() stopped because cancel() was called.
class Cancelled : public Error {
public:
    using Error::Error;
};

struct ContextOptions {
    // EGL device index for the EGL device platform; -1 picks automatically
    // (first hardware device, else Mesa surfaceless, else the default
    // display). The environment variable DEFERRED_EGL_DEVICE overrides -1.
    int device_index = -1;
};

struct GLInfo {
    std::string vendor, renderer, version;
    std::string display;      // which step of the cascade gave the display, and which GPU
    std::string device_note;  // a fallback taken choosing the device (CUDA_VISIBLE_DEVICES), or ""
    std::string allocator_note;  // a setting of the process's allocator that slows the CPU rasteriser, or ""
};

// What a Cryptomatte layer names: the object (its name), the material
// (the slot's material name) or the asset (the top-most parent's name).
// The hashes are the caller's (MurmurHash3_32 of the name, as Cycles).
enum class CryptomatteKind : std::uint32_t { Object = 0, Material = 1, Asset = 2 };
const char* cryptomatte_name(CryptomatteKind kind);  // "CryptoObject", ...

// A view layer AOV to fill (aov_module.h): its name, which AOV Output nodes
// of node materials name (MaterialGraph::aovs), and its type.
struct AovRequest {
    std::string name;
    bool color = true;  // Color (RGBA) or Value (one channel)
};

struct RenderSettings {
    int width = 640;
    int height = 480;
    PassSet passes;
    bool film_transparent = false;
    Mist mist;
    // Film samples averaged per pixel. Each is jittered by Blender's pixel
    // filter (Blackman-Harris of filter_width px, as Cycles) and uses new
    // points on the light shapes, so edges and soft light converge as the
    // samples grow. Depth, Position and the indices come from sample 0, the
    // unjittered pixel centre.
    int samples = 1;
    float filter_width = 1.5f;
    // Filter splatting (film.h PixelFilter::splat_taps): with more than one
    // sample, each pixel adds its neighbours' samples weighted by the filter
    // for the sample's jitter (weights summing to 1), which converges to the
    // same filtered pixel with less variance where the filter's tail meets
    // a small bright feature. Off: each pixel its own sample only, as
    // Cycles. Filters 0.5 px wide or narrower, or over 4 px, are never
    // splatted; where the splat's scratch images alone would exceed the
    // memory budget, the frame is rendered without, warned.
    bool filter_splat = true;
    // The visibility buffer (visibility_module.h): the raster pipeline
    // decides only which triangle each pixel sees, and the G-buffer is
    // written in compute (the materials evaluated there), which data-centre
    // GPUs run far faster than fragment shading (materials that drive
    // alpha are still tested in the raster, by their own programs). The
    // image is the raster path's up to rounding and to where a rasteriser
    // snaps vertices (tests/native/test_visibility.cpp). On by default: on
    // an H200 a textured node material's geometry pass took 1.28x a
    // constant one's this way against 3.78x in the raster, and on llvmpipe
    // the G-buffer costs the same or less (bench/gpu/results/). Where its
    // targets (20 bytes a pixel) would take the frame over the memory budget
    // or the image is too large for it, the raster path draws the frame,
    // warned.
    bool visibility_buffer = true;
    // Partly transparent planes and convex solids as exact layers
    // (layer_order.h): the partly transparent materials whose every surface
    // in view is planar or convex and ordered by the plane test are drawn by
    // the forward pass, each layer composited with its alpha at every
    // sample (Cycles' transmittance, exactly) instead of kept in a share
    // alpha of the samples: the same image converged, without the
    // coverage's noise. Taken in frames whose passes are Combined and the
    // data passes (Depth, Position, Normal, UV, IndexOB, IndexMA: the data
    // G-buffer keeps the layers at the Alpha Threshold, as before); not
    // with light, colour or Mist passes, Cryptomatte, shader AOVs, light
    // groups (the forward layer reaches none of them), motion blur (the
    // order is the frame's), Blend-mode materials (the forward pass orders
    // those by object), shadow catchers, or emission samples
    // (FrameTimings::exact_layers says what a frame took). Their shadows
    // stay stochastic. Off: every partly transparent surface stochastic.
    bool exact_transparent_planes = true;
    // Benchmarks: count the fragments the shadow maps' draws shade
    // (FrameTimings::shadow_fragments) with a pipeline-statistics query
    // around each map layer's draws. Off for renders: a driver may wait for
    // its pipeline to drain at each end of such a query, tens of times a
    // sample.
    bool count_shadow_fragments = false;
    // Light culling (tiled, 2.5D depth masks). Blender's lights reach to
    // infinity; a light is cut off where even a white Lambertian surface
    // facing it would reflect less than `light_threshold` (scene-linear
    // radiance, the units of the Combined pass; the add-on divides it by
    // 2^exposure so it is relative to what the view shows). Off: every pixel
    // evaluates every light (the reference the culling is tested against).
    // Scenes with fewer than 8 lights are never culled (it would cost more).
    bool light_culling = true;
    float light_threshold = 1e-3f;
    // Stochastic light selection: 0 shades every light that reaches a pixel
    // each sample (exact per sample). N > 0: where more than N lights reach
    // a pixel (suns and emissive meshes apart, always shaded), each is shaded
    // with a probability from its rough share of the light there and weighted
    // by its inverse (at most N per pixel, sample and lighting dispatch of
    // 512 lights, 8 with shadow rays: N at or above that selects nothing,
    // warned), so the image converges over the film's samples to the same sum
    // (lighting_comp.glsl LIGHT_SAMPLING).
    int light_samples = 0;
    // Emission samples: camera samples of directly seen emission per film
    // sample (0..64). K > 1 adds K - 1 G-buffer passes per film sample, at
    // jitters of their own, whose surfaces' emission goes to Combined and
    // the Emit pass (emission_samples.h): a small bright emitter in view
    // (fairy lights, a bulb) converges as with K times the samples, the
    // lighting with the film's. Taken only by frames with more than one
    // sample and an emissive mesh in view, without Blend-mode materials or
    // light groups (FrameTimings::emission_samples says what a frame took).
    // 0: automatic, kAutoEmissionSamples where an emissive mesh in view is
    // brighter than kAutoEmissionRadiance, else none.
    int emission_samples = 1;
    // Shadow maps for lights whose cast_shadow is on (one set per sample,
    // from that sample's point on the light: soft shadows converge with
    // samples; lights without size are rendered once). Each light's
    // resolution follows its projected footprint: shadow_quality texels per
    // pixel of the visible surfaces it reaches (90th percentile), at most
    // shadow_resolution per cube face / cascade side (clamped to 32..8192,
    // lowered to fit the memory budget).
    bool shadows = true;
    int shadow_resolution = 1024;
    float shadow_quality = 1.0f;
    // Shadow rays instead of maps: each sample's visibility of the same light
    // points and world directions traced against the scene's triangles
    // (ray_scene.h), so shadows converge to Cycles' without a map's
    // resolution. A scene with a node material that drives alpha falls back
    // to maps, warned (a ray cannot evaluate the graph).
    bool shadow_rays = false;
    // The view layer's Alpha Threshold: Depth, Position, Normal, UV and the
    // indices come from the first surface whose alpha reaches it (Cycles'
    // film_write_data_passes; 0: the first surface whatever its alpha).
    float alpha_threshold = 0.5f;
    // Cryptomatte (cryptomatte_module.h): the kinds asked for (none: no
    // cryptomatte work at all) and the view layer's Levels, the ids kept
    // per pixel (Cycles' pass_cryptomatte_depth, 1..16).
    std::vector<CryptomatteKind> cryptomatte;
    int cryptomatte_levels = 6;
    // Shader AOVs to fill (none: no AOV work at all).
    std::vector<AovRequest> aovs;
    // Light groups: how many (Light/World::light_group and the instances'
    // index them from 1); each gets a Combined-like RGB image of the light
    // its members give (lights, emissive surfaces, the world). 0: none.
    int light_groups = 0;
    // Motion blur (Render Properties > Motion Blur): each film sample renders
    // the scene at one time of the shutter, the instances, the camera and
    // deforming meshes moved between the motion the caller gives (previous,
    // now, next: the shutter's open, middle and close), so the accumulated
    // image converges to Cycles' motion blur. The Vector pass is then 0, as
    // Cycles leaves it. Shadow rays place the moving instances each sample
    // (the instances' hierarchy rebuilt) and fall back to maps when a mesh
    // deforms (warned); emissive meshes light others from where they are at
    // the middle of the shutter.
    bool motion_blur = false;
    // Progressive preview (the 3D viewport): >= 0 publishes the Combined
    // estimate after the first sample, then at most every this many
    // milliseconds, and after the last sample, for Renderer::preview().
    // -1: off (no read-back inside the sample loop).
    int preview_interval_ms = -1;
    // The pass the preview shows (one of `passes`, or Combined): the
    // viewport's Render Pass. Not DiffDir, GlossDir or Shadow (resolved
    // only after the last sample).
    Pass preview_pass = Pass::Combined;
};

// The newest estimate of a render in progress (preview_interval_ms) of its
// preview_pass: RGBA, rows bottom-up, the average of the `samples_done`
// samples so far (a pass taken from the first sample as it is; one-channel
// passes grey, alpha 1 but for Combined).
// `version` grows with every image and every new render.
struct PreviewImage {
    std::uint64_t version = 0;
    int samples_done = 0, samples_total = 0;
    int width = 0, height = 0;
    std::vector<float> pixels;  // empty until the render's first sample
};

// One shader AOV of a finished frame: RGBA (colour) or one channel per
// pixel, rows bottom-up.
struct AovImage {
    std::string name;
    bool color = true;
    int width = 0, height = 0;
    std::vector<float> pixels;
};

// One Cryptomatte layer of a finished frame: per pixel `levels` pairs
// (id as Cycles' float, coverage), most coverage first; rows bottom-up.
struct CryptomatteImage {
    CryptomatteKind kind;
    int width = 0, height = 0, levels = 0;
    std::vector<float> pixels;  // width * height * levels * 2
};

// One pass of a finished frame: rows bottom-up (row 0 is the bottom of the
// image, as Blender's RenderResult expects), channels interleaved.
struct PassImage {
    Pass pass;
    int width = 0, height = 0, channels = 0;
    std::vector<float> pixels;
};

// Wall-clock split of the last render, in milliseconds (GPU work is fenced
// per stage, so the numbers are what each stage really cost).
struct FrameTimings {
    double upload_ms = 0, shadow_ms = 0, geometry_ms = 0, culling_ms = 0, lighting_ms = 0, passes_ms = 0,
           readback_ms = 0;
    double forward_ms = 0;  // the forward pass (Blend-mode materials), all samples
    // Draws of the Blend-mode surfaces per sample, one per batch of lights
    // (as the lighting's dispatches); 0 without a forward pass.
    std::uint32_t forward_batches = 0;
    // Partly transparent planar or convex surfaces in view drawn as exact
    // layers (RenderSettings::exact_transparent_planes), instances; 0: none.
    std::uint32_t exact_layers = 0;
    // geometry_ms holds the emission samples' passes too (emission_samples.h),
    // and camera_instances_drawn their instances.
    double total_ms = 0;
    std::uint64_t tile_light_pairs = 0;  // entries in the culled per-tile light lists
    // Pixels the lighting's batches after the first ran over (their light
    // lists go past one batch: 512 lights, 8 with shadow rays), summed over
    // the samples; 0 where one batch holds every light.
    std::uint64_t lighting_later_pixels = 0;
    std::size_t shadow_map_bytes = 0;    // shadow map array + its depth buffer
    std::size_t shadowed_lights = 0;     // lights with shadow maps this frame
    std::vector<int> shadow_resolutions;  // texels per side of each shadowed light's maps
    std::size_t shadow_layers_rendered = 0;  // cube faces + cascades drawn over all samples
    // Texels of those layers inside their scissor (faces a spot or an area
    // light does not shine through, and their parts, are left out).
    std::uint64_t shadow_texels_rendered = 0;
    // Fragments those draws shaded (the fill; RenderSettings::
    // count_shadow_fragments only, and 0 without pipeline statistics).
    std::uint64_t shadow_fragments = 0;
    std::uint64_t shadow_instances_drawn = 0;  // instances drawn into them (after culling per map)
    // Of those, drawn without their back faces: closed meshes seen from
    // outside (draw_style.h; DEFERRED_FACE_CULLING=off: none).
    std::uint64_t shadow_instances_one_sided = 0;
    std::uint64_t camera_instances_drawn = 0;  // instances in the view frustum, over all samples
    int emission_samples = 1;  // the frame's emission samples per film sample (settings.emission_samples or 1)
    std::size_t shadow_lights_dropped = 0;  // would cast shadows, over the layer/memory limits
    bool shadow_rays = false;              // visibility came from shadow rays (settings.shadow_rays)
    bool visibility_buffer = false;        // the G-buffer came from the visibility buffer (settings.visibility_buffer)
    double ray_build_ms = 0;               // building the ray hierarchies (meshes new to them, instances)
    std::size_t ray_scene_bytes = 0;       // the ray scene's buffer
    std::size_t ray_triangles = 0;         // triangles the rays are traced against (over instances)
    std::size_t gbuffer_bytes = 0;  // G-buffer + pass targets allocated for the frame
    std::size_t programs_compiled = 0;  // GL programs compiled by this render (0: all cached)
    double compile_ms = 0;              // time spent compiling them
    std::size_t programs_loaded = 0;    // GL programs loaded from the disk cache instead
    double load_ms = 0;
    std::size_t material_programs = 0;  // distinct node-material programs the frame drew with
    std::size_t images_uploaded = 0;    // images uploaded for this scene (since clear_scene)
    std::size_t images_reused = 0;      // images kept from the previous scene and found by key
    std::size_t meshes_uploaded = 0;    // meshes uploaded for this scene (since clear_scene)
    std::size_t meshes_reused = 0;      // meshes kept from the previous scene and found by key
    double world_bake_ms = 0;           // baking the world's node tree and its sampling CDF
    int world_map_width = 0;            // the baked world map's width (0: a constant world)
    std::size_t emitter_triangles = 0;  // emissive mesh triangles lighting the scene
    double emission_bake_ms = 0;        // baking the emission of textured emitters (emitter_module.h)
    std::size_t emission_baked_triangles = 0;  // ... the triangles baked
};

struct FrameResult {
    std::vector<PassImage> passes;
    std::vector<CryptomatteImage> cryptomatte;
    std::vector<AovImage> aovs;
    std::vector<std::vector<float>> light_groups;  // RGBA per pixel, rows bottom-up, one per group
    FrameTimings timings;
    // What the frame could not render as asked, e.g. a node material whose
    // program failed to compile (drawn with the default surface instead).
    std::vector<std::string> warnings;
    const PassImage* find(Pass p) const;
};

class Renderer {
public:
    explicit Renderer(const ContextOptions& options = {});
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    const GLInfo& gl_info() const;
    // Renderers alive in this process (each holds a GL context and a
    // thread): what tests check to see that closed viewports, reloaded
    // files and a disabled add-on released theirs.
    static int live_count();

    // Drops the scene (meshes, materials, lights, world) and keeps what the
    // next one can reuse: the GL context, compiled programs, frame targets
    // and keyed images (see add_image).
    void clear_scene();
    // Drops the scene, the kept meshes and images, and every frame target
    // and shadow map; keeps the GL context and the compiled programs. What
    // a render without Persistent Data leaves for the next one (as Blender
    // keeps EEVEE's shaders): the next render starts no context and links
    // no program, and nothing of this scene's stays in memory meanwhile.
    // Past DEFERRED_MAX_KEPT_PROGRAMS programs (default 256) it drops them
    // too, so edited node materials do not pile up over a long session.
    void release_scene_memory();
    // Returns the mesh id. The data is validated and uploaded before returning.
    // With a key (the caller's name for the mesh's content), the mesh
    // outlives clear_scene() while each scene uses it, and find_mesh(key)
    // gives its id back without an upload (-1: not kept), as for images.
    std::uint32_t add_mesh(const MeshData& mesh, const std::string& key = {});
    std::int64_t find_mesh(const std::string& key);
    std::uint32_t add_material(const Material& material);
    // `count` instances of `mesh_id`: world matrices (column-major, 16 doubles
    // each), object pass indices (may be null: 0), and a material slot map
    // (slot -> material id; empty: slot i -> material i). `cast_shadow`
    // false: the instances are seen but block no light and no world light
    // (Blender's Object > Visibility > Ray Visibility > Shadow).
    // Node materials read per instance `colors` (RGBA, Object Info Color and
    // Alpha; null: white) and `randoms` (Object Info Random; null: 0).
    // `terminator_offsets`: per instance, Cycles' Shadow Terminator Geometry
    // Offset in 0..1 (null: 0, shadow rays leave from the triangle itself).
    // `motion`: per instance its world matrices at the previous and the next
    // frame (2 x 16 doubles, column-major; null: it does not move), for the
    // Vector pass and motion blur. `shadow_catcher`: Object > Visibility >
    // Shadow Catcher (Pass::ShadowCatcher says what it does to the image).
    void add_instances(std::uint32_t mesh_id, const double* matrices, std::size_t count,
                       const std::uint32_t* object_indices,
                       const std::vector<std::uint32_t>& material_slots, bool cast_shadow = true,
                       const float* colors = nullptr, const float* randoms = nullptr,
                       const std::uint32_t* crypto = nullptr, bool holdout = false,
                       std::uint32_t light_group = 0, const float* terminator_offsets = nullptr,
                       const double* motion = nullptr, bool shadow_catcher = false);
    // Node materials: an image texture nodes sample (returns its id), and a
    // material evaluated from a graph (material_graph.h). `base` gives what
    // the graph does not: the pass index. Returns the material id.
    // An image for node materials. With a key (the caller's name for its
    // content), it outlives clear_scene() while each scene uses it, and
    // find_image(key) gives its id back without an upload (-1: not kept).
    std::uint32_t add_image(const ImageData& image, const std::string& key = {});
    std::int64_t find_image(const std::string& key);
    // `base`: pass_index, and in `emission` the constant radiance the graph
    // emits (what makes its meshes lights; 0 where the graph varies it).
    std::uint32_t add_graph_material(const Material& base, const MaterialGraph& graph);
    void add_light(const Light& light);
    // `graph` (optional): the world's node tree, whose surface closure's
    // emission is the radiance along each direction (Background nodes); it
    // is baked into an environment map the lighting importance-samples, and
    // `world.color` is then unused. Without it the world is `world.color`.
    void set_world(const World& world, const MaterialGraph* graph = nullptr);

    FrameResult render(const Camera& camera, const RenderSettings& settings);
    // Thread-safe, callable while render() runs on another thread: the
    // render stops before its next sample, shadow maps, lighting or light
    // batch and throws Cancelled. A render that starts clears the request
    // (a cancel meant for the last one), so a caller stopping a render it
    // has just started repeats cancel() until the render has returned.
    void cancel();
    // Thread-safe, never waits for a render: copies the newest preview image
    // into `out` when its version is newer than `since` (false otherwise).
    bool preview(std::uint64_t since, PreviewImage& out) const;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace deferred
