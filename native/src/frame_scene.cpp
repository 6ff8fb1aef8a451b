#include "frame_scene.h"

#include "material_module.h"
#include "motion_module.h"

#include "../../shaders/shader_defines.h"

#include <algorithm>
#include <cmath>

namespace deferred {

gpu::mat4 to_gpu(const glm::dmat4& m) {
    gpu::mat4 r{};
    for (int c = 0; c < 4; ++c)
        r.cols[c] = {float(m[c][0]), float(m[c][1]), float(m[c][2]), float(m[c][3])};
    return r;
}

ViewVolume::ViewVolume(const CameraMatrices& cam, int width, int height, std::uint32_t reach_px)
    : to_view(cam.view), clip_start(cam.clip_start), clip_end(cam.clip_end), orthographic(cam.orthographic) {
    const double margin_px = double(reach_px) + 1.0;
    const glm::dvec4 vp = cam.viewplane;
    const double px = (vp.y - vp.x) / width * margin_px, py = (vp.w - vp.z) / height * margin_px;
    left = vp.x - px;
    right = vp.y + px;
    bottom = vp.z - py;
    top = vp.w + py;
}

bool ViewVolume::contains(const glm::dvec3& c, double r) const {
    const glm::dvec3 v = to_view * (c - eye);
    const double d = -v.z;
    if (d + r < clip_start || d - r > clip_end) return false;
    if (orthographic) return v.x + r >= left && v.x - r <= right && v.y + r >= bottom && v.y - r <= top;
    // Distance of the sphere's centre outside each side plane of the frustum.
    auto inside = [&](double x, double lo, double hi) {
        return (lo * d - x) / std::sqrt(1.0 + lo * lo) <= r && (x - hi * d) / std::sqrt(1.0 + hi * hi) <= r;
    };
    return inside(v.x, left, right) && inside(v.y, bottom, top);
}

namespace {

// The most `linear` stretches any vector (its spectral norm): the square
// root of the largest eigenvalue of L^T L, at most Gershgorin's largest
// absolute row sum of it. Exact where L^T L is diagonal (a rotation times
// a scale); a shear gets a little more. The longest column, used before, is
// exact there too but falls short of a shear's stretch (sqrt 2 against
// 1.618 for a unit shear), so its sphere could miss a corner in view.
double largest_stretch(const glm::dmat3& linear) {
    const glm::dmat3 g = glm::transpose(linear) * linear;
    double row = 0.0;
    for (int i = 0; i < 3; ++i) row = std::max(row, std::abs(g[0][i]) + std::abs(g[1][i]) + std::abs(g[2][i]));
    return std::sqrt(row);
}

}  // namespace

// An instance's world matrix -> its camera-relative model, normal matrix,
// mirrored flag (ids.w bit 0) and bounding sphere.
void FrameScene::place(const glm::dmat4& world, const GpuMesh& mesh, gpu::GpuInstance& g, Bound& bound) const {
    glm::dmat4 model = world;
    model[3] = glm::dvec4(glm::dvec3(model[3]) - camera_position_, 1.0);
    const glm::dmat3 linear(model);
    const double det = glm::determinant(linear);
    const double scale = largest_stretch(linear);
    bound = {glm::dvec3(model * glm::dvec4(mesh.bound_center[0], mesh.bound_center[1], mesh.bound_center[2], 1.0)),
             mesh.bound_radius * scale};
    const glm::dmat3 nm = std::abs(det) > 1e-300 ? glm::transpose(glm::inverse(linear)) : glm::dmat3(1.0);
    g.model = to_gpu(model);
    g.normal_matrix = to_gpu(glm::dmat4(nm));
    g.ids.w = (g.ids.w & ~1u) | (det < 0 ? 1u : 0u);
}

void FrameScene::build(const SceneStore& scene, const MaterialModule& materials, const glm::dvec3& camera_position,
                       const Options& options, GLuint empty_vao, GLuint dummy_ssbo) {
    release();
    scene_ = &scene;
    camera_position_ = camera_position;
    empty_vao_ = empty_vao;
    dummy_ssbo_ = dummy_ssbo;
    instances_.reserve(scene.instance_count());
    bounds_.reserve(scene.instance_count());
    std::vector<std::uint32_t> groups;  // light group per instance
    for (const InstanceBatch& b : scene.batches()) {
        const std::uint32_t slot_offset = static_cast<std::uint32_t>(slots_.size());
        slots_.insert(slots_.end(), b.material_slots.begin(), b.material_slots.end());
        const std::size_t n = b.object_indices.size();
        draws_.push_back({b.mesh_id, static_cast<std::uint32_t>(instances_.size()), static_cast<std::uint32_t>(n),
                          b.cast_shadow, slot_offset, static_cast<std::uint32_t>(b.material_slots.size())});
        const GpuMesh& mesh = scene.meshes()[b.mesh_id];
        if (options.motion_blur && (mesh.flags & 8u) != 0u) deforming_ = true;
        for (std::size_t i = 0; i < n; ++i) {
            Mat4d m;
            std::copy(b.matrices.begin() + long(i * 16), b.matrices.begin() + long(i * 16 + 16), m.begin());
            const glm::dmat4 world = to_glm(m);
            gpu::GpuInstance g{};
            g.ids = {b.object_indices[i], slot_offset, static_cast<std::uint32_t>(b.material_slots.size()),
                     (b.holdout ? 2u : 0u) | (b.shadow_catcher ? 4u : 0u)};
            Bound bound;
            place(world, mesh, g, bound);
            bounds_.push_back(bound);
            if (options.motion_blur && !b.motion.empty()) {
                Moving mi{instances_.size(), {world, world, world}, b.mesh_id};
                for (int step = 0; step < 2; ++step) {
                    std::copy(b.motion.begin() + long(i * 32 + std::size_t(step) * 16),
                              b.motion.begin() + long(i * 32 + std::size_t(step) * 16 + 16), m.begin());
                    mi.steps[step == 0 ? 0 : 2] = to_glm(m);
                }
                if (mi.steps[0] != world || mi.steps[2] != world) moving_.push_back(mi);
            }
            g.color = {b.colors[i * 4], b.colors[i * 4 + 1], b.colors[i * 4 + 2], b.colors[i * 4 + 3]};
            g.info = {b.randoms[i], b.terminator_offsets[i], 0.0f, 0.0f};
            if (b.terminator_offsets[i] > 0.0f && mesh.terminator_reach > 0.0) {
                // A moving instance's at each step of the shutter.
                double stretch = largest_stretch(glm::dmat3(world));
                if (!moving_.empty() && moving_.back().index == instances_.size())
                    for (const glm::dmat4& w : moving_.back().steps)
                        stretch = std::max(stretch, largest_stretch(glm::dmat3(w)));
                terminator_lift_ = std::max(terminator_lift_, stretch * mesh.terminator_reach);
            }
            instances_.push_back(g);
            if (options.cryptomatte) crypto_.insert(crypto_.end(), {b.crypto[2 * i], b.crypto[2 * i + 1]});
            if (options.light_groups) groups.push_back(b.light_group);
        }
    }
    for (const Material& m : scene.materials()) {
        gpu::GpuMaterial g{};
        // The closure model (gbuffer_lib.glsl): -1 Principled, 0..1 Diffuse
        // BSDF (Oren-Nayar sigma), 1 + glossy_model for a Glossy BSDF.
        g.base_diffuse = {m.base_color[0], m.base_color[1], m.base_color[2],
                          m.glossy_model > 0 ? 1.0f + float(m.glossy_model)
                          : m.diffuse_roughness < 0.0f ? -1.0f : std::min(m.diffuse_roughness, 1.0f)};
        g.params0 = {m.metallic, m.roughness, m.specular, m.specular_tint};
        g.params1 = {m.sheen, m.sheen_tint, m.clearcoat, m.clearcoat_roughness};
        g.emission = {m.emission[0] * m.emission_strength, m.emission[1] * m.emission_strength,
                      m.emission[2] * m.emission_strength, float(m.pass_index)};
        const float constants = m.graph >= 0 ? float(materials.constants_offset(std::uint32_t(m.graph))) : 0.0f;
        g.mix = {float(m.mix_with), m.mix_probability, constants, m.alpha};
        if (m.holdout) g.base_diffuse.w = kClosureHoldout;
        gpu_materials_.push_back(g);
    }
    // Updated every sample when instances move (storage without data is dynamic).
    instance_buffer_ = make_storage_buffer(moving_.empty() ? instances_.data() : nullptr,
                                           instances_.size() * sizeof(gpu::GpuInstance), "instances");
    if (!moving_.empty()) upload_instances();
    slot_buffer_ = make_storage_buffer(slots_.data(), slots_.size() * sizeof(std::uint32_t), "material slots");
    material_buffer_ = make_storage_buffer(gpu_materials_.data(), gpu_materials_.size() * sizeof(gpu::GpuMaterial),
                                           "materials");
    if (options.light_groups) {
        const std::uint32_t none = 0;
        instance_group_buffer_ = groups.empty()
            ? make_storage_buffer(&none, 4, "instance light groups")
            : make_storage_buffer(groups.data(), groups.size() * 4, "instance light groups");
    }
}

void FrameScene::release() {
    scene_ = nullptr;
    one_sided_ = 0;
    instances_.clear();
    bounds_.clear();
    slots_.clear();
    draws_.clear();
    moving_.clear();
    deforming_ = false;
    terminator_lift_ = 0.0;
    gpu_materials_.clear();
    crypto_.clear();
    casters_.clear();
    caster_of_instance_.clear();
    casters_built_ = false;
    instance_buffer_.reset();
    slot_buffer_.reset();
    material_buffer_.reset();
    instance_group_buffer_.reset();
    remap_.clear();
    remap_buffer_.reset();
    remap_capacity_ = 0;
    visible_.clear();
}

void FrameScene::upload_instances() const {
    glNamedBufferSubData(instance_buffer_.get(), 0, GLsizeiptr(instances_.size() * sizeof(gpu::GpuInstance)),
                         instances_.data());
}

float FrameScene::coverage(std::uint32_t id) const {
    float alpha = 0.0f, weight = 1.0f;
    const gpu::GpuMaterial* m = &gpu_materials_[id];
    for (int k = 0; k < 16; ++k) {
        const float p = m->mix.x >= 0.0f ? m->mix.y : 0.0f;
        alpha += weight * (1.0f - p) * m->mix.w;
        weight *= p;
        if (m->mix.x < 0.0f) break;
        m = &gpu_materials_[std::size_t(m->mix.x)];
    }
    return alpha + weight * m->mix.w;
}

const std::vector<RayScene::Instance>& FrameScene::ray_casters() {
    if (casters_built_) return casters_;
    casters_built_ = true;
    caster_of_instance_.assign(instances_.size(), -1);
    std::size_t first_instance = 0;
    for (const InstanceBatch& b : scene_->batches()) {
        const std::size_t batch_first = first_instance;
        first_instance += b.object_indices.size();
        if (!b.cast_shadow) continue;
        const GpuMesh& mesh = scene_->meshes()[b.mesh_id];
        if (mesh.triangle_count == 0) continue;
        std::vector<float> slot_alpha;
        for (std::uint32_t id : b.material_slots) slot_alpha.push_back(coverage(id));
        const std::shared_ptr<const MeshBvh> bvh = mesh_bvh(mesh);
        for (std::size_t i = 0; i < b.object_indices.size(); ++i) {
            Mat4d m;
            std::copy(b.matrices.begin() + long(i * 16), b.matrices.begin() + long(i * 16 + 16), m.begin());
            glm::dmat4 model = to_glm(m);
            model[3] = glm::dvec4(glm::dvec3(model[3]) - camera_position_, 1.0);
            caster_of_instance_[batch_first + i] = std::int64_t(casters_.size());
            casters_.push_back({bvh, model, slot_alpha});
        }
    }
    return casters_;
}

bool FrameScene::place_at(double r) {
    if (moving_.empty()) return false;
    bool casters_moved = false;
    for (const Moving& mi : moving_) {
        const glm::dmat4 world = interpolate_motion(mi.steps[0], mi.steps[1], mi.steps[2], r);
        place(world, scene_->meshes()[mi.mesh], instances_[mi.index], bounds_[mi.index]);
        if (casters_built_ && caster_of_instance_[mi.index] >= 0) {
            glm::dmat4 model = world;
            model[3] = glm::dvec4(glm::dvec3(model[3]) - camera_position_, 1.0);
            casters_[std::size_t(caster_of_instance_[mi.index])].model = model;
            casters_moved = true;
        }
    }
    upload_instances();
    return casters_moved;
}

glm::dmat4 FrameScene::model_matrix(std::uint32_t i) const {
    const gpu::mat4& m = instances_[i].model;
    glm::dmat4 out(1.0);
    for (int c = 0; c < 4; ++c) out[c] = glm::dvec4(m.cols[c].x, m.cols[c].y, m.cols[c].z, m.cols[c].w);
    return out;
}

Box FrameScene::instance_box(std::uint32_t i, const GpuMesh& mesh) const {
    const glm::dmat4 m = model_matrix(i);
    Box b;
    b.center = glm::dvec3(m[3]);
    for (int k = 0; k < 3; ++k) {
        b.center += glm::dvec3(m[k]) * mesh.bound_center[k];
        b.half[std::size_t(k)] = glm::dvec3(m[k]) * mesh.bound_half[k];
    }
    return b;
}

std::vector<Box> FrameScene::boxes_in_view(const ViewVolume& view) const {
    std::vector<Box> boxes;
    for (const Draw& d : draws_) {
        const GpuMesh& mesh = scene_->meshes()[d.mesh];
        if (mesh.triangle_count == 0) continue;
        for (std::uint32_t i = d.first; i < d.first + d.count; ++i) {
            if (!view.contains(bounds_[i].center, bounds_[i].radius)) continue;
            // The packed matrix the vertex stage uses (float: box_in_volume's
            // widening covers its rounding).
            boxes.push_back(instance_box(i, mesh));
        }
    }
    return boxes;
}

void FrameScene::bind_buffers() const {
    glBindVertexArray(empty_vao_);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_INSTANCES, instance_buffer_.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_MATERIAL_SLOTS, slot_buffer_.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_MATERIALS, material_buffer_.get());
}

