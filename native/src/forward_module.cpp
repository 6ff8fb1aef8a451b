#include "forward_module.h"

#include "geometry_stage.h"
#include "ray_scene.h"
#include "material_module.h"

#include <deferred/renderer.h>

#include "../../shaders/shader_defines.h"

#include <algorithm>
#include <limits>
#include <string>

namespace deferred {

std::vector<bool> ForwardModule::prepare(ShaderLibrary& shaders, MaterialModule& materials, const FrameScene& scene,
                                         const GeometryStage& geometry, const ShaderVariant& variant,
                                         std::uint32_t light_count, std::uint32_t lights_per_draw,
                                         const ExactLayers& exact, std::vector<std::string>& warnings) {
    materials_ = &materials;
    geometry_ = &geometry;
    light_count_ = light_count;
    lights_per_draw_ = std::max(lights_per_draw, 1u);
    programs_.clear();
    rank_ = exact.any() ? exact.rank : std::vector<std::uint32_t>{};
    std::vector<bool> forward(scene.material_count(), false);
    for (std::uint32_t id = 0; id < scene.material_count(); ++id) {
        const Material& m = scene.scene_material(id);
        const bool layer = exact.any() && id < exact.materials.size() && exact.materials[id];
        if (!m.blend && !layer) continue;
        try {
            programs_[id] = m.graph >= 0 && !geometry.failed(id)
                ? materials.program(shaders, std::uint32_t(m.graph), variant)
                : shaders.graphics_program("geometry_vert.glsl", "geometry_frag.glsl", variant);
            forward[id] = true;
        } catch (const Error& e) {
            warnings.push_back("Material " + std::to_string(id) + ": its " +
                               (m.blend ? "Blend-mode" : "exact layer") + " (forward) program did not compile; "
                               "rendered with stochastic transparency instead: " + std::string(e.what()));
        }
    }
    return forward;
}

std::uint64_t ForwardModule::draw(FrameScene& scene, const ViewVolume& view,
                                  const std::function<void()>& between_batches) {
    const std::uint64_t kept = scene.cull([&](const glm::dvec3& c, double r) { return view.contains(c, r); }, false);
    sorted_.clear();
    for (const FrameScene::Culled& c : scene.visible()) {
        const GpuMesh& mesh = scene.mesh(*c.draw);
        bool any = false;
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s)
            if (programs_.count(scene.slot_material(*c.draw, s)) && mesh.slot_ranges[s].second > 0) any = true;
        if (!any) continue;
        for (std::uint32_t j = 0; j < c.count; ++j) {
            // Relative to this sample's eye (it moves under camera motion blur).
            const std::uint32_t instance = scene.kept(c.first + j);
            const glm::dvec3 v = view.to_view * (scene.bounds()[instance].center - view.eye);
            const double depth = !rank_.empty() ? double(rank_[instance]) : view.orthographic ? -v.z : glm::length(v);
            sorted_.push_back({depth, {c.draw, c.first + j, 1}});
        }
    }
    // Nearest first (the "under" operator); among equal depths in the order
    // the scene lists them.
    std::stable_sort(sorted_.begin(), sorted_.end(), [](const Sorted& a, const Sorted& b) { return a.depth < b.depth; });
    begin_sample();
    materials_->bind_constants();
    const std::uint32_t draws = batches();
    for (std::uint32_t batch = 0; batch < draws; ++batch) {
        const std::uint32_t begin = batch * lights_per_draw_;
        // Light count 0 still draws once: the world and the emission.
        for (const auto& [id, program] : programs_) glProgramUniform2ui(program, 25, begin, begin + lights_per_draw_);
        if (batch > 0) {
            try {
                between_batches();
            } catch (...) {
                end_sample();  // a cancel leaves the GL state as the frame's other stages expect it
                throw;
            }
            begin_later_batch();
        }
        GLuint bound = 0;  // the program in use (a glUseProgram resets its subroutine)
        for (const Sorted& f : sorted_) {
            const GpuMesh& mesh = scene.mesh(*f.one.draw);
            // A convex exact layer (layer_order.h) is two: the side facing
            // the eye, then the far side (geometry_frag.glsl forward_side:
            // 1 the fragments seen from the front of their winding, 2 from
            // behind; a mesh facing in has its near side behind).
            const bool two_sides = mesh.convex && !rank_.empty() &&
                                   rank_[scene.kept(f.one.first)] != std::numeric_limits<std::uint32_t>::max();
            const int sides[2] = {two_sides ? (mesh.closed > 0 ? 1 : 2) : 0, mesh.closed > 0 ? 2 : 1};
            // The rasteriser leaves out the other side's triangles before
            // shading them (the shader's test is the definition; the same
            // gl_FrontFacing decides both): side 1 keeps the fragments seen
            // from the front of their winding, which a mirrored instance's
            // window winding reverses.
            const bool mirrored = scene.mirrored(scene.kept(f.one.first));
            if (two_sides) glEnable(GL_CULL_FACE);
            for (int side = 0; side < (two_sides ? 2 : 1); ++side) {
            if (two_sides) glCullFace((sides[side] == 1) != mirrored ? GL_BACK : GL_FRONT);
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                const std::uint32_t id = scene.slot_material(*f.one.draw, s);
                auto program = programs_.find(id);
                if (program == programs_.end() || mesh.slot_ranges[s].second == 0) continue;
                if (program->second != bound) {
                    glUseProgram(program->second);
                    use_ray_traversal(program->second, GL_FRAGMENT_SHADER);  // with shadow rays: lights them
                    bound = program->second;
                }
                const Material& m = scene.scene_material(id);
                if (m.graph >= 0 && !geometry_->failed(id)) {
                    materials_->bind_for_draw(std::uint32_t(m.graph), mesh);
                    scene.bind_attributes(mesh);
                }
                glProgramUniform1i(program->second, 26, sides[side]);
                scene.draw_range(f.one, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
            }
            }
            if (two_sides) glDisable(GL_CULL_FACE);
        }
    }
    end_sample();
    return kept;
}

