#include "material_module.h"

#include "material_codegen.h"
#include "scene_store.h"

#include "../../shaders/shader_defines.h"

#include <deferred/renderer.h>

#include <algorithm>
#include <cmath>

namespace deferred {

void MaterialModule::clear() {
    // A clear right after a clear (nothing added or found in between) keeps
    // the images: "used by the last scene" means the last non-empty one.
    if (!scene_started_) return;
    scene_started_ = false;
    for (StoredImage& im : images_) {
        if (im.texture && (!im.used || im.key.empty())) {
            image_bytes_ -= im.bytes;
            im = StoredImage();
        }
        im.used = false;
    }
    graphs_.clear();
    constants_.clear();
    constants_buffer_.reset();
    images_uploaded_ = images_reused_ = 0;
}

void MaterialModule::release_unused() {
    for (StoredImage& im : images_)
        if (im.texture && !im.used) {
            image_bytes_ -= im.bytes;
            im = StoredImage();
        }
}

std::int64_t MaterialModule::find_image(const std::string& key) {
    if (key.empty()) return -1;
    for (std::size_t i = 0; i < images_.size(); ++i)
        if (images_[i].texture && images_[i].key == key) {
            if (!images_[i].used) ++images_reused_;
            images_[i].used = true;
            scene_started_ = true;
            return std::int64_t(i);
        }
    return -1;
}

std::uint32_t MaterialModule::add_image(const ImageData& image, const std::string& key) {
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (image.width <= 0 || image.height <= 0)
        throw InvalidInput("image: size " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                           " must be positive");
    if (image.width > max_size || image.height > max_size)
        throw InvalidInput("image: " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                           " exceeds the GPU's texture limit of " + std::to_string(max_size));
    if ((image.bytes == nullptr) == (image.floats == nullptr))
        throw InvalidInput("image: exactly one of bytes and floats must be given");
    const std::size_t texels = std::size_t(image.width) * std::size_t(image.height);
    if (image.floats) {
        // Non-finite texels would reach the G-buffer through any node.
        for (std::size_t i = 0; i < texels * 4; ++i)
            if (!std::isfinite(image.floats[i]))
                throw InvalidInput("image: texel " + std::to_string(i / 4) + " is NaN or infinite");
    }
    const GLenum format = image.bytes ? GL_RGBA8 : GL_RGBA32F;
    StoredImage stored;
    stored.texture = make_texture_2d(format, image.width, image.height, "material image");
    stored.width = image.width;
    stored.height = image.height;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (image.bytes)
        glTextureSubImage2D(stored.texture.get(), 0, 0, 0, image.width, image.height, GL_RGBA, GL_UNSIGNED_BYTE,
                            image.bytes);
    else
        glTextureSubImage2D(stored.texture.get(), 0, 0, 0, image.width, image.height, GL_RGBA, GL_FLOAT, image.floats);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);  // GL's default, as the rest of the library expects
    check_gl("uploading a material image");
    stored.bytes = texels * (image.bytes ? 4 : 16);
    stored.used = true;
    scene_started_ = true;
    image_bytes_ += stored.bytes;
    ++images_uploaded_;
    if (!key.empty()) {
        // A new upload under a kept key replaces that image (its content changed).
        for (StoredImage& old : images_)
            if (old.texture && old.key == key && !old.used) {
                image_bytes_ -= old.bytes;
                old = StoredImage();
            }
        stored.key = key;
    }
    for (std::size_t i = 0; i < images_.size(); ++i)
        if (!images_[i].texture) {
            images_[i] = std::move(stored);
            return std::uint32_t(i);
        }
    images_.push_back(std::move(stored));
    return std::uint32_t(images_.size() - 1);
}

