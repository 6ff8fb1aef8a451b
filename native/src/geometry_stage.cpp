#include "geometry_stage.h"

#include "aov_module.h"
#include "material_module.h"

#include "../../shaders/shader_defines.h"

#include <algorithm>

namespace deferred {

void GeometryStage::prepare(ShaderLibrary& shaders, MaterialModule& materials, const FrameScene& scene,
                            const ShaderVariant& base, bool scene_alpha, std::vector<std::string>& warnings,
                            bool graph_programs) {
    *this = GeometryStage();
    materials_ = &materials;
    scene_alpha_ = scene_alpha;
    ShaderVariant geometry_variant = base;
    if (scene_alpha) geometry_variant.defines.push_back("SCENE_ALPHA");
    geometry_ = shaders.graphics_program("geometry_vert.glsl", "geometry_frag.glsl", geometry_variant);
    // Every node material's program (a graph used by no visible slot still
    // compiles: the set is the scene's).
    failed_.assign(scene.material_count(), false);
    alpha_.assign(scene.material_count(), false);
    partly_transparent_.assign(scene.material_count(), false);
    for (std::uint32_t id = 0; id < scene.material_count(); ++id)
        partly_transparent_[id] = scene.scene_material(id).graph < 0 && scene.coverage(id) < 1.0f;
    // Every graph's compile started first, then each waited for: with the
    // driver's compiler threads (ShaderLibrary::prefetch_graphics) a scene's
    // node materials compile in parallel.
    if (graph_programs)
        for (std::uint32_t id = 0; id < scene.material_count(); ++id)
            if (scene.scene_material(id).graph >= 0)
                materials.prefetch(shaders, std::uint32_t(scene.scene_material(id).graph), base);
    for (std::uint32_t id = 0; id < scene.material_count(); ++id) {
        const Material& m = scene.scene_material(id);
        if (m.graph < 0) continue;
        if (!graph_programs) {
            graph_programs_.emplace_back(id, 0);
            alpha_[id] = materials.alpha(std::uint32_t(m.graph));
            if (alpha_[id]) alpha_graphs_ = true;
            continue;
        }
        try {
            graph_programs_.emplace_back(id, materials.program(shaders, std::uint32_t(m.graph), base));
            alpha_[id] = materials.alpha(std::uint32_t(m.graph));
            if (alpha_[id]) alpha_graphs_ = true;
        } catch (const Error& e) {
            // Its GpuMaterial holds Material's defaults: the default surface.
            failed_[id] = true;
            const std::string& name = materials.name(std::uint32_t(m.graph));
            warnings.push_back("Material '" + (name.empty() ? std::to_string(id) : name) +
                               "': its node graph did not compile (default surface used): " + e.what());
        }
    }
}

std::size_t GeometryStage::distinct_graph_programs() const {
    std::vector<GLuint> distinct;
    for (auto& [id, p] : graph_programs_)
        if (p != 0 && std::find(distinct.begin(), distinct.end(), p) == distinct.end()) distinct.push_back(p);
    return distinct.size();
}

void GeometryStage::draw_material(const FrameScene& scene, std::uint32_t id, GLuint program) const {
    draw_material_slots(scene, *materials_, id, program);
}

void draw_material_slots(const FrameScene& scene, const MaterialModule& materials, std::uint32_t id, GLuint program) {
    const std::uint32_t graph = std::uint32_t(scene.scene_material(id).graph);
    bool bound = false;
    for (const FrameScene::Culled& c : scene.visible()) {
        const GpuMesh& mesh = scene.mesh(*c.draw);
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
            if (scene.slot_material(*c.draw, s) != id || mesh.slot_ranges[s].second == 0) continue;
            if (!bound) glUseProgram(program);
            bound = true;
            materials.bind_for_draw(graph, mesh);
            scene.bind_attributes(mesh);
            scene.draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
        }
    }
}

