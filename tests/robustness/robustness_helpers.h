// Shared helpers of the robustness suite (issue 7): finiteness checks over
// every pass, small scene builders, environment overrides.
#pragma once

#include "builtin_scenes.h"
#include "camera.h"
#include "test_helpers.h"

#include <deferred/renderer.h>

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

namespace deferred::robustness {

// Every pass the renderer can produce.
inline PassSet all_passes() {
    PassSet s;
    for (std::uint32_t i = 0; i < kPassCount; ++i) s.insert(Pass(i));
    return s;
}

struct FiniteReport {
    std::size_t bad = 0;          // non-finite values over all passes
    std::string first;            // "Pass(x, y) channel c = nan"
    bool ok() const { return bad == 0; }
};

inline FiniteReport check_finite(const FrameResult& f) {
    FiniteReport r;
    for (const PassImage& img : f.passes)
        for (std::size_t i = 0; i < img.pixels.size(); ++i)
            if (!std::isfinite(img.pixels[i])) {
                if (r.bad++ == 0) {
                    const std::size_t px = i / std::size_t(img.channels);
                    r.first = std::string(pass_info(img.pass).name) + "(" + std::to_string(px % img.width) + ", " +
                              std::to_string(px / img.width) + ") channel " + std::to_string(i % img.channels) +
                              " = " + std::to_string(img.pixels[i]);
                }
            }
    return r;
}

inline const float* pixel(const PassImage& img, int x, int y) {
    return &img.pixels[(std::size_t(y) * img.width + x) * img.channels];
}

inline std::uint64_t env_u64(const char* name, std::uint64_t fallback) {
    if (const char* v = std::getenv(name)) {
        char* end = nullptr;
        const unsigned long long x = std::strtoull(v, &end, 0);
        if (end && *end == '\0' && end != v) return x;
    }
    return fallback;
}

inline Mat4d rotation_z(double angle, double tx = 0, double ty = 0, double tz = 0) {
    Mat4d m = tools::translation(tx, ty, tz);
    m[0] = std::cos(angle);
    m[1] = std::sin(angle);
    m[4] = -std::sin(angle);
    m[5] = std::cos(angle);
    return m;
}

// The parameter corners of the material (issue 7): every roughness given x
// metallic 0/1 x specular 0/0.5 x base colour 0/1.
inline std::vector<Material> corner_materials(std::initializer_list<float> roughnesses) {
    std::vector<Material> out;
    for (float roughness : roughnesses)
        for (float metallic : {0.0f, 1.0f})
            for (float specular : {0.0f, 0.5f})
                for (float base : {0.0f, 1.0f}) {
                    Material m;
                    m.base_color = {base, base, base};
                    m.roughness = roughness;
                    m.metallic = metallic;
                    m.specular = specular;
                    out.push_back(m);
                }
    return out;
}

// The library's own Mat4d -> glm conversion and the native tests' camera.
using deferred::to_glm;
inline Camera top_down(double h, float extent) { return deferred::testing::top_down_ortho(h, extent); }

// A single triangle mesh (corner normals optional, all equal to `n`).
struct TriangleMesh {
    float positions[9];
    std::uint32_t indices[3] = {0, 1, 2};
    float normals[9];
    MeshData view(bool with_normals) const {
        MeshData m;
        m.positions = positions;
        m.vertex_count = 3;
        m.indices = indices;
        m.triangle_count = 1;
        m.corner_normals = with_normals ? normals : nullptr;
        return m;
    }
};

}  // namespace deferred::robustness
