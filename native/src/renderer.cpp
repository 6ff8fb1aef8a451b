// Renderer: owns every module (EEVEE Next's Instance pattern) and runs the
// frame as a short sequence of stages, each a module that owns its GL
// resources and programs:
//
//   sync      FrameScene (instances, materials), RayScene, WorldModule's
//             bake, EmitterModule, LightModule, FilmModule's accumulations
//   programs  GeometryStage, ForwardModule, LightingStage, PassStage
//   per film sample:
//     geometry   GeometryStage -> GBuffer (+ AOVs, Vector's motion), or
//                VisibilityBuffer: ids raster, then the G-buffer in compute
//     shadows    ShadowModule's maps (or rays: nothing to draw)
//     culling    LightCulling's tile lists (sample 0)
//     forward    ForwardModule's Blend-mode layer
//     lighting   LightingStage -> FilmModule
//     passes     PassStage, CryptomatteModule -> FilmModule
//   resolve   PassStage's resolves
//   readback  FilmModule (one pixel pack buffer), Cryptomatte, AOVs
//
// All GL work happens on the render thread.
#include <deferred/renderer.h>

#include "aov_module.h"
#include "camera.h"
#include "cpu_rasteriser.h"
#include "cryptomatte_module.h"
#include "egl_context.h"
#include "emission_samples.h"
#include "emitter_module.h"
#include "film.h"
#include "film_module.h"
#include "forward_module.h"
#include "layer_order.h"
#include "frame_scene.h"
#include "gbuffer.h"
#include "geometry_stage.h"
#include "gl_util.h"
#include "light_culling.h"
#include "light_module.h"
#include "lighting_stage.h"
#include "material_module.h"
#include "motion_module.h"
#include "pass_stage.h"
#include "progressive_preview.h"
#include "render_thread.h"
#include "scene_store.h"
#include "shader_library.h"
#include "ray_scene.h"
#include "shadow_module.h"
#include "visibility_module.h"
#include "world_module.h"

#include "../../shaders/shader_defines.h"
#include "../../shaders/shader_shared.h"

#include <array>
#include <atomic>
#include <cstring>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <optional>

namespace deferred {

namespace {

// Light groups per render (layers of the accumulation, LIGHT_GROUPS sums in
// the lighting pass's registers).
constexpr int kMaxLightGroups = 32;
// Below this many lights, building tile lists costs more than it saves
// (deferred_bench_lights: 1 light 117 ms culled vs 38 ms brute force,
// 16 lights 90 vs 225 ms, at 480x270 on llvmpipe).
constexpr std::uint32_t kCullingMinLights = 8;
// Occlusion directions (maps) per film sample for a world map (world_module.h).
constexpr int kWorldMapOcclusionDirections = 4;

std::string gl_string(GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? reinterpret_cast<const char*>(s) : "";
}

// Memory a frame may allocate for its targets, checked before allocating:
// DEFERRED_MEMORY_BUDGET_MB, default 8192 MiB.
std::size_t memory_budget_bytes() {
    std::size_t mb = 8192;
    if (const char* env = std::getenv("DEFERRED_MEMORY_BUDGET_MB")) {
        char* end = nullptr;
        unsigned long v = std::strtoul(env, &end, 10);
        if (end && *end == '\0' && v > 0) mb = v;
    }
    return mb << 20;
}

// Programs a renderer keeps through release_scene_memory(): past this the
// library starts afresh, so a long session of edited node materials does
// not keep every program it ever linked. DEFERRED_MAX_KEPT_PROGRAMS,
// default 256 (a sample scene links 10-20).
std::size_t max_kept_programs() {
    std::size_t n = 256;
    if (const char* env = std::getenv("DEFERRED_MAX_KEPT_PROGRAMS")) {
        char* end = nullptr;
        unsigned long v = std::strtoul(env, &end, 10);
        if (end && *end == '\0' && end != env) n = v;
    }
    return n;
}

// The settings a frame refuses before it allocates anything.
void validate_settings(const RenderSettings& settings) {
    if (settings.samples < 1 || settings.samples > 65536)
        throw InvalidInput("samples must be in 1..65536, got " + std::to_string(settings.samples));
    if (!(settings.filter_width > 0.0f && settings.filter_width <= 100.0f))
        throw InvalidInput("filter_width must be in (0, 100] pixels");
    if (!(settings.light_threshold >= 0.0f) || !std::isfinite(settings.light_threshold))
        throw InvalidInput("light_threshold must be a finite number >= 0");
    if (settings.light_samples < 0 || settings.light_samples > 65536)
        throw InvalidInput("light_samples must be in 0..65536 (0: every light), got " +
                           std::to_string(settings.light_samples));
    if (settings.emission_samples < 0 || settings.emission_samples > 64)
        throw InvalidInput("emission_samples must be in 0..64 (0: automatic), got " +
                           std::to_string(settings.emission_samples));
    if (!(settings.alpha_threshold >= 0.0f && settings.alpha_threshold <= 1.0f))
        throw InvalidInput("alpha_threshold must be in [0, 1]");
    if (!(settings.shadow_quality > 0.0f && settings.shadow_quality <= 16.0f))
        throw InvalidInput("shadow_quality must be in (0, 16] texels per pixel");
    if (!std::isfinite(settings.mist.start) || !std::isfinite(settings.mist.depth))
        throw InvalidInput("mist start/depth must be finite");
    if (settings.light_groups < 0 || settings.light_groups > kMaxLightGroups)
        throw InvalidInput("light_groups must be in 0.." + std::to_string(kMaxLightGroups) + ", got " +
                           std::to_string(settings.light_groups));
    const Pass p = settings.preview_pass;
    if (p != Pass::Combined) {
        if (p == Pass::DiffDir || p == Pass::GlossDir || p == Pass::Shadow || p == Pass::Vector ||
            p == Pass::ShadowCatcher)
            throw InvalidInput(std::string("preview_pass: ") + pass_info(p).name +
                               " is resolved after the last sample and cannot be previewed");
        if (!settings.passes.contains(p))
            throw InvalidInput(std::string("preview_pass: ") + pass_info(p).name + " is not among the passes rendered");
    }
}

}  // namespace

const PassImage* FrameResult::find(Pass p) const {
    for (const PassImage& img : passes)
        if (img.pass == p) return &img;
    return nullptr;
}

struct Renderer::Impl {
    // Declaration order is destruction order reversed: GL objects must die
    // before the context, and everything before the thread.
    RenderThread thread;
    std::unique_ptr<EglContext> context;
    GLInfo info;
    std::optional<ShaderLibrary> shaders;
    SceneStore scene;
    MaterialModule materials;
    GBuffer gbuffer;
    VisibilityBuffer visibility;  // the G-buffer in compute (RenderSettings::visibility_buffer)
    LightModule lights;
    LightCulling culling;
    ShadowModule shadows;
    RayScene ray_scene;
    WorldModule world_module;
    EmitterModule emitters;
    ForwardModule forward;
    CryptomatteModule cryptomatte;
    AovModule aovs;
    MotionModule motion;
    ProgressivePreview preview;
    std::int32_t world_graph = -1;  // the world's node graph in `materials`, -1: a constant colour
    VertexArray empty_vao;
    Buffer dummy_ssbo;
    Buffer receiver_grid;  // receivers_comp.glsl's output, kept across frames
    std::size_t receiver_grid_bytes = 0;
    GLint max_texture_size = 0, max_fb_width = 0, max_fb_height = 0;
    std::atomic<bool> cancel_requested{false};

    void check_cancel() {
        if (cancel_requested.exchange(false)) {
            glFinish();  // leave the GL work of this frame done before unwinding
            throw Cancelled("render cancelled");
        }
    }

    ~Impl() {
        thread.run([this] {
            // Release every GL object while the context is still current.
            release_scene_memory();
            shaders.reset();
            empty_vao.reset();
            dummy_ssbo.reset();
            context.reset();
        });
    }

    // Everything a scene and its frames hold (on the render thread): the
    // frame's targets and maps, the meshes and images, kept ones too. What
    // stays is what any scene reuses: the context, the compiled programs
    // (and the driver's code for them), two empty objects.
    void release_scene_memory() {
        gbuffer = GBuffer();
        visibility = VisibilityBuffer();
        lights = LightModule();
        culling = LightCulling();
        shadows = ShadowModule();
        ray_scene.release();
        world_module.release();
        emitters.release();
        forward.release();
        cryptomatte.release();
        aovs.release();
        motion.release();
        scene.release_all();
        materials.release_all();
        world_graph = -1;
        receiver_grid.reset();
        receiver_grid_bytes = 0;
    }

    void init(const ContextOptions& options) {
        context = std::make_unique<EglContext>(options.device_index);
        info.vendor = gl_string(GL_VENDOR);
        info.renderer = gl_string(GL_RENDERER);
        info.version = gl_string(GL_VERSION);
        info.display = context->display_description();
        info.device_note = context->device_note();
        if (is_cpu_rasteriser(info.renderer)) {
            keep_freed_memory_at_heap_tops();
            info.allocator_note = jemalloc_note();
        }
        if (epoxy_gl_version() < 45)
            throw Error("OpenGL 4.5 core is required, the context gives " + info.version);
        glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture_size);
        glGetIntegerv(GL_MAX_FRAMEBUFFER_WIDTH, &max_fb_width);
        glGetIntegerv(GL_MAX_FRAMEBUFFER_HEIGHT, &max_fb_height);
        shaders.emplace();
        GLuint vao = 0;
        glCreateVertexArrays(1, &vao);
        empty_vao = VertexArray(vao);
        dummy_ssbo = make_storage_buffer(nullptr, 16, "dummy");
        check_gl("initialising the renderer");
    }