std::uint32_t ForwardModule::batches() const {
    return std::max((light_count_ + lights_per_draw_ - 1) / lights_per_draw_, 1u);
}

void ForwardModule::ensure(int width, int height) {
    if (layer_ && width == width_ && height == height_) return;
    release();
    // Float: the layer carries lit radiance (any range) and the
    // transmittance multiplied over many layers.
    layer_ = make_texture_2d(GL_RGBA32F, width, height, "forward layer");
    GLuint fbo = 0;
    glCreateFramebuffers(1, &fbo);
    fbo_ = Framebuffer(fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, layer_.get(), 0);
    glNamedFramebufferDrawBuffer(fbo, GL_COLOR_ATTACHMENT0);
    const GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        throw Error("forward layer framebuffer incomplete (status 0x" + std::to_string(status) + ")");
    width_ = width;
    height_ = height;
    check_gl("allocating the forward layer");
}

void ForwardModule::begin_sample() const {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    glViewport(0, 0, width_, height_);
    const float empty[4] = {0.0f, 0.0f, 0.0f, 1.0f};  // no light, everything behind shows
    glClearNamedFramebufferfv(fbo_.get(), GL_COLOR, 0, empty);
    glDisable(GL_DEPTH_TEST);  // tested against the opaque depth in the shader
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);   // two-sided, as Cycles
    glFrontFace(GL_CCW);       // gl_FrontFacing as geometry_frag.glsl reads it
    // Front to back "under" with premultiplied colour (src = a L): c = T src
    // + c; the alpha channel keeps the transmittance, T = (1 - a) T.
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_DST_ALPHA, GL_ONE, GL_ZERO, GL_ONE_MINUS_SRC_ALPHA);
}

void ForwardModule::begin_later_batch() const {
    // A clear obeys the colour mask: T alone back to 1.
    glColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_TRUE);
    const float one[4] = {0.0f, 0.0f, 0.0f, 1.0f};
    glClearNamedFramebufferfv(fbo_.get(), GL_COLOR, 0, one);
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
}

void ForwardModule::end_sample() const {
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
    glEnable(GL_DEPTH_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void ForwardModule::bind_layer() const { glBindTextureUnit(TEX_FORWARD_LAYER, layer_.get()); }

void ForwardModule::end_frame() {
    programs_.clear();
    sorted_.clear();
    rank_.clear();
    materials_ = nullptr;
    geometry_ = nullptr;
}

void ForwardModule::release() {
    fbo_.reset();
    layer_.reset();
    width_ = height_ = 0;
}

}  // namespace deferred
