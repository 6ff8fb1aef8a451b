#include "emitter_module.h"

#include "../../shaders/shader_defines.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace deferred {

namespace {

double luminance(const glm::dvec3& c) { return 0.2126729 * c.x + 0.7151522 * c.y + 0.0721750 * c.z; }

// The radiance a constant material emits (colour x strength x alpha), as the
// expectation over its stochastic mix chain (what the film converges to).
glm::dvec3 material_emission(const std::vector<Material>& materials, std::uint32_t id, int depth = 0) {
    if (id >= materials.size() || depth > 64) return glm::dvec3(0.0);
    const Material& m = materials[id];
    // A node material: the constant radiance the add-on found in its graph
    // (add_graph_material's light_emission; 0 where the graph varies it).
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

std::size_t EmitterModule::sync(const SceneStore& scene, const glm::dvec3& camera_position) {
    release();
    const std::vector<Material>& materials = scene.materials();
    std::vector<glm::dvec3> emission(materials.size());
    bool any = false;
    for (std::size_t i = 0; i < materials.size(); ++i) {
        emission[i] = material_emission(materials, std::uint32_t(i));
        // Negative light is not sampled; radiance beyond the lights' power
        // limit (InputLimits::kMaxLightPower) lights as that limit, which keeps
        // every float product of the lighting finite (the fuzzer found 1e25).
        emission[i] = glm::clamp(emission[i], glm::dvec3(0.0), glm::dvec3(double(InputLimits::kMaxLightPower)));
        if (!std::isfinite(emission[i].x + emission[i].y + emission[i].z)) emission[i] = glm::dvec3(0.0);
        any = any || luminance(emission[i]) > 0.0;
    }
    if (!any) return 0;

    for (const InstanceBatch& batch : scene.batches()) {
        const GpuMesh& mesh = scene.meshes()[batch.mesh_id];
        if (mesh.triangle_count == 0 || batch.material_slots.empty()) continue;
        // The slots of this batch that emit.
        std::vector<glm::dvec3> slot_emission(mesh.slot_ranges.size(), glm::dvec3(0.0));
        bool emits = false;
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
            const std::uint32_t id = batch.material_slots[std::min(s, batch.material_slots.size() - 1)];
            if (id < emission.size() && luminance(emission[id]) > 0.0 && mesh.slot_ranges[s].second > 0) {
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
            glm::dvec3 lo(1e300), hi(-1e300);
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s) {
                const glm::dvec3 Le = slot_emission[s];
                if (!(luminance(Le) > 0.0)) continue;
                const auto [first, count] = mesh.slot_ranges[s];
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
                    g.e2 = {float(e2.x), float(e2.y), float(e2.z), float(area * luminance(Le))};  // power, normalised below
                    g.radiance = {float(Le.x), float(Le.y), float(Le.z), 0.0f};
                    triangles_.push_back(g);
                    light.area += area;
                    light.power += area * luminance(Le);
                    light.max_radiance = std::max({light.max_radiance, Le.x, Le.y, Le.z});
                    for (int k = 0; k < 3; ++k) {
                        lo = glm::min(lo, v[k]);
                        hi = glm::max(hi, v[k]);
                    }
                }
            }
            light.count = std::uint32_t(triangles_.size()) - light.first;
            if (light.count == 0 || !(light.power > 0.0)) {
                triangles_.resize(light.first);
                continue;
            }
            // The CDF over the light's triangles by power: v0.w the running
            // sum (ending at 1), e2.w the triangle's probability.
            double running = 0.0;
            for (std::uint32_t t = light.first; t < light.first + light.count; ++t) {
                const double p = double(triangles_[t].e2.w) / light.power;
                running += p;
                triangles_[t].e2.w = float(p);
                triangles_[t].v0.w = float(running);
            }
            triangles_[light.first + light.count - 1].v0.w = 1.0f;
            light.center = 0.5 * (lo + hi);
            light.radius = 0.5 * glm::length(hi - lo);
            lights_.push_back(light);
        }
    }
    if (!triangles_.empty())
        buffer_ = make_storage_buffer(triangles_.data(), triangles_.size() * sizeof(gpu::GpuEmitterTriangle),
                                      "emitter triangles");
    return triangles_.size();
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
    out.radiance = glm::dvec3(t.radiance.x, t.radiance.y, t.radiance.z);
    out.pdf = p / double(t.e1.w);
    return out;
}

void EmitterModule::bind() const {
    if (buffer_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_EMITTERS, buffer_.get());
}

}  // namespace deferred