    void check_settings(const RenderSettings& s, std::size_t frame_bytes) const {
        if (s.width <= 0 || s.height <= 0)
            throw InvalidInput("resolution " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                               " must be positive");
        const int limit_w = std::min(max_texture_size, max_fb_width);
        const int limit_h = std::min(max_texture_size, max_fb_height);
        if (s.width > limit_w || s.height > limit_h)
            throw InvalidInput("resolution " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                               " exceeds the GPU limit of " + std::to_string(limit_w) + "x" +
                               std::to_string(limit_h) + " (" + info.renderer + ")");
        if (frame_bytes > memory_budget_bytes())
            throw InvalidInput("resolution " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                               " needs " + std::to_string(frame_bytes >> 20) + " MiB of render targets, over the " +
                               std::to_string(memory_budget_bytes() >> 20) +
                               " MiB budget (set DEFERRED_MEMORY_BUDGET_MB to raise it)");
    }

    // What a frame's settings and scene ask of its targets, checked against
    // the GPU's limits and the memory budget before anything is allocated.
    struct FramePlan {
        GBufferFeatures features;
        bool light_split = false;  // DiffDir / GlossDir
        bool shadow_pass = false;
        bool catchers = false;     // some visible shadow catcher
        bool splat = false;        // filter splatting (film_module.h)
        std::string splat_dropped; // why it is off where it was asked for (a warning)
        bool visibility = false;   // the visibility buffer's targets fit the budget
        std::string visibility_dropped;  // why not, where it was asked for (a warning)
        // Closure models some surface of the scene can have (a Diffuse
        // BSDF's Oren-Nayar lobe, a Glossy BSDF's Beckmann one): without
        // them the programs leave their code out (CLOSURES_NO_*).
        bool oren_nayar = false, beckmann = false;
    };
    FramePlan plan_frame(const RenderSettings& settings) const;

    // One frame in flight: its settings, camera and plan, the per-frame
    // modules (the scene as drawn, the film, the stages) and its timings.
    struct Frame {
        Frame(const Camera& camera_in, const RenderSettings& settings_in, const FramePlan& plan_in)
            : camera(camera_in), settings(settings_in), plan(plan_in),
              cam(build_camera(camera_in, settings_in.width, settings_in.height)), filter(settings_in.filter_width) {}
        const Camera& camera;
        const RenderSettings& settings;
        const FramePlan plan;
        const CameraMatrices cam;
        const PixelFilter filter;
        FrameResult result;
        StageTimer timer;  // the CPU stages (sync, programs, readback)

        FrameScene scene;
        FilmModule film;
        GeometryStage geometry;
        LightingStage lighting;
        PassStage passes;
        EmissionSamples emission_samples;

        bool shadow_rays = false;
        std::string rays_fallback;  // why shadow maps answer instead of rays
        bool casters_move = false;  // motion blur moves a shadow caster
        bool camera_moves = false;
        bool culled = false;        // tile light lists
        bool scene_alpha = false;   // a constant material partly transparent
        ExactLayers exact_layers;   // partly transparent planes the forward pass composites (layer_order.h)
        bool visibility = false;    // the G-buffer from the visibility buffer
        ShaderVariant base_variant;  // the G-buffer's targets
        std::vector<std::string> caster_defines;
        GLuint motion_program = 0;   // the Vector pass's
        gpu::FrameConstants fc{};
        std::optional<UniformRing> frame_ring;
        std::uint32_t reach = 0;     // whole pixels a jittered sample looks from its pixel
        std::uint32_t tiles_x = 0, tiles_y = 0;
        ViewVolume view;             // this sample's camera
        std::array<glm::dmat4, 3> camera_steps;  // camera motion blur
        GLuint preview_image = 0;

        std::optional<GpuStageTimer> gpu_timer;  // the sample loop's stages
        double geometry_ms = 0, lighting_ms = 0, passes_ms = 0, culling_ms = 0, shadow_ms = 0, forward_ms = 0,
               preview_ms = 0;
        std::uint64_t shadow_instances_drawn = 0, camera_instances_drawn = 0;
        std::uint64_t shadow_one_sided = 0;  // of those, without back faces
        std::size_t compiles_before = 0, loads_before = 0;
        double compile_ms_before = 0, load_ms_before = 0;

        FrameScene::Test in_view() const {
            return [this](const glm::dvec3& c, double r) { return view.contains(c, r); };
        }
    };

    FrameResult render(const Camera& camera, const RenderSettings& settings);
    // The stages of render(), in order.
    void sync(Frame& f);
    void sync_ray_scene(Frame& f);
    void sync_world_and_emitters(Frame& f);
    void warn_unreflected_emitters(std::vector<std::string>& warnings) const;
    void sync_film(Frame& f);
    void prepare_programs(Frame& f);
    int emission_sample_count(const Frame& f) const;
    ExactLayers exact_layers(const Frame& f) const;
    void render_sample(Frame& f, int sample);
    void place_at_shutter_time(Frame& f, int sample);
    void fit_shadow_maps(Frame& f);
    FrameResult finish(Frame& f);
    // Drops what the modules kept for this frame only (on every way out of render()).
    void end_frame();
    void abandon_frame();  // end_frame() after an exception, and the GL state reset
    // The frame block of the bakes (world, emission): the unjittered
    // camera, for Camera and Window coordinates and the Bump's differential.
    Buffer bake_frame_block(const Frame& f) const;

    // The visible surfaces the shadow maps are sized for: sample 0's depth
    // (unjittered pixel centres) on a grid of at most 128 x 128 points, as
    // camera-relative positions with the width of a pixel there.
    // `visible_depths` gets the nearest and farthest view depth of all the
    // pixels that see a surface ((0, 0) if none does). The GPU reduces the
    // depth buffer to those (receivers_comp.glsl): the grid's depths and two
    // numbers come back, not the whole buffer.
    std::vector<ShadowModule::Receiver> visible_receivers(const CameraMatrices& cam, int width, int height,
                                                          std::pair<double, double>& visible_depths) {
        const int step = std::max(1, std::max(width, height) / 128);
        const int grid_w = (width - step / 2 + step - 1) / step, grid_h = (height - step / 2 + step - 1) / step;
        const std::size_t header = 4 * sizeof(std::uint32_t);
        const std::size_t bytes = header + std::size_t(grid_w) * std::size_t(grid_h) * sizeof(float);
        if (bytes > receiver_grid_bytes) {
            receiver_grid = make_storage_buffer(nullptr, bytes, "shadow receivers");
            receiver_grid_bytes = bytes;
        }
        float two = 2.0f;
        std::uint32_t start[4] = {0u, 0u, 0u, 0u};
        std::memcpy(&start[1], &two, sizeof two);
        glNamedBufferSubData(receiver_grid.get(), 0, sizeof start, start);
        glUseProgram(shaders->compute_program("receivers_comp.glsl", {}));
        glUniform4i(0, width, height, step, grid_w);
        glBindTextureUnit(TEX_DEPTH, gbuffer.depth_texture());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_RECEIVERS, receiver_grid.get());
        glDispatchCompute(GLuint((width + 15) / 16), GLuint((height + 15) / 16), 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        std::vector<float> grid(std::size_t(grid_w) * std::size_t(grid_h));
        std::uint32_t range_bits[2];
        glGetNamedBufferSubData(receiver_grid.get(), 0, sizeof range_bits, range_bits);
        glGetNamedBufferSubData(receiver_grid.get(), GLintptr(header), GLsizeiptr(grid.size() * sizeof(float)),
                                grid.data());
        check_gl("reducing the depth for shadow map sizes");
        const glm::dmat4 to_view = glm::inverse(cam.projection);
        // Reversed Z: the largest stored value is the nearest surface.
        float z_near, z_far;
        std::memcpy(&z_near, &range_bits[0], sizeof z_near);
        std::memcpy(&z_far, &range_bits[1], sizeof z_far);
        visible_depths = {0.0, 0.0};
        if (z_near > 0.0f) {
            auto view_depth = [&](double z) {
                glm::dvec4 v = to_view * glm::dvec4(0.0, 0.0, z, 1.0);
                return -v.z / v.w;
            };
            visible_depths = {view_depth(z_near), view_depth(z_far)};
        }
        const glm::dmat4 to_world = glm::inverse(cam.view);
        const glm::dvec4& vp = cam.viewplane;
        const double pixel = std::min((vp.y - vp.x) / width, (vp.w - vp.z) / height);  // at unit depth (persp)
        std::vector<ShadowModule::Receiver> out;
        for (int y = step / 2; y < height; y += step)
            for (int x = step / 2; x < width; x += step) {
                const double z = grid[std::size_t(y / step) * std::size_t(grid_w) + std::size_t(x / step)];
                if (!(z > 0.0)) continue;  // background (reversed Z: 0 is far)
                const glm::dvec4 ndc(2.0 * (x + 0.5) / width - 1.0, 2.0 * (y + 0.5) / height - 1.0, z, 1.0);
                glm::dvec4 v = to_view * ndc;
                v /= v.w;
                const double view_depth = -v.z;
                const double footprint = cam.orthographic ? pixel : pixel * view_depth;
                if (!(footprint > 0.0) || !std::isfinite(footprint)) continue;
                out.push_back({glm::dvec3(to_world * glm::dvec4(glm::dvec3(v), 1.0)), view_depth, footprint});
            }
        return out;
    }
};

