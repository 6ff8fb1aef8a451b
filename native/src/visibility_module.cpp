#include "visibility_module.h"

#include "geometry_stage.h"
#include "material_module.h"
#include "scene_store.h"

#include "../../shaders/shader_defines.h"

#include <deferred/renderer.h>

#include <algorithm>

namespace deferred {

std::string VisibilityBuffer::unsupported(int width, int height) {
    // The classification packs a tile's x and y into 16 bits each.
    if (width > 65535 * VIS_TILE || height > 65535 * VIS_TILE) return "the image is too large";
    return {};
}

void VisibilityBuffer::prepare(ShaderLibrary& shaders, MaterialModule& materials, const ShaderVariant& base,
                               const std::vector<GraphMaterial>& graphs, const std::vector<bool>& partly_transparent,
                               std::vector<std::string>& warnings) {
    ShaderVariant raster;
    raster.defines.push_back("VISIBILITY_PASS");
    // The node materials' programs compile on the driver's threads together.
    for (const GraphMaterial& g : graphs) {
        if (g.alpha) materials.prefetch(shaders, g.graph, raster);
        materials.prefetch_resolve(shaders, g.graph, base);
    }
    partly_transparent_ = partly_transparent;
    const bool scene_alpha = std::find(partly_transparent.begin(), partly_transparent.end(), true) != partly_transparent.end();
    alpha_raster_ = alpha_test_ = 0;
    one_program_style_ = DrawStyle{};
    if (scene_alpha) {
        // The constant materials' alpha test (pick_material, transparent_here),
        // then the same ids as visibility_frag.glsl.
        ShaderVariant alpha = raster;
        alpha.defines.push_back("SCENE_ALPHA");
        alpha_test_ = shaders.graphics_program("geometry_vert.glsl", "geometry_frag.glsl", alpha);
    }
    if (scene_alpha && !alpha_apart_enabled()) {
        raster_ = alpha_test_;
    } else {
        ShaderVariant ids = raster;
        one_program_style_.by_vertex = draw_by_vertex_enabled();
        one_program_style_.first_triangle_location = LOC_FIRST_TRIANGLE;
        if (one_program_style_.by_vertex) ids.defines.push_back("INDEXED_DRAW");
        raster_ = shaders.graphics_program("geometry_vert.glsl", "visibility_frag.glsl", ids);
        alpha_raster_ = alpha_test_;
    }
    ShaderVariant v;
    v.defines = {"VIS_COUNT"};
    count_ = shaders.compute_program("visibility_classify_comp.glsl", v);
    v.defines = {"VIS_SCAN"};
    scan_ = shaders.compute_program("visibility_classify_comp.glsl", v);
    v.defines = {"VIS_SCATTER"};
    scatter_ = shaders.compute_program("visibility_classify_comp.glsl", v);
    resolve_ = shaders.compute_program("gbuffer_resolve_comp.glsl", base);
    graph_resolves_.clear();
    graph_rasters_.clear();
    graph_of_.clear();
    for (const GraphMaterial& g : graphs) {
        GLuint resolve = 0, alpha_raster = 0;
        try {
            resolve = materials.resolve_program(shaders, g.graph, base);
            if (g.alpha) alpha_raster = materials.program(shaders, g.graph, raster);
        } catch (const Error& e) {
            // Its GpuMaterial holds Material's defaults: the default surface,
            // resolved and rasterised as a constant material.
            const std::string& name = materials.name(g.graph);
            warnings.push_back("Material '" + (name.empty() ? std::to_string(g.id) : name) +
                               "': its node graph did not compile (default surface used): " + e.what());
            continue;
        }
        graph_resolves_.emplace_back(g.id, resolve);
        if (alpha_raster) graph_rasters_.emplace_back(g.id, alpha_raster);
        if (graph_of_.size() <= g.id) graph_of_.resize(std::size_t(g.id) + 1, ~0u);
        graph_of_[g.id] = g.graph;
    }
}

std::size_t VisibilityBuffer::distinct_graph_programs() const {
    std::vector<GLuint> distinct;
    for (auto& [id, p] : graph_resolves_)
        if (std::find(distinct.begin(), distinct.end(), p) == distinct.end()) distinct.push_back(p);
    return distinct.size();
}

void VisibilityBuffer::set_alpha_mode(bool data, float threshold) const {
    const float mode = data ? 1.0f : 0.0f;
    if (alpha_test_) glProgramUniform2f(alpha_test_, 22, mode, threshold);
    for (auto& [id, program] : graph_rasters_) glProgramUniform2f(program, 22, mode, threshold);
}

void VisibilityBuffer::ensure(int width, int height, std::size_t slot_count, GLuint depth) {
    slot_count = std::max<std::size_t>(slot_count, 1);
    if (width != width_ || height != height_) {
        ids_ = make_texture_2d(GL_RGBA32UI, width, height, "visibility buffer");
        GLuint fbo = 0;
        glCreateFramebuffers(1, &fbo);
        fbo_ = Framebuffer(fbo);
        glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, ids_.get(), 0);
        glNamedFramebufferDrawBuffer(fbo, GL_COLOR_ATTACHMENT0);
        tiles_x_ = (width + VIS_TILE - 1) / VIS_TILE;
        tiles_y_ = (height + VIS_TILE - 1) / VIS_TILE;
        width_ = width;
        height_ = height;
    }
    // Attached every frame: a G-buffer reallocated since may have been given
    // the old depth texture's name for a new texture.
    glNamedFramebufferTexture(fbo_.get(), GL_DEPTH_ATTACHMENT, depth, 0);
    const GLenum status = glCheckNamedFramebufferStatus(fbo_.get(), GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        throw Error("visibility buffer framebuffer incomplete (status 0x" + std::to_string(status) + ")");
    if (slot_count > slot_capacity_) {
        keys_ = make_storage_buffer(nullptr, slot_count * VIS_KEY_STRIDE * sizeof(std::uint32_t),
                                    "visibility buffer keys");
        slot_capacity_ = slot_count;
    }
    // Each (tile, key) pair has a pixel of its own: at most one per pixel,
    // and at most every key in every tile.
    const std::size_t pixels = std::size_t(width_) * std::size_t(height_);
    const std::size_t pairs = std::min(pixels, std::size_t(tiles_x_) * std::size_t(tiles_y_) * slot_capacity_);
    if (pairs > tile_capacity_) {
        tiles_ = make_storage_buffer(nullptr, pairs * sizeof(std::uint32_t), "visibility buffer tiles");
        tile_capacity_ = pairs;
    }
    bytes_ = pixels * 16 + tile_capacity_ * sizeof(std::uint32_t) + slot_capacity_ * VIS_KEY_STRIDE * sizeof(std::uint32_t);
    check_gl("allocating the visibility buffer");
}

GLuint VisibilityBuffer::resolve_for(std::uint32_t material) const {
    if (material < graph_of_.size() && graph_of_[material] != ~0u)
        for (auto& [id, program] : graph_resolves_)
            if (id == material) return program;
    return resolve_;
}

GLuint VisibilityBuffer::raster_for(std::uint32_t material) const {
    for (auto& [id, program] : graph_rasters_)
        if (id == material) return program;
    return 0;
}

void VisibilityBuffer::draw(const FrameScene& scene, const MaterialModule& materials, const GBuffer& gbuffer,
                            const std::vector<bool>& skip, const std::vector<bool>* resolve_only) const {
    auto skipped = [&](std::uint32_t id) { return id < skip.size() && skip[id]; };
    const bool any_skipped = std::find(skip.begin(), skip.end(), true) != skip.end();
    const GLuint key_count = GLuint(scene.slot_count());

    // Raster: depth and ids. The G-buffer's targets were cleared by its
    // bind_for_geometry(), depth included; the ids are cleared to 0 (none).
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    glViewport(0, 0, width_, height_);
    const GLuint none[4] = {0, 0, 0, 0};
    glClearNamedFramebufferuiv(fbo_.get(), GL_COLOR, 0, none);
    // The shared program for every slot without one of its own, then the
    // partly transparent constant materials' (their alpha test).
    glUseProgram(raster_);
    for (const FrameScene::Culled& c : scene.visible()) {
        const GpuMesh& mesh = scene.mesh(*c.draw);
        if (!any_skipped && graph_rasters_.empty() && alpha_raster_ == 0) {
            scene.draw_range(c, 0, mesh.triangle_count, one_program_style_);
            continue;
        }
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
            const std::uint32_t id = scene.slot_material(*c.draw, s);
            if (!skipped(id) && raster_for(id) == 0 && !transparent(id))
                scene.draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second, one_program_style_);
        }
    }
    if (alpha_raster_) {
        glUseProgram(alpha_raster_);
        for (const FrameScene::Culled& c : scene.visible()) {
            const GpuMesh& mesh = scene.mesh(*c.draw);
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                const std::uint32_t id = scene.slot_material(*c.draw, s);
                if (!skipped(id) && raster_for(id) == 0 && transparent(id))
                    scene.draw_range(c, mesh.slot_ranges[s].first, mesh.slot_ranges[s].second);
            }
        }
    }
    // Node materials that drive alpha: each with its own program (the graph
    // evaluated for its alpha test), as GeometryStage::draw_material.
    if (!graph_rasters_.empty()) materials.bind_constants();
    for (auto& [material, program] : graph_rasters_)
        if (!skipped(material)) draw_material_slots(scene, materials, material, program);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    // Classify: the tiles listed by the keys they see.
    glClearNamedBufferData(keys_.get(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_VIS_KEYS, keys_.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_VIS_TILES, tiles_.get());
    glBindTextureUnit(TEX_VISIBILITY, ids_.get());
    const GLuint groups_x = GLuint(tiles_x_), groups_y = GLuint(tiles_y_);
    glUseProgram(count_);
    glUniform1ui(LOC_VIS_KEY_COUNT, key_count);
    glDispatchCompute(groups_x, groups_y, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    glUseProgram(scan_);
    glUniform1ui(LOC_VIS_KEY_COUNT, key_count);
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    glUseProgram(scatter_);
    glUniform1ui(LOC_VIS_KEY_COUNT, key_count);
    glDispatchCompute(groups_x, groups_y, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);

    // Resolve: one indirect dispatch per key drawn, over its tiles.
    gbuffer.bind_images();
    materials.bind_constants();
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, keys_.get());
    std::vector<bool> done(key_count, false);
    for (const FrameScene::Culled& c : scene.visible()) {
        const FrameScene::Draw& d = *c.draw;
        const GpuMesh& mesh = scene.mesh(d);
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
            if (mesh.slot_ranges[s].second == 0) continue;
            const std::uint32_t id = scene.slot_material(d, s);
            // The key the vertex stage gave these triangles (geometry_vert.glsl).
            const std::uint32_t key = d.slot_offset + std::uint32_t(std::min<std::size_t>(s, std::max(d.slot_count, 1u) - 1));
            if (skipped(id) || key >= key_count || done[key]) continue;
            done[key] = true;
            if (resolve_only && !(id < resolve_only->size() && (*resolve_only)[id])) continue;
            const GLuint program = resolve_for(id);
            glUseProgram(program);
            scene.bind_mesh(mesh);
            scene.bind_attributes(mesh);
            if (program != resolve_) materials.bind_for_draw(graph_of_[id], mesh);
            glUniform1ui(1, mesh.flags);
            glUniform1ui(LOC_VIS_KEY, key);
            glDispatchComputeIndirect(GLintptr(std::size_t(key) * VIS_KEY_STRIDE * sizeof(std::uint32_t)));
        }
    }
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
    // Before the G-buffer is read, and before the next clears of it and of
    // the key buffer (a framebuffer clear, a buffer clear).
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT |
                    GL_BUFFER_UPDATE_BARRIER_BIT);
    check_gl("visibility buffer");
}

}  // namespace deferred
