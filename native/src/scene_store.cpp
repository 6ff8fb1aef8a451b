#include "scene_store.h"

#include "mesh_topology.h"

#include <deferred/renderer.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <type_traits>

namespace deferred {

namespace {

[[noreturn]] void invalid(const std::string& what) { throw InvalidInput(what); }

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

template <class T>
void require_finite(const T* data, std::size_t n, const char* what) {
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(data[i]))
            invalid(std::string(what) + ": element " + std::to_string(i) + " is NaN or infinite");
}

template <class T>
void require_bounded(const T* data, std::size_t n, double limit, const char* what, const char* unit) {
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(data[i]))
            invalid(std::string(what) + ": element " + std::to_string(i) + " is NaN or infinite");
        if (std::abs(double(data[i])) > limit)
            invalid(std::string(what) + ": element " + std::to_string(i) + " = " + num(double(data[i])) +
                    " exceeds the limit of " + num(limit) + unit);
    }
}

bool finite3(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

void require_range(float v, float lo, float hi, const char* owner, const char* name) {
    if (!std::isfinite(v))
        invalid(std::string(owner) + ": " + name + " is NaN or infinite");
    if (!(v >= lo && v <= hi))
        invalid(std::string(owner) + ": " + name + " = " + num(v) + " is outside [" + num(lo) + ", " + num(hi) + "]");
}

void require_colour(const Vec3& c, float hi, const char* owner, const char* name) {
    if (!finite3(c)) invalid(std::string(owner) + ": " + name + " must be finite (got NaN/Inf)");
    for (int k = 0; k < 3; ++k)
        if (!(c[std::size_t(k)] >= 0.0f && c[std::size_t(k)] <= hi))
            invalid(std::string(owner) + ": " + name + " component " + std::to_string(k) + " = " +
                    num(c[std::size_t(k)]) + " is outside [0, " + num(hi) + "]");
}

double axis_length(const Mat4d& m, int axis) {
    const double x = m[std::size_t(axis * 4)], y = m[std::size_t(axis * 4 + 1)], z = m[std::size_t(axis * 4 + 2)];
    return std::sqrt(x * x + y * y + z * z);
}

}  // namespace

std::int32_t validate_mesh(const MeshData& m) {
    // Nothing reaches the GPU that could make it read out of bounds (an
    // index past the vertex count would be an unchecked SSBO read).
    if (m.triangle_count > 0 && (!m.positions || !m.indices)) invalid("mesh: positions and indices are required");
    if (m.vertex_count > 0 && !m.positions) invalid("positions: null pointer for " + std::to_string(m.vertex_count) + " vertices");
    constexpr std::size_t kMaxCorners = std::numeric_limits<std::int32_t>::max() / 4;
    if (m.triangle_count > kMaxCorners / 3)
        invalid("mesh: " + std::to_string(m.triangle_count) + " triangles exceed the per-draw limit");
    if (m.vertex_count > std::numeric_limits<std::uint32_t>::max() / 3)
        invalid("mesh: too many vertices");
    require_bounded(m.positions, m.vertex_count * 3, InputLimits::kMaxCoordinate, "positions", " m");
    if (m.motion_positions)
        require_bounded(m.motion_positions, m.vertex_count * 6, InputLimits::kMaxCoordinate, "motion_positions", " m");
    for (std::size_t i = 0; i < m.triangle_count * 3; ++i)
        if (m.indices[i] >= m.vertex_count)
            invalid("indices: element " + std::to_string(i) + " = " + std::to_string(m.indices[i]) +
                    " is out of range for " + std::to_string(m.vertex_count) + " vertices");
    if (m.corner_normals) require_finite(m.corner_normals, m.triangle_count * 9, "corner_normals");
    if (m.corner_uvs) require_finite(m.corner_uvs, m.triangle_count * 6, "corner_uvs");
    for (std::size_t a = 0; a < m.attributes.size(); ++a) {
        const CornerAttribute& attr = m.attributes[a];
        const std::string what = "attribute '" + attr.name + "'";
        if (attr.name.empty()) invalid("attributes: element " + std::to_string(a) + " has no name");
        if (attr.components < 1 || attr.components > 4) invalid(what + ": components must be 1..4");
        if (m.triangle_count > 0 && !attr.data) invalid(what + ": null data");
        require_finite(attr.data, m.triangle_count * 3 * std::size_t(attr.components), what.c_str());
        for (std::size_t b = 0; b < a; ++b)
            if (m.attributes[b].name == attr.name) invalid(what + ": given twice");
    }
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(m.texspace_location[std::size_t(k)]) || !std::isfinite(m.texspace_size[std::size_t(k)]))
            invalid("texspace: location and size must be finite");
    std::int32_t max_mat = 0;
    if (m.material_indices) {
        for (std::size_t t = 0; t < m.triangle_count; ++t) {
            if (m.material_indices[t] < 0)
                invalid("material_indices: element " + std::to_string(t) + " = " +
                        std::to_string(m.material_indices[t]) + " is negative");
            if (m.material_indices[t] > InputLimits::kMaxMaterialSlot)
                invalid("material_indices: element " + std::to_string(t) + " = " +
                        std::to_string(m.material_indices[t]) + " is outside 0.." +
                        std::to_string(InputLimits::kMaxMaterialSlot) + " (Blender's material slots)");
            max_mat = std::max(max_mat, m.material_indices[t]);
        }
    }
    return max_mat;
}