// The frame: sync the scene, prepare the programs, the film samples, the
// resolves and the readback.
FrameResult Renderer::Impl::render(const Camera& camera, const RenderSettings& settings) {
    Frame f(camera, settings, plan_frame(settings));
    f.compiles_before = shaders->compile_count();
    f.compile_ms_before = shaders->compile_ms();
    f.loads_before = shaders->disk_loads();
    f.load_ms_before = shaders->load_ms();
    try {
        sync(f);
        prepare_programs(f);
        preview.begin(settings.width, settings.height, settings.samples, settings.preview_interval_ms);
        for (int sample = 0; sample < settings.samples; ++sample) render_sample(f, sample);
        FrameResult result = finish(f);
        end_frame();
        return result;
    } catch (...) {
        abandon_frame();
        throw;
    }
}

// A cancelled or failed frame leaves no per-frame state in the modules the
// renderer keeps (the next frame would draw the Vector pass or AOVs it did
// not ask for), and none of the GL state a stage changes and restores
// itself: a stage that threw half-way (a lazy compile, a GL error) could
// leave the scissor test or a colour or depth mask on, which the next
// frame's G-buffer clear obeys.
void Renderer::Impl::abandon_frame() {
    end_frame();
    shadows.abandon_frame();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glDisable(GL_DEPTH_CLAMP);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);
}

void Renderer::Impl::end_frame() {
    motion.release();
    aovs.release();
    cryptomatte.release();
    forward.end_frame();
}

Renderer::Impl::FramePlan Renderer::Impl::plan_frame(const RenderSettings& settings) const {
    validate_settings(settings);
    const PassSet& wanted = settings.passes;
    FramePlan plan;
    GBufferFeatures& features = plan.features;
    for (const Material& m : scene.materials())
        if (m.graph < 0 && (m.sheen > 1e-5f || m.clearcoat > 1e-5f)) features.params1 = true;
    if (materials.uses_params1()) features.params1 = true;
    // As FrameScene packs a constant material (base_diffuse.w: a Glossy
    // BSDF's model, else a Diffuse BSDF's sigma >= 0), and any graph with
    // the node.
    for (const Material& m : scene.materials()) {
        if (m.graph >= 0) continue;
        if (m.glossy_model == 2) plan.beckmann = true;
        if (m.glossy_model <= 0 && m.diffuse_roughness >= 0.0f) plan.oren_nayar = true;
        if (m.glossy_model > 0 && m.metallic < 0.5f) plan.oren_nayar = true;  // Lambert + Glossy (scene.h)
    }
    if (materials.uses_node("node_bsdf_diffuse")) plan.oren_nayar = true;
    if (materials.uses_node("node_bsdf_glossy")) plan.beckmann = true;
    // Shadow maps compare against the true normal's plane and move the
    // receiver by its terminator offset (geometry target), as do bent closures.
    features.geometry = materials.uses_smooth_normal() || settings.shadows;
    features.ids = wanted.contains(Pass::IndexOB) || wanted.contains(Pass::IndexMA);
    features.uv = wanted.contains(Pass::UV);
    features.instance_ids = !settings.cryptomatte.empty() || settings.light_groups > 0;
    plan.light_split = wanted.contains(Pass::DiffDir) || wanted.contains(Pass::GlossDir);
    plan.shadow_pass = wanted.contains(Pass::Shadow);
    // Shadow catchers (lighting_comp.glsl SHADOW_CATCHER): their light kept
    // apart (two RGBA32F accumulations); Combined becomes the matte.
    for (const InstanceBatch& b : scene.batches())
        if (b.shadow_catcher && !b.object_indices.empty()) plan.catchers = true;

    // Memory: G-buffer (depth 4, emission 16, base 8, params0 8, normal 4,
    // optional params1 8, ids 8, uv 8, geometry 16), the Combined
    // accumulation (16), light split (32), Shadow (16), one RGBA32F image per
    // other pass (16), the splat's scratch images and the CPU copies of the
    // passes.
    const std::size_t pixels = std::size_t(settings.width > 0 ? settings.width : 0) *
                               std::size_t(settings.height > 0 ? settings.height : 0);
    std::size_t per_pixel = 4 + 16 + 8 + 8 + 4 + (features.params1 ? 8 : 0) + (features.ids ? 8 : 0) +
                            (features.uv ? 8 : 0) + (features.geometry ? 16 : 0) + 16 + (plan.light_split ? 32 : 0) +
                            (plan.shadow_pass ? 16 : 0);
    for (Pass p : wanted.list()) per_pixel += (p == Pass::Combined ? 0 : 16) + 4 * std::size_t(pass_info(p).channels);
    if (features.instance_ids) per_pixel += 16;  // the ids target grows to RGBA32UI
    per_pixel += 16 * std::size_t(settings.light_groups) + (settings.light_groups > 0 ? 16 : 0);
    if (plan.catchers) per_pixel += 32;
    const std::size_t frame_bytes = pixels * per_pixel + 2 * CryptomatteModule::bytes(settings) +
                                    AovModule::bytes(settings) +
                                    (wanted.contains(Pass::Vector) ? MotionModule::bytes(settings) : 0);
    check_settings(settings, frame_bytes);
    // Filter splatting: a scratch image beside each accumulation Combined
    // is made of (film_module.h: Combined, the light split, Shadow's and the
    // catchers' sums, the light groups, FilmModule::splatted's passes).
    // Where only they would go over the budget, the frame renders without
    // them, warned.
    std::size_t splat_bytes = 0;
    if (settings.samples > 1 && settings.filter_splat && PixelFilter::splat_margin(settings.filter_width) > 0) {
        std::size_t scratch = 16 + (plan.light_split ? 32 : 0) + (plan.shadow_pass ? 16 : 0) +
                              (plan.catchers ? 32 : 0) + 16 * std::size_t(settings.light_groups);
        for (Pass p : wanted.list())
            if (FilmModule::splatted(p)) scratch += 16;
        plan.splat = frame_bytes + pixels * scratch <= memory_budget_bytes();
        if (!plan.splat)
            plan.splat_dropped = "Filter Splatting is off for this frame: its scratch images (" +
                                 std::to_string((pixels * scratch) >> 20) + " MiB) would take the frame over the " +
                                 std::to_string(memory_budget_bytes() >> 20) +
                                 " MiB budget (DEFERRED_MEMORY_BUDGET_MB); each pixel keeps its own samples";
        else
            splat_bytes = pixels * scratch;
    }
    // The visibility buffer last: it changes no pixel (the raster path
    // writes the same G-buffer), so where its targets would take the frame
    // over the budget the raster path draws it, where the splat's scratch
    // changes the image.
    if (settings.visibility_buffer) {
        const std::size_t vis_bytes = pixels * VisibilityBuffer::kBytesPerPixel;
        plan.visibility = frame_bytes + splat_bytes + vis_bytes <= memory_budget_bytes();
        if (!plan.visibility)
            plan.visibility_dropped = "its targets (" + std::to_string(vis_bytes >> 20) +
                                      " MiB) would take the frame over the " +
                                      std::to_string(memory_budget_bytes() >> 20) +
                                      " MiB budget (DEFERRED_MEMORY_BUDGET_MB)";
    }
    return plan;
}

Buffer Renderer::Impl::bake_frame_block(const Frame& f) const {
    gpu::FrameConstants b{};
    b.view = to_gpu(f.cam.view);
    b.projection = to_gpu(f.cam.projection);
    b.camera_position = {float(f.cam.position.x), float(f.cam.position.y), float(f.cam.position.z),
                         f.cam.orthographic ? 1.0f : 0.0f};
    b.viewport = {float(f.settings.width), float(f.settings.height), 1.0f / float(f.settings.width),
                  1.0f / float(f.settings.height)};
    return make_storage_buffer(&b, sizeof(b), "bake frame");
}

// --- Sync: the scene packed camera-relative in double, the lights, the
// world, the film's targets and the frame constants. ---
void Renderer::Impl::sync(Frame& f) {
    const RenderSettings& settings = f.settings;
    FrameScene::Options options;
    options.motion_blur = settings.motion_blur;
    options.cryptomatte = !settings.cryptomatte.empty();
    options.light_groups = settings.light_groups > 0;
    f.scene.build(scene, materials, f.cam.position, options, empty_vao.get(), dummy_ssbo.get());
    // Motion blur moves something: the shadow casters (instances, deforming
    // meshes) or only the camera.
    f.casters_move = settings.motion_blur && (f.scene.any_moving() || f.scene.deforming());
    f.camera_moves = settings.motion_blur && f.camera.has_motion;
    materials.upload_constants();
    {
        std::vector<std::uint32_t> crypto_materials;
        if (!settings.cryptomatte.empty())
            for (const Material& m : scene.materials()) crypto_materials.push_back(m.crypto);
        cryptomatte.begin(settings, f.scene.crypto_hashes(), crypto_materials);
    }
    sync_ray_scene(f);
    sync_world_and_emitters(f);
    // (Not with a moving camera: the tiles' light lists come from sample 0's view.)
    f.culled = settings.light_culling && lights.count() >= kCullingMinLights && !f.camera_moves;
    sync_film(f);
    check_gl("frame sync");
    f.result.timings.upload_ms = f.timer.lap_ms();
}