std::uint64_t GeometryStage::draw(FrameScene& scene, const FrameScene::Test& keep, bool data) {
    const std::uint64_t n = scene.cull(keep, false);
    const std::vector<bool>& skip = data ? data_skipped_ : forward_;
    auto is_forward = [&](std::uint32_t id) { return id < skip.size() && skip[id]; };
    glUseProgram(geometry_);
    const bool forward_pass = std::find(skip.begin(), skip.end(), true) != skip.end();
    // Per slot range when some slots are not this program's or not the
    // G-buffer's (node materials, Blend-mode materials).
    const bool by_slot = !graph_programs_.empty() || forward_pass;
    if (!graph_programs_.empty()) {
        // Depth first; node materials that drive alpha lay down their own
        // depth (their program discards what is transparent this sample).
        glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
        for (const FrameScene::Culled& c : scene.visible()) {
            const GpuMesh& mesh = scene.mesh(*c.draw);
            if (!alpha_graphs_ && !forward_pass) {
                scene.draw_range(c, 0, mesh.triangle_count);
                continue;
            }
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                const std::uint32_t id = scene.slot_material(*c.draw, s);
                if (!is_alpha_graph(id) && !is_forward(id))
                    scene.draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
            }
        }
        if (alpha_graphs_) {
            materials_->bind_constants();
            for (auto& [id, program] : graph_programs_)
                if (is_alpha_graph(id) && !is_forward(id)) draw_material(scene, id, program);
            glUseProgram(geometry_);
        }
        glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        glDepthMask(GL_FALSE);
        glDepthFunc(GL_EQUAL);
    }
    for (const FrameScene::Culled& c : scene.visible()) {
        const GpuMesh& mesh = scene.mesh(*c.draw);
        if (!by_slot) {
            scene.draw_range(c, 0, mesh.triangle_count);
            continue;
        }
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
            const std::uint32_t id = scene.slot_material(*c.draw, s);
            if ((scene.scene_material(id).graph < 0 || failed_[id]) && !is_forward(id))
                scene.draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
        }
    }
    if (graph_programs_.empty()) return n;
    materials_->bind_constants();
    for (auto& [id, program] : graph_programs_)
        if (!is_forward(id)) draw_material(scene, id, program);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_GREATER);  // reversed Z
    return n;
}

void GeometryStage::set_alpha_mode(bool data, float threshold) const {
    if (!stochastic_alpha()) return;
    const float mode = data ? 1.0f : 0.0f;
    if (scene_alpha_) glProgramUniform2f(geometry_, 22, mode, threshold);
    for (auto& [id, program] : graph_programs_)
        if (is_alpha_graph(id) && program != 0) glProgramUniform2f(program, 22, mode, threshold);
}

void GeometryStage::prepare_aovs(ShaderLibrary& shaders, MaterialModule& materials, const FrameScene& scene,
                                 const ShaderVariant& base, const std::vector<AovRequest>& aovs,
                                 std::vector<std::string>& warnings) {
    aov_programs_.clear();
    aov_writers_.assign(aovs.size(), {});
    if (aovs.empty()) return;
    ShaderVariant aov_variant = base;
    aov_variant.defines.push_back("AOV_PASS");
    for (auto& [id, program] : graph_programs_) {
        const std::uint32_t graph = std::uint32_t(scene.scene_material(id).graph);
        if (!materials.aovs(graph).empty()) materials.prefetch(shaders, graph, aov_variant);
    }
    for (auto& [id, program] : graph_programs_) {
        const std::uint32_t graph = std::uint32_t(scene.scene_material(id).graph);
        const std::vector<std::string>& names = materials.aovs(graph);
        for (std::size_t k = 0; k < aovs.size(); ++k)
            for (std::size_t slot = 0; slot < names.size(); ++slot)
                if (names[slot] == aovs[k].name) aov_writers_[k].emplace_back(id, int(slot));
        if (names.empty()) continue;
        try {
            aov_programs_[id] = materials.program(shaders, graph, aov_variant);
        } catch (const Error& e) {
            warnings.push_back("Material " + std::to_string(id) + ": its AOV program did not compile (its AOVs stay 0): " +
                               e.what());
        }
    }
}

void GeometryStage::draw_aovs(const FrameScene& scene, const AovModule& aovs, const std::vector<AovRequest>& requests,
                              int samples) const {
    if (!aovs.active()) return;
    materials_->bind_constants();
    for (std::size_t k = 0; k < aovs.count(); ++k) {
        aovs.bind(k, samples);
        for (auto& [id, slot] : aov_writers_[k]) {
            auto program = aov_programs_.find(id);
            if (program == aov_programs_.end()) continue;
            glProgramUniform1i(program->second, 23, slot);
            glProgramUniform1i(program->second, 24, requests[k].color ? 1 : 0);
            draw_material(scene, id, program->second);
        }
    }
    aovs.end_draws();
}