std::uint32_t MaterialModule::add_graph(const MaterialGraph& graph) {
    validate_material_graph(graph);
    for (std::uint32_t id : graph.images)
        if (id >= images_.size() || !images_[id].texture)
            throw InvalidInput("material graph: image id " + std::to_string(id) + " does not exist (" +
                               std::to_string(images_.size()) + " images)");
    scene_started_ = true;
    StoredGraph g;
    g.graph = graph;
    g.graph.constants.clear();
    g.glsl = material_graph_glsl(graph);
    g.constants_offset = std::uint32_t(constants_.size());
    constants_.insert(constants_.end(), graph.constants.begin(), graph.constants.end());
    for (const GraphNode& n : graph.nodes)
        if (n.func == "node_bsdf_principled") g.principled = true;
    graphs_.push_back(std::move(g));
    return std::uint32_t(graphs_.size() - 1);
}

bool MaterialModule::uses_params1() const {
    // A Principled BSDF node gives sheen (its argument 5) or clearcoat (7)
    // unless both are constants of at most 0 (node_bsdf_principled clamps
    // them to [0, 1]): the usual node material, whose G-buffer then needs
    // no params1 and whose lighting folds both lobes away.
    for (const StoredGraph& g : graphs_) {
        if (!g.principled) continue;
        for (const GraphNode& n : g.graph.nodes) {
            if (n.func != "node_bsdf_principled") continue;
            auto may_be_positive = [&](std::size_t k) {
                if (k >= n.args.size()) return true;
                const GraphArg& a = n.args[k];
                if (a.kind != GraphArg::Kind::Const || a.type != SocketType::Float) return true;
                const std::size_t at = std::size_t(g.constants_offset) + std::size_t(a.value);
                return at >= constants_.size() || !(constants_[at] <= 0.0f);
            };
            if (may_be_positive(5) || may_be_positive(7)) return true;
        }
    }
    return false;
}

bool MaterialModule::uses_node(const std::string& func) const {
    for (const StoredGraph& g : graphs_)
        for (const GraphNode& n : g.graph.nodes)
            if (n.func == func) return true;
    return false;
}

bool MaterialModule::uses_smooth_normal() const {
    for (const StoredGraph& g : graphs_)
        if (g.graph.closure_normal) return true;
    return false;
}

void MaterialModule::upload_constants() {
    constants_buffer_ = make_storage_buffer(constants_.data(), constants_.size() * sizeof(float), "material constants");
}

void MaterialModule::bind_constants() const {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_MATERIAL_CONSTANTS, constants_buffer_.get());
}

GLuint MaterialModule::program(ShaderLibrary& shaders, std::uint32_t graph, const ShaderVariant& base) {
    return shaders.graphics_program("geometry_vert.glsl", "geometry_frag.glsl", program_variant(graph, base),
                                    {{kMaterialGraphFile, graph_source(shaders, graph)}});
}

void MaterialModule::prefetch(ShaderLibrary& shaders, std::uint32_t graph, const ShaderVariant& base) {
    if (!shaders.parallel_compile()) return;
    try {
        shaders.prefetch_graphics("geometry_vert.glsl", "geometry_frag.glsl", program_variant(graph, base),
                                  {{kMaterialGraphFile, graph_source(shaders, graph)}});
    } catch (const std::exception&) {
        // program() reports it.
    }
}

GLuint MaterialModule::resolve_program(ShaderLibrary& shaders, std::uint32_t graph, const ShaderVariant& base) {
    return shaders.compute_program("gbuffer_resolve_comp.glsl", program_variant(graph, base),
                                   {{kMaterialGraphFile, graph_source(shaders, graph)}});
}

void MaterialModule::prefetch_resolve(ShaderLibrary& shaders, std::uint32_t graph, const ShaderVariant& base) {
    if (!shaders.parallel_compile()) return;
    try {
        shaders.prefetch_compute("gbuffer_resolve_comp.glsl", program_variant(graph, base),
                                 {{kMaterialGraphFile, graph_source(shaders, graph)}});
    } catch (const std::exception&) {
        // resolve_program() reports it.
    }
}

