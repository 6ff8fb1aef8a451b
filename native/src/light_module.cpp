#include "light_module.h"

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
                       ShadowModule* shadows) {
    std::vector<gpu::GpuLight> packed;
    packed.reserve(lights.size());
    for (auto& t : has_type_) t = false;
    for (const Light& l : lights) {
        // Lights that cannot contribute are dropped here, not in the shader.
        if (l.energy == 0.0f || (l.color[0] == 0 && l.color[1] == 0 && l.color[2] == 0)) continue;
        if (l.type == LightType::Area && (l.size <= 0 || (l.shape == AreaShape::Rectangle && l.size_y <= 0) ||
                                          (l.shape == AreaShape::Ellipse && l.size_y <= 0)))
            continue;  // zero-size area light: no emitting surface (Cycles renders nothing either)
        packed.push_back(pack_light(l, camera_position, threshold));
        if (shadows) shadows->offer(packed.size() - 1, l, packed.back());
        has_type_[static_cast<int>(l.type)] = true;
    }
    if (shadows) {
        const std::vector<int> shadow_index = shadows->allocate(packed.size());
        for (std::size_t i = 0; i < packed.size(); ++i) packed[i].params.w = float(shadow_index[i]);
    }
    count_ = static_cast<std::uint32_t>(packed.size());
    buffer_ = make_storage_buffer(packed.data(), packed.size() * sizeof(gpu::GpuLight), "lights");
}

void LightModule::add_defines(ShaderVariant& variant) const {
    static const char* names[4] = {"HAS_POINT_LIGHTS", "HAS_SPOT_LIGHTS", "HAS_SUN_LIGHTS", "HAS_AREA_LIGHTS"};
    for (int i = 0; i < 4; ++i)
        if (has_type_[i]) variant.defines.push_back(names[i]);
}

void LightModule::bind() const { glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_LIGHTS, buffer_.get()); }

}  // namespace deferred