void FrameScene::bind_mesh(const GpuMesh& mesh) const {
    auto bind = [&](GLuint slot, const Buffer& b) {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot, b ? b.get() : dummy_ssbo_);
    };
    bind(SSBO_POSITIONS, mesh.positions);
    bind(SSBO_INDICES, mesh.indices);
    bind(SSBO_NORMALS, mesh.normals);
    bind(SSBO_UVS, mesh.uvs);
    bind(SSBO_MATERIAL_INDICES, mesh.material_indices);
    bind(SSBO_MOTION_POSITIONS, mesh.motion_positions);
}

void FrameScene::bind_attributes(const GpuMesh& mesh) const {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_ATTRIBUTES, mesh.attributes ? mesh.attributes.get() : dummy_ssbo_);
}

std::uint64_t FrameScene::caster_triangles(const Test& keep) const {
    std::uint64_t n = 0;
    for (const Draw& d : draws_) {
        const GpuMesh& mesh = scene_->meshes()[d.mesh];
        if (!d.cast_shadow || mesh.triangle_count == 0) continue;
        for (std::uint32_t i = d.first; i < d.first + d.count; ++i)
            if (keep(bounds_[i].center, bounds_[i].radius)) n += mesh.triangle_count;
    }
    return n;
}

std::uint64_t FrameScene::cull(const Test& keep, bool casters_only, const FaceCulling* faces) {
    remap_.clear();
    visible_.clear();
    facing_ccw_ = faces ? faces->facing_ccw : true;
    for (const Draw& d : draws_) {
        const GpuMesh& mesh = scene_->meshes()[d.mesh];
        if ((casters_only && !d.cast_shadow) || mesh.triangle_count == 0) continue;
        if (!faces || mesh.closed == 0) {
            const std::uint32_t first = std::uint32_t(remap_.size());
            for (std::uint32_t i = d.first; i < d.first + d.count; ++i)
                if (keep(bounds_[i].center, bounds_[i].radius)) remap_.push_back(i);
            if (remap_.size() > first) visible_.push_back({&d, first, std::uint32_t(remap_.size()) - first, 0});
            continue;
        }
        // Grouped by the side that faces the viewer: the mesh's own
        // orientation, flipped by a mirroring instance (ids.w bit 0).
        const std::uint32_t first = std::uint32_t(remap_.size());
        facing_groups_[0].clear();
        facing_groups_[1].clear();
        for (std::uint32_t i = d.first; i < d.first + d.count; ++i) {
            if (!keep(bounds_[i].center, bounds_[i].radius)) continue;
            if (!faces->applies(bounds_[i].center, bounds_[i].radius)) facing_groups_[1].push_back(i);
            else if ((mesh.closed > 0) != ((instances_[i].ids.w & 1u) != 0u)) remap_.push_back(i);
            else facing_groups_[0].push_back(i);
        }
        std::uint32_t at = first;
        const int facing[3] = {1, -1, 0};
        for (int g = 0; g < 3; ++g) {
            if (g > 0) remap_.insert(remap_.end(), facing_groups_[g - 1].begin(), facing_groups_[g - 1].end());
            const std::uint32_t end = std::uint32_t(remap_.size());
            if (end > at) visible_.push_back({&d, at, end - at, facing[g]});
            at = end;
        }
    }
    if (visible_.empty()) return 0;
    if (remap_.size() > remap_capacity_) {
        remap_capacity_ = std::max<std::size_t>(remap_.size(), instances_.size());
        remap_buffer_ = make_storage_buffer(nullptr, remap_capacity_ * sizeof(std::uint32_t), "instance remap");
    }
    glNamedBufferSubData(remap_buffer_.get(), 0, GLsizeiptr(remap_.size() * sizeof(std::uint32_t)), remap_.data());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_INSTANCE_REMAP, remap_buffer_.get());
    bind_buffers();
    return remap_.size();
}