ShaderVariant MaterialModule::program_variant(std::uint32_t graph, const ShaderVariant& base) const {
    const StoredGraph& g = graphs_.at(graph);
    ShaderVariant v = base;
    // The constant program's transparency switch is not this program's.
    v.defines.erase(std::remove(v.defines.begin(), v.defines.end(), std::string("SCENE_ALPHA")), v.defines.end());
    v.defines.push_back("MATERIAL_GRAPH");
    if (g.graph.alpha) v.defines.push_back("MATERIAL_ALPHA");
    v.defines.push_back("MATERIAL_ATTRIBUTE_COUNT " + std::to_string(g.graph.attributes.size()));
    // Random Per Island is constant per triangle and meant to be hashed
    // further: read flat, since interpolating three equal values may move
    // the last bit (material_graph.h).
    for (std::size_t k = 0; k < g.graph.attributes.size(); ++k)
        if (g.graph.attributes[k].rfind(kFlatAttributePrefix, 0) == 0) {
            v.defines.push_back("MATERIAL_FLAT_ATTRIBUTE " + std::to_string(k));
            break;
        }
    v.defines.push_back("MATERIAL_IMAGE_COUNT " + std::to_string(g.graph.images.size()));
    if (calls(graph, "node_bump_offset")) v.defines.push_back("MATERIAL_BUMP");
    return v;
}

std::string MaterialModule::graph_source(ShaderLibrary& shaders, std::uint32_t graph) const {
    const StoredGraph& g = graphs_.at(graph);
    // Made once per graph: a prefetch and the request after it both need it.
    if (!g.source.empty()) return g.source;
    // The node library files the graph calls into (and theirs), then the graph.
    std::vector<std::string> functions = material_graph_functions(g.graph);
    functions.push_back("node_closure_none");
    std::string source = "#include \"material_lib.glsl\"\n";
    for (const std::string& file : shaders.node_files_for(functions)) source += "#include \"" + file + "\"\n";
    g.source = source + g.glsl;
    return g.source;
}

bool MaterialModule::calls(std::uint32_t graph, const std::string& function) const {
    for (const GraphNode& n : graphs_.at(graph).graph.nodes)
        if (n.func == function) return true;
    return false;
}

void MaterialModule::bind_images(std::uint32_t graph) const {
    const StoredGraph& g = graphs_.at(graph);
    for (std::size_t k = 0; k < g.graph.images.size(); ++k)
        glBindTextureUnit(GLuint(TEX_MATERIAL_IMAGE0 + k), images_[g.graph.images[k]].texture.get());
}

std::array<int, 2> MaterialModule::largest_image(std::uint32_t graph) const {
    std::array<int, 2> size{0, 0};
    for (std::uint32_t id : graphs_.at(graph).graph.images) {
        size[0] = std::max(size[0], images_[id].width);
        size[1] = std::max(size[1], images_[id].height);
    }
    return size;
}

ShaderVariant MaterialModule::caster_variant(bool world_map) {
    ShaderVariant v;
    v.defines.push_back("SHADOW_PASS");
    if (world_map) v.defines.push_back("WORLD_MAP");
    return v;
}

GLuint MaterialModule::caster_program(ShaderLibrary& shaders, std::uint32_t graph, bool world_map) {
    return program(shaders, graph, caster_variant(world_map));
}

void MaterialModule::bind_for_draw(std::uint32_t graph, const GpuMesh& mesh) const {
    const StoredGraph& g = graphs_.at(graph);
    bind_images(graph);
    GLint layout[4 * kMaxGraphAttributes];
    for (int k = 0; k < kMaxGraphAttributes; ++k) {
        layout[4 * k] = -1;
        layout[4 * k + 1] = layout[4 * k + 2] = layout[4 * k + 3] = 0;
        if (std::size_t(k) >= g.graph.attributes.size()) continue;
        for (const MeshAttributeLayout& a : mesh.attribute_layout)
            if (a.name == g.graph.attributes[std::size_t(k)]) {
                layout[4 * k] = GLint(a.offset);
                layout[4 * k + 1] = a.components;
            }
    }
    glUniform4iv(3, kMaxGraphAttributes, layout);
    glUniform3f(11, mesh.texspace_location[0], mesh.texspace_location[1], mesh.texspace_location[2]);
    glUniform3f(12, mesh.texspace_size[0], mesh.texspace_size[1], mesh.texspace_size[2]);
}

}  // namespace deferred