void validate_material(const Material& m) {
    const char* o = "material";
    require_colour(m.base_color, InputLimits::kMaxHalf, o, "base_color");
    require_colour(m.emission, std::numeric_limits<float>::max(), o, "emission");
    require_range(m.metallic, 0, 1, o, "metallic");
    require_range(m.roughness, 0, 1, o, "roughness");
    require_range(m.specular, 0, InputLimits::kMaxSpecular, o, "specular");
    require_range(m.specular_tint, 0, 1, o, "specular_tint");
    require_range(m.sheen, 0, 1, o, "sheen");
    require_range(m.sheen_tint, 0, 1, o, "sheen_tint");
    require_range(m.clearcoat, 0, 1, o, "clearcoat");
    require_range(m.clearcoat_roughness, 0, 1, o, "clearcoat_roughness");
    require_range(m.emission_strength, 0, std::numeric_limits<float>::max(), o, "emission_strength");
    require_range(m.alpha, 0, 1, o, "alpha");
    require_range(m.diffuse_roughness, -1, 1, o, "diffuse_roughness (-1: Principled, 0..1: Diffuse BSDF)");
    if (m.glossy_model < 0 || m.glossy_model > 2)
        invalid("material: glossy_model " + std::to_string(m.glossy_model) +
                " must be 0 (Principled), 1 (Glossy GGX) or 2 (Glossy Beckmann)");
    if (m.pass_index >= InputLimits::kMaxPassIndex)
        invalid("material: pass_index " + std::to_string(m.pass_index) + " must be below 2^24");
}

void validate_instances(const double* matrices, std::size_t count) {
    if (count > 0 && !matrices) invalid("add_instances: matrices are required");
    require_bounded(matrices, count * 16, InputLimits::kMaxCoordinate, "matrices", "");
}

