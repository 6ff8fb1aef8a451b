#include "light_culling.h"

#include "../../shaders/shader_defines.h"
#include "../../shaders/shader_shared.h"

#include <deferred/renderer.h>

#include <algorithm>
#include <limits>

namespace deferred {

void LightCulling::build(ShaderLibrary& shaders, std::uint32_t tiles_x, std::uint32_t tiles_y) {
    const std::size_t tile_count = std::size_t(tiles_x) * tiles_y;
    if (tile_count > tile_capacity_) {
        tiles_ = make_storage_buffer(nullptr, tile_count * sizeof(gpu::GpuTile), "light tiles");
        tile_capacity_ = tile_count;
    }
    if (!indices_) {
        index_capacity_ = std::uint32_t(std::max<std::size_t>(tile_count * 8, 1024));
        indices_ = make_storage_buffer(nullptr, std::size_t(index_capacity_) * 4, "tile light indices");
    }
    if (!counter_) counter_ = make_storage_buffer(nullptr, 16, "cull counter");

    auto dispatch = [&](const char* mode) {
        const std::uint32_t counter[2] = {0u, index_capacity_};
        glNamedBufferSubData(counter_.get(), 0, sizeof(counter), counter);
        ShaderVariant v;
        v.defines.push_back(mode);
        glUseProgram(shaders.compute_program("light_cull_comp.glsl", v));
        bind();
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_CULL_COUNTER, counter_.get());
        glDispatchCompute(tiles_x, tiles_y, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    };
    dispatch("CULL_COUNT");
    std::uint32_t total = 0;
    glGetNamedBufferSubData(counter_.get(), 0, sizeof(total), &total);
    last_count_ = total;
    if (total > index_capacity_) {
        // Grow with headroom so a camera move does not reallocate every frame.
        const std::uint64_t want = std::uint64_t(total) + total / 2;
        if (want * 4 > std::uint64_t(std::numeric_limits<GLsizeiptr>::max()) || want > 0xffffffffu)
            throw Error("light culling: " + std::to_string(total) + " tile-light pairs exceed the index buffer limit");
        index_capacity_ = std::uint32_t(want);
        indices_ = make_storage_buffer(nullptr, std::size_t(index_capacity_) * 4, "tile light indices");
    }
    // The write pass reads each tile's reserved offset from the count pass.
    dispatch("CULL_WRITE");
    check_gl("light culling");
}

void LightCulling::bind() const {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_TILES, tiles_.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_TILE_LIGHTS, indices_.get());
}

}  // namespace deferred