void FrameScene::draw_range(const Culled& c, std::uint32_t first, std::uint32_t count, const DrawStyle& style) const {
    if (count == 0) return;
    const GpuMesh& m = mesh(*c.draw);
    bind_mesh(m);
    glUniform1ui(0, c.first);
    glUniform1ui(1, m.flags);
    const bool cull = style.cull_faces && c.facing != 0;
    if (cull) {
        one_sided_ += c.count;
        glEnable(GL_CULL_FACE);
        glCullFace(GL_BACK);
        glFrontFace((c.facing > 0) == facing_ccw_ ? GL_CCW : GL_CW);
    }
    if (style.by_vertex) {
        // Triangle t's corners are elements 3t..3t+2 of the index buffer.
        if (style.first_triangle_location >= 0) glUniform1ui(style.first_triangle_location, first);
        glVertexArrayElementBuffer(empty_vao_, m.indices.get());
        glDrawElementsInstanced(GL_TRIANGLES, GLsizei(count * 3), GL_UNSIGNED_INT,
                                reinterpret_cast<const void*>(std::uintptr_t(first) * 3u * sizeof(std::uint32_t)),
                                GLsizei(c.count));
    } else {
        glDrawArraysInstanced(GL_TRIANGLES, GLint(first * 3), GLsizei(count * 3), GLsizei(c.count));
    }
    if (cull) {
        glDisable(GL_CULL_FACE);
        glFrontFace(GL_CCW);  // what the two-sided passes' gl_FrontFacing reads (geometry_frag.glsl)
    }
}

std::uint64_t FrameScene::draw_culled(const Test& keep, bool casters_only, const DrawStyle& style,
                                      const FaceCulling* faces) {
    const std::uint64_t n = cull(keep, casters_only, faces);
    for (const Culled& c : visible_) draw_range(c, 0, mesh(*c.draw).triangle_count, style);
    return n;
}

std::uint32_t FrameScene::slot_material(const Draw& d, std::size_t s) const {
    const std::uint32_t slot = std::uint32_t(std::min<std::size_t>(s, std::max(d.slot_count, 1u) - 1));
    return slots_[d.slot_offset + slot];
}

}  // namespace deferred
