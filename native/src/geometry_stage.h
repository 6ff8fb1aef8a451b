// The geometry stage: every draw of the scene's surfaces with their
// material programs — the G-buffer (shaders/geometry_frag.glsl for the
// constant materials, one generated program per node-material graph), the
// data G-buffer under transparency, shader AOVs, and the shadow casters of
// node materials that drive alpha (their caster programs evaluate the graph).
//
// Programs are compiled before the first sample (prepare*); a graph that
// does not compile takes the default surface, warned, never a failed frame.
// With node materials the G-buffer is drawn depth first, so the expensive
// fragments shade each pixel once: the colour pass then tests for equal
// depth (gl_Position is invariant across the programs).
#pragma once

#include "frame_scene.h"
#include "shader_library.h"

#include <deferred/renderer.h>

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace deferred {

class AovModule;
class MaterialModule;

// Draws the slot ranges of the last cull's instances that use node material
// `id`, with `program` and the graph's per-draw state (images, the mesh's
// attribute slots): GeometryStage's programs and the visibility buffer's.
void draw_material_slots(const FrameScene& scene, const MaterialModule& materials, std::uint32_t id, GLuint program);

class GeometryStage {
public:
    // The G-buffer program (SCENE_ALPHA when a constant material is partly
    // transparent) and every node material's program for `base`.
    // `graph_programs` false (the visibility buffer resolves the G-buffer):
    // the node materials' G-buffer programs are not compiled (their ids and
    // alpha flags are still known; graph_programs() lists them with 0).
    void prepare(ShaderLibrary& shaders, MaterialModule& materials, const FrameScene& scene,
                 const ShaderVariant& base, bool scene_alpha, std::vector<std::string>& warnings,
                 bool graph_programs = true);
    // Materials drawn by the forward pass instead (forward_module.h): left
    // out of the G-buffer.
    // The data G-buffer (draw with `data`) leaves out `data_skipped`
    // instead: the Blend-mode materials, which write no data pass (as in
    // EEVEE), while the exact layers (layer_order.h) stay in it with the
    // Alpha Threshold's coverage, as every partly transparent surface.
    void exclude(const std::vector<bool>& forward) { forward_ = data_skipped_ = forward; }
    void exclude_from_data(const std::vector<bool>& data_skipped) { data_skipped_ = data_skipped; }
    const std::vector<bool>& data_skipped() const { return data_skipped_; }

    GLuint program() const { return geometry_; }
    // material id -> its graph's program, for the graphs that compiled.
    const std::vector<std::pair<std::uint32_t, GLuint>>& graph_programs() const { return graph_programs_; }
    std::size_t distinct_graph_programs() const;
    // A node material whose graph did not compile (drawn as a constant one).
    bool failed(std::uint32_t id) const { return failed_[id]; }
    // A node material whose alpha can be below 1 (its program discards).
    bool is_alpha_graph(std::uint32_t id) const { return alpha_[id]; }
    bool alpha_graphs() const { return alpha_graphs_; }
    // Something in the scene can be partly transparent this sample.
    bool stochastic_alpha() const { return scene_alpha_ || alpha_graphs_; }

    // Draws the instances that pass `keep` into the bound G-buffer (`data`:
    // the data G-buffer, leaving out data_skipped() instead of forward());
    // returns how many were kept.
    std::uint64_t draw(FrameScene& scene, const FrameScene::Test& keep, bool data = false);
    // Draws the slot ranges of the last cull's instances that use node
    // material `id`, with `program`.
    void draw_material(const FrameScene& scene, std::uint32_t id, GLuint program) const;
    // Stochastic coverage (false) or the Alpha Threshold's (true, the data G-buffer).
    void set_alpha_mode(bool data, float threshold) const;

    // Shader AOVs: the AOV program of every graph that writes one of `aovs`.
    void prepare_aovs(ShaderLibrary& shaders, MaterialModule& materials, const FrameScene& scene,
                      const ShaderVariant& base, const std::vector<AovRequest>& aovs,
                      std::vector<std::string>& warnings);
    // Each AOV's writers over the G-buffer just drawn (the last cull's instances).
    void draw_aovs(const FrameScene& scene, const AovModule& aovs, const std::vector<AovRequest>& requests,
                   int samples) const;

    // The caster programs of the alpha graphs (for the lights' maps, and the
    // world's when world_map); one that fails casts an opaque shadow, warned.
    void prepare_casters(ShaderLibrary& shaders, MaterialModule& materials, const FrameScene& scene, bool world_map,
                         std::vector<std::string>& warnings);
    // The shadow casters that pass `casts`, with the bound program (the
    // shadow module's, drawn as `style` says) or their own (by corner, both
    // sides); `world_map`: the bound program draws a world occlusion map.
    // `alpha_program` (0: none): the shadow module's program for partly
    // transparent constant materials (SCENE_ALPHA: each fragment kept with
    // probability alpha), whose slots it draws by corner, both sides, with
    // the bound program's uniforms; the bound one then draws only opaque
    // slots. Returns how many instances were kept.
    std::uint64_t draw_casters(FrameScene& scene, const FrameScene::Test& casts, bool world_map,
                               const DrawStyle& style = {}, const FaceCulling* faces = nullptr,
                               GLuint alpha_program = 0) const;
    // A constant material whose coverage (FrameScene::coverage) is below 1.
    bool is_partly_transparent(std::uint32_t id) const { return id < partly_transparent_.size() && partly_transparent_[id]; }
    const std::vector<bool>& partly_transparent() const { return partly_transparent_; }  // per material id

    bool is_forward(std::uint32_t id) const { return id < forward_.size() && forward_[id]; }
    // Per material id: drawn by the forward pass (left out of the G-buffer).
    const std::vector<bool>& forward() const { return forward_; }

private:

    const MaterialModule* materials_ = nullptr;
    GLuint geometry_ = 0;
    bool scene_alpha_ = false, alpha_graphs_ = false;
    std::vector<std::pair<std::uint32_t, GLuint>> graph_programs_;
    std::vector<bool> failed_, alpha_, forward_, data_skipped_, partly_transparent_;  // per material id
    std::map<std::uint32_t, GLuint> aov_programs_;
    std::vector<std::vector<std::pair<std::uint32_t, int>>> aov_writers_;  // per AOV: (material id, slot)
    std::map<std::uint32_t, GLuint> light_casters_, world_casters_;
};

}  // namespace deferred