// Shadow rays, unless a shadow-casting node material drives alpha (a ray
// cannot evaluate its graph), a mesh deforms under motion blur, or the ray
// scene outgrows a storage block: then maps, warned (f.rays_fallback) once
// something casts shadows, which only the lights' sync knows.
void Renderer::Impl::sync_ray_scene(Frame& f) {
    const RenderSettings& settings = f.settings;
    f.shadow_rays = settings.shadows && settings.shadow_rays;
    std::string& fallback = f.rays_fallback;
    if (f.shadow_rays) {
        for (const InstanceBatch& b : scene.batches()) {
            if (!b.cast_shadow || !fallback.empty()) continue;
            for (std::uint32_t id : b.material_slots) {
                // The slot's material and its mix chain.
                for (std::int64_t k = id, n = 0; k >= 0 && n < 16; ++n) {
                    const Material& m = scene.materials()[std::size_t(k)];
                    if (m.graph >= 0 && materials.alpha(std::uint32_t(m.graph))) {
                        const std::string& name = materials.name(std::uint32_t(m.graph));
                        fallback = "Shadow rays cannot evaluate the alpha of node material '" +
                                   (name.empty() ? std::string("?") : name) + "': this render uses shadow maps";
                    }
                    k = m.mix_with;
                }
            }
        }
        // Moving instances are placed in the ray scene each sample; a
        // mesh's hierarchy is built from its vertices at the middle of the
        // shutter, so deforming ones cannot follow.
        if (fallback.empty() && f.scene.deforming())
            fallback = "Shadow rays do not follow deforming meshes under motion blur yet: this render uses "
                       "shadow maps";
        f.shadow_rays = fallback.empty();
    }
    if (f.shadow_rays) {
        StageTimer ray_timer;
        ray_scene.build(f.scene.ray_casters());
        GLint64 max_block = 0;
        glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
        if (max_block > 0 && ray_scene.bytes() > std::size_t(max_block)) {
            fallback = "Shadow rays: the scene's " + std::to_string(ray_scene.triangles()) + " triangles need " +
                       std::to_string(ray_scene.bytes() >> 20) + " MiB, over this GPU's " +
                       std::to_string(max_block >> 20) + " MiB storage block: this render uses shadow maps";
            ray_scene.release();
            f.shadow_rays = false;
        } else {
            ray_scene.upload();
        }
        f.result.timings.ray_build_ms = ray_timer.lap_ms();
    }
    shadows.begin_frame(f.cam, settings.shadow_resolution, settings.shadow_quality, memory_budget_bytes() / 4,
                        f.shadow_rays, settings.count_shadow_fragments);
}

// The world (its node tree baked into an environment map), emissive meshes
// as lights, the scene's lights and what casts shadows.
void Renderer::Impl::sync_world_and_emitters(Frame& f) {
    const RenderSettings& settings = f.settings;
    FrameResult& result = f.result;
    // A world node tree: baked into its environment map (with the sampling
    // distribution) before anything asks whether the world lights the
    // scene. The bake reads the camera (Camera and Window texture
    // coordinates) from the frame block.
    {
        Buffer bake_buffer = bake_frame_block(f);
        glBindBufferBase(GL_UNIFORM_BUFFER, UBO_FRAME, bake_buffer.get());
        try {
            result.timings.world_bake_ms = world_module.prepare(*shaders, materials, world_graph);
        } catch (const Error& e) {
            // A world graph that does not compile: the world's fallback colour, warned.
            world_module.release();
            result.warnings.push_back("World: its node tree could not be baked (" + std::string(e.what()) +
                                      "); rendered with the viewport colour");
        }
        result.timings.world_map_width = world_module.width();
    }
    // The world's occlusion map, when the world lights anything or the AO
    // pass is asked for.
    const World& world = scene.world();
    const bool world_lights = world_module.has_map() ? world_module.lights()
        : world.color[0] > 0.0f || world.color[1] > 0.0f || world.color[2] > 0.0f;
    // A world map (an HDRI) gets several occlusion directions per sample:
    // each map is one draw of the casters, while one direction shared by
    // every pixel leaves correlated noise that dominates the error (the
    // hdri_studio report); a constant world keeps one.
    const int world_maps = world_module.has_map() ? kWorldMapOcclusionDirections : 1;
    if (settings.shadows && (world_lights || settings.passes.contains(Pass::AO)) && scene.instance_count() > 0)
        shadows.offer_world(world_maps);
    // Emissive meshes become lights (emitter_module.h); the triangles of
    // node materials whose emission varies are baked with their graphs.
    emitters.sync(scene, f.cam.position);
    if (emitters.needs_bake()) {
        Buffer bake_buffer = bake_frame_block(f);
        glBindBufferBase(GL_UNIFORM_BUFFER, UBO_FRAME, bake_buffer.get());
        f.scene.bind_buffers();
        materials.bind_constants();
        try {
            result.timings.emission_bake_ms = emitters.bake(
                *shaders, materials,
                [&](const EmissionBakeRun& run, GLuint) {
                    const GpuMesh& mesh = scene.meshes()[run.mesh];
                    f.scene.bind_mesh(mesh);
                    f.scene.bind_attributes(mesh);
                    materials.bind_for_draw(run.graph, mesh);
                    glUniform1ui(1, mesh.flags);
                    glDrawArraysInstanced(GL_TRIANGLES, GLint(run.first * 3), GLsizei(run.count * 3), 1);
                },
                result.warnings);
            result.timings.emission_baked_triangles = emitters.baked_triangles();
        } catch (const Error& e) {
            result.warnings.push_back(std::string("Emissive node materials light nothing around them (their "
                                                  "emission could not be baked): ") + e.what());
        }
    }
    result.timings.emitter_triangles = emitters.finish();
    warn_unreflected_emitters(result.warnings);
    lights.sync(scene.lights(), f.cam.position, settings.light_threshold, settings.shadows ? &shadows : nullptr,
                &emitters);
    // Shadow rays' fallback to maps, said once something casts shadows.
    if (!f.rays_fallback.empty() && !shadows.empty()) result.warnings.push_back(f.rays_fallback);
    // Nothing casts a shadow: no rays either.
    f.shadow_rays = f.shadow_rays && !shadows.empty();
    if (f.shadow_rays) {
        result.timings.ray_scene_bytes = ray_scene.bytes();
        result.timings.ray_triangles = ray_scene.triangles();
    } else {
        ray_scene.release();
    }
    result.timings.shadow_rays = f.shadow_rays;
}

// A mirror lobe (alpha^2 <= 1e-7, roughness below ~0.0178) meets a mesh
// light along its reflected ray only when the light has at most
// MESH_LIGHT_TRACED_TRIANGLES triangles (light_lib.glsl: bounded loops over
// its chunks); a larger emitter is missing from mirrors. Said when a
// constant material of the scene is such a mirror, or when the scene has a
// node material (whose roughness, perhaps from a texture, is not known
// here; README, Accuracy -> Emissive meshes).
void Renderer::Impl::warn_unreflected_emitters(std::vector<std::string>& warnings) const {
    std::size_t unreflected = 0, most = 0;
    for (const MeshLight& l : emitters.lights())
        if (l.count > std::uint32_t(MESH_LIGHT_TRACED_TRIANGLES)) {
            ++unreflected;
            most = std::max<std::size_t>(most, l.count);
        }
    if (unreflected == 0) return;
    auto sharp = [](float roughness) { return std::pow(double(roughness), 4.0) <= 1e-7; };  // alpha^2, alpha = r^2
    bool mirror = false;
    for (const Material& m : scene.materials())
        if (m.graph >= 0 ||
            ((m.specular > 1e-5f || m.metallic > 1e-5f || m.glossy_model != 0) && sharp(m.roughness)) ||
            (m.clearcoat > 1e-5f && sharp(m.clearcoat_roughness)))
            mirror = true;
    if (!mirror) return;
    warnings.push_back("Mirror-like surfaces (roughness below 0.018) do not reflect " + std::to_string(unreflected) +
                       " emissive mesh" + (unreflected == 1 ? "" : "es") + " of more than " +
                       std::to_string(MESH_LIGHT_TRACED_TRIANGLES) + " triangles (up to " + std::to_string(most) +
                       "): their light still reaches every other surface");
}