void validate_light(const Light& l) {
    const char* o = "light";
    for (std::size_t i = 0; i < 16; ++i) {
        if (!std::isfinite(l.matrix[i])) invalid("light: matrix has NaN/Inf (element " + std::to_string(i) + ")");
        if (std::abs(l.matrix[i]) > InputLimits::kMaxCoordinate)
            invalid("light: matrix element " + std::to_string(i) + " = " + num(l.matrix[i]) +
                    " exceeds the limit of " + num(InputLimits::kMaxCoordinate));
    }
    if (static_cast<std::uint32_t>(l.type) > 3u) invalid("light: unknown type");
    if (static_cast<std::uint32_t>(l.shape) > 3u) invalid("light: unknown area shape");
    require_colour(l.color, std::numeric_limits<float>::max(), o, "color");
    if (!std::isfinite(l.energy)) invalid("light: energy is NaN or infinite");
    const double power = std::abs(double(l.energy)) * std::max({double(l.color[0]), double(l.color[1]), double(l.color[2])});
    if (power > InputLimits::kMaxLightPower)
        invalid("light: energy x colour = " + num(power) + " exceeds the limit of " + num(InputLimits::kMaxLightPower) +
                (l.type == LightType::Sun ? " W/m^2" : " W"));
    require_range(l.radius, 0, InputLimits::kMaxLightSize, o, "radius");
    require_range(l.spot_size, 0, float(M_PI) + 1e-6f, o, "spot_size");
    require_range(l.spot_blend, 0, 1, o, "spot_blend");
    require_range(l.angle, 0, float(M_PI) + 1e-6f, o, "angle");
    require_range(l.size, 0, InputLimits::kMaxLightSize, o, "size");
    require_range(l.size_y, 0, InputLimits::kMaxLightSize, o, "size_y");
}

void validate_world(const World& w) { require_colour(w.color, InputLimits::kMaxWorld, "world", "color"); }

Light sanitized_light(const Light& in) {
    validate_light(in);
    Light l = in;
    if (l.radius < InputLimits::kMinLightExtent) l.radius = 0.0f;
    if (l.type == LightType::Area) {
        const bool separate_y = l.shape == AreaShape::Rectangle || l.shape == AreaShape::Ellipse;
        auto raise = [](float& size, double axis) {
            if (size <= 0.0f) return;  // zero size: emits nothing (skipped by the light module)
            if (axis < 1e-20) { size = 0.0f; return; }  // collapsed axis: no emitting surface
            if (double(size) * axis < InputLimits::kMinLightExtent)
                size = float(InputLimits::kMinLightExtent / axis * (1.0 + 1e-6));
        };
        raise(l.size, axis_length(l.matrix, 0));
        if (separate_y) {
            raise(l.size_y, axis_length(l.matrix, 1));
        } else {
            // SQUARE/DISK use `size` on both axes: it must cover the smaller axis too.
            raise(l.size, std::min(axis_length(l.matrix, 0), axis_length(l.matrix, 1)));
        }
    }
    return l;
}

void SceneStore::clear() {
    // A clear right after a clear keeps the kept meshes: "used by the last
    // scene" means the last non-empty one.
    if (scene_started_) {
        for (std::size_t i = 0; i < meshes_.size(); ++i) {
            MeshSlot& slot = mesh_slots_[i];
            if (slot.alive && (!slot.used || slot.key.empty())) {
                if (!slot.key.empty()) mesh_by_key_.erase(slot.key);
                meshes_[i] = GpuMesh();
                slot = MeshSlot();
            }
            slot.used = false;
        }
        scene_started_ = false;
    }
    meshes_uploaded_ = meshes_reused_ = 0;
    batches_.clear();
    materials_.clear();
    lights_.clear();
    world_ = World{};
    instance_count_ = 0;
}

void SceneStore::release_all() {
    clear();
    meshes_.clear();
    mesh_slots_.clear();
    mesh_by_key_.clear();
}

std::int64_t SceneStore::find_mesh(const std::string& key) {
    if (key.empty()) return -1;
    const auto found = mesh_by_key_.find(key);
    if (found == mesh_by_key_.end()) return -1;
    MeshSlot& slot = mesh_slots_[found->second];
    if (!slot.used) ++meshes_reused_;
    slot.used = true;
    scene_started_ = true;
    return std::int64_t(found->second);
}

