#include "lighting_stage.h"

#include "film_module.h"
#include "light_culling.h"
#include "light_module.h"
#include "ray_scene.h"
#include "world_module.h"

#include "../../shaders/shader_defines.h"

#include <algorithm>
#include <string>

namespace deferred {

std::uint32_t LightingStage::batch_size(const Config& config) {
    if (config.chunked_mesh_lights) return config.shadow_rays ? kChunkedMeshLightRayBatch : kChunkedMeshLightBatch;
    return config.shadow_rays ? kRayLightBatch : kLightBatch;
}

ShaderVariant LightingStage::variant(const ShaderVariant& base, const LightModule& lights, const WorldModule& world,
                                     const Config& config, bool& light_sampling) {
    ShaderVariant v = base;
    lights.add_defines(v);
    if (config.light_split) v.defines.push_back("OUT_LIGHT_SPLIT");
    if (config.culled) v.defines.push_back("LIGHT_CULLING");
    if (config.kind_loops) v.defines.push_back("LIGHT_KIND_LOOPS");
    // Selection only where some pixel can have more lights than the budget,
    // within one lighting dispatch (512 lights, 8 with shadow rays): a budget
    // of a dispatch's size or more never selects.
    const std::uint32_t batch = batch_size(config);
    const std::uint32_t budget = std::uint32_t(std::max(config.light_samples, 0));
    light_sampling = budget > 0 && lights.count() > budget && budget < batch;
    if (light_sampling) v.defines.push_back("LIGHT_SAMPLING " + std::to_string(budget));
    if (config.shadow_maps) v.defines.push_back("HAS_SHADOWS");
    if (config.shadow_rays) {
        v.defines.push_back("SHADOW_RAYS");
        add_ray_traversal_define(v.defines);
    }
    if (config.world_occlusion) v.defines.push_back("HAS_WORLD_OCCLUSION");
    world.add_defines(v);
    if (config.ao) v.defines.push_back("OUT_AO");
    if (config.light_groups > 0) v.defines.push_back("LIGHT_GROUPS " + std::to_string(config.light_groups));
    if (config.shadow_pass) v.defines.push_back("OUT_SHADOW");
    if (config.catchers) v.defines.push_back("SHADOW_CATCHER");
    if (config.forward_layer) v.defines.push_back("FORWARD_LAYER");
    return v;
}

void LightingStage::prefetch(ShaderLibrary& shaders, const ShaderVariant& base, const LightModule& lights,
                             const WorldModule& world, const Config& config) {
    bool light_sampling = false;
    shaders.prefetch_compute("lighting_comp.glsl", variant(base, lights, world, config, light_sampling));
}

void LightingStage::prepare(ShaderLibrary& shaders, const ShaderVariant& base, const LightModule& lights,
                            const WorldModule& world, const Config& config, std::vector<std::string>& warnings) {
    const ShaderVariant v = variant(base, lights, world, config, light_sampling_);
    batch_ = batch_size(config);
    const std::uint32_t budget = std::uint32_t(std::max(config.light_samples, 0));
    if (budget > 0 && !light_sampling_ && lights.count() > budget)
        warnings.push_back("Light Samples " + std::to_string(budget) + " has no effect: the lighting runs in groups of " +
                           std::to_string(batch_) + " lights" + (config.shadow_rays ? " with shadow rays" : "") +
                           ", and a budget that large never selects; every light is shaded");
    program_ = shaders.compute_program("lighting_comp.glsl", v);
}

void LightingStage::run(const LightModule& lights, const LightCulling* culling, const FilmModule& film,
                        GLuint instance_groups, std::uint32_t world_group, int width, int height,
                        const std::function<void()>& between_batches) {
    glUseProgram(program_);
    use_ray_traversal(program_, GL_COMPUTE_SHADER);
    if (culling) culling->bind();
    film.bind_for_lighting();
    if (instance_groups) {
        lights.bind_groups();
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_INSTANCE_GROUPS, instance_groups);
        glUniform1ui(1, world_group);
    }
    const GLuint groups_x = GLuint((width + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    const GLuint groups_y = GLuint((height + LIGHTING_GROUP_SIZE - 1) / LIGHTING_GROUP_SIZE);
    // Later batches over the pixels the first one lists (lighting_comp.glsl),
    // where the list fits one storage block; over the image otherwise.
    const bool later_batches = lights.count() > batch_;
    const std::size_t pixels = std::size_t(width) * std::size_t(height);
    GLint64 max_block = 0;
    if (later_batches) glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
    const bool from_list = later_batches && kLaterHeader + 4 * std::uint64_t(pixels) <= std::uint64_t(max_block);
    glUniform1i(2, from_list ? 1 : 0);
    if (from_list) {
        if (!later_ || later_pixels_ < pixels) {
            later_ = make_storage_buffer(nullptr, kLaterHeader + pixels * 4, "lighting: later batches' pixels");
            later_pixels_ = pixels;
            const std::uint32_t totals[4] = {0u, 0u, 0u, 0u};  // pixels listed over the samples
            glNamedBufferSubData(later_.get(), 16, sizeof(totals), totals);
        }
        const std::uint32_t header[4] = {0u, 1u, 1u, 0u};  // groups x, y, z; pixels
        glNamedBufferSubData(later_.get(), 0, sizeof(header), header);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_LIGHTING_LATER, later_.get());
    }
    glUniform2ui(0, 0, batch_);
    glDispatchCompute(groups_x, groups_y, 1);
    if (!later_batches) {
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        return;
    }
    // The list's header is read as dispatch arguments and cleared by the
    // next sample's glNamedBufferSubData: both wait for these writes.
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT |
                    GL_BUFFER_UPDATE_BARRIER_BIT);
    if (from_list) glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, later_.get());
    for (std::uint32_t begin = batch_; begin < lights.count(); begin += batch_) {
        between_batches();
        glUniform2ui(0, begin, begin + batch_);
        if (from_list) glDispatchComputeIndirect(0);
        else glDispatchCompute(groups_x, groups_y, 1);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    if (from_list) glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
}

std::uint64_t LightingStage::later_pixels() const {
    if (!later_) return 0;
    std::uint32_t totals[4] = {0u, 0u, 0u, 0u};
    glGetNamedBufferSubData(later_.get(), 16, sizeof(totals), totals);
    return totals[0];
}

}  // namespace deferred