// The frame constants (the per-sample ones are set by render_sample), the
// G-buffer and the film's accumulations.
void Renderer::Impl::sync_film(Frame& f) {
    const RenderSettings& settings = f.settings;
    const CameraMatrices& cam = f.cam;
    const World& world = scene.world();
    gpu::FrameConstants& fc = f.fc;
    fc.view = to_gpu(cam.view);
    fc.inv_view = to_gpu(glm::inverse(cam.view));
    fc.camera_position = {float(cam.position.x), float(cam.position.y), float(cam.position.z),
                          cam.orthographic ? 1.0f : 0.0f};
    fc.world_color = {world.color[0], world.color[1], world.color[2], settings.film_transparent ? 1.0f : 0.0f};
    fc.viewport = {float(settings.width), float(settings.height), 1.0f / float(settings.width),
                   1.0f / float(settings.height)};
    const float mist_depth = settings.mist.depth > 0 ? settings.mist.depth : 1e-6f;
    fc.mist = {settings.mist.start, 1.0f / mist_depth, float(static_cast<std::uint32_t>(settings.mist.falloff)), 0};
    fc.counts = {lights.count(), settings.passes.bits(), kLightShapePoints, std::uint32_t(settings.samples)};
    f.tiles_x = std::uint32_t((settings.width + TILE_SIZE - 1) / TILE_SIZE);
    f.tiles_y = std::uint32_t((settings.height + TILE_SIZE - 1) / TILE_SIZE);
    f.reach = settings.samples > 1 ? std::uint32_t(std::ceil(f.filter.support())) : 0u;
    fc.tiles = {f.tiles_x, f.tiles_y, f.culled ? 1u : 0u, f.reach};
    fc.world_occlusion = {float(shadows.world_index()), float(shadows.world_count()), float(world_module.width()),
                          float(world_module.height())};
    fc.jitter.w = 1.0f;  // a directly seen emission's share (emission_samples.h): whole until render_sample says
    // The frame constants, new each sample: a ring of slots in a persistently
    // mapped buffer (gl_util.h UniformRing), so updating them never waits
    // for the samples still in flight.
    f.frame_ring.emplace(sizeof(fc), 4, UBO_FRAME, "frame constants");
    f.frame_ring->push(&fc);
    f.view = ViewVolume(cam, settings.width, settings.height, f.reach);
    if (f.camera_moves)
        f.camera_steps = {to_glm(f.camera.matrix_previous), to_glm(f.camera.matrix), to_glm(f.camera.matrix_next)};

    // The per-sample G-buffer and the accumulations (the film).
    gbuffer.ensure(settings.width, settings.height, f.plan.features);
    FilmModule::Layout layout;
    layout.width = settings.width;
    layout.height = settings.height;
    for (Pass p : settings.passes.list())
        if (p != Pass::Combined) layout.passes.push_back(p);
    layout.light_split = f.plan.light_split;
    layout.shadow_pass = f.plan.shadow_pass;
    layout.catchers = f.plan.catchers;
    layout.light_groups = settings.light_groups;
    // Filter splatting with more than one sample, every sample splatted (a
    // one-sample render is the pixel centre, unjittered and unsplatted, as
    // without it).
    layout.splat_margin = f.plan.splat ? f.filter.splat_margin() : 0;
    if (!f.plan.splat_dropped.empty()) f.result.warnings.push_back(f.plan.splat_dropped);
    f.film.allocate(layout);
    f.film.prefetch(*shaders);
    f.result.timings.gbuffer_bytes = gbuffer.bytes() + f.film.bytes();
    f.preview_image = settings.preview_pass == Pass::Combined ? f.film.combined() : f.film.image(settings.preview_pass);
}

// --- Programs: every variant the frame draws with, compiled before the
// first sample (only the variants the scene and its outputs need). ---
void Renderer::Impl::prepare_programs(Frame& f) {
    const RenderSettings& settings = f.settings;
    FrameResult& result = f.result;
    const GBufferFeatures& features = f.plan.features;
    // Which G-buffer targets exist.
    ShaderVariant& base = f.base_variant;
    if (features.params1) base.defines.push_back("GBUF_PARAMS1");
    // On a CPU rasteriser a branch costs both its sides (masked SIMD): the
    // closure models no surface has are left out of the lighting's code
    // (gbuffer_lib.glsl, bsdf_lib.glsl). DEFERRED_CLOSURE_MODELS=all keeps
    // every model's code (the same image but for float rounding: the
    // reference for what this saves).
    const char* models = std::getenv("DEFERRED_CLOSURE_MODELS");
    const bool every_model = models && std::string(models) == "all";
    if (!f.plan.oren_nayar && !every_model) base.defines.push_back("CLOSURES_NO_OREN_NAYAR");
    if (!f.plan.beckmann && !every_model) base.defines.push_back("CLOSURES_NO_BECKMANN");
    // Shadow rays towards emissive meshes: one ray per pixel and sample for
    // all of them, to a candidate picked by its unshadowed light
    // (light_lib.glsl, MESH_LIGHT_RAY_POOL). DEFERRED_MESH_LIGHT_RAYS=light:
    // one per mesh light; =every: each candidate's own ray (the reference
    // the picks are measured against).
    const char* mesh_rays_env = std::getenv("DEFERRED_MESH_LIGHT_RAYS");
    const std::string mesh_rays = mesh_rays_env ? mesh_rays_env : "pixel";
    if (f.shadow_rays && lights.has_mesh_lights()) {
        if (mesh_rays == "every") base.defines.push_back("MESH_LIGHT_RAY_EVERY_POINT");
        else if (mesh_rays != "light") base.defines.push_back("MESH_LIGHT_RAY_POOL");
    }
    if (features.ids) base.defines.push_back("GBUF_IDS");
    if (features.instance_ids) base.defines.push_back("GBUF_INSTANCE_IDS");
    if (features.uv) base.defines.push_back("GBUF_UV");
    if (features.geometry) base.defines.push_back("GBUF_GEOMETRY");
    // Stochastic transparency, only when some constant material is partly
    // transparent (node materials carry their own switch, MATERIAL_ALPHA).
    for (const Material& m : scene.materials())
        if (m.graph < 0 && m.alpha < 1.0f) f.scene_alpha = true;
    if (f.scene_alpha) f.caster_defines.push_back("SCENE_ALPHA");

    LightingStage::Config lighting;
    lighting.light_split = f.plan.light_split;
    lighting.culled = f.culled;
    // Mesa's CPU rasterisers run both sides of every branch (masked SIMD).
    // DEFERRED_LIGHT_KIND_LOOPS=on|off overrides (the tests hold the two
    // forms equal on one driver). Not for culled frames: a tile's list
    // mixes kinds, so the kind loops would need the loop over every kind
    // after them, which doubled the program's compile on llvmpipe (759
    // against 334 ms, many_lights) for a tenth of its lighting time.
    lighting.kind_loops = is_cpu_rasteriser(info.renderer);
    if (const char* env = std::getenv("DEFERRED_LIGHT_KIND_LOOPS")) lighting.kind_loops = std::string(env) == "on";
    if (f.culled) lighting.kind_loops = false;
    for (const MeshLight& l : emitters.lights())
        if (l.count > EmitterModule::kChunk) lighting.chunked_mesh_lights = true;
    lighting.light_samples = settings.light_samples;
    lighting.shadow_maps = !shadows.empty();
    lighting.shadow_rays = f.shadow_rays;
    lighting.world_occlusion = shadows.world_index() >= 0;
    lighting.ao = settings.passes.contains(Pass::AO);
    lighting.light_groups = settings.light_groups;
    lighting.shadow_pass = f.plan.shadow_pass;
    lighting.catchers = f.plan.catchers;
    // The lighting program, the frame's largest, starts compiling first, to
    // overlap the node materials' compiles, where its variant is already
    // known: without Blend-mode materials there is no forward layer.
    f.exact_layers = exact_layers(f);
    bool any_blend = f.exact_layers.any();
    for (const Material& m : scene.materials()) any_blend = any_blend || m.blend;
    if (!any_blend) LightingStage::prefetch(*shaders, base, lights, world_module, lighting);

    // With the visibility buffer the node materials' G-buffer programs are
    // not compiled: their resolves (below) replace them.
    std::string visibility_why_not;
    if (settings.visibility_buffer) visibility_why_not = VisibilityBuffer::unsupported(settings.width, settings.height);
    if (visibility_why_not.empty() && settings.visibility_buffer && !f.plan.visibility)
        visibility_why_not = f.plan.visibility_dropped;
    const bool want_visibility = settings.visibility_buffer && visibility_why_not.empty();
    f.geometry.prepare(*shaders, materials, f.scene, base, f.scene_alpha, result.warnings, !want_visibility);
    result.timings.material_programs = f.geometry.distinct_graph_programs();

    // Blend-mode materials (Material::blend): drawn by the forward pass, not
    // into the G-buffer, lit by the lighting pass's own code.
    ShaderVariant forward_variant;
    // The closure models no surface has are left out of its lighting code
    // too, as of the lighting pass's (a CPU rasteriser runs both sides of
    // every branch).
    for (const std::string& d : base.defines)
        if (d.rfind("CLOSURES_NO_", 0) == 0) forward_variant.defines.push_back(d);
    lights.add_defines(forward_variant);
    if (!shadows.empty()) forward_variant.defines.push_back("HAS_SHADOWS");
    if (f.shadow_rays) {
        forward_variant.defines.push_back("SHADOW_RAYS");
        add_ray_traversal_define(forward_variant.defines);
    }
    if (shadows.world_index() >= 0) forward_variant.defines.push_back("HAS_WORLD_OCCLUSION");
    world_module.add_defines(forward_variant);
    forward_variant.defines.push_back("FORWARD_PASS");
    f.geometry.exclude(forward.prepare(*shaders, materials, f.scene, f.geometry, forward_variant, lights.count(),
                                       LightingStage::batch_size(lighting), f.exact_layers, result.warnings));
    // The exact layers stay in the data G-buffer (the frame has only data
    // passes besides Combined); Blend-mode materials write no data pass.
    std::vector<bool> data_skipped = f.geometry.forward();
    for (std::uint32_t id = 0; id < data_skipped.size(); ++id)
        data_skipped[id] = data_skipped[id] && scene.materials()[id].blend;
    f.geometry.exclude_from_data(data_skipped);
    result.timings.exact_layers = f.exact_layers.instances;
    bool blend_drawn = false;
    for (std::uint32_t id = 0; id < data_skipped.size(); ++id) blend_drawn = blend_drawn || data_skipped[id];
    if (forward.active()) {
        // What the forward pass does not write (forward_module.h): said, not silent.
        std::vector<std::string> skipped;
        for (Pass p : settings.passes.list())
            if (p != Pass::Combined) skipped.push_back(pass_info(p).name);
        if (!settings.cryptomatte.empty()) skipped.push_back("Cryptomatte");
        if (!settings.aovs.empty()) skipped.push_back("shader AOVs");
        if (settings.light_groups > 0) skipped.push_back("light groups");
        if (!skipped.empty() && blend_drawn) {
            std::string list;
            for (const std::string& name : skipped) list += (list.empty() ? "" : ", ") + name;
            result.warnings.push_back("Blend-mode materials reach Combined only; " + list +
                                      " show what is behind them");
        }
        forward.ensure(settings.width, settings.height);
        result.timings.gbuffer_bytes += forward.bytes();
    }

    // The visibility buffer: every program it resolves with, compiled now.
    if (want_visibility) {
        std::vector<VisibilityBuffer::GraphMaterial> graphs;
        for (auto& [id, program] : f.geometry.graph_programs())
            if (!f.geometry.is_forward(id) || !data_skipped[id])  // an exact layer: the data G-buffer draws it
                graphs.push_back({id, std::uint32_t(scene.materials()[id].graph), f.geometry.is_alpha_graph(id)});
        try {
            visibility.prepare(*shaders, materials, base, graphs, f.geometry.partly_transparent(), result.warnings);
            visibility.ensure(settings.width, settings.height, f.scene.slot_count(), gbuffer.depth_texture());
            result.timings.gbuffer_bytes += visibility.bytes();
            result.timings.material_programs = visibility.distinct_graph_programs();
            f.visibility = true;
        } catch (const Error& e) {
            // One of its own programs (not a material's) did not compile on
            // this driver: the raster path, with the programs it needs.
            visibility_why_not = std::string("its programs did not compile: ") + e.what();
            const std::vector<bool> forward_materials = f.geometry.forward();
            f.geometry.prepare(*shaders, materials, f.scene, base, f.scene_alpha, result.warnings);
            f.geometry.exclude(forward_materials);
            f.geometry.exclude_from_data(data_skipped);
            result.timings.material_programs = f.geometry.distinct_graph_programs();
        }
    }
    if (settings.visibility_buffer && !f.visibility)
        result.warnings.push_back("The visibility buffer is not used for this frame (the G-buffer is drawn by the "
                                  "raster pipeline, the same image): " + visibility_why_not);
    // Its targets are released when a frame does not use it (a viewport
    // that turned it off keeps no 20 B per pixel).
    if (!f.visibility) visibility = VisibilityBuffer();
    result.timings.visibility_buffer = f.visibility;

    lighting.forward_layer = forward.active();
    f.lighting.prepare(*shaders, base, lights, world_module, lighting, result.warnings);

    // Shader AOVs, with their writers' programs.
    f.geometry.prepare_aovs(*shaders, materials, f.scene, base, settings.aovs, result.warnings);
    if (!settings.aovs.empty()) aovs.begin(settings.aovs, settings.width, settings.height, gbuffer.depth_texture());
    // The Vector pass: every instance's and the camera's motion
    // (motion_module.h); with motion blur 0, as Cycles.
    if (const GLuint vector = f.film.image(Pass::Vector); vector && !settings.motion_blur) {
        motion.begin(scene, f.camera, f.cam, settings.width, settings.height, vector, gbuffer.depth_texture());
        ShaderVariant motion_variant;
        motion_variant.defines.push_back("MOTION_PASS");
        f.motion_program = shaders->graphics_program("geometry_vert.glsl", "motion_frag.glsl", motion_variant);
    }
    f.passes.prepare(*shaders, base, f.film, world_module, f.geometry.stochastic_alpha(), settings.width,
                     settings.height);
    f.emission_samples.prepare(*shaders, base, f.film, scene.materials(), emission_sample_count(f), settings.width,
                               settings.height);
    f.geometry.set_alpha_mode(false, settings.alpha_threshold);
    if (f.visibility) visibility.set_alpha_mode(false, settings.alpha_threshold);
    // The caster programs of node materials that drive alpha.
    if (f.geometry.alpha_graphs() && !shadows.empty()) {
        f.geometry.prepare_casters(*shaders, materials, f.scene, false, result.warnings);
        if (shadows.world_index() >= 0) f.geometry.prepare_casters(*shaders, materials, f.scene, true, result.warnings);
    }
    check_gl("preparing the programs");
    // The frame's own programs (and the forward, AOV and Vector targets)
    // count before the first sample; the passes', the tile lists', the
    // shadow casters' and Cryptomatte's programs still compile at first use,
    // inside their stage of sample 0 (when not cached).
    result.timings.upload_ms += f.timer.lap_ms();
    // From here to the readback the stages are timed on the GPU's clock:
    // no glFinish inside the sample loop.
    f.gpu_timer.emplace();
}

