// Node materials on the GPU: their graphs (validated, turned into GLSL),
// the constants buffer every graph material reads, the images texture nodes
// sample, and the per-draw state a graph needs (program, images, attribute
// layout of the mesh drawn). The constant Principled materials stay in the
// SceneStore; a material with `graph >= 0` is drawn with its graph's program.
#pragma once

#include "gl_util.h"
#include "shader_library.h"

#include <deferred/material_graph.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace deferred {

struct GpuMesh;

class MaterialModule {
public:
    // Drops the graphs and constants of the scene. Images outlive it: one
    // added with a key, or found by it, since the previous clear stays on
    // the GPU for the next scene (a persistent renderer finds it again by
    // its key and uploads nothing); every other image is released.
    void clear();
    // Releases everything, images included.
    void release_all() { *this = MaterialModule(); }

    // Validates and uploads an image (RGBA8 or RGBA32F); returns its id.
    // A non-empty key (the caller's name for the content: file, time,
    // settings) lets the next scene find it with find_image().
    std::uint32_t add_image(const ImageData& image, const std::string& key = {});
    // Releases the kept images this scene has not used yet (to make room).
    void release_unused();
    // The id of a kept image with this key (marked as used by this scene), or -1.
    std::int64_t find_image(const std::string& key);
    std::size_t images_uploaded() const { return images_uploaded_; }  // since the last clear
    std::size_t images_reused() const { return images_reused_; }      // found by key since the last clear
    // Validates a graph (images must exist) and keeps it; returns its index.
    std::uint32_t add_graph(const MaterialGraph& graph);

    std::size_t image_bytes() const { return image_bytes_; }
    std::uint32_t constants_offset(std::uint32_t graph) const { return graphs_[graph].constants_offset; }
    const std::string& name(std::uint32_t graph) const { return graphs_[graph].graph.name; }
    bool alpha(std::uint32_t graph) const { return graphs_[graph].graph.alpha; }
    // The AOV names the graph's AOV Output slots write.
    const std::vector<std::string>& aovs(std::uint32_t graph) const { return graphs_[graph].graph.aovs; }
    // True if some graph can produce sheen or clearcoat (the G-buffer's
    // params1): a Principled BSDF node whose Sheen or Clearcoat is linked
    // or a constant above 0.
    bool uses_params1() const;
    // True if some graph calls the node function `func` (node_bsdf_diffuse, ...).
    bool uses_node(const std::string& func) const;
    // True if some graph gives a closure another normal than the smooth one
    // (the G-buffer's smooth normal).
    bool uses_smooth_normal() const;

    // Per frame: the constants buffer (bound while the geometry pass runs).
    void upload_constants();
    void bind_constants() const;

    // The geometry-pass program of a graph, compiled on first use (cached by
    // its GLSL in the ShaderLibrary, so graphs of one structure share it).
    GLuint program(ShaderLibrary& shaders, std::uint32_t graph, const ShaderVariant& base);
    // The shadow-map caster program of a graph that drives alpha (SHADOW_PASS;
    // world_map: the world's occlusion map). Uniforms: the map's view-projection
    // at location 2, origin at 20, axis at 21 (shadow_frag.glsl's 2, 3, 4).
    GLuint caster_program(ShaderLibrary& shaders, std::uint32_t graph, bool world_map);
    static ShaderVariant caster_variant(bool world_map);
    // The graph's G-buffer resolve for the visibility buffer
    // (gbuffer_resolve_comp.glsl: the same surface code in compute), and its
    // prefetch (never throws).
    GLuint resolve_program(ShaderLibrary& shaders, std::uint32_t graph, const ShaderVariant& base);
    void prefetch_resolve(ShaderLibrary& shaders, std::uint32_t graph, const ShaderVariant& base);
    // Starts compiling program(shaders, graph, base) on the driver's threads
    // (ShaderLibrary::prefetch_graphics): prefetch every graph a frame needs,
    // then ask for each, and the compiles overlap. Never throws.
    void prefetch(ShaderLibrary& shaders, std::uint32_t graph, const ShaderVariant& base);
    // The generated file (kMaterialGraphFile) a graph's programs include:
    // material_lib.glsl, the node-library files the graph calls, the graph.
    std::string graph_source(ShaderLibrary& shaders, std::uint32_t graph) const;
    // True if the graph calls the node-library function `function`.
    bool calls(std::uint32_t graph, const std::string& function) const;
    std::size_t image_count(std::uint32_t graph) const { return graphs_[graph].graph.images.size(); }
    // Largest width and height among the graph's images (0, 0 without images).
    std::array<int, 2> largest_image(std::uint32_t graph) const;
    // The graph's images at TEX_MATERIAL_IMAGE0 + slot.
    void bind_images(std::uint32_t graph) const;
    // Per draw: the graph's images and the mesh's attribute slots and texture space.
    void bind_for_draw(std::uint32_t graph, const GpuMesh& mesh) const;

private:
    ShaderVariant program_variant(std::uint32_t graph, const ShaderVariant& base) const;
    struct StoredGraph {
        MaterialGraph graph;   // constants moved to the shared buffer
        std::string glsl;
        mutable std::string source;  // graph_source(), made on first use
        std::uint32_t constants_offset = 0;
        bool principled = false;
    };
    struct StoredImage {
        Texture texture;  // null: a released slot, reused by the next upload
        int width = 0, height = 0;
        std::size_t bytes = 0;
        std::string key;
        bool used = false;  // added or found since the last clear
    };
    std::vector<StoredGraph> graphs_;
    std::vector<StoredImage> images_;
    std::size_t images_uploaded_ = 0, images_reused_ = 0;
    bool scene_started_ = false;  // something added or found since the last clear
    std::vector<float> constants_;
    std::size_t image_bytes_ = 0;
    Buffer constants_buffer_;
};

}  // namespace deferred