void GeometryStage::prepare_casters(ShaderLibrary& shaders, MaterialModule& materials, const FrameScene& scene,
                                    bool world_map, std::vector<std::string>& warnings) {
    std::map<std::uint32_t, GLuint>& out = world_map ? world_casters_ : light_casters_;
    for (auto& [id, program] : graph_programs_)
        if (is_alpha_graph(id))
            materials.prefetch(shaders, std::uint32_t(scene.scene_material(id).graph),
                               MaterialModule::caster_variant(world_map));
    for (auto& [id, program] : graph_programs_) {
        if (!is_alpha_graph(id)) continue;
        const std::uint32_t graph = std::uint32_t(scene.scene_material(id).graph);
        try {
            out[id] = materials.caster_program(shaders, graph, world_map);
        } catch (const Error& e) {
            const std::string& name = materials.name(graph);
            warnings.push_back("Material '" + (name.empty() ? std::to_string(id) : name) +
                               "': its shadow caster did not compile (opaque shadow): " + e.what());
        }
    }
}

std::uint64_t GeometryStage::draw_casters(FrameScene& scene, const FrameScene::Test& casts, bool world_map,
                                          const DrawStyle& style, const FaceCulling* faces,
                                          GLuint alpha_program) const {
    if (!alpha_graphs_ && alpha_program == 0) return scene.draw_culled(casts, true, style, faces);
    GLint caster = 0;
    glGetIntegerv(GL_CURRENT_PROGRAM, &caster);
    const std::map<std::uint32_t, GLuint>& own = world_map ? world_casters_ : light_casters_;
    // Slots drawn by a program of their own: an alpha graph's caster, or
    // the partly transparent constant materials' alpha_program.
    auto apart = [&](std::uint32_t id) { return own.count(id) > 0 || (alpha_program != 0 && is_partly_transparent(id)); };
    // A closed mesh with a cut-out slot shows its inside through the cut:
    // its back faces stay where any of its slots is drawn apart.
    const std::uint64_t n = scene.cull(casts, true, faces);
    bool any_transparent = false;
    for (const FrameScene::Culled& c : scene.visible()) {
        const GpuMesh& mesh = scene.mesh(*c.draw);
        bool cut = false;
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) cut = cut || apart(scene.slot_material(*c.draw, s));
        DrawStyle slot_style = style;
        slot_style.cull_faces = style.cull_faces && !cut;
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
            const std::uint32_t id = scene.slot_material(*c.draw, s);
            if (!apart(id)) scene.draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second, slot_style);
            else if (!own.count(id)) any_transparent = true;
        }
    }
    // The map's uniforms (shadow_frag.glsl's 2, 3, 4) onto the other
    // programs' (alpha_program: the same; the graphs' casters 2, 20, 21:
    // material_module.h).
    float view_projection[16], origin[4], axis[4] = {0, 0, 0, 0}, clip[4 * SHADOW_CLIP_PLANES];
    glGetUniformfv(GLuint(caster), 2, view_projection);
    glGetUniformfv(GLuint(caster), 3, origin);
    glGetUniformfv(GLuint(caster), 4, axis);
    for (int i = 0; i < SHADOW_CLIP_PLANES; ++i) glGetUniformfv(GLuint(caster), LOC_SHADOW_CLIP + i, clip + 4 * i);
    if (any_transparent) {
        glProgramUniform4fv(alpha_program, LOC_SHADOW_CLIP, SHADOW_CLIP_PLANES, clip);
        glProgramUniformMatrix4fv(alpha_program, 2, 1, GL_FALSE, view_projection);
        glProgramUniform4fv(alpha_program, 3, 1, origin);
        glProgramUniform3fv(alpha_program, 4, 1, axis);
        glUseProgram(alpha_program);
        for (const FrameScene::Culled& c : scene.visible()) {
            const GpuMesh& mesh = scene.mesh(*c.draw);
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                const std::uint32_t id = scene.slot_material(*c.draw, s);
                if (is_partly_transparent(id) && !own.count(id))
                    scene.draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
            }
        }
    }
    if (!own.empty()) {
        materials_->bind_constants();
        for (auto& [id, p] : own) {
            glProgramUniform4fv(p, LOC_SHADOW_CLIP, SHADOW_CLIP_PLANES, clip);
            glProgramUniformMatrix4fv(p, 2, 1, GL_FALSE, view_projection);
            glProgramUniform4fv(p, 20, 1, origin);
            glProgramUniform3fv(p, 21, 1, axis);
            draw_material(scene, id, p);
        }
    }
    glUseProgram(GLuint(caster));
    return n;
}

}  // namespace deferred