// Motion blur: the camera and the moving instances at sample s's time of
// the shutter (motion_module.h). Positions stay relative to the frame's
// camera; this sample's camera is at `eye` from it (frame.motion.xyz).
void Renderer::Impl::place_at_shutter_time(Frame& f, int sample) {
    const double r = 2.0 * shutter_time(sample) - 1.0;
    if (f.camera_moves) {
        Camera c = f.camera;
        const glm::dmat4 m = interpolate_motion(f.camera_steps[0], f.camera_steps[1], f.camera_steps[2], r);
        for (int col = 0; col < 4; ++col)
            for (int row = 0; row < 4; ++row) c.matrix[std::size_t(col * 4 + row)] = m[col][row];
        const CameraMatrices at = build_camera(c, f.settings.width, f.settings.height);
        f.view.eye = at.position - f.cam.position;
        f.view.to_view = glm::dmat3(at.view);
        glm::dmat4 view = at.view;
        view[3] = glm::dvec4(-(glm::dmat3(at.view) * f.view.eye), 1.0);  // view x translate(-eye)
        f.fc.view = to_gpu(view);
        f.fc.inv_view = to_gpu(glm::inverse(view));
    }
    f.fc.motion = {float(f.view.eye.x), float(f.view.eye.y), float(f.view.eye.z), float(r)};
    // The ray scene again at this time: the instances' hierarchy over the
    // meshes' kept ones (each mesh's hierarchy is built once).
    if (f.scene.place_at(r) && f.shadow_rays) {
        StageTimer ray_timer;  // CPU work: its own clock, no glFinish
        ray_scene.build(f.scene.ray_casters());
        ray_scene.upload();
        f.result.timings.ray_build_ms += ray_timer.lap_cpu_ms();
    }
}

// The partly transparent planes the forward pass composites exactly
// (RenderSettings::exact_transparent_planes, layer_order.h): only in frames
// whose every output the forward layer reaches, whose order holds for every
// sample, and that lose nothing by a forward pass.
ExactLayers Renderer::Impl::exact_layers(const Frame& f) const {
    const RenderSettings& s = f.settings;
    // Combined and the data G-buffer's passes (which keep every partly
    // transparent surface at the Alpha Threshold, exact layers too); the
    // forward layer reaches no light, colour or Mist pass.
    const std::vector<Pass> passes = s.passes.list();
    const bool layer_passes = std::all_of(passes.begin(), passes.end(), [](Pass p) {
        return p == Pass::Combined || p == Pass::Depth || p == Pass::Position || p == Pass::Normal || p == Pass::UV ||
               p == Pass::IndexOB || p == Pass::IndexMA;
    });
    if (!s.exact_transparent_planes || !layer_passes || !s.cryptomatte.empty() || !s.aovs.empty() ||
        s.light_groups > 0 || s.motion_blur || f.plan.catchers || emission_sample_count(f) > 1)
        return {};
    std::vector<bool> transparent(scene.materials().size(), false);
    for (std::uint32_t id = 0; id < scene.materials().size(); ++id) {
        const Material& m = scene.materials()[id];
        if (m.blend) return {};  // the forward pass orders those by object
        if (m.holdout) continue;
        transparent[id] = m.graph >= 0 ? materials.alpha(std::uint32_t(m.graph)) : f.scene.coverage(id) < 1.0f;
    }
    if (std::find(transparent.begin(), transparent.end(), true) == transparent.end()) return {};
    return select_exact_layers(f.scene, transparent, f.view);
}

// Emission samples per film sample (emission_samples.h): the setting's
// where they can change the image, else 1; automatic (0): where an
// emissive mesh in view is bright enough for its edges to be the noise.
int Renderer::Impl::emission_sample_count(const Frame& f) const {
    const RenderSettings& s = f.settings;
    if (s.emission_samples == 1 || s.samples <= 1 || forward.active() || s.light_groups > 0) return 1;
    const bool automatic = s.emission_samples == 0;
    // An emissive mesh in view (with motion blur, any: it may move into view).
    for (const MeshLight& light : emitters.lights())
        if ((s.motion_blur || f.view.contains(light.center, light.radius)) &&
            (!automatic || light.max_radiance > kAutoEmissionRadiance))
            return automatic ? kAutoEmissionSamples : s.emission_samples;
    return 1;
}

