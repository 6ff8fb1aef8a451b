#include "light_module.h"

#include "emitter_module.h"
#include "shadow_module.h"

#include "../../shaders/shader_defines.h"

#include <algorithm>
#include <cmath>

namespace deferred {

namespace {
gpu::vec4 v4(const glm::dvec3& v, double w) {
    return {float(v.x), float(v.y), float(v.z), float(w)};
}
}  // namespace

double influence_radius(const Light& l, double threshold) {
    if (l.type == LightType::Sun || !(threshold > 0.0)) return -1.0;
    const double S = std::abs(double(l.energy)) *
                     std::max({std::abs(double(l.color[0])), std::abs(double(l.color[1])), std::abs(double(l.color[2]))});
    if (l.type == LightType::Area) {
        const glm::dmat4 m = to_glm(l.matrix);
        const bool separate_y = l.shape == AreaShape::Rectangle || l.shape == AreaShape::Ellipse;
        const double hx = 0.5 * l.size * glm::length(glm::dvec3(m[0]));
        const double hy = 0.5 * (separate_y ? l.size_y : l.size) * glm::length(glm::dvec3(m[1]));
        return std::sqrt(hx * hx + hy * hy) + std::sqrt(S / (4.0 * M_PI * threshold));
    }
    return double(l.radius) + std::sqrt(S / (4.0 * M_PI * M_PI * threshold));
}

gpu::GpuLight pack_light(const Light& l, const glm::dvec3& camera_position, double threshold) {
    const glm::dmat4 m = to_glm(l.matrix);
    const glm::dvec3 position = glm::dvec3(m[3]) - camera_position;  // camera-relative, in double
    const glm::dvec3 x_axis(m[0]), y_axis(m[1]), z_axis(m[2]);
    const double zlen = glm::length(z_axis);
    const glm::dvec3 direction = zlen > 0 ? -z_axis / zlen : glm::dvec3(0, 0, -1);
    const glm::dvec3 S = glm::dvec3(l.color[0], l.color[1], l.color[2]) * double(l.energy);

    gpu::GpuLight g{};
    g.position_type = v4(position, double(static_cast<std::uint32_t>(l.type)));
    const double radius = (l.type == LightType::Sun) ? 0.5 * l.angle : l.radius;
    g.strength = v4(S, radius);
    const double cs = std::cos(0.5 * double(l.spot_size));
    g.direction = v4(direction, cs);
    // Area extents: size along the object's X axis, size_y (RECTANGLE/ELLIPSE)
    // or size along Y, both scaled by the object's scale (Cycles 3.4 light.cpp).
    const bool separate_y = l.shape == AreaShape::Rectangle || l.shape == AreaShape::Ellipse;
    const double sx = l.size, sy = separate_y ? l.size_y : l.size;
    const glm::dvec3 half_x = 0.5 * sx * x_axis, half_y = 0.5 * sy * y_axis;
    const bool ellipse = l.shape == AreaShape::Disk || l.shape == AreaShape::Ellipse;
    g.axis_x = v4(half_x, (1.0 - cs) * double(l.spot_blend));
    g.axis_y = v4(half_y, ellipse ? AREA_ELLIPSE : AREA_RECT);
    if (l.type == LightType::Sun) {
        // The disk's tangent radius and the cone's cosine, in double here:
        // a GPU's fast tan() near 90 degrees (a 180-degree sun) gave inf and
        // a whole image of NaN on NVIDIA. Capped as float tanf(pi/2) is in
        // Cycles (light.cpp: radius = tanf(angle / 2)).
        g.axis_x.w = float(std::min(std::tan(radius), 1e7));
        g.axis_y.w = float(std::cos(radius));
    }
    const double area = 4.0 * glm::length(half_x) * glm::length(half_y) * (ellipse ? M_PI / 4.0 : 1.0);
    g.params = {float(area), l.cast_shadow ? 1.0f : 0.0f, float(influence_radius(l, threshold)), -1.0f};
    return g;
}

void LightModule::sync(const std::vector<Light>& lights, const glm::dvec3& camera_position, double threshold,
                       ShadowModule* shadows, const EmitterModule* emitters) {
    std::vector<gpu::GpuLight>& packed = packed_;
    packed.clear();
    packed.reserve(lights.size());
    groups_.clear();
    for (auto& t : has_type_) t = false;
    // Packed in order of type (point, spot, sun, area; then the mesh
    // lights), each type in the scene's order: on llvmpipe the lighting
    // pass shades each kind in a loop of its own whose body holds only that
    // kind's code (lighting_comp.glsl LIGHT_KIND_LOOPS), over a sequence in
    // this order.
    std::vector<const Light*> by_type;
    by_type.reserve(lights.size());
    for (const Light& l : lights) by_type.push_back(&l);
    std::stable_sort(by_type.begin(), by_type.end(),
                     [](const Light* a, const Light* b) { return int(a->type) < int(b->type); });
    for (const Light* lp : by_type) {
        const Light& l = *lp;
        // Lights that cannot contribute are dropped here, not in the shader.
        if (l.energy == 0.0f || (l.color[0] == 0 && l.color[1] == 0 && l.color[2] == 0)) continue;
        if (l.type == LightType::Area && (l.size <= 0 || (l.shape == AreaShape::Rectangle && l.size_y <= 0) ||
                                          (l.shape == AreaShape::Ellipse && l.size_y <= 0)))
            continue;  // zero-size area light: no emitting surface (Cycles renders nothing either)
        packed.push_back(pack_light(l, camera_position, threshold));
        groups_.push_back(l.light_group);
        if (shadows) shadows->offer(packed.size() - 1, l, packed.back());
        has_type_[static_cast<int>(l.type)] = true;
    }
    first_mesh_ = packed.size();
    emission_texels_ = emitters && emitters->has_texels();
    if (emitters) {
        for (const MeshLight& m : emitters->lights()) {
            gpu::GpuLight g{};
            g.position_type = v4(m.center, double(LIGHT_MESH));
            g.direction = {float(m.first), float(m.count), float(m.area), float(m.radius)};
            // A point at distance d from a two-sided emitter of radiance
            // <= Lmax and area A gets E <= Lmax A / d^2, so a white diffuse
            // surface reflects E / pi < T beyond d = sqrt(Lmax A / (pi T))
            // from the emitter's bounding sphere.
            const double reach = threshold > 0.0 ? m.radius + std::sqrt(m.max_radiance * m.area / (M_PI * threshold))
                                                 : -1.0;
            g.params = {float(m.area), m.cast_shadow ? 1.0f : 0.0f, float(reach), -1.0f};
            packed.push_back(g);
            groups_.push_back(m.light_group);
            if (shadows && m.cast_shadow)
                shadows->offer_mesh(packed.size() - 1, packed.back(), m.power * M_PI);
            has_type_[LIGHT_MESH] = true;
        }
    }
    if (shadows) {
        const std::vector<int> shadow_index = shadows->allocate(packed.size());
        for (std::size_t i = 0; i < packed.size(); ++i) packed[i].params.w = float(shadow_index[i]);
    }
    count_ = static_cast<std::uint32_t>(packed.size());
    const std::uint32_t no_group = 0;  // a buffer is never empty
    groups_buffer_ = groups_.empty() ? make_storage_buffer(&no_group, 4, "light groups")
                                     : make_storage_buffer(groups_.data(), groups_.size() * 4, "light groups");
    if (first_mesh_ < packed.size()) {
        // Mesh lights change every sample (their shared point): a buffer updated in place.
        buffer_ = make_storage_buffer(nullptr, packed.size() * sizeof(gpu::GpuLight), "lights");
        glNamedBufferSubData(buffer_.get(), 0, GLsizeiptr(packed.size() * sizeof(gpu::GpuLight)), packed.data());
    } else {
        buffer_ = make_storage_buffer(packed.data(), packed.size() * sizeof(gpu::GpuLight), "lights");
    }
}

void LightModule::update_mesh_points(const EmitterModule& emitters, const std::array<float, 2>& u,
                                     ShadowModule* shadows) {
    if (first_mesh_ >= packed_.size()) return;
    for (std::size_t k = 0; k < emitters.lights().size() && first_mesh_ + k < packed_.size(); ++k) {
        const MeshLightPoint p = emitters.sample_point(k, u);
        gpu::GpuLight& g = packed_[first_mesh_ + k];
        g.strength = v4(p.radiance, 0.0);
        g.axis_x = v4(p.position, p.pdf);
        g.axis_y = v4(p.normal, double(emitters.lights()[k].side));
        if (shadows) shadows->update_light(first_mesh_ + k, g);
    }
    glNamedBufferSubData(buffer_.get(), GLintptr(first_mesh_ * sizeof(gpu::GpuLight)),
                         GLsizeiptr((packed_.size() - first_mesh_) * sizeof(gpu::GpuLight)), &packed_[first_mesh_]);
}

void LightModule::add_defines(ShaderVariant& variant) const {
    static const char* names[5] = {"HAS_POINT_LIGHTS", "HAS_SPOT_LIGHTS", "HAS_SUN_LIGHTS", "HAS_AREA_LIGHTS",
                                   "HAS_MESH_LIGHTS"};
    for (int i = 0; i < 5; ++i)
        if (has_type_[i]) variant.defines.push_back(names[i]);
    if (emission_texels_ && has_type_[LIGHT_MESH]) variant.defines.push_back("HAS_EMISSION_TEXELS");
}

void LightModule::bind() const { glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_LIGHTS, buffer_.get()); }

void LightModule::bind_groups() const {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_LIGHT_GROUPS, groups_buffer_.get());
}

}  // namespace deferred