// The bound's derivation: scene_store.h.
double terminator_reach(const MeshData& m) {
    if (!m.corner_normals) return 0.0;
    double g = 0.0, n_max = 0.0;
    for (std::size_t t = 0; t < m.triangle_count; ++t) {
        glm::dvec3 v[3], n[3];
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t i = m.indices[t * 3 + std::size_t(k)];
            const float* p = m.positions + std::size_t(i) * 3;
            const float* c = m.corner_normals + (t * 3 + std::size_t(k)) * 3;
            v[k] = glm::dvec3(p[0], p[1], p[2]);
            n[k] = glm::dvec3(c[0], c[1], c[2]);
        }
        for (int i = 0; i < 3; ++i) {
            n_max = std::max(n_max, glm::length(n[i]));
            for (int j = 0; j < 3; ++j)
                if (i != j) g = std::max(g, std::abs(glm::dot(v[j] - v[i], n[i])));
        }
    }
    return 1.8 * g * n_max;
}

std::uint32_t SceneStore::add_mesh(const MeshData& m, const std::string& key) {
    const std::int32_t max_mat = validate_mesh(m);

    GpuMesh g;
    g.triangle_count = static_cast<std::uint32_t>(m.triangle_count);
    g.max_material_index = max_mat;
    if (m.vertex_count > 0) {
        double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
        for (std::size_t v = 0; v < m.vertex_count; ++v)
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(lo[k], double(m.positions[v * 3 + k]));
                hi[k] = std::max(hi[k], double(m.positions[v * 3 + k]));
            }
        for (int k = 0; k < 3; ++k) {
            g.bound_center[k] = 0.5 * (lo[k] + hi[k]);
            g.bound_half[k] = 0.5 * (hi[k] - lo[k]);
        }
        double r2 = 0.0;
        for (std::size_t v = 0; v < m.vertex_count; ++v) {
            double d2 = 0.0;
            for (int k = 0; k < 3; ++k) d2 += (m.positions[v * 3 + k] - g.bound_center[k]) * (m.positions[v * 3 + k] - g.bound_center[k]);
            r2 = std::max(r2, d2);
        }
        g.bound_radius = std::sqrt(r2);
    }
    // A deforming mesh's winding is known at rest only.
    if (!m.motion_positions) {
        g.closed = closed_orientation(m.positions, m.vertex_count, m.indices, m.triangle_count);
        g.planar = planar_mesh(m.positions, m.vertex_count, m.indices, m.triangle_count, g.plane_normal, g.plane_offset);
        g.convex = convex_mesh(m.positions, m.vertex_count, m.indices, m.triangle_count, g.closed);
    }
    g.terminator_reach = terminator_reach(m);
    // Triangles sorted by material slot (stable), so each slot is one draw
    // range: node materials bind a program per slot. Per-triangle and
    // per-corner arrays are permuted together; unsorted input is copied.
    const std::size_t nt = m.triangle_count;
    std::vector<std::uint32_t> order;
    bool sorted = true;
    if (m.material_indices)
        for (std::size_t t = 1; t < nt && sorted; ++t) sorted = m.material_indices[t - 1] <= m.material_indices[t];
    if (!sorted) {
        order.resize(nt);
        for (std::size_t t = 0; t < nt; ++t) order[t] = std::uint32_t(t);
        std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            return m.material_indices[a] < m.material_indices[b];
        });
    }
    // Per-triangle element of `width` values (T::value_type) in sorted order.
    auto permuted = [&](const auto* data, std::size_t width) {
        using T = std::remove_const_t<std::remove_pointer_t<decltype(data)>>;
        std::vector<T> out(nt * width);
        for (std::size_t t = 0; t < nt; ++t)
            std::copy(data + order[t] * width, data + (order[t] + 1) * width, out.begin() + long(t * width));
        return out;
    };
    auto upload = [&](const auto* data, std::size_t width, const char* what) {
        using T = std::remove_const_t<std::remove_pointer_t<decltype(data)>>;
        if (sorted) return make_storage_buffer(data, nt * width * sizeof(T), what);
        std::vector<T> p = permuted(data, width);
        return make_storage_buffer(p.data(), p.size() * sizeof(T), what);
    };
    g.positions = make_storage_buffer(m.positions, m.vertex_count * 3 * sizeof(float), "positions");
    g.indices = upload(m.indices, 3, "indices");
    if (m.motion_positions && m.vertex_count > 0) {
        g.motion_positions =
            make_storage_buffer(m.motion_positions, m.vertex_count * 6 * sizeof(float), "motion_positions");
        g.flags |= 8u;
    }
    if (m.corner_normals) {
        g.normals = upload(m.corner_normals, 9, "corner_normals");
        g.flags |= 1u;
    }
    if (m.corner_uvs) {
        g.uvs = upload(m.corner_uvs, 6, "corner_uvs");
        g.flags |= 2u;
    }
    g.slot_ranges.assign(std::size_t(max_mat) + 1, {0u, 0u});
    if (m.material_indices) {
        std::vector<std::int32_t> mi = sorted ? std::vector<std::int32_t>(m.material_indices, m.material_indices + nt)
                                              : permuted(m.material_indices, 1);
        for (std::size_t t = 0; t < nt; ++t) {
            auto& r = g.slot_ranges[std::size_t(mi[t])];
            if (r.second == 0) r.first = std::uint32_t(t);
            ++r.second;
        }
        g.material_indices = make_storage_buffer(mi.data(), nt * sizeof(std::int32_t), "material_indices");
        g.flags |= 4u;
    } else {
        g.slot_ranges[0] = {0u, std::uint32_t(nt)};
    }
    if (!m.attributes.empty()) {
        // One buffer, each attribute uploaded straight from the caller's array.
        std::size_t total = 0;
        for (const CornerAttribute& a : m.attributes) {
            g.attribute_layout.push_back({a.name, std::uint32_t(total), a.components});
            total += nt * 3 * std::size_t(a.components);
        }
        g.attributes = make_storage_buffer(nullptr, total * sizeof(float), "corner attributes");
        for (std::size_t k = 0; k < m.attributes.size(); ++k) {
            const CornerAttribute& a = m.attributes[k];
            const std::size_t width = 3 * std::size_t(a.components);
            std::vector<float> p;
            if (!sorted) p = permuted(a.data, width);
            glNamedBufferSubData(g.attributes.get(), GLintptr(g.attribute_layout[k].offset * sizeof(float)),
                                 GLsizeiptr(nt * width * sizeof(float)), sorted ? a.data : p.data());
        }
        check_gl("uploading corner attributes");
    }
    for (int k = 0; k < 3; ++k) {
        g.texspace_location[k] = m.texspace_location[std::size_t(k)];
        g.texspace_size[k] = m.texspace_size[std::size_t(k)];
    }
    // A slot another scene dropped, else a new one; ids stay stable while
    // meshes are kept.
    MeshSlot slot;
    slot.key = key;
    slot.alive = slot.used = true;
    scene_started_ = true;
    ++meshes_uploaded_;
    // A key uploaded again (the caller did not find it first) replaces the
    // old mapping; the old mesh stays alive for this scene if it is used.
    std::uint32_t id = static_cast<std::uint32_t>(meshes_.size());
    for (std::size_t i = 0; i < meshes_.size(); ++i)
        if (!mesh_slots_[i].alive) {
            id = static_cast<std::uint32_t>(i);
            break;
        }
    if (!key.empty()) {
        const auto old = mesh_by_key_.find(key);
        if (old != mesh_by_key_.end()) mesh_slots_[old->second].key.clear();  // unkeyed: dropped at the next clear
        mesh_by_key_[key] = id;
    }
    if (id == meshes_.size()) {
        meshes_.push_back(std::move(g));
        mesh_slots_.push_back(std::move(slot));
    } else {
        meshes_[id] = std::move(g);
        mesh_slots_[id] = std::move(slot);
    }
    return id;
}