// One film sample: its camera, the G-buffer (and the data G-buffer under
// transparency), the shadow maps, the tile lists (sample 0), the forward
// layer, the lighting and the passes, then the progressive preview.
void Renderer::Impl::render_sample(Frame& f, int sample) {
    const RenderSettings& settings = f.settings;
    GpuStageTimer& gpu_timer = *f.gpu_timer;
    check_cancel();
    // Jitter: one pixel-filter offset for the whole image (sample 0: none).
    const std::array<float, 4> u = sample_point(sample);
    const double ox = f.filter.offset(u[0]), oy = f.filter.offset(u[1]);
    glm::dmat4 jitter(1.0);
    jitter[3][0] = 2.0 * ox / settings.width;  // clip.xy += offset_ndc * clip.w
    jitter[3][1] = 2.0 * oy / settings.height;
    const glm::dmat4 projection = jitter * f.cam.projection;
    f.fc.projection = to_gpu(projection);
    f.fc.jitter = {float(jitter[3][0]), float(jitter[3][1]), float(f.cam.clip_start),
                   f.emission_samples.own_share()};
    f.fc.inv_projection = to_gpu(glm::inverse(projection));
    if (settings.motion_blur) place_at_shutter_time(f, sample);
    // Where in each light-shape cell (and on the sun's disk) this sample looks.
    f.fc.sample_shift = {u[2], u[3], float(std::fmod(0.5 + sample * 0.6180339887498949, 1.0)), float(sample)};
    // Each emissive mesh's shared point this sample (its cube map's origin).
    lights.update_mesh_points(emitters, {u[2], u[3]}, settings.shadows ? &shadows : nullptr);
    // This sample's directions of the world's occlusion maps and the
    // density each pair (a map answers for the opposite direction too)
    // was drawn with: consecutive points of one low-discrepancy sequence.
    std::vector<glm::dvec4> world_dirs;
    for (int k = 0; k < shadows.world_count(); ++k) {
        const WorldDirection d =
            world_module.occlusion_direction(world_sample_point(sample * shadows.world_count() + k));
        world_dirs.emplace_back(d.dir, d.pair_pdf);
    }
    f.frame_ring->push(&f.fc);
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);

    const FrameScene::Test in_view = f.in_view();
    // resolve_only: the materials an emission sample's visibility buffer resolves (emission_samples.h).
    auto draw_gbuffer = [&](const std::vector<bool>* resolve_only = nullptr, bool data = false) {
        gbuffer.bind_for_geometry();
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_GREATER);  // reversed Z
        glDepthMask(GL_TRUE);
        glDisable(GL_CULL_FACE);  // two-sided, as Cycles
        glDisable(GL_BLEND);
        if (f.visibility) {
            f.camera_instances_drawn += f.scene.cull(in_view, false);
            visibility.draw(f.scene, materials, gbuffer, data ? f.geometry.data_skipped() : f.geometry.forward(),
                            resolve_only);
        } else {
            f.camera_instances_drawn += f.geometry.draw(f.scene, in_view, data);
        }
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    };
    // The Vector pass's share of this sample: the visible instances again,
    // against the depth of the G-buffer just drawn.
    auto draw_motion = [&] {
        if (!motion.active()) return;
        motion.bind(f.motion_program);
        gbuffer.bind_textures();
        f.scene.draw_culled(in_view, false);
        motion.end_draws();
    };
    // Emission sub-samples (emission_samples.h): the G-buffer at K - 1
    // more jitters, the emission it sees added to Combined and Emit; the
    // frame constants then go back to this sample's own.
    if (f.emission_samples.count() > 1) {
        const gpu::FrameConstants own = f.fc;
        for (int k = 1; k < f.emission_samples.count(); ++k) {
            check_cancel();
            const std::array<float, 2> v = f.emission_samples.point(sample, settings.samples, k);
            const double vx = f.filter.offset(v[0]), vy = f.filter.offset(v[1]);
            glm::dmat4 sub_jitter(1.0);
            sub_jitter[3][0] = 2.0 * vx / settings.width;
            sub_jitter[3][1] = 2.0 * vy / settings.height;
            const glm::dmat4 sub_projection = sub_jitter * f.cam.projection;
            f.fc.projection = to_gpu(sub_projection);
            f.fc.inv_projection = to_gpu(glm::inverse(sub_projection));
            f.fc.jitter.x = float(sub_jitter[3][0]);
            f.fc.jitter.y = float(sub_jitter[3][1]);
            f.frame_ring->push(&f.fc);
            f.film.begin_sample(true);
            draw_gbuffer(&f.emission_samples.emitting_materials());
            f.emission_samples.add(gbuffer);
            f.film.splat(*shaders, f.filter.splat_taps(float(vx)), f.filter.splat_taps(float(vy)), true);
        }
        f.fc = own;
        f.frame_ring->push(&f.fc);
        check_gl("emission samples");
        gpu_timer.lap(f.geometry_ms);
    }
    // The sample's scratch images, where the film splats (film_module.h).
    f.film.begin_sample();
    // The data passes' own G-buffer (Alpha Threshold coverage).
    if (f.passes.data_gbuffer() && (sample == 0 || f.passes.data_every_sample())) {
        f.geometry.set_alpha_mode(true, settings.alpha_threshold);
        if (f.visibility) visibility.set_alpha_mode(true, settings.alpha_threshold);
        draw_gbuffer(nullptr, true);
        draw_motion();
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        gpu_timer.lap(f.geometry_ms);
        f.passes.run(sample, true, gbuffer);
        f.geometry.set_alpha_mode(false, settings.alpha_threshold);
        if (f.visibility) visibility.set_alpha_mode(false, settings.alpha_threshold);
        gpu_timer.lap(f.passes_ms);
    }

    // Geometry pass, with the shader AOVs of the surfaces it holds (the
    // camera's instances are still the culled set).
    draw_gbuffer();
    f.geometry.draw_aovs(f.scene, aovs, settings.aovs, settings.samples);
    if (!f.passes.data_gbuffer()) draw_motion();
    check_gl("geometry pass");
    gpu_timer.lap(f.geometry_ms);

    // A cancel (a viewport edit waits for it) stops between stages too,
    // not only between samples: everything below is redone from scratch
    // by the next render.
    check_cancel();
    // Shadow maps from this sample's point on each shadowed light, sized
    // at sample 0 from what the visible surfaces need.
    if (!shadows.empty()) {
        if (sample == 0) fit_shadow_maps(f);
        // The maps' grid offset: the R2 sequence (Roberts 2018) over the
        // samples, apart from the light points' numbers.
        const std::array<float, 2> grid = {float(std::fmod(0.5 + sample * 0.7548776662466927, 1.0)),
                                           float(std::fmod(0.5 + sample * 0.5698402909980532, 1.0))};
        shadows.render_sample(
            *shaders, {u[2], u[3]}, grid, world_dirs,
            [&](const ShadowModule::CasterTest& casts, bool world_map, const DrawStyle& style, const FaceCulling* faces,
                GLuint alpha_program) {
                const std::uint64_t one_sided = f.scene.one_sided_instances();
                f.shadow_instances_drawn +=
                    f.geometry.draw_casters(f.scene, casts, world_map, style, faces, alpha_program);
                f.shadow_one_sided += f.scene.one_sided_instances() - one_sided;
            },
            f.caster_defines, f.geometry.stochastic_alpha() || f.casters_move);
        gpu_timer.lap(f.shadow_ms);
    }

    // Light lists, once per frame from sample 0's depth (later samples
    // fall back to every light where they see outside a tile's bounds).
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    gbuffer.bind_textures();
    lights.bind();
    if (f.culled && sample == 0) {
        culling.build(*shaders, f.tiles_x, f.tiles_y);
        gpu_timer.lap(f.culling_ms);
    }

    shadows.bind();
    ray_scene.bind();
    world_module.bind();
    emitters.bind();
    // Forward pass: Blend-mode surfaces in front of this sample's opaque
    // depth, lit by the same lights and maps, into the forward layer.
    if (forward.active()) {
        f.camera_instances_drawn += forward.draw(f.scene, f.view, [this] { check_cancel(); });
        glViewport(0, 0, settings.width, settings.height);
        forward.bind_layer();
        check_gl("forward pass");
        gpu_timer.lap(f.forward_ms);
    }

    check_cancel();
    // Lighting pass: adds this sample's share to the film.
    f.lighting.run(lights, f.culled ? &culling : nullptr, f.film,
                   settings.light_groups > 0 ? f.scene.instance_group_buffer() : 0, scene.world().light_group,
                   settings.width, settings.height, [this] { check_cancel(); });
    check_gl("lighting pass");
    gpu_timer.lap(f.lighting_ms);

    // Other passes (the data passes came from their own G-buffer above).
    f.passes.run(sample, false, gbuffer);
    if (cryptomatte.active()) {
        gbuffer.bind_textures();
        cryptomatte.accumulate(*shaders, settings.samples, unsigned((settings.width + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE),
                               unsigned((settings.height + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE));
    }
    // This sample's values into the accumulations, each pixel from its
    // neighbours' samples with the filter's weights for this jitter.
    f.film.splat(*shaders, f.filter.splat_taps(float(ox)), f.filter.splat_taps(float(oy)));
    check_gl("passes");
    gpu_timer.lap(f.passes_ms);
    preview.publish(f.preview_image, sample + 1, !pass_from_first_sample(settings.preview_pass),
                    pass_info(settings.preview_pass).channels);
    gpu_timer.lap(f.preview_ms);
}

// Sample 0: each shadowed light's map resolution from the visible surfaces
// it reaches (shadow_module.h fit()); with rays, no maps to size.
void Renderer::Impl::fit_shadow_maps(Frame& f) {
    if (f.shadow_rays) {
        shadows.fit({});
        return;
    }
    const CameraMatrices& cam = f.cam;
    std::pair<double, double> visible_depths;
    const auto receivers = visible_receivers(cam, f.settings.width, f.settings.height, visible_depths);
    if (forward.active() || f.geometry.stochastic_alpha()) {
        // Surfaces sample 0's depth may not hold: Blend-mode layers (the
        // forward pass) and stochastic alpha seen at later samples. The
        // bounding spheres of every instance in view widen the cascades'
        // range to them.
        const glm::dmat3 to_view(cam.view);
        double near = visible_depths.second > 0.0 ? visible_depths.first : 1e300;
        double far = visible_depths.second > 0.0 ? visible_depths.second : 0.0;
        for (const FrameScene::Bound& b : f.scene.bounds())
            if (f.view.contains(b.center, b.radius)) {
                const double d = -(to_view * b.center).z;
                near = std::min(near, d - b.radius);
                far = std::max(far, d + b.radius);
            }
        if (far > 0.0) visible_depths = {std::max(near, double(cam.clip_start)), far};
    }
    // Where later samples' lookups land: the frame's view volume (the
    // sample cameras' own, unless the camera moves) between the depths of
    // the bounding spheres in it (every visible surface lies in one; not
    // where something moves or deforms over the shutter, beyond its
    // sphere), and the terminator's lift.
    ShadowModule::LookupVolume lookups;
    lookups.viewplane = {f.view.left, f.view.right, f.view.bottom, f.view.top};
    lookups.depths = {cam.clip_start, cam.clip_end};
    if (!f.casters_move) {
        const glm::dmat3 to_view(cam.view);
        double near = 1e300, far = -1e300;
        for (const FrameScene::Bound& b : f.scene.bounds())
            if (f.view.contains(b.center, b.radius)) {
                const double d = -(to_view * b.center).z;
                near = std::min(near, d - b.radius);
                far = std::max(far, d + b.radius);
            }
        if (far >= near) lookups.depths = {std::max(near, double(cam.clip_start)), std::min(far, double(cam.clip_end))};
        // Where nothing moves or deforms, each visible surface lies in its
        // instance's box.
        lookups.boxes = f.scene.boxes_in_view(f.view);
    }
    lookups.lift = f.scene.terminator_lift();
    shadows.fit(receivers, visible_depths, f.camera_moves ? nullptr : &lookups,
                [&](const ShadowModule::CasterTest& casts) { return f.scene.caster_triangles(casts); });
}

// After the last sample: the resolves, the stages' times, the readback.
FrameResult Renderer::Impl::finish(Frame& f) {
    const RenderSettings& settings = f.settings;
    FrameResult& result = f.result;
    // The viewport's last image with the catchers' shadows (the samples'
    // images show them as holes).
    if (f.passes.resolve(f.plan.catchers, motion) && settings.preview_pass == Pass::Combined)
        preview.publish(f.film.combined(), settings.samples);
    f.gpu_timer->lap(f.passes_ms);

    // The stages' times (waits for the GPU once), then the readback on the CPU's clock.
    f.gpu_timer->collect(true);
    f.timer.restart();

    // --- Readback (film_module.h: one pixel pack buffer, mapped once). ---
    result.passes = f.film.read_passes();
    result.cryptomatte = cryptomatte.finish();
    result.aovs = aovs.finish();
    result.light_groups = f.film.read_light_groups();
    check_gl("readback");
    FrameTimings& t = result.timings;
    t.readback_ms = f.timer.lap_ms() + f.preview_ms;
    t.geometry_ms = f.geometry_ms;
    t.lighting_ms = f.lighting_ms;
    t.forward_ms = f.forward_ms;
    t.forward_batches = forward.active() ? forward.batches() : 0u;
    t.culling_ms = f.culling_ms;
    t.shadow_ms = f.shadow_ms;
    t.shadow_map_bytes = shadows.empty() ? 0 : shadows.map_bytes();
    t.shadowed_lights = shadows.count();
    t.shadow_resolutions = shadows.resolutions();
    t.shadow_layers_rendered = shadows.layers_rendered();
    t.shadow_texels_rendered = shadows.texels_rendered();
    t.shadow_fragments = shadows.collect_fragments();  // after the frame's last wait: no stall
    t.lighting_later_pixels = f.lighting.later_pixels();  // likewise
    t.shadow_instances_drawn = f.shadow_instances_drawn;
    t.shadow_instances_one_sided = f.shadow_one_sided;
    t.camera_instances_drawn = f.camera_instances_drawn;
    t.emission_samples = f.emission_samples.count();
    t.shadow_lights_dropped = shadows.dropped();
    t.tile_light_pairs = f.culled ? culling.last_index_count() : 0;
    t.passes_ms = f.passes_ms;
    t.programs_compiled = shaders->compile_count() - f.compiles_before;
    t.images_uploaded = materials.images_uploaded();
    t.images_reused = materials.images_reused();
    t.meshes_uploaded = scene.meshes_uploaded();
    t.meshes_reused = scene.meshes_reused();
    t.compile_ms = shaders->compile_ms() - f.compile_ms_before;
    t.programs_loaded = shaders->disk_loads() - f.loads_before;
    t.load_ms = shaders->load_ms() - f.load_ms_before;
    t.total_ms = t.upload_ms + t.shadow_ms + t.geometry_ms + t.culling_ms + t.lighting_ms + t.passes_ms + t.forward_ms +
                 t.readback_ms;
    return std::move(result);
}

namespace {
std::atomic<int> live_renderers{0};
}

Renderer::Renderer(const ContextOptions& options) : impl_(std::make_unique<Impl>()) {
    try {
        impl_->thread.run([&] { impl_->init(options); });
    } catch (...) {
        impl_.reset();  // ~Impl releases whatever init created, on the thread
        throw;
    }
    ++live_renderers;
}

Renderer::~Renderer() {
    if (impl_) --live_renderers;
}

int Renderer::live_count() { return live_renderers.load(); }

const GLInfo& Renderer::gl_info() const { return impl_->info; }

void Renderer::clear_scene() {
    impl_->thread.run([&] {
        impl_->scene.clear();
        impl_->materials.clear();
        impl_->world_graph = -1;
    });
}

void Renderer::release_scene_memory() {
    impl_->thread.run([&] {
        impl_->release_scene_memory();
        if (impl_->shaders->compiled_program_count() > max_kept_programs()) {
            impl_->shaders.reset();
            impl_->shaders.emplace();
        }
    });
}

std::uint32_t Renderer::add_mesh(const MeshData& mesh, const std::string& key) {
    return impl_->thread.run([&] { return impl_->scene.add_mesh(mesh, key); });
}

std::int64_t Renderer::find_mesh(const std::string& key) {
    return impl_->thread.run([&] { return impl_->scene.find_mesh(key); });
}

std::uint32_t Renderer::add_material(const Material& material) {
    Material m = material;
    m.graph = -1;  // graphs come through add_graph_material
    return impl_->thread.run([&] { return impl_->scene.add_material(m); });
}

std::uint32_t Renderer::add_image(const ImageData& image, const std::string& key) {
    return impl_->thread.run([&] {
        // Images count against the same memory budget as the frame's targets;
        // images kept from the previous scene and not used by this one go
        // first when the new one would not fit.
        const std::size_t bytes = std::size_t(std::max(image.width, 0)) * std::size_t(std::max(image.height, 0)) *
                                  (image.floats ? 16 : 4);
        if (impl_->materials.image_bytes() + bytes > memory_budget_bytes()) impl_->materials.release_unused();
        if (impl_->materials.image_bytes() + bytes > memory_budget_bytes())
            throw InvalidInput("image: " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                               " would take the images over the " + std::to_string(memory_budget_bytes() >> 20) +
                               " MiB budget (DEFERRED_MEMORY_BUDGET_MB)");
        return impl_->materials.add_image(image, key);
    });
}

std::int64_t Renderer::find_image(const std::string& key) {
    return impl_->thread.run([&] { return impl_->materials.find_image(key); });
}

std::uint32_t Renderer::add_graph_material(const Material& base, const MaterialGraph& graph) {
    return impl_->thread.run([&] {
        validate_material(base);
        Material m = base;
        m.mix_with = -1;
        m.mix_probability = 0.0f;
        m.graph = std::int32_t(impl_->materials.add_graph(graph));
        return impl_->scene.add_material(m);
    });
}

void Renderer::add_instances(std::uint32_t mesh_id, const double* matrices, std::size_t count,
                             const std::uint32_t* object_indices, const std::vector<std::uint32_t>& material_slots,
                             bool cast_shadow, const float* colors, const float* randoms,
                             const std::uint32_t* crypto, bool holdout, std::uint32_t light_group,
                             const float* terminator_offsets, const double* motion, bool shadow_catcher) {
    impl_->thread.run([&] {
        impl_->scene.add_instances(mesh_id, matrices, count, object_indices, material_slots, cast_shadow, colors,
                                   randoms, crypto, holdout, light_group, terminator_offsets, motion,
                                   shadow_catcher);
    });
}

void Renderer::add_light(const Light& light) {
    impl_->thread.run([&] { impl_->scene.add_light(light); });
}

void Renderer::set_world(const World& world, const MaterialGraph* graph) {
    impl_->thread.run([&] {
        impl_->scene.set_world(world);
        impl_->world_graph = graph ? std::int32_t(impl_->materials.add_graph(*graph)) : -1;
    });
}

FrameResult Renderer::render(const Camera& camera, const RenderSettings& settings) {
    impl_->cancel_requested = false;
    return impl_->thread.run([&] { return impl_->render(camera, settings); });
}

void Renderer::cancel() { impl_->cancel_requested = true; }

bool Renderer::preview(std::uint64_t since, PreviewImage& out) const { return impl_->preview.take(since, out); }

}  // namespace deferred
