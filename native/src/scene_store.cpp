#include "scene_store.h"

#include <deferred/renderer.h>

#include <cmath>
#include <limits>
#include <string>

namespace deferred {

namespace {

[[noreturn]] void invalid(const std::string& what) { throw InvalidInput(what); }

template <class T>
void require_finite(const T* data, std::size_t n, const char* what) {
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(data[i]))
            invalid(std::string(what) + ": element " + std::to_string(i) + " is NaN or infinite");
}

bool finite3(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

}  // namespace

void SceneStore::clear() {
    meshes_.clear();
    batches_.clear();
    materials_.clear();
    lights_.clear();
    world_ = World{};
    instance_count_ = 0;
}

std::uint32_t SceneStore::add_mesh(const MeshData& m) {
    // Validation first: nothing reaches the GPU that could make it read out
    // of bounds (an index past the vertex count would be an unchecked SSBO read).
    if (m.triangle_count > 0 && (!m.positions || !m.indices)) invalid("mesh: positions and indices are required");
    constexpr std::size_t kMaxCorners = std::numeric_limits<std::int32_t>::max() / 4;
    if (m.triangle_count * 3 > kMaxCorners)
        invalid("mesh: " + std::to_string(m.triangle_count) + " triangles exceed the per-draw limit");
    if (m.vertex_count > std::numeric_limits<std::uint32_t>::max() / 3)
        invalid("mesh: too many vertices");
    require_finite(m.positions, m.vertex_count * 3, "positions");
    for (std::size_t i = 0; i < m.triangle_count * 3; ++i)
        if (m.indices[i] >= m.vertex_count)
            invalid("indices: element " + std::to_string(i) + " = " + std::to_string(m.indices[i]) +
                    " is out of range for " + std::to_string(m.vertex_count) + " vertices");
    if (m.corner_normals) require_finite(m.corner_normals, m.triangle_count * 9, "corner_normals");
    if (m.corner_uvs) require_finite(m.corner_uvs, m.triangle_count * 6, "corner_uvs");
    std::int32_t max_mat = 0;
    if (m.material_indices) {
        for (std::size_t t = 0; t < m.triangle_count; ++t) {
            if (m.material_indices[t] < 0)
                invalid("material_indices: element " + std::to_string(t) + " is negative");
            max_mat = std::max(max_mat, m.material_indices[t]);
        }
    }

    GpuMesh g;
    g.triangle_count = static_cast<std::uint32_t>(m.triangle_count);
    g.max_material_index = max_mat;
    g.positions = make_storage_buffer(m.positions, m.vertex_count * 3 * sizeof(float), "positions");
    g.indices = make_storage_buffer(m.indices, m.triangle_count * 3 * sizeof(std::uint32_t), "indices");
    if (m.corner_normals) {
        g.normals = make_storage_buffer(m.corner_normals, m.triangle_count * 9 * sizeof(float), "corner_normals");
        g.flags |= 1u;
    }
    if (m.corner_uvs) {
        g.uvs = make_storage_buffer(m.corner_uvs, m.triangle_count * 6 * sizeof(float), "corner_uvs");
        g.flags |= 2u;
    }
    if (m.material_indices) {
        g.material_indices = make_storage_buffer(m.material_indices, m.triangle_count * sizeof(std::int32_t),
                                                 "material_indices");
        g.flags |= 4u;
    }
    meshes_.push_back(std::move(g));
    return static_cast<std::uint32_t>(meshes_.size() - 1);
}

std::uint32_t SceneStore::add_material(const Material& m) {
    const float scalars[] = {m.metallic, m.roughness, m.specular, m.specular_tint, m.sheen, m.sheen_tint,
                             m.clearcoat, m.clearcoat_roughness, m.emission_strength, m.alpha};
    require_finite(scalars, 10, "material parameters");
    if (!finite3(m.base_color) || !finite3(m.emission)) invalid("material colours must be finite");
    materials_.push_back(m);
    return static_cast<std::uint32_t>(materials_.size() - 1);
}

void SceneStore::add_instances(std::uint32_t mesh_id, const double* matrices, std::size_t count,
                               const std::uint32_t* object_indices, const std::vector<std::uint32_t>& slots) {
    if (mesh_id >= meshes_.size())
        invalid("add_instances: mesh id " + std::to_string(mesh_id) + " does not exist (" +
                std::to_string(meshes_.size()) + " meshes)");
    if (count > 0 && !matrices) invalid("add_instances: matrices are required");
    require_finite(matrices, count * 16, "matrices");
    for (std::uint32_t s : slots)
        if (s >= materials_.size())
            invalid("material_slots: material id " + std::to_string(s) + " does not exist (" +
                    std::to_string(materials_.size()) + " materials)");
    const GpuMesh& mesh = meshes_[mesh_id];
    const std::size_t slot_count = slots.empty() ? materials_.size() : slots.size();
    if (mesh.triangle_count > 0 && static_cast<std::size_t>(mesh.max_material_index) >= slot_count)
        invalid("material_indices: mesh " + std::to_string(mesh_id) + " uses slot " +
                std::to_string(mesh.max_material_index) + " but only " + std::to_string(slot_count) +
                " material slot(s) are given");
    if (count == 0) return;
    InstanceBatch b;
    b.mesh_id = mesh_id;
    b.matrices.assign(matrices, matrices + count * 16);
    b.object_indices = object_indices ? std::vector<std::uint32_t>(object_indices, object_indices + count)
                                      : std::vector<std::uint32_t>(count, 0u);
    if (slots.empty()) {
        if (materials_.empty()) invalid("add_instances: no materials exist; add one first");
        for (std::uint32_t i = 0; i < materials_.size(); ++i) b.material_slots.push_back(i);
    } else {
        b.material_slots = slots;
    }
    instance_count_ += count;
    batches_.push_back(std::move(b));
}

void SceneStore::add_light(const Light& l) {
    for (double v : l.matrix)
        if (!std::isfinite(v)) invalid("light: matrix has NaN/Inf");
    const float scalars[] = {l.energy, l.radius, l.spot_size, l.spot_blend, l.angle, l.size, l.size_y};
    require_finite(scalars, 7, "light parameters");
    if (!finite3(l.color)) invalid("light: colour must be finite");
    if (l.radius < 0 || l.size < 0 || l.size_y < 0 || l.angle < 0 || l.spot_size < 0)
        invalid("light: sizes and angles must not be negative");
    lights_.push_back(l);
}

void SceneStore::set_world(const World& w) {
    if (!finite3(w.color)) invalid("world: colour must be finite");
    world_ = w;
}

}  // namespace deferred
