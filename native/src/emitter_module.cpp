#include "emitter_module.h"

#include <deferred/renderer.h>

#include "../../shaders/shader_defines.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>

namespace deferred {

static_assert(EmitterModule::kChunk == MESH_LIGHT_CHUNK, "light_lib.glsl reads chunks of MESH_LIGHT_CHUNK triangles");

namespace {

double luminance(const glm::dvec3& c) { return 0.2126729 * c.x + 0.7151522 * c.y + 0.0721750 * c.z; }

// The radiance a constant material emits (colour x strength x alpha), as the
// expectation over its stochastic mix chain (what the film converges to).
glm::dvec3 material_emission(const std::vector<Material>& materials, std::uint32_t id, int depth = 0) {
    if (id >= materials.size() || depth > 64) return glm::dvec3(0.0);
    const Material& m = materials[id];
    // A node material: the constant radiance the add-on found in its graph
    // (add_graph_material's light_emission; 0 where the graph varies it:
    // emission_varies, baked).
    if (m.graph >= 0) return glm::dvec3(m.emission[0], m.emission[1], m.emission[2]);
    const glm::dvec3 own = glm::dvec3(m.emission[0], m.emission[1], m.emission[2]) * double(m.emission_strength) *
                           double(std::clamp(m.alpha, 0.0f, 1.0f));
    if (m.mix_with < 0 || !(m.mix_probability > 0.0f)) return own;
    const double p = std::clamp(double(m.mix_probability), 0.0, 1.0);
    return own * (1.0 - p) + material_emission(materials, std::uint32_t(m.mix_with), depth + 1) * p;
}

// +1 / -1: the mesh is closed (every edge, with vertices merged by
// position, shared by exactly two triangles running it in opposite
// directions) and its winding normals point out (+1) or in (-1), by the sign
// of its volume; 0: an open mesh.
int closed_mesh_side(const std::vector<float>& positions, const std::vector<std::uint32_t>& indices) {
    const std::size_t vertex_count = positions.size() / 3;
    // Vertices split by UV seams or sharp edges share a position: one id each.
    std::map<std::array<float, 3>, std::uint32_t> by_position;
    std::vector<std::uint32_t> id(vertex_count);
    for (std::size_t v = 0; v < vertex_count; ++v) {
        const std::array<float, 3> p{positions[v * 3], positions[v * 3 + 1], positions[v * 3 + 2]};
        id[v] = by_position.emplace(p, std::uint32_t(by_position.size())).first->second;
    }
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;  // directed edge -> count
    double volume = 0.0;
    for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
        std::uint32_t v[3];
        for (int k = 0; k < 3; ++k) {
            if (indices[t + std::size_t(k)] >= vertex_count) return 0;
            v[k] = id[indices[t + std::size_t(k)]];
        }
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;  // degenerate: no edge of the surface
        for (int k = 0; k < 3; ++k) ++edges[{v[k], v[(k + 1) % 3]}];
        const std::uint32_t* i = &indices[t];
        const glm::dvec3 a(positions[i[0] * 3], positions[i[0] * 3 + 1], positions[i[0] * 3 + 2]);
        const glm::dvec3 b(positions[i[1] * 3], positions[i[1] * 3 + 1], positions[i[1] * 3 + 2]);
        const glm::dvec3 c(positions[i[2] * 3], positions[i[2] * 3 + 1], positions[i[2] * 3 + 2]);
        volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    if (edges.empty()) return 0;
    for (const auto& [edge, count] : edges) {
        const auto twin = edges.find({edge.second, edge.first});
        if (count != 1 || twin == edges.end() || twin->second != 1) return 0;
    }
    return volume > 0.0 ? 1 : volume < 0.0 ? -1 : 0;
}

}  // namespace

void EmitterModule::sync(const SceneStore& scene, const glm::dvec3& camera_position) {
    release();
    const std::vector<Material>& materials = scene.materials();
    std::vector<glm::dvec3> emission(materials.size());
    // A node material whose emission varies: baked (bake()), its power known after.
    std::vector<bool> textured(materials.size(), false);
    bool any = false;
    for (std::size_t i = 0; i < materials.size(); ++i) {
        textured[i] = materials[i].graph >= 0 && materials[i].emission_varies;
        emission[i] = material_emission(materials, std::uint32_t(i));
        // Negative light is not sampled; radiance beyond the lights' power
        // limit (InputLimits::kMaxLightPower) lights as that limit, which keeps
        // every float product of the lighting finite (the fuzzer found 1e25).
        emission[i] = glm::clamp(emission[i], glm::dvec3(0.0), glm::dvec3(double(InputLimits::kMaxLightPower)));
        if (!std::isfinite(emission[i].x + emission[i].y + emission[i].z)) emission[i] = glm::dvec3(0.0);
        any = any || luminance(emission[i]) > 0.0 || textured[i];
    }
    if (!any) return;

    std::uint32_t instance_base = 0;  // the frame's instance index of the batch's first
    for (const InstanceBatch& batch : scene.batches()) {
        const std::uint32_t batch_base = instance_base;
        instance_base += std::uint32_t(batch.object_indices.size());
        const GpuMesh& mesh = scene.meshes()[batch.mesh_id];
        if (mesh.triangle_count == 0 || batch.material_slots.empty()) continue;
        // The slots of this batch that emit (a constant, or baked).
        std::vector<glm::dvec3> slot_emission(mesh.slot_ranges.size(), glm::dvec3(0.0));
        std::vector<std::int64_t> slot_textured(mesh.slot_ranges.size(), -1);  // material id when baked
        bool emits = false;
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
            const std::uint32_t id = batch.material_slots[std::min(s, batch.material_slots.size() - 1)];
            if (id >= emission.size() || mesh.slot_ranges[s].second == 0) continue;
            if (textured[id]) {
                slot_textured[s] = id;
                emits = true;
            } else if (luminance(emission[id]) > 0.0) {
                slot_emission[s] = emission[id];
                emits = true;
            }
        }
        if (!emits) continue;
        // Read back only what emits: the mesh's positions and its indices.
        GLint64 position_bytes = 0;
        glGetNamedBufferParameteri64v(mesh.positions.get(), GL_BUFFER_SIZE, &position_bytes);
        std::vector<float> positions(std::size_t(position_bytes) / sizeof(float));
        glGetNamedBufferSubData(mesh.positions.get(), 0, position_bytes, positions.data());
        std::vector<std::uint32_t> indices(std::size_t(mesh.triangle_count) * 3);
        glGetNamedBufferSubData(mesh.indices.get(), 0, GLsizeiptr(indices.size() * sizeof(std::uint32_t)),
                                indices.data());
        const std::size_t vertex_count = positions.size() / 3;
        const int mesh_side = closed_mesh_side(positions, indices);
        for (std::size_t inst = 0; inst < batch.matrices.size() / 16; ++inst) {
            glm::dmat4 model;
            for (int c = 0; c < 4; ++c)
                for (int r = 0; r < 4; ++r) model[c][r] = batch.matrices[inst * 16 + std::size_t(c) * 4 + std::size_t(r)];
            MeshLight light;
            light.first = std::uint32_t(triangles_.size());
            light.cast_shadow = batch.cast_shadow;
            light.light_group = batch.light_group;
            // A mirroring transform turns the winding (and the outside) over.
            light.side = glm::determinant(glm::dmat3(model)) < 0.0 ? -mesh_side : mesh_side;
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                const glm::dvec3 Le = slot_emission[s];
                const bool baked = slot_textured[s] >= 0;
                if (!baked && !(luminance(Le) > 0.0)) continue;
                const auto [first, count] = mesh.slot_ranges[s];
                std::uint32_t first_tile = 0;
                if (baked) {
                    // One tile per triangle of the range (a degenerate one keeps its unused tile).
                    first_tile = std::uint32_t(tile_count_);
                    EmissionBakeRun run;
                    run.instance = batch_base + std::uint32_t(inst);
                    run.mesh = batch.mesh_id;
                    run.material = std::uint32_t(slot_textured[s]);
                    run.graph = std::uint32_t(materials[run.material].graph);
                    run.first = first;
                    run.count = count;
                    run.first_tile = first_tile;
                    bake_runs_.push_back(run);
                    tile_count_ += count;
                }
                for (std::uint32_t t = first; t < first + count; ++t) {
                    glm::dvec3 v[3];
                    bool ok = true;
                    for (int k = 0; k < 3; ++k) {
                        const std::uint32_t i = indices[std::size_t(t) * 3 + std::size_t(k)];
                        if (i >= vertex_count) { ok = false; break; }
                        const glm::dvec4 p = model * glm::dvec4(positions[i * 3], positions[i * 3 + 1],
                                                                positions[i * 3 + 2], 1.0);
                        v[k] = glm::dvec3(p) - camera_position;
                    }
                    if (!ok) continue;
                    const glm::dvec3 e1 = v[1] - v[0], e2 = v[2] - v[0];
                    const double area = 0.5 * glm::length(glm::cross(e1, e2));
                    if (!(area > 0.0) || !std::isfinite(area)) continue;  // degenerate: emits nothing
                    gpu::GpuEmitterTriangle g{};
                    g.v0 = {float(v[0].x), float(v[0].y), float(v[0].z), 0.0f};
                    g.e1 = {float(e1.x), float(e1.y), float(e1.z), float(area)};
                    // e2.w: the triangle's power (area x luminance), a probability after finish().
                    g.e2 = {float(e2.x), float(e2.y), float(e2.z), float(area * luminance(Le))};
                    g.radiance = {float(Le.x), float(Le.y), float(Le.z),
                                  baked ? float(first_tile + (t - first) + 1) : 0.0f};
                    triangles_.push_back(g);
                }
            }
            light.count = std::uint32_t(triangles_.size()) - light.first;
            if (light.count > 0) lights_.push_back(light);
        }
    }
}