std::uint32_t SceneStore::add_material(const Material& m) {
    validate_material(m);
    if (m.mix_with >= 0) {
        if (std::size_t(m.mix_with) >= materials_.size())
            invalid("material: mix_with " + std::to_string(m.mix_with) + " is not an earlier material (" +
                    std::to_string(materials_.size()) + " materials)");
        if (materials_[std::size_t(m.mix_with)].graph >= 0)
            invalid("material: mix_with " + std::to_string(m.mix_with) + " is a node material (graphs mix inside)");
        int depth = 1;
        for (std::int32_t k = m.mix_with; k >= 0; k = materials_[std::size_t(k)].mix_with) ++depth;
        if (depth > kMaxMixChain)
            invalid("material: a mix chain longer than " + std::to_string(kMaxMixChain) + " materials");
    } else if (m.mix_with != -1) {
        invalid("material: mix_with must be -1 (no mix) or a material id");
    }
    require_range(m.mix_probability, 0, 1, "material", "mix_probability");
    materials_.push_back(m);
    return static_cast<std::uint32_t>(materials_.size() - 1);
}

void SceneStore::add_instances(std::uint32_t mesh_id, const double* matrices, std::size_t count,
                               const std::uint32_t* object_indices, const std::vector<std::uint32_t>& slots,
                               bool cast_shadow, const float* colors, const float* randoms,
                               const std::uint32_t* crypto, bool holdout, std::uint32_t light_group,
                               const float* terminator_offsets, const double* motion, bool shadow_catcher) {
    if (mesh_id >= meshes_.size() || !mesh_slots_[mesh_id].alive)
        invalid("add_instances: mesh id " + std::to_string(mesh_id) + " does not exist (" +
                std::to_string(meshes_.size()) + " meshes)");
    validate_instances(matrices, count);
    // The previous and next matrices obey the same contract as this frame's.
    if (motion) require_bounded(motion, count * 32, InputLimits::kMaxCoordinate, "motion", "");
    if (colors) require_finite(colors, count * 4, "colors");
    if (randoms) require_finite(randoms, count, "randoms");
    if (terminator_offsets) {
        require_finite(terminator_offsets, count, "terminator_offsets");
        for (std::size_t i = 0; i < count; ++i)
            if (terminator_offsets[i] < 0.0f || terminator_offsets[i] > 1.0f)
                invalid("terminator_offsets: " + std::to_string(terminator_offsets[i]) + " is outside 0..1 "
                        "(Blender's Shadow Terminator Geometry Offset range)");
    }
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
    b.cast_shadow = cast_shadow;
    b.holdout = holdout;
    b.shadow_catcher = shadow_catcher;
    b.light_group = light_group;
    b.matrices.assign(matrices, matrices + count * 16);
    b.object_indices = object_indices ? std::vector<std::uint32_t>(object_indices, object_indices + count)
                                      : std::vector<std::uint32_t>(count, 0u);
    b.colors = colors ? std::vector<float>(colors, colors + count * 4) : std::vector<float>(count * 4, 1.0f);
    b.terminator_offsets = terminator_offsets ? std::vector<float>(terminator_offsets, terminator_offsets + count)
                                              : std::vector<float>(count, 0.0f);
    b.randoms = randoms ? std::vector<float>(randoms, randoms + count) : std::vector<float>(count, 0.0f);
    b.crypto = crypto ? std::vector<std::uint32_t>(crypto, crypto + count * 2) : std::vector<std::uint32_t>(count * 2, 0u);
    if (motion) b.motion.assign(motion, motion + count * 32);
    if (slots.empty()) {
        if (materials_.empty()) invalid("add_instances: no materials exist; add one first");
        for (std::uint32_t i = 0; i < materials_.size(); ++i) b.material_slots.push_back(i);
    } else {
        b.material_slots = slots;
    }
    instance_count_ += count;
    batches_.push_back(std::move(b));
}

void SceneStore::add_light(const Light& l) { lights_.push_back(sanitized_light(l)); }

void SceneStore::set_world(const World& w) {
    validate_world(w);
    world_ = w;
}

}  // namespace deferred
