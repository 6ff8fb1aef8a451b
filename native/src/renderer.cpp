// Renderer: owns every module (EEVEE Next's Instance pattern) and runs the
// frame: sync scene -> geometry pass (G-buffer) -> lighting (compute) ->
// passes (compute) -> readback. All GL work happens on the render thread.
#include <deferred/renderer.h>

#include "aov_module.h"
#include "camera.h"
#include "cryptomatte_module.h"
#include "egl_context.h"
#include "emitter_module.h"
#include "film.h"
#include "film_module.h"
#include "forward_module.h"
#include "gbuffer.h"
#include "gl_util.h"
#include "light_culling.h"
#include "light_module.h"
#include "material_module.h"
#include "motion_module.h"
#include "progressive_preview.h"
#include "render_thread.h"
#include "scene_store.h"
#include "shader_library.h"
#include "ray_scene.h"
#include "shadow_module.h"
#include "world_module.h"

#include "../../shaders/shader_defines.h"
#include "../../shaders/shader_shared.h"

#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>

namespace deferred {

namespace {

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
// GpuMaterial.base_diffuse.w of a Holdout material (the closure model codes
// of gbuffer_lib.glsl end at 3); geometry_frag.glsl turns it into a hole.
constexpr float kClosureHoldout = 4.0f;
// Light groups per render (layers of the accumulation, LIGHT_GROUPS sums in
// the lighting pass's registers).
constexpr int kMaxLightGroups = 32;
// Below this many lights, building tile lists costs more than it saves
// (deferred_bench_lights: 1 light 117 ms culled vs 38 ms brute force,
// 16 lights 90 vs 225 ms, at 480x270 on llvmpipe).
constexpr std::uint32_t kCullingMinLights = 8;
// Occlusion directions (maps) per film sample for a world map (world_module.h).
constexpr int kWorldMapOcclusionDirections = 4;

gpu::mat4 to_gpu(const glm::dmat4& m) {
    gpu::mat4 r{};
    for (int c = 0; c < 4; ++c)
        r.cols[c] = {float(m[c][0]), float(m[c][1]), float(m[c][2]), float(m[c][3])};
    return r;
}

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
            gbuffer = GBuffer();
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
            shaders.reset();
            empty_vao.reset();
            dummy_ssbo.reset();
            context.reset();
        });
    }

    void init(const ContextOptions& options) {
        context = std::make_unique<EglContext>(options.device_index);
        info.vendor = gl_string(GL_VENDOR);
        info.renderer = gl_string(GL_RENDERER);
        info.version = gl_string(GL_VERSION);
        info.display = context->display_description();
        info.device_note = context->device_note();
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

    FrameResult render(const Camera& camera, const RenderSettings& settings);

    // The visible surfaces the shadow maps are sized for: sample 0's depth
    // (unjittered pixel centres) read back on a grid of at most 128 x 128
    // points, as camera-relative positions with the width of a pixel there.
    // `visible_depths` gets the nearest and farthest view depth of all the
    // pixels that see a surface ((0, 0) if none does).
    std::vector<ShadowModule::Receiver> visible_receivers(const CameraMatrices& cam, int width, int height,
                                                          std::pair<double, double>& visible_depths) const {
        std::vector<float> depth(std::size_t(width) * std::size_t(height));
        glGetTextureImage(gbuffer.depth_texture(), 0, GL_DEPTH_COMPONENT, GL_FLOAT,
                          GLsizei(depth.size() * sizeof(float)), depth.data());
        check_gl("reading the depth for shadow map sizes");
        const glm::dmat4 to_view = glm::inverse(cam.projection);
        // Reversed Z: the largest stored value is the nearest surface.
        float z_near = 0.0f, z_far = 2.0f;
        for (float z : depth)
            if (z > 0.0f) {
                z_near = std::max(z_near, z);
                z_far = std::min(z_far, z);
            }
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
        const int step = std::max(1, std::max(width, height) / 128);
        std::vector<ShadowModule::Receiver> out;
        for (int y = step / 2; y < height; y += step)
            for (int x = step / 2; x < width; x += step) {
                const double z = depth[std::size_t(y) * std::size_t(width) + std::size_t(x)];
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

namespace {
// Passes Cycles takes from the first sample, unfiltered; the others are
// averaged over the film's samples like Combined.
bool pass_from_first_sample(Pass p) {
    return p == Pass::Depth || p == Pass::Position || p == Pass::IndexOB || p == Pass::IndexMA;
}
}  // namespace

FrameResult Renderer::Impl::render(const Camera& camera_in, const RenderSettings& settings) {
    const PassSet& wanted = settings.passes;
    GBufferFeatures features;
    for (const Material& m : scene.materials())
        if (m.graph < 0 && (m.sheen > 1e-5f || m.clearcoat > 1e-5f)) features.params1 = true;
    if (materials.uses_params1()) features.params1 = true;
    // Shadow maps compare against the true normal's plane and move the
    // receiver by its terminator offset (geometry target), as do bent closures.
    features.geometry = materials.uses_smooth_normal() || settings.shadows;
    features.ids = wanted.contains(Pass::IndexOB) || wanted.contains(Pass::IndexMA);
    features.uv = wanted.contains(Pass::UV);
    features.instance_ids = !settings.cryptomatte.empty() || settings.light_groups > 0;
    const bool light_split = wanted.contains(Pass::DiffDir) || wanted.contains(Pass::GlossDir);
    const bool shadow_pass = wanted.contains(Pass::Shadow);
    if (settings.samples < 1 || settings.samples > 65536)
        throw InvalidInput("samples must be in 1..65536, got " + std::to_string(settings.samples));
    if (!(settings.filter_width > 0.0f && settings.filter_width <= 100.0f))
        throw InvalidInput("filter_width must be in (0, 100] pixels");
    if (!(settings.light_threshold >= 0.0f) || !std::isfinite(settings.light_threshold))
        throw InvalidInput("light_threshold must be a finite number >= 0");
    if (settings.light_samples < 0 || settings.light_samples > 65536)
        throw InvalidInput("light_samples must be in 0..65536 (0: every light), got " +
                           std::to_string(settings.light_samples));
    if (!(settings.alpha_threshold >= 0.0f && settings.alpha_threshold <= 1.0f))
        throw InvalidInput("alpha_threshold must be in [0, 1]");
    if (!(settings.shadow_quality > 0.0f && settings.shadow_quality <= 16.0f))
        throw InvalidInput("shadow_quality must be in (0, 16] texels per pixel");
    if (!std::isfinite(settings.mist.start) || !std::isfinite(settings.mist.depth))
        throw InvalidInput("mist start/depth must be finite");

    // Memory check before any allocation: G-buffer (depth 4, emission 16,
    // base 8, params0 8, normal 4, optional params1 8, ids 8, uv 8), the
    // Combined accumulation (16), light split (32), one RGBA32F image per
    // other pass (16) and the CPU copies of the passes.
    const std::size_t pixels = std::size_t(settings.width > 0 ? settings.width : 0) *
                               std::size_t(settings.height > 0 ? settings.height : 0);
    std::size_t per_pixel = 4 + 16 + 8 + 8 + 4 + (features.params1 ? 8 : 0) + (features.ids ? 8 : 0) +
                            (features.uv ? 8 : 0) + (features.geometry ? 16 : 0) + 16 + (light_split ? 32 : 0) + (shadow_pass ? 16 : 0);
    for (Pass p : wanted.list()) per_pixel += (p == Pass::Combined ? 0 : 16) + 4 * std::size_t(pass_info(p).channels);
    if (features.instance_ids) per_pixel += 16;  // the ids target grows to RGBA32UI
    if (settings.light_groups < 0 || settings.light_groups > kMaxLightGroups)
        throw InvalidInput("light_groups must be in 0.." + std::to_string(kMaxLightGroups) + ", got " +
                           std::to_string(settings.light_groups));
    per_pixel += 16 * std::size_t(settings.light_groups) + (settings.light_groups > 0 ? 16 : 0);
    // Shadow catchers (lighting_comp.glsl SHADOW_CATCHER): their light kept
    // apart (two RGBA32F accumulations); Combined becomes the matte.
    bool catchers = false;
    for (const InstanceBatch& b : scene.batches())
        if (b.shadow_catcher && !b.object_indices.empty()) catchers = true;
    if (catchers) per_pixel += 32;
    check_settings(settings, pixels * per_pixel + 2 * CryptomatteModule::bytes(settings) + AovModule::bytes(settings) +
                                 (wanted.contains(Pass::Vector) ? MotionModule::bytes(settings) : 0));

    FrameResult result;
    StageTimer timer;
    const std::size_t compiles_before = shaders->compile_count();
    const double compile_ms_before = shaders->compile_ms();
    const std::size_t loads_before = shaders->disk_loads();
    const double load_ms_before = shaders->load_ms();
    const CameraMatrices cam = build_camera(camera_in, settings.width, settings.height);

    // --- Sync: pack per-frame buffers, camera-relative in double. ---
    std::vector<gpu::GpuInstance> instances;
    instances.reserve(scene.instance_count());
    // Camera-relative bounding sphere of every instance (shadow-map culling).
    struct Bound { glm::dvec3 center; double radius; };
    std::vector<Bound> bounds;
    bounds.reserve(scene.instance_count());
    std::vector<std::uint32_t> slots;
    std::vector<std::uint32_t> crypto_instances;  // object and asset hash per instance (Cryptomatte)
    std::vector<std::uint32_t> instance_groups;   // light group per instance (light-group passes)
    // One per batch: its instances [first, first + count) and its slot map.
    struct Draw { std::uint32_t mesh, first, count; bool cast_shadow; std::uint32_t slot_offset, slot_count; };
    std::vector<Draw> draws;
    // An instance's world matrix -> its camera-relative model, normal matrix,
    // mirrored flag (ids.w bit 0) and bounding sphere.
    auto place = [&](const glm::dmat4& world, const GpuMesh& mesh, gpu::GpuInstance& g, Bound& bound) {
        glm::dmat4 model = world;
        model[3] = glm::dvec4(glm::dvec3(model[3]) - cam.position, 1.0);
        const glm::dmat3 linear(model);
        const double det = glm::determinant(linear);
        const double scale = std::max({glm::length(linear[0]), glm::length(linear[1]), glm::length(linear[2])});
        bound = {glm::dvec3(model * glm::dvec4(mesh.bound_center[0], mesh.bound_center[1], mesh.bound_center[2], 1.0)),
                 mesh.bound_radius * scale};
        const glm::dmat3 nm = std::abs(det) > 1e-300 ? glm::transpose(glm::inverse(linear)) : glm::dmat3(1.0);
        g.model = to_gpu(model);
        g.normal_matrix = to_gpu(glm::dmat4(nm));
        g.ids.w = (g.ids.w & ~1u) | (det < 0 ? 1u : 0u);
    };
    // Motion blur (motion_module.h): the instances that move over the
    // shutter, with their three steps in world space; each sample places
    // them at its time. Deforming meshes move in the vertex stage.
    struct MovingInstance { std::size_t index; glm::dmat4 steps[3]; std::uint32_t mesh; };
    std::vector<MovingInstance> moving;
    bool deforming = false;
    for (const InstanceBatch& b : scene.batches()) {
        const std::uint32_t slot_offset = static_cast<std::uint32_t>(slots.size());
        slots.insert(slots.end(), b.material_slots.begin(), b.material_slots.end());
        const std::size_t n = b.object_indices.size();
        draws.push_back({b.mesh_id, static_cast<std::uint32_t>(instances.size()), static_cast<std::uint32_t>(n),
                         b.cast_shadow, slot_offset, static_cast<std::uint32_t>(b.material_slots.size())});
        const GpuMesh& mesh = scene.meshes()[b.mesh_id];
        if (settings.motion_blur && (mesh.flags & 8u) != 0u) deforming = true;
        for (std::size_t i = 0; i < n; ++i) {
            Mat4d m;
            std::copy(b.matrices.begin() + long(i * 16), b.matrices.begin() + long(i * 16 + 16), m.begin());
            const glm::dmat4 world = to_glm(m);
            gpu::GpuInstance g{};
            g.ids = {b.object_indices[i], slot_offset, static_cast<std::uint32_t>(b.material_slots.size()),
                     (b.holdout ? 2u : 0u) | (b.shadow_catcher ? 4u : 0u)};
            Bound bound;
            place(world, mesh, g, bound);
            bounds.push_back(bound);
            if (settings.motion_blur && !b.motion.empty()) {
                MovingInstance mi{instances.size(), {world, world, world}, b.mesh_id};
                for (int step = 0; step < 2; ++step) {
                    std::copy(b.motion.begin() + long(i * 32 + std::size_t(step) * 16),
                              b.motion.begin() + long(i * 32 + std::size_t(step) * 16 + 16), m.begin());
                    mi.steps[step == 0 ? 0 : 2] = to_glm(m);
                }
                if (mi.steps[0] != world || mi.steps[2] != world) moving.push_back(mi);
            }
            g.color = {b.colors[i * 4], b.colors[i * 4 + 1], b.colors[i * 4 + 2], b.colors[i * 4 + 3]};
            g.info = {b.randoms[i], b.terminator_offsets[i], 0.0f, 0.0f};
            instances.push_back(g);
            if (!settings.cryptomatte.empty())
                crypto_instances.insert(crypto_instances.end(), {b.crypto[2 * i], b.crypto[2 * i + 1]});
            if (settings.light_groups > 0) instance_groups.push_back(b.light_group);
        }
    }
    // Motion blur moves something: the shadow casters (instances, deforming
    // meshes) or only the camera.
    const bool casters_move = settings.motion_blur && (!moving.empty() || deforming);
    const bool camera_moves = settings.motion_blur && camera_in.has_motion;
    std::vector<gpu::GpuMaterial> gpu_materials;
    for (const Material& m : scene.materials()) {
        gpu::GpuMaterial g{};
        // The closure model (gbuffer_lib.glsl): -1 Principled, 0..1 Diffuse
        // BSDF (Oren-Nayar sigma), 1 + glossy_model for a Glossy BSDF.
        g.base_diffuse = {m.base_color[0], m.base_color[1], m.base_color[2],
                          m.glossy_model > 0 ? 1.0f + float(m.glossy_model)
                          : m.diffuse_roughness < 0.0f ? -1.0f : std::min(m.diffuse_roughness, 1.0f)};
        g.params0 = {m.metallic, m.roughness, m.specular, m.specular_tint};
        g.params1 = {m.sheen, m.sheen_tint, m.clearcoat, m.clearcoat_roughness};
        g.emission = {m.emission[0] * m.emission_strength, m.emission[1] * m.emission_strength,
                      m.emission[2] * m.emission_strength, float(m.pass_index)};
        const float constants = m.graph >= 0 ? float(materials.constants_offset(std::uint32_t(m.graph))) : 0.0f;
        g.mix = {float(m.mix_with), m.mix_probability, constants, m.alpha};
        if (m.holdout) g.base_diffuse.w = kClosureHoldout;
        gpu_materials.push_back(g);
    }
    // Updated every sample when instances move (storage without data is dynamic).
    Buffer instance_buffer = make_storage_buffer(moving.empty() ? instances.data() : nullptr,
                                                 instances.size() * sizeof(gpu::GpuInstance), "instances");
    if (!moving.empty())
        glNamedBufferSubData(instance_buffer.get(), 0, GLsizeiptr(instances.size() * sizeof(gpu::GpuInstance)),
                             instances.data());
    Buffer slot_buffer = make_storage_buffer(slots.data(), slots.size() * sizeof(std::uint32_t), "material slots");
    Buffer material_buffer = make_storage_buffer(gpu_materials.data(), gpu_materials.size() * sizeof(gpu::GpuMaterial), "materials");
    this->materials.upload_constants();
    {
        std::vector<std::uint32_t> crypto_materials;
        if (!settings.cryptomatte.empty())
            for (const Material& m : scene.materials()) crypto_materials.push_back(m.crypto);
        cryptomatte.begin(settings, crypto_instances, crypto_materials);
    }
    // Shadow rays, unless a shadow-casting node material drives alpha (a ray
    // cannot evaluate its graph) or the ray scene outgrows a storage block:
    // then maps, warned (once something casts shadows).
    bool shadow_rays = settings.shadows && settings.shadow_rays;
    std::string rays_fallback;
    if (shadow_rays) {
        for (const InstanceBatch& b : scene.batches()) {
            if (!b.cast_shadow || !rays_fallback.empty()) continue;
            for (std::uint32_t id : b.material_slots) {
                // The slot's material and its mix chain.
                for (std::int64_t k = id, n = 0; k >= 0 && n < 16; ++n) {
                    const Material& m = scene.materials()[std::size_t(k)];
                    if (m.graph >= 0 && this->materials.alpha(std::uint32_t(m.graph))) {
                        const std::string& name = this->materials.name(std::uint32_t(m.graph));
                        rays_fallback = "Shadow rays cannot evaluate the alpha of node material '" +
                                        (name.empty() ? std::string("?") : name) + "': this render uses shadow maps";
                    }
                    k = m.mix_with;
                }
            }
        }
        // Moving instances are placed in the ray scene each sample; a
        // mesh's hierarchy is built from its vertices at the middle of the
        // shutter, so deforming ones cannot follow.
        if (rays_fallback.empty() && deforming)
            rays_fallback = "Shadow rays do not follow deforming meshes under motion blur yet: this render uses "
                            "shadow maps";
        shadow_rays = rays_fallback.empty();
    }
    // The ray scene: every shadow-casting instance, with its slots' alphas
    // (constant materials; a mix chain averaged, as material_alpha_lib.glsl).
    std::vector<RayScene::Instance> casters;
    std::vector<std::int64_t> caster_of_instance;  // instance -> its entry in casters, -1: casts nothing
    if (shadow_rays) {
        StageTimer ray_timer;
        auto chain_alpha = [&](std::uint32_t id) {
            float alpha = 0.0f, weight = 1.0f;
            const gpu::GpuMaterial* m = &gpu_materials[id];
            for (int k = 0; k < 16; ++k) {
                const float p = m->mix.x >= 0.0f ? m->mix.y : 0.0f;
                alpha += weight * (1.0f - p) * m->mix.w;
                weight *= p;
                if (m->mix.x < 0.0f) break;
                m = &gpu_materials[std::size_t(m->mix.x)];
            }
            return alpha + weight * m->mix.w;
        };
        caster_of_instance.assign(instances.size(), -1);
        std::size_t first_instance = 0;
        for (const InstanceBatch& b : scene.batches()) {
            const std::size_t batch_first = first_instance;
            first_instance += b.object_indices.size();
            if (!b.cast_shadow) continue;
            const GpuMesh& mesh = scene.meshes()[b.mesh_id];
            if (mesh.triangle_count == 0) continue;
            std::vector<float> slot_alpha;
            for (std::uint32_t id : b.material_slots) slot_alpha.push_back(chain_alpha(id));
            const std::shared_ptr<const MeshBvh> bvh = mesh_bvh(mesh);
            for (std::size_t i = 0; i < b.object_indices.size(); ++i) {
                Mat4d m;
                std::copy(b.matrices.begin() + long(i * 16), b.matrices.begin() + long(i * 16 + 16), m.begin());
                glm::dmat4 model = to_glm(m);
                model[3] = glm::dvec4(glm::dvec3(model[3]) - cam.position, 1.0);
                caster_of_instance[batch_first + i] = std::int64_t(casters.size());
                casters.push_back({bvh, model, slot_alpha});
            }
        }
        ray_scene.build(casters);
        GLint64 max_block = 0;
        glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
        if (max_block > 0 && ray_scene.bytes() > std::size_t(max_block)) {
            rays_fallback = "Shadow rays: the scene's " + std::to_string(ray_scene.triangles()) + " triangles need " +
                            std::to_string(ray_scene.bytes() >> 20) + " MiB, over this GPU's " +
                            std::to_string(max_block >> 20) + " MiB storage block: this render uses shadow maps";
            ray_scene.release();
            shadow_rays = false;
        } else {
            ray_scene.upload();
        }
        result.timings.ray_build_ms = ray_timer.lap_ms();
    }
    shadows.begin_frame(cam, settings.shadow_resolution, settings.shadow_quality, memory_budget_bytes() / 4,
                        shadow_rays);
    // A world node tree: baked into its environment map (with the sampling
    // distribution) before anything asks whether the world lights the scene.
    // The bake reads the camera (Camera and Window texture coordinates) from the frame block.
    // The frame block of the bakes (world, emission): the unjittered camera,
    // for Camera and Window coordinates and the Bump's differential.
    auto make_bake_frame = [&]() {
        gpu::FrameConstants f{};
        f.view = to_gpu(cam.view);
        f.projection = to_gpu(cam.projection);
        f.camera_position = {float(cam.position.x), float(cam.position.y), float(cam.position.z),
                             cam.orthographic ? 1.0f : 0.0f};
        f.viewport = {float(settings.width), float(settings.height), 1.0f / float(settings.width),
                      1.0f / float(settings.height)};
        return make_storage_buffer(&f, sizeof(f), "bake frame");
    };
    // A mesh's buffers for vertex pulling (geometry_vert.glsl).
    auto bind_mesh = [&](const GpuMesh& mesh) {
        auto bind = [&](GLuint slot, const Buffer& b) {
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot, b ? b.get() : dummy_ssbo.get());
        };
        bind(SSBO_POSITIONS, mesh.positions);
        bind(SSBO_INDICES, mesh.indices);
        bind(SSBO_NORMALS, mesh.normals);
        bind(SSBO_UVS, mesh.uvs);
        bind(SSBO_MATERIAL_INDICES, mesh.material_indices);
        bind(SSBO_MOTION_POSITIONS, mesh.motion_positions);
    };
    {
        Buffer bake_buffer = make_bake_frame();
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
    const bool ao_pass = wanted.contains(Pass::AO);
    // A world map (an HDRI) gets several occlusion directions per sample:
    // each map is one draw of the casters, while one direction shared by
    // every pixel leaves correlated noise that dominates the error (the
    // hdri_studio report); a constant world keeps one.
    const int world_maps = world_module.has_map() ? kWorldMapOcclusionDirections : 1;
    if (settings.shadows && (world_lights || ao_pass) && scene.instance_count() > 0) shadows.offer_world(world_maps);
    // Emissive meshes become lights (emitter_module.h); the triangles of
    // node materials whose emission varies are baked with their graphs.
    emitters.sync(scene, cam.position);
    if (emitters.needs_bake()) {
        Buffer bake_buffer = make_bake_frame();
        glBindBufferBase(GL_UNIFORM_BUFFER, UBO_FRAME, bake_buffer.get());
        glBindVertexArray(empty_vao.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_INSTANCES, instance_buffer.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_MATERIAL_SLOTS, slot_buffer.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_MATERIALS, material_buffer.get());
        this->materials.bind_constants();
        try {
            result.timings.emission_bake_ms = emitters.bake(
                *shaders, this->materials, [&](const EmissionBakeRun& run, GLuint) {
                    const GpuMesh& mesh = scene.meshes()[run.mesh];
                    bind_mesh(mesh);
                    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_ATTRIBUTES,
                                     mesh.attributes ? mesh.attributes.get() : dummy_ssbo.get());
                    this->materials.bind_for_draw(run.graph, mesh);
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
    lights.sync(scene.lights(), cam.position, settings.light_threshold, settings.shadows ? &shadows : nullptr,
                &emitters);
    // (Not with a moving camera: the tiles' light lists come from sample 0's view.)
    const bool culled = settings.light_culling && lights.count() >= kCullingMinLights && !camera_moves;
    if (!rays_fallback.empty() && !shadows.empty()) result.warnings.push_back(rays_fallback);
    // Nothing casts a shadow: no rays either.
    shadow_rays = shadow_rays && !shadows.empty();
    if (shadow_rays) {
        result.timings.ray_scene_bytes = ray_scene.bytes();
        result.timings.ray_triangles = ray_scene.triangles();
    } else {
        ray_scene.release();
    }
    result.timings.shadow_rays = shadow_rays;

    gpu::FrameConstants fc{};
    fc.view = to_gpu(cam.view);
    fc.inv_view = to_gpu(glm::inverse(cam.view));
    fc.camera_position = {float(cam.position.x), float(cam.position.y), float(cam.position.z),
                          cam.orthographic ? 1.0f : 0.0f};
    fc.world_color = {world.color[0], world.color[1], world.color[2], settings.film_transparent ? 1.0f : 0.0f};
    fc.viewport = {float(settings.width), float(settings.height), 1.0f / float(settings.width),
                   1.0f / float(settings.height)};
    const float mist_depth = settings.mist.depth > 0 ? settings.mist.depth : 1e-6f;
    fc.mist = {settings.mist.start, 1.0f / mist_depth, float(static_cast<std::uint32_t>(settings.mist.falloff)), 0};
    fc.counts = {lights.count(), wanted.bits(), kLightShapePoints, std::uint32_t(settings.samples)};
    const PixelFilter filter(settings.filter_width);
    const std::uint32_t tiles_x = std::uint32_t((settings.width + TILE_SIZE - 1) / TILE_SIZE);
    const std::uint32_t tiles_y = std::uint32_t((settings.height + TILE_SIZE - 1) / TILE_SIZE);
    // How far (whole pixels) a jittered sample can look from its pixel centre.
    const std::uint32_t reach = settings.samples > 1 ? std::uint32_t(std::ceil(filter.support())) : 0u;
    fc.tiles = {tiles_x, tiles_y, culled ? 1u : 0u, reach};
    fc.world_occlusion = {float(shadows.world_index()), float(shadows.world_count()), float(world_module.width()),
                          float(world_module.height())};
    // The frame constants, new each sample: a ring of slots in a persistently
    // mapped buffer (gl_util.h UniformRing), so updating them never waits
    // for the samples still in flight.
    UniformRing frame_ring(sizeof(fc), 4, UBO_FRAME, "frame constants");
    frame_ring.push(&fc);

    // --- Targets: the per-sample G-buffer, the accumulations (the film). ---
    gbuffer.ensure(settings.width, settings.height, features);
    FilmModule film;
    {
        FilmModule::Layout layout;
        layout.width = settings.width;
        layout.height = settings.height;
        for (Pass p : wanted.list())
            if (p != Pass::Combined) layout.passes.push_back(p);
        layout.light_split = light_split;
        layout.shadow_pass = shadow_pass;
        layout.catchers = catchers;
        layout.light_groups = settings.light_groups;
        film.allocate(layout);
    }
    // Each instance's light group.
    Buffer instance_group_buffer;
    if (settings.light_groups > 0) {
        const std::uint32_t none = 0;
        instance_group_buffer = instance_groups.empty()
            ? make_storage_buffer(&none, 4, "instance light groups")
            : make_storage_buffer(instance_groups.data(), instance_groups.size() * 4, "instance light groups");
    }
    result.timings.gbuffer_bytes = gbuffer.bytes() + film.bytes();

    // Variants: which G-buffer targets exist, which light types are present.
    ShaderVariant base_variant;
    if (features.params1) base_variant.defines.push_back("GBUF_PARAMS1");
    if (features.ids) base_variant.defines.push_back("GBUF_IDS");
    if (features.instance_ids) base_variant.defines.push_back("GBUF_INSTANCE_IDS");
    if (features.uv) base_variant.defines.push_back("GBUF_UV");
    if (features.geometry) base_variant.defines.push_back("GBUF_GEOMETRY");
    // Stochastic transparency, only when some constant material is partly
    // transparent (node materials carry their own switch, MATERIAL_ALPHA).
    bool scene_alpha = false;
    for (const Material& m : scene.materials())
        if (m.graph < 0 && m.alpha < 1.0f) scene_alpha = true;
    std::vector<std::string> caster_defines;
    if (scene_alpha) caster_defines.push_back("SCENE_ALPHA");
    ShaderVariant lighting_variant = base_variant;
    lights.add_defines(lighting_variant);
    if (light_split) lighting_variant.defines.push_back("OUT_LIGHT_SPLIT");
    if (culled) lighting_variant.defines.push_back("LIGHT_CULLING");
    // Selection only where some pixel can have more lights than the budget,
    // within one lighting dispatch (512 lights, 8 with shadow rays): a budget
    // of a dispatch's size or more never selects.
    const std::uint32_t light_dispatch = shadow_rays ? kRayLightBatch : kLightBatch;
    const bool light_sampling = settings.light_samples > 0 && lights.count() > std::uint32_t(settings.light_samples) &&
                                std::uint32_t(settings.light_samples) < light_dispatch;
    if (light_sampling) lighting_variant.defines.push_back("LIGHT_SAMPLING " + std::to_string(settings.light_samples));
    if (settings.light_samples > 0 && !light_sampling && lights.count() > std::uint32_t(settings.light_samples))
        result.warnings.push_back("Light Samples " + std::to_string(settings.light_samples) +
                                  " has no effect: the lighting runs in groups of " + std::to_string(light_dispatch) +
                                  " lights" + (shadow_rays ? " with shadow rays" : "") +
                                  ", and a budget that large never selects; every light is shaded");
    if (!shadows.empty()) lighting_variant.defines.push_back("HAS_SHADOWS");
    if (shadow_rays) lighting_variant.defines.push_back("SHADOW_RAYS");
    if (shadows.world_index() >= 0) lighting_variant.defines.push_back("HAS_WORLD_OCCLUSION");
    world_module.add_defines(lighting_variant);
    if (ao_pass) lighting_variant.defines.push_back("OUT_AO");
    if (settings.light_groups > 0)
        lighting_variant.defines.push_back("LIGHT_GROUPS " + std::to_string(settings.light_groups));
    if (shadow_pass) lighting_variant.defines.push_back("OUT_SHADOW");
    if (catchers) lighting_variant.defines.push_back("SHADOW_CATCHER");
    ShaderVariant geometry_variant = base_variant;
    if (scene_alpha) geometry_variant.defines.push_back("SCENE_ALPHA");
    const GLuint geometry = shaders->graphics_program("geometry_vert.glsl", "geometry_frag.glsl", geometry_variant);
    auto pass_program = [&](Pass p, const char* mode) {
        ShaderVariant v = base_variant;
        v.defines.push_back("PASS_ID " + std::to_string(static_cast<int>(p)));
        if (mode) v.defines.push_back(mode);
        if (p == Pass::Env) world_module.add_defines(v);
        return shaders->compute_program("passes_comp.glsl", v);
    };
    check_gl("frame sync");
    result.timings.upload_ms = timer.lap_ms();

    const GLuint groups_x = GLuint((settings.width + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    const GLuint groups_y = GLuint((settings.height + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    double geometry_ms = 0, lighting_ms = 0, passes_ms = 0, culling_ms = 0, shadow_ms = 0, forward_ms = 0;

    auto bind_scene_buffers = [&]() {
        glBindVertexArray(empty_vao.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_INSTANCES, instance_buffer.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_MATERIAL_SLOTS, slot_buffer.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_MATERIALS, material_buffer.get());
    };
    // The instances whose bounding sphere passes `keep`, drawn with the
    // currently bound program through the remap buffer (geometry_vert.glsl):
    // the geometry pass keeps what the camera can see, each shadow map what
    // can cast into it (casters_only: without the cast_shadow-off ones).
    std::vector<std::uint32_t> remap;
    Buffer remap_buffer;
    std::size_t remap_capacity = 0;
    std::uint64_t shadow_instances_drawn = 0, camera_instances_drawn = 0;
    struct Culled { const Draw* draw; std::uint32_t first, count; };
    std::vector<Culled> visible;
    // Fills `visible` and the remap buffer with the instances that pass `keep`.
    auto cull = [&](const ShadowModule::CasterTest& keep, bool casters_only) -> std::uint64_t {
        remap.clear();
        visible.clear();
        for (const Draw& d : draws) {
            if ((casters_only && !d.cast_shadow) || scene.meshes()[d.mesh].triangle_count == 0) continue;
            const std::uint32_t first = std::uint32_t(remap.size());
            for (std::uint32_t i = d.first; i < d.first + d.count; ++i)
                if (keep(bounds[i].center, bounds[i].radius)) remap.push_back(i);
            if (remap.size() > first) visible.push_back({&d, first, std::uint32_t(remap.size()) - first});
        }
        if (visible.empty()) return 0;
        if (remap.size() > remap_capacity) {
            remap_capacity = std::max<std::size_t>(remap.size(), instances.size());
            remap_buffer = make_storage_buffer(nullptr, remap_capacity * sizeof(std::uint32_t), "instance remap");
        }
        glNamedBufferSubData(remap_buffer.get(), 0, GLsizeiptr(remap.size() * sizeof(std::uint32_t)), remap.data());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_INSTANCE_REMAP, remap_buffer.get());
        bind_scene_buffers();
        return remap.size();
    };
    // Draws triangles [first, first + count) of the visible instances of one batch.
    auto draw_range = [&](const Culled& c, std::uint32_t first, std::uint32_t count) {
        if (count == 0) return;
        const GpuMesh& mesh = scene.meshes()[c.draw->mesh];
        bind_mesh(mesh);
        glUniform1ui(0, c.first);
        glUniform1ui(1, mesh.flags);
        glDrawArraysInstanced(GL_TRIANGLES, GLint(first * 3), GLsizei(count * 3), GLsizei(c.count));
    };
    auto draw_culled = [&](const ShadowModule::CasterTest& keep, bool casters_only) -> std::uint64_t {
        const std::uint64_t n = cull(keep, casters_only);
        for (const Culled& c : visible) draw_range(c, 0, scene.meshes()[c.draw->mesh].triangle_count);
        return n;
    };
    // The material drawing slot s of a batch.
    auto slot_material_id = [&](const Draw& d, std::size_t s) -> std::uint32_t {
        const std::uint32_t slot = std::uint32_t(std::min<std::size_t>(s, std::max(d.slot_count, 1u) - 1));
        return slots[d.slot_offset + slot];
    };
    auto slot_material = [&](const Draw& d, std::size_t s) -> const Material& {
        return scene.materials()[slot_material_id(d, s)];
    };
    // Node-material programs, compiled before the first sample (a graph
    // used by no visible slot still compiles: the set is the scene's).
    std::vector<std::pair<std::uint32_t, GLuint>> graph_programs;  // material id -> program
    std::vector<bool> graph_failed(scene.materials().size(), false);
    for (std::uint32_t id = 0; id < scene.materials().size(); ++id) {
        if (scene.materials()[id].graph < 0) continue;
        try {
            graph_programs.emplace_back(
                id, this->materials.program(*shaders, std::uint32_t(scene.materials()[id].graph), base_variant));
        } catch (const Error& e) {
            // Never a failed frame for one material: it takes the default
            // surface (its GpuMaterial holds Material's defaults).
            graph_failed[id] = true;
            const std::string& name = this->materials.name(std::uint32_t(scene.materials()[id].graph));
            result.warnings.push_back("Material '" + (name.empty() ? std::to_string(id) : name) +
                                      "': its node graph did not compile (default surface used): " + e.what());
        }
    }
    {
        std::vector<GLuint> distinct;
        for (auto& [id, p] : graph_programs)
            if (std::find(distinct.begin(), distinct.end(), p) == distinct.end()) distinct.push_back(p);
        result.timings.material_programs = distinct.size();
    }
    result.timings.upload_ms += timer.lap_ms();  // compiling stays out of the geometry pass's time
    // From here to the readback the stages are timed on the GPU's clock:
    // no glFinish inside the sample loop.
    GpuStageTimer gpu_timer;
    // Node materials whose alpha can be below 1 (their program discards).
    auto is_alpha_graph = [&](std::uint32_t id) {
        const Material& m = scene.materials()[id];
        return m.graph >= 0 && !graph_failed[id] && this->materials.alpha(std::uint32_t(m.graph));
    };
    bool alpha_graphs = false;
    for (auto& [id, program] : graph_programs)
        if (is_alpha_graph(id)) alpha_graphs = true;
    // Blend-mode materials (Material::blend): drawn by the forward pass, not
    // into the G-buffer. Each gets its forward program now; one that does not
    // compile stays in the stochastic path, warned.
    ShaderVariant forward_variant;
    lights.add_defines(forward_variant);
    if (!shadows.empty()) forward_variant.defines.push_back("HAS_SHADOWS");
    if (shadow_rays) forward_variant.defines.push_back("SHADOW_RAYS");
    if (shadows.world_index() >= 0) forward_variant.defines.push_back("HAS_WORLD_OCCLUSION");
    world_module.add_defines(forward_variant);
    forward_variant.defines.push_back("FORWARD_PASS");
    forward_variant.defines.push_back("FORWARD_MAX_LIGHTS " + std::to_string(kLightBatch));
    std::map<std::uint32_t, GLuint> forward_programs;  // material id -> its forward program
    for (std::uint32_t id = 0; id < scene.materials().size(); ++id) {
        const Material& m = scene.materials()[id];
        if (!m.blend) continue;
        try {
            forward_programs[id] = m.graph >= 0 && !graph_failed[id]
                ? this->materials.program(*shaders, std::uint32_t(m.graph), forward_variant)
                : shaders->graphics_program("geometry_vert.glsl", "geometry_frag.glsl", forward_variant);
        } catch (const Error& e) {
            result.warnings.push_back("Material " + std::to_string(id) +
                                      ": its Blend-mode (forward) program did not compile; rendered with "
                                      "stochastic transparency instead: " + std::string(e.what()));
        }
    }
    auto is_forward = [&](std::uint32_t id) { return forward_programs.count(id) != 0; };
    const bool forward_pass = !forward_programs.empty();
    if (forward_pass && lights.count() > kLightBatch)
        result.warnings.push_back("Blend-mode materials are lit by the first " + std::to_string(kLightBatch) +
                                  " of the scene's " + std::to_string(lights.count()) + " lights");
    if (forward_pass) {
        // What the forward pass does not write (forward_module.h): said, not silent.
        std::vector<std::string> skipped;
        for (Pass p : wanted.list())
            if (p != Pass::Combined) skipped.push_back(pass_info(p).name);
        if (!settings.cryptomatte.empty()) skipped.push_back("Cryptomatte");
        if (!settings.aovs.empty()) skipped.push_back("shader AOVs");
        if (settings.light_groups > 0) skipped.push_back("light groups");
        if (!skipped.empty()) {
            std::string list;
            for (const std::string& name : skipped) list += (list.empty() ? "" : ", ") + name;
            result.warnings.push_back("Blend-mode materials reach Combined only; " + list +
                                      " show what is behind them");
        }
        forward.ensure(settings.width, settings.height);
        result.timings.gbuffer_bytes += forward.bytes();
        lighting_variant.defines.push_back("FORWARD_LAYER");
    }
    const GLuint lighting = shaders->compute_program("lighting_comp.glsl", lighting_variant);
    // Shader AOVs: the AOV program of every graph material that writes one
    // of the asked AOVs, with its slot for each (material id -> (AOV, slot)).
    std::map<std::uint32_t, GLuint> aov_programs;
    std::vector<std::vector<std::pair<std::uint32_t, int>>> aov_writers(settings.aovs.size());
    if (!settings.aovs.empty()) {
        ShaderVariant aov_variant = base_variant;
        aov_variant.defines.push_back("AOV_PASS");
        for (auto& [id, program] : graph_programs) {
            const std::vector<std::string>& names = this->materials.aovs(std::uint32_t(scene.materials()[id].graph));
            for (std::size_t k = 0; k < settings.aovs.size(); ++k)
                for (std::size_t slot = 0; slot < names.size(); ++slot)
                    if (names[slot] == settings.aovs[k].name) aov_writers[k].emplace_back(id, int(slot));
            if (names.empty()) continue;
            try {
                aov_programs[id] =
                    this->materials.program(*shaders, std::uint32_t(scene.materials()[id].graph), aov_variant);
            } catch (const Error& e) {
                result.warnings.push_back("Material " + std::to_string(id) +
                                          ": its AOV program did not compile (its AOVs stay 0): " + e.what());
            }
        }
        aovs.begin(settings.aovs, settings.width, settings.height, gbuffer.depth_texture());
    }
    // The Vector pass: every instance's and the camera's motion (motion_module.h).
    GLuint motion_program = 0;
    for (auto& [p, image] : film.pass_images()) {
        if (p != Pass::Vector || settings.motion_blur) continue;  // with motion blur 0, as Cycles
        motion.begin(scene, camera_in, cam, settings.width, settings.height, image.get(), gbuffer.depth_texture());
        ShaderVariant motion_variant;
        motion_variant.defines.push_back("MOTION_PASS");
        motion_program = shaders->graphics_program("geometry_vert.glsl", "motion_frag.glsl", motion_variant);
    }
    // Draws the slot ranges of the visible instances that use node material `id`.
    auto draw_graph_material = [&](std::uint32_t id, GLuint program) {
        const Material& material = scene.materials()[id];
        bool bound = false;
        for (const Culled& c : visible) {
            const GpuMesh& mesh = scene.meshes()[c.draw->mesh];
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                if (&slot_material(*c.draw, s) != &material || mesh.slot_ranges[s].second == 0) continue;
                if (!bound) glUseProgram(program);
                bound = true;
                this->materials.bind_for_draw(std::uint32_t(material.graph), mesh);
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_ATTRIBUTES,
                                 mesh.attributes ? mesh.attributes.get() : dummy_ssbo.get());
                draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
            }
        }
    };
    // The geometry pass: constant materials with the shared program, then
    // each node material with its own over the slot ranges that use it.
    auto draw_geometry = [&](const ShadowModule::CasterTest& keep) -> std::uint64_t {
        const std::uint64_t n = cull(keep, false);
        glUseProgram(geometry);
        // Per slot range when some slots are not this program's or not the
        // G-buffer's (node materials, Blend-mode materials).
        const bool by_slot = !graph_programs.empty() || forward_pass;
        if (!graph_programs.empty()) {
            // Depth first, so node materials (the expensive fragments) shade
            // each pixel once: the colour pass then tests for equal depth
            // (gl_Position is invariant across the programs).
            // Node materials that drive alpha lay down their own depth (their
            // program discards what is transparent this sample).
            glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
            for (const Culled& c : visible) {
                const GpuMesh& mesh = scene.meshes()[c.draw->mesh];
                if (!alpha_graphs && !forward_pass) {
                    draw_range(c, 0, mesh.triangle_count);
                    continue;
                }
                for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                    const std::uint32_t id = slot_material_id(*c.draw, s);
                    if (!is_alpha_graph(id) && !is_forward(id))
                        draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
                }
            }
            if (alpha_graphs) {
                this->materials.bind_constants();
                for (auto& [id, program] : graph_programs)
                    if (is_alpha_graph(id) && !is_forward(id)) draw_graph_material(id, program);
                glUseProgram(geometry);
            }
            glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
            glDepthMask(GL_FALSE);
            glDepthFunc(GL_EQUAL);
        }
        for (const Culled& c : visible) {
            const GpuMesh& mesh = scene.meshes()[c.draw->mesh];
            if (!by_slot) {
                draw_range(c, 0, mesh.triangle_count);
                continue;
            }
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                const std::uint32_t id = slot_material_id(*c.draw, s);
                if ((scene.materials()[id].graph < 0 || graph_failed[id]) && !is_forward(id))
                    draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
            }
        }
        if (graph_programs.empty()) return n;
        this->materials.bind_constants();
        for (auto& [id, program] : graph_programs)
            if (!is_forward(id)) draw_graph_material(id, program);
        glDepthMask(GL_TRUE);
        glDepthFunc(GL_GREATER);  // reversed Z
        return n;
    };
    // The camera's frustum, widened by the pixel filter's reach (jittered
    // samples look that far) and a pixel, in the view space of `cam`.
    const double margin_px = double(reach) + 1.0;
    const glm::dvec4 vp = cam.viewplane;
    const double px = (vp.y - vp.x) / settings.width * margin_px, py = (vp.w - vp.z) / settings.height * margin_px;
    const double left = vp.x - px, right = vp.y + px, bottom = vp.z - py, top = vp.w + py;
    // This sample's camera: rotation and position relative to the frame's
    // (the frame's own but under camera motion blur).
    glm::dmat3 to_view(cam.view);
    glm::dvec3 eye(0.0);
    auto in_view = [&, left, right, bottom, top](const glm::dvec3& c, double r) {
        const glm::dvec3 v = to_view * (c - eye);
        const double d = -v.z;
        if (d + r < cam.clip_start || d - r > cam.clip_end) return false;
        if (cam.orthographic)
            return v.x + r >= left && v.x - r <= right && v.y + r >= bottom && v.y - r <= top;
        auto inside = [&](double x, double lo, double hi) {
            return (lo * d - x) / std::sqrt(1.0 + lo * lo) <= r && (x - hi * d) / std::sqrt(1.0 + hi * hi) <= r;
        };
        return inside(v.x, left, right) && inside(v.y, bottom, top);
    };
    auto draw_scene = [&]() { camera_instances_drawn += draw_geometry(in_view); };
    // The Vector pass's share of this sample: the visible instances again,
    // against the depth of the G-buffer just drawn.
    auto draw_motion = [&]() {
        if (!motion.active()) return;
        motion.bind(motion_program);
        gbuffer.bind_textures();
        draw_culled(in_view, false);
        motion.end_draws();
    };
    // Data passes (Depth, Position, Normal, UV, indices) follow the Alpha
    // Threshold, not the stochastic coverage: with transparency in the scene
    // they come from a G-buffer of their own each sample, where a surface
    // stays when its alpha reaches the threshold.
    auto is_data_pass = [](Pass p) {
        return p == Pass::Depth || p == Pass::Position || p == Pass::Normal || p == Pass::UV ||
               p == Pass::IndexOB || p == Pass::IndexMA || p == Pass::Vector;
    };
    bool data_gbuffer = false, data_every_sample = false;
    if (scene_alpha || alpha_graphs)
        for (auto& [p, image] : film.pass_images())
            if (is_data_pass(p)) {
                data_gbuffer = true;
                // Depth, Position and the indices come from sample 0 only;
                // Normal and UV are averaged over the samples.
                if (!pass_from_first_sample(p)) data_every_sample = true;
            }
    auto set_alpha_mode = [&](bool data) {
        const float mode = data ? 1.0f : 0.0f;
        if (scene_alpha) glProgramUniform2f(geometry, 22, mode, settings.alpha_threshold);
        for (auto& [id, program] : graph_programs)
            if (is_alpha_graph(id)) glProgramUniform2f(program, 22, mode, settings.alpha_threshold);
    };
    if (scene_alpha || alpha_graphs) set_alpha_mode(false);
    auto run_passes = [&](int sample, bool data) {
        // Filtered passes every sample, the rest at sample 0.
        for (auto& [p, image] : film.pass_images()) {
            const bool first_only = pass_from_first_sample(p);
            // Shadow: resolved below; AO: accumulated by the lighting pass;
            // Vector: drawn by the motion module; Shadow Catcher: resolved below.
            if ((first_only && sample > 0) || p == Pass::Shadow || p == Pass::AO || p == Pass::Vector ||
                p == Pass::ShadowCatcher)
                continue;
            if (data_gbuffer && is_data_pass(p) != data) continue;
            glUseProgram(pass_program(p, first_only ? nullptr : "ACCUMULATE"));
            gbuffer.bind_textures();
            if (p == Pass::Env) world_module.bind();
            glBindImageTexture(IMG_PASS_OUT, image.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
            glDispatchCompute(groups_x, groups_y, 1);
        }
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    };
    // Shadow casters: everything with the shadow module's program, except
    // node materials that drive alpha, drawn with their caster programs
    // (which evaluate the graph for alpha) and the map's uniforms.
    ShaderVariant world_caster_variant;
    world_caster_variant.defines = caster_defines;
    world_caster_variant.defines.push_back("SHADOW_PASS");
    world_caster_variant.defines.push_back("WORLD_MAP");
    // Caster programs of the alpha graphs, compiled before the first sample
    // like the graphs' own; one that fails casts an opaque shadow, warned.
    std::map<std::uint32_t, GLuint> light_casters, world_casters;
    auto compile_casters = [&](std::map<std::uint32_t, GLuint>& out, bool world_map) {
        for (auto& [id, program] : graph_programs) {
            if (!is_alpha_graph(id)) continue;
            try {
                out[id] = this->materials.caster_program(*shaders, std::uint32_t(scene.materials()[id].graph),
                                                         world_map);
            } catch (const Error& e) {
                const std::string& name = this->materials.name(std::uint32_t(scene.materials()[id].graph));
                result.warnings.push_back("Material '" + (name.empty() ? std::to_string(id) : name) +
                                          "': its shadow caster did not compile (opaque shadow): " + e.what());
            }
        }
    };
    if (alpha_graphs && !shadows.empty()) {
        compile_casters(light_casters, false);
        if (shadows.world_index() >= 0) compile_casters(world_casters, true);
    }
    auto draw_shadow_casters = [&](const ShadowModule::CasterTest& casts) {
        if (!alpha_graphs) {
            shadow_instances_drawn += draw_culled(casts, true);
            return;
        }
        GLint caster = 0;
        glGetIntegerv(GL_CURRENT_PROGRAM, &caster);
        // (The world map's program is the shadow module's, already compiled.)
        const bool world_map = shadows.world_index() >= 0 &&
            GLuint(caster) == shaders->graphics_program("geometry_vert.glsl", "shadow_frag.glsl", world_caster_variant);
        const std::map<std::uint32_t, GLuint>& own = world_map ? world_casters : light_casters;
        shadow_instances_drawn += cull(casts, true);
        for (const Culled& c : visible) {
            const GpuMesh& mesh = scene.meshes()[c.draw->mesh];
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s)
                if (!own.count(slot_material_id(*c.draw, s)))
                    draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
        }
        float view_projection[16], origin[4], axis[4] = {0, 0, 0, 0};
        glGetUniformfv(GLuint(caster), 2, view_projection);
        glGetUniformfv(GLuint(caster), 3, origin);
        glGetUniformfv(GLuint(caster), 4, axis);
        this->materials.bind_constants();
        for (auto& [id, p] : own) {
            glProgramUniformMatrix4fv(p, 2, 1, GL_FALSE, view_projection);
            glProgramUniform4fv(p, 20, 1, origin);
            glProgramUniform3fv(p, 21, 1, axis);
            draw_graph_material(id, p);
        }
        glUseProgram(GLuint(caster));
    };



    // The forward pass of one sample: the visible instances with Blend-mode
    // slots, one draw each, farthest first (by the bounding sphere's centre
    // along the view), over the layer begin_sample cleared.
    struct ForwardDraw { double depth; Culled one; };
    std::vector<ForwardDraw> forward_draws;
    auto draw_forward = [&]() {
        camera_instances_drawn += cull(in_view, false);
        forward_draws.clear();
        for (const Culled& c : visible) {
            const GpuMesh& mesh = scene.meshes()[c.draw->mesh];
            bool any = false;
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s)
                if (is_forward(slot_material_id(*c.draw, s)) && mesh.slot_ranges[s].second > 0) any = true;
            if (!any) continue;
            for (std::uint32_t j = 0; j < c.count; ++j) {
                const glm::dvec3 v = to_view * bounds[remap[c.first + j]].center;
                forward_draws.push_back({cam.orthographic ? -v.z : glm::length(v), {c.draw, c.first + j, 1}});
            }
        }
        std::stable_sort(forward_draws.begin(), forward_draws.end(),
                         [](const ForwardDraw& a, const ForwardDraw& b) { return a.depth > b.depth; });
        forward.begin_sample();
        this->materials.bind_constants();
        for (const ForwardDraw& f : forward_draws) {
            const GpuMesh& mesh = scene.meshes()[f.one.draw->mesh];
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                const std::uint32_t id = slot_material_id(*f.one.draw, s);
                auto program = forward_programs.find(id);
                if (program == forward_programs.end() || mesh.slot_ranges[s].second == 0) continue;
                glUseProgram(program->second);
                const Material& m = scene.materials()[id];
                if (m.graph >= 0 && !graph_failed[id]) {
                    this->materials.bind_for_draw(std::uint32_t(m.graph), mesh);
                    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_ATTRIBUTES,
                                     mesh.attributes ? mesh.attributes.get() : dummy_ssbo.get());
                }
                draw_range(f.one, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
            }
        }
        forward.end_sample();
    };

    double preview_ms = 0;  // progressive preview read-backs, counted as readback
    GLuint preview_image = film.combined();
    if (settings.preview_pass != Pass::Combined) {
        const Pass p = settings.preview_pass;
        if (p == Pass::DiffDir || p == Pass::GlossDir || p == Pass::Shadow || p == Pass::Vector ||
            p == Pass::ShadowCatcher)
            throw InvalidInput(std::string("preview_pass: ") + pass_info(p).name +
                               " is resolved after the last sample and cannot be previewed");
        preview_image = 0;
        for (auto& [q, image] : film.pass_images())
            if (q == p) preview_image = image.get();
        if (!preview_image)
            throw InvalidInput(std::string("preview_pass: ") + pass_info(p).name + " is not among the passes rendered");
    }
    const bool preview_averaged = !pass_from_first_sample(settings.preview_pass);
    const int preview_channels = pass_info(settings.preview_pass).channels;
    // Motion blur: the camera and the moving instances at sample s's time of
    // the shutter (motion_module.h). Positions stay relative to the frame's
    // camera; this sample's camera is at `eye` from it (frame.motion.xyz).
    std::array<glm::dmat4, 3> camera_steps;
    if (camera_moves)
        camera_steps = {to_glm(camera_in.matrix_previous), to_glm(camera_in.matrix), to_glm(camera_in.matrix_next)};
    auto place_at_shutter_time = [&](int sample) {
        const double r = 2.0 * shutter_time(sample) - 1.0;
        if (camera_moves) {
            Camera c = camera_in;
            const glm::dmat4 m = interpolate_motion(camera_steps[0], camera_steps[1], camera_steps[2], r);
            for (int col = 0; col < 4; ++col)
                for (int row = 0; row < 4; ++row) c.matrix[std::size_t(col * 4 + row)] = m[col][row];
            const CameraMatrices at = build_camera(c, settings.width, settings.height);
            eye = at.position - cam.position;
            to_view = glm::dmat3(at.view);
            glm::dmat4 view = at.view;
            view[3] = glm::dvec4(-(glm::dmat3(at.view) * eye), 1.0);  // view x translate(-eye)
            fc.view = to_gpu(view);
            fc.inv_view = to_gpu(glm::inverse(view));
        }
        fc.motion = {float(eye.x), float(eye.y), float(eye.z), float(r)};
        if (moving.empty()) return;
        bool casters_moved = false;
        for (const MovingInstance& mi : moving) {
            const glm::dmat4 world = interpolate_motion(mi.steps[0], mi.steps[1], mi.steps[2], r);
            place(world, scene.meshes()[mi.mesh], instances[mi.index], bounds[mi.index]);
            if (shadow_rays && caster_of_instance[mi.index] >= 0) {
                glm::dmat4 model = world;
                model[3] = glm::dvec4(glm::dvec3(model[3]) - cam.position, 1.0);
                casters[std::size_t(caster_of_instance[mi.index])].model = model;
                casters_moved = true;
            }
        }
        glNamedBufferSubData(instance_buffer.get(), 0, GLsizeiptr(instances.size() * sizeof(gpu::GpuInstance)),
                             instances.data());
        // The ray scene again at this time: the instances' hierarchy over the
        // meshes' kept ones (each mesh's hierarchy is built once).
        if (casters_moved) {
            StageTimer ray_timer;  // CPU work: its own clock, no glFinish
            ray_scene.build(casters);
            ray_scene.upload();
            result.timings.ray_build_ms += ray_timer.lap_cpu_ms();
        }
    };
    preview.begin(settings.width, settings.height, settings.samples, settings.preview_interval_ms);
    for (int sample = 0; sample < settings.samples; ++sample) {
        check_cancel();
        // Jitter: one pixel-filter offset for the whole image (sample 0: none).
        const std::array<float, 4> u = sample_point(sample);
        const double ox = filter.offset(u[0]), oy = filter.offset(u[1]);
        glm::dmat4 jitter(1.0);
        jitter[3][0] = 2.0 * ox / settings.width;  // clip.xy += offset_ndc * clip.w
        jitter[3][1] = 2.0 * oy / settings.height;
        const glm::dmat4 projection = jitter * cam.projection;
        fc.projection = to_gpu(projection);
        fc.jitter = {float(jitter[3][0]), float(jitter[3][1]), float(cam.clip_start), 0.0f};
        fc.inv_projection = to_gpu(glm::inverse(projection));
        if (settings.motion_blur) place_at_shutter_time(sample);
        // Where in each light-shape cell (and on the sun's disk) this sample looks.
        fc.sample_shift = {u[2], u[3], float(std::fmod(0.5 + sample * 0.6180339887498949, 1.0)),
                           float(sample)};
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
        frame_ring.push(&fc);
        glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);

        if (data_gbuffer && (sample == 0 || data_every_sample)) {
            set_alpha_mode(true);
            gbuffer.bind_for_geometry();
            glEnable(GL_DEPTH_TEST);
            glDepthFunc(GL_GREATER);
            glDepthMask(GL_TRUE);
            glDisable(GL_CULL_FACE);
            glDisable(GL_BLEND);
            draw_scene();
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
            draw_motion();
            glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
            gpu_timer.lap(geometry_ms);
            run_passes(sample, true);
            set_alpha_mode(false);
            gpu_timer.lap(passes_ms);
        }

        // Geometry pass.
        gbuffer.bind_for_geometry();
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_GREATER);  // reversed Z
        glDepthMask(GL_TRUE);
        glDisable(GL_CULL_FACE);  // two-sided, as Cycles
        glDisable(GL_BLEND);
        draw_scene();
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        // Shader AOVs of the surfaces this G-buffer holds (the camera's
        // instances are still the culled set).
        if (aovs.active()) {
            this->materials.bind_constants();
            for (std::size_t k = 0; k < aovs.count(); ++k) {
                aovs.bind(k, settings.samples);
                for (auto& [id, slot] : aov_writers[k]) {
                    auto program = aov_programs.find(id);
                    if (program == aov_programs.end()) continue;
                    glProgramUniform1i(program->second, 23, slot);
                    glProgramUniform1i(program->second, 24, settings.aovs[k].color ? 1 : 0);
                    draw_graph_material(id, program->second);
                }
            }
            aovs.end_draws();
        }
        if (!data_gbuffer) draw_motion();
        check_gl("geometry pass");
        gpu_timer.lap(geometry_ms);

        // A cancel (a viewport edit waits for it) stops between stages too,
        // not only between samples: everything below is redone from scratch
        // by the next render.
        check_cancel();
        // Shadow maps from this sample's point on each shadowed light, sized
        // at sample 0 from what the visible surfaces need.
        if (!shadows.empty()) {
            if (sample == 0 && shadow_rays) {
                shadows.fit({});  // no maps to size
            } else if (sample == 0) {
                std::pair<double, double> visible_depths;
                const auto receivers = visible_receivers(cam, settings.width, settings.height, visible_depths);
                if (forward_pass || scene_alpha || alpha_graphs) {
                    // Surfaces sample 0's depth may not hold: Blend-mode
                    // layers (the forward pass) and stochastic alpha seen
                    // at later samples. The bounding spheres of every
                    // instance in view widen the cascades' range to them.
                    const glm::dmat3 to_view(cam.view);
                    double near = visible_depths.second > 0.0 ? visible_depths.first : 1e300;
                    double far = visible_depths.second > 0.0 ? visible_depths.second : 0.0;
                    for (const auto& b : bounds)
                        if (in_view(b.center, b.radius)) {
                            const double d = -(to_view * b.center).z;
                            near = std::min(near, d - b.radius);
                            far = std::max(far, d + b.radius);
                        }
                    if (far > 0.0) visible_depths = {std::max(near, double(cam.clip_start)), far};
                }
                shadows.fit(receivers, visible_depths);
            }
            // The maps' grid offset: the R2 sequence (Roberts 2018) over the
            // samples, apart from the light points' numbers.
            const std::array<float, 2> grid = {float(std::fmod(0.5 + sample * 0.7548776662466927, 1.0)),
                                               float(std::fmod(0.5 + sample * 0.5698402909980532, 1.0))};
            shadows.render_sample(*shaders, {u[2], u[3]}, grid, world_dirs, draw_shadow_casters,
                                  caster_defines, scene_alpha || alpha_graphs || casters_move);
            gpu_timer.lap(shadow_ms);
        }

        // Light lists, once per frame from sample 0's depth (later samples
        // fall back to every light where they see outside a tile's bounds).
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        gbuffer.bind_textures();
        lights.bind();
        if (culled && sample == 0) {
            culling.build(*shaders, tiles_x, tiles_y);
            gpu_timer.lap(culling_ms);
        }

        shadows.bind();
        ray_scene.bind();
        world_module.bind();
        emitters.bind();
        // Forward pass: Blend-mode surfaces in front of this sample's opaque
        // depth, lit by the same lights and maps, into the forward layer.
        if (forward_pass) {
            draw_forward();
            glViewport(0, 0, settings.width, settings.height);
            forward.bind_layer();
            check_gl("forward pass");
            gpu_timer.lap(forward_ms);
        }

        check_cancel();
        // Lighting pass: adds this sample's share to the film.
        glUseProgram(lighting);
        if (culled) culling.bind();
        film.bind_for_lighting();
        if (settings.light_groups > 0) {
            lights.bind_groups();
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_INSTANCE_GROUPS, instance_group_buffer.get());
            glUniform1ui(1, world.light_group);
        }
        const std::uint32_t batch = shadow_rays ? kRayLightBatch : kLightBatch;
        for (std::uint32_t begin = 0; begin == 0 || begin < lights.count(); begin += batch) {
            if (begin > 0) check_cancel();
            glUniform2ui(0, begin, begin + batch);
            glDispatchCompute(groups_x, groups_y, 1);
            glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        }
        check_gl("lighting pass");
        gpu_timer.lap(lighting_ms);

        // Other passes (the data passes came from their own G-buffer above).
        run_passes(sample, false);
        if (cryptomatte.active()) {
            gbuffer.bind_textures();
            cryptomatte.accumulate(*shaders, settings.samples, groups_x, groups_y);
        }
        check_gl("passes");
        gpu_timer.lap(passes_ms);
        preview.publish(preview_image, sample + 1, preview_averaged, preview_channels);
        gpu_timer.lap(preview_ms);
    }

    // Shadow catchers: the Shadow Catcher pass from the catchers' light and
    // the matte's alpha, or without it Combined carries their shadow.
    if (catchers) {
        glBindTextureUnit(TEX_CATCHER_HIT, film.catcher_hit());
        glBindTextureUnit(TEX_CATCHER_PASS, film.catcher_pass());
        glBindTextureUnit(TEX_CATCHER_FILM, film.combined());
        bool pass = false;
        for (auto& [p, image] : film.pass_images()) {
            if (p != Pass::ShadowCatcher) continue;
            pass = true;
            glUseProgram(pass_program(p, "RESOLVE_CATCHER"));
            glBindImageTexture(IMG_PASS_OUT, image.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
            glDispatchCompute(groups_x, groups_y, 1);
        }
        if (!pass) {
            ShaderVariant v = base_variant;
            v.defines.push_back("PASS_ID " + std::to_string(int(Pass::ShadowCatcher)));
            v.defines.push_back("RESOLVE_CATCHER_COMBINED");
            world_module.add_defines(v);
            glUseProgram(shaders->compute_program("passes_comp.glsl", v));
            world_module.bind();
            glBindImageTexture(IMG_PASS_OUT, film.combined(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
            glDispatchCompute(groups_x, groups_y, 1);
        }
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        // The viewport's last image with the catchers' shadows (the samples'
        // images show them as holes).
        if (!pass && settings.preview_pass == Pass::Combined) preview.publish(film.combined(), settings.samples);
    }
    // DiffDir/GlossDir: accumulated light over accumulated colour; Shadow:
    // shadowed over unshadowed light; Vector: summed motion over its count.
    for (auto& [p, image] : film.pass_images()) {
        if (p == Pass::Vector) {
            glUseProgram(pass_program(p, "RESOLVE_MOTION"));
            motion.bind_resolve();
            glBindImageTexture(IMG_PASS_OUT, image.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
            glDispatchCompute(groups_x, groups_y, 1);
            continue;
        }
        if (p != Pass::DiffDir && p != Pass::GlossDir && p != Pass::Shadow) continue;
        glUseProgram(pass_program(p, p == Pass::Shadow ? "RESOLVE_SHADOW" : "RESOLVE_LIGHT"));
        glBindTextureUnit(TEX_DIFF_LIGHT, film.diffuse_light());
        glBindTextureUnit(TEX_GLOSS_LIGHT, film.glossy_light());
        glBindTextureUnit(TEX_SHADOW_LIGHT, film.shadow_light());
        glBindImageTexture(IMG_PASS_OUT, image.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glDispatchCompute(groups_x, groups_y, 1);
    }
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_PIXEL_BUFFER_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    gpu_timer.lap(passes_ms);

    // The stages' times (waits for the GPU once), then the readback on the CPU's clock.
    gpu_timer.collect(true);
    timer.restart();

    // --- Readback (film_module.h: one pixel pack buffer, mapped once). ---
    result.passes = film.read_passes();
    result.cryptomatte = cryptomatte.finish();
    result.aovs = aovs.finish();
    motion.release();
    result.light_groups = film.read_light_groups();
    check_gl("readback");
    result.timings.readback_ms = timer.lap_ms() + preview_ms;
    result.timings.geometry_ms = geometry_ms;
    result.timings.lighting_ms = lighting_ms;
    result.timings.forward_ms = forward_ms;
    result.timings.culling_ms = culling_ms;
    result.timings.shadow_ms = shadow_ms;
    result.timings.shadow_map_bytes = shadows.empty() ? 0 : shadows.map_bytes();
    result.timings.shadowed_lights = shadows.count();
    result.timings.shadow_resolutions = shadows.resolutions();
    result.timings.shadow_layers_rendered = shadows.layers_rendered();
    result.timings.shadow_instances_drawn = shadow_instances_drawn;
    result.timings.camera_instances_drawn = camera_instances_drawn;
    result.timings.shadow_lights_dropped = shadows.dropped();
    result.timings.tile_light_pairs = culled ? culling.last_index_count() : 0;
    result.timings.passes_ms = passes_ms;
    result.timings.programs_compiled = shaders->compile_count() - compiles_before;
    result.timings.images_uploaded = materials.images_uploaded();
    result.timings.images_reused = materials.images_reused();
    result.timings.meshes_uploaded = scene.meshes_uploaded();
    result.timings.meshes_reused = scene.meshes_reused();
    result.timings.compile_ms = shaders->compile_ms() - compile_ms_before;
    result.timings.programs_loaded = shaders->disk_loads() - loads_before;
    result.timings.load_ms = shaders->load_ms() - load_ms_before;
    result.timings.total_ms = result.timings.upload_ms + shadow_ms + geometry_ms + culling_ms + lighting_ms + passes_ms +
                              forward_ms +
                              result.timings.readback_ms;
    return result;
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