namespace {
// Restores what the bake changes of the GL state, also when it throws.
struct BakeStateGuard {
    GLint viewport[4];
    GLboolean depth_test, cull, blend, scissor;
    BakeStateGuard() {
        glGetIntegerv(GL_VIEWPORT, viewport);
        depth_test = glIsEnabled(GL_DEPTH_TEST);
        cull = glIsEnabled(GL_CULL_FACE);
        blend = glIsEnabled(GL_BLEND);
        scissor = glIsEnabled(GL_SCISSOR_TEST);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glDisable(GL_BLEND);
        glDisable(GL_SCISSOR_TEST);
    }
    ~BakeStateGuard() {
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
        if (depth_test) glEnable(GL_DEPTH_TEST);
        if (cull) glEnable(GL_CULL_FACE);
        if (blend) glEnable(GL_BLEND);
        if (scissor) glEnable(GL_SCISSOR_TEST);
    }
};
}  // namespace

double EmitterModule::bake(ShaderLibrary& shaders, MaterialModule& materials,
                           const std::function<void(const EmissionBakeRun& run, GLuint program)>& draw,
                           std::vector<std::string>& warnings) {
    if (bake_runs_.empty()) return 0.0;
    const auto start = std::chrono::steady_clock::now();
    // The tile edge: the largest T whose T(T + 1)/2 texels per triangle fit the budget.
    int T = kMaxTileSize;
    while (T > 1 && tile_count_ * std::size_t(T) * std::size_t(T + 1) / 2 > kTexelBudget) --T;
    tile_size_ = T;
    const std::size_t per_tile = std::size_t(T) * std::size_t(T + 1) / 2;
    // The target holds tiles as T x T squares (the triangle covers the lower
    // half); large counts go through it in chunks.
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    const int side = std::max(std::min(2048, int(max_size)), T);
    const int columns = side / T;
    const std::size_t chunk_tiles = std::size_t(columns) * std::size_t(side / T);
    const std::size_t rows = std::min((tile_count_ + std::size_t(columns) - 1) / std::size_t(columns),
                                      std::size_t(side / T));
    const int width = columns * T, height = int(rows) * T;
    Texture target = make_texture_2d(GL_RGBA32F, width, height, "emission bake");
    GLuint fbo_id = 0;
    glCreateFramebuffers(1, &fbo_id);
    Framebuffer fbo(fbo_id);
    glNamedFramebufferTexture(fbo.get(), GL_COLOR_ATTACHMENT0, target.get(), 0);
    if (glCheckNamedFramebufferStatus(fbo.get(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw Error("emission bake: the bake target is not complete");
    // Instance remap: entry k is run k's instance (uniform 0 of the draw).
    std::vector<std::uint32_t> remap;
    for (const EmissionBakeRun& r : bake_runs_) remap.push_back(r.instance);
    Buffer remap_buffer = make_storage_buffer(remap.data(), remap.size() * sizeof(std::uint32_t), "bake remap");
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_INSTANCE_REMAP, remap_buffer.get());
    // graph -> its bake program; 0 where it does not compile (its triangles
    // then emit nothing, warned, and the other graphs still bake).
    std::map<std::uint32_t, GLuint> programs;
    ShaderVariant variant;
    variant.defines.push_back("EMISSION_BAKE");
    for (const EmissionBakeRun& r : bake_runs_) {
        if (programs.count(r.graph)) continue;
        try {
            programs[r.graph] = materials.program(shaders, r.graph, variant);
        } catch (const Error& e) {
            programs[r.graph] = 0;
            warnings.push_back("Material '" + materials.name(r.graph) + "': its emission lights nothing around "
                               "it (its emission bake did not compile): " + e.what());
        }
    }

    const BakeStateGuard guard;
    glBindFramebuffer(GL_FRAMEBUFFER, fbo.get());
    glViewport(0, 0, width, height);
    texels_.assign(tile_count_ * per_tile * 3, 0.0f);
    std::vector<float> pixels(std::size_t(width) * std::size_t(height) * 4);
    for (std::size_t chunk = 0; chunk < tile_count_; chunk += chunk_tiles) {
        const std::size_t chunk_end = std::min(chunk + chunk_tiles, tile_count_);
        const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        glClearNamedFramebufferfv(fbo.get(), GL_COLOR, 0, zero);
        for (std::size_t k = 0; k < bake_runs_.size(); ++k) {
            const EmissionBakeRun& r = bake_runs_[k];
            const std::size_t lo = std::max<std::size_t>(r.first_tile, chunk);
            const std::size_t hi = std::min<std::size_t>(r.first_tile + r.count, chunk_end);
            if (lo >= hi) continue;
            EmissionBakeRun part = r;
            part.first = r.first + std::uint32_t(lo - r.first_tile);
            part.count = std::uint32_t(hi - lo);
            part.first_tile = std::uint32_t(lo);
            const GLuint program = programs.at(r.graph);
            if (program == 0) continue;
            glUseProgram(program);
            glUniform1ui(0, std::uint32_t(k));
            glUniform1i(30, int(lo - chunk));
            glUniform1ui(31, part.first);
            glUniform4i(32, T, columns, width, height);
            draw(part, program);
        }
        glGetTextureImage(target.get(), 0, GL_RGBA, GL_FLOAT, GLsizei(pixels.size() * sizeof(float)), pixels.data());
        // Each tile's covered texels, rows j = 0.. after one another.
        for (std::size_t tile = chunk; tile < chunk_end; ++tile) {
            const std::size_t local = tile - chunk;
            const std::size_t x0 = (local % std::size_t(columns)) * std::size_t(T);
            const std::size_t y0 = (local / std::size_t(columns)) * std::size_t(T);
            float* out = &texels_[tile * per_tile * 3];
            for (int j = 0; j < T; ++j)
                for (int i = 0; i + j <= T - 1; ++i) {
                    const float* px = &pixels[((y0 + std::size_t(j)) * std::size_t(width) + x0 + std::size_t(i)) * 4];
                    for (int c = 0; c < 3; ++c) *out++ = std::isfinite(px[c]) ? std::max(px[c], 0.0f) : 0.0f;
                }
        }
    }
    try {
        check_gl("emission bake");
    } catch (...) {
        texels_.clear();  // finish() then lets the baked triangles emit nothing
        throw;
    }
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

std::size_t EmitterModule::finish() {
    const std::size_t per_tile = std::size_t(tile_size_) * std::size_t(tile_size_ + 1) / 2;
    const bool baked = !texels_.empty();
    std::vector<gpu::GpuEmitterTriangle> kept;
    std::vector<MeshLight> lights;
    std::size_t emitting = 0;
    for (MeshLight light : lights_) {
        const std::uint32_t first = std::uint32_t(kept.size());
        light.area = light.power = light.max_radiance = 0.0;
        glm::dvec3 lo(1e300), hi(-1e300);
        for (std::uint32_t t = light.first; t < light.first + light.count; ++t) {
            gpu::GpuEmitterTriangle g = triangles_[t];
            const double area = double(g.e1.w);
            glm::dvec3 mean(g.radiance.x, g.radiance.y, g.radiance.z), peak = mean;
            if (g.radiance.w > 0.0f) {
                // A baked triangle: its texels' mean and largest radiance
                // (without a bake, a failed one, it emits nothing).
                mean = peak = glm::dvec3(0.0);
                if (baked) {
                    float* px = &texels_[(std::size_t(g.radiance.w) - 1) * per_tile * 3];
                    for (std::size_t k = 0; k < per_tile; ++k) {
                        const glm::dvec3 c(px[3 * k], px[3 * k + 1], px[3 * k + 2]);
                        mean += c;
                        peak = glm::max(peak, c);
                    }
                    mean /= double(per_tile);
                    // The lighting's limit on radiance (see sync()).
                    const double cap = double(InputLimits::kMaxLightPower);
                    if (peak.x > cap || peak.y > cap || peak.z > cap) {
                        for (std::size_t k = 0; k < per_tile * 3; ++k) px[k] = std::min(px[k], float(cap));
                        mean = glm::min(mean, glm::dvec3(cap));
                        peak = glm::min(peak, glm::dvec3(cap));
                    }
                }
                g.radiance = {float(mean.x), float(mean.y), float(mean.z), g.radiance.w};
            }
            const double power = area * luminance(mean);
            if (!(power > 0.0) || !std::isfinite(power)) continue;  // lights nothing
            g.e2.w = float(power);
            kept.push_back(g);
            light.area += area;
            light.power += power;
            light.max_radiance = std::max({light.max_radiance, peak.x, peak.y, peak.z});
            const glm::dvec3 v0(g.v0.x, g.v0.y, g.v0.z), e1(g.e1.x, g.e1.y, g.e1.z), e2(g.e2.x, g.e2.y, g.e2.z);
            for (const glm::dvec3& v : {v0, v0 + e1, v0 + e2}) {
                lo = glm::min(lo, v);
                hi = glm::max(hi, v);
            }
        }
        light.first = first;
        light.count = std::uint32_t(kept.size()) - first;
        if (light.count == 0 || !(light.power > 0.0)) {
            kept.resize(first);
            continue;
        }
        // The CDF over the light's triangles by power: v0.w the running
        // sum (ending at 1), e2.w the triangle's probability.
        double running = 0.0;
        for (std::uint32_t t = light.first; t < light.first + light.count; ++t) {
            const double p = double(kept[t].e2.w) / light.power;
            running += p;
            kept[t].e2.w = float(p);
            kept[t].v0.w = float(running);
        }
        kept[light.first + light.count - 1].v0.w = 1.0f;
        light.center = 0.5 * (lo + hi);
        light.radius = 0.5 * glm::length(hi - lo);
        lights.push_back(light);
        emitting += light.count;
        // A light of more than kChunk triangles: the bounding sphere of each
        // run of kChunk of them follows its triangles (v0: centre, radius),
        // so the lighting can meet its triangles along a ray chunk by chunk
        // (light_lib.glsl emitter_chunk_sphere). No light's range and no CDF
        // covers these entries.
        if (light.count > kChunk) {
            for (std::uint32_t c = light.first; c < light.first + light.count; c += kChunk) {
                const std::uint32_t end = std::min(c + kChunk, light.first + light.count);
                glm::dvec3 clo(1e300), chi(-1e300);
                auto corners = [&](const gpu::GpuEmitterTriangle& g) {
                    const glm::dvec3 v0(g.v0.x, g.v0.y, g.v0.z), e1(g.e1.x, g.e1.y, g.e1.z), e2(g.e2.x, g.e2.y, g.e2.z);
                    return std::array<glm::dvec3, 3>{v0, v0 + e1, v0 + e2};
                };
                for (std::uint32_t t = c; t < end; ++t)
                    for (const glm::dvec3& v : corners(kept[t])) {
                        clo = glm::min(clo, v);
                        chi = glm::max(chi, v);
                    }
                const glm::dvec3 center = 0.5 * (clo + chi);
                double radius = 0.0;
                for (std::uint32_t t = c; t < end; ++t)
                    for (const glm::dvec3& v : corners(kept[t])) radius = std::max(radius, glm::length(v - center));
                gpu::GpuEmitterTriangle sphere{};
                // A little wider than the farthest corner: float rounding of
                // the corners the lighting reads must not fall outside it.
                sphere.v0 = {float(center.x), float(center.y), float(center.z), float(radius * (1.0 + 1e-5) + 1e-6)};
                kept.push_back(sphere);
            }
        }
    }
    triangles_ = std::move(kept);
    lights_ = std::move(lights);
    bake_runs_.clear();
    if (!triangles_.empty())
        buffer_ = make_storage_buffer(triangles_.data(), triangles_.size() * sizeof(gpu::GpuEmitterTriangle),
                                      "emitter triangles");
    if (baked && !triangles_.empty()) {
        // Header (tile edge, 3 unused) and the texels (light_lib.glsl EmissionTexels).
        std::vector<float> data(4 + texels_.size());
        const std::uint32_t header[4] = {std::uint32_t(tile_size_), 0u, 0u, 0u};
        std::memcpy(data.data(), header, sizeof(header));
        std::copy(texels_.begin(), texels_.end(), data.begin() + 4);
        texel_buffer_ = make_storage_buffer(data.data(), data.size() * sizeof(float), "emission texels");
    }
    return emitting;
}

glm::dvec3 EmitterModule::radiance_at(const gpu::GpuEmitterTriangle& t, double b1, double b2) const {
    if (!(t.radiance.w > 0.0f) || texels_.empty())
        return glm::dvec3(t.radiance.x, t.radiance.y, t.radiance.z);
    const int T = tile_size_;
    int i = std::clamp(int(std::floor(b1 * (T + 0.5))), 0, T - 1);
    int j = std::clamp(int(std::floor(b2 * (T + 0.5))), 0, T - 1);
    if (i + j > T - 1) {
        if (b1 >= b2) i = T - 1 - j; else j = T - 1 - i;
    }
    const std::size_t per_tile = std::size_t(T) * std::size_t(T + 1) / 2;
    const std::size_t texel = (std::size_t(t.radiance.w) - 1) * per_tile + std::size_t(j * T - j * (j - 1) / 2 + i);
    return glm::dvec3(texels_[3 * texel], texels_[3 * texel + 1], texels_[3 * texel + 2]);
}

MeshLightPoint EmitterModule::sample_point(std::size_t k, const std::array<float, 2>& u) const {
    const MeshLight& light = lights_.at(k);
    // The triangle: the first whose running sum exceeds u0; u0 rescaled inside it.
    const double x = std::min(double(u[0]), std::nextafter(1.0, 0.0));
    std::uint32_t lo = light.first, hi = light.first + light.count - 1;
    while (lo < hi) {
        const std::uint32_t mid = (lo + hi) / 2;
        if (double(triangles_[mid].v0.w) > x) hi = mid; else lo = mid + 1;
    }
    const gpu::GpuEmitterTriangle& t = triangles_[lo];
    const double p = double(t.e2.w);
    const double before = double(t.v0.w) - p;
    const double a = p > 0.0 ? std::clamp((x - before) / p, 0.0, 1.0) : 0.5;
    // Uniform on the triangle (Turk 1990): sqrt of one number.
    const double r = std::sqrt(a), b = double(u[1]);
    const glm::dvec3 v0(t.v0.x, t.v0.y, t.v0.z), e1(t.e1.x, t.e1.y, t.e1.z), e2(t.e2.x, t.e2.y, t.e2.z);
    MeshLightPoint out;
    out.position = v0 + e1 * (r * (1.0 - b)) + e2 * (r * b);
    out.normal = glm::normalize(glm::cross(e1, e2));
    out.radiance = radiance_at(t, r * (1.0 - b), r * b);
    out.pdf = p / double(t.e1.w);
    return out;
}

void EmitterModule::bind() const {
    if (buffer_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_EMITTERS, buffer_.get());
    if (texel_buffer_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_EMISSION_TEXELS, texel_buffer_.get());
}

}  // namespace deferred
