// Input validation without GL (issue 7, "Bad input"): the scene contract of
// native/src/scene_store.h (InputLimits) and the camera checks of camera.cpp.
// Runs no GL at all, so it is the test the sanitizer build
// (scripts/sanitize.sh, -DDEFERRED_SANITIZE=ON) runs first.
//   - every kind of bad value is refused with InvalidInput naming the field;
//   - values on the contract's boundary are accepted;
//   - the documented fallbacks of sanitized_light();
//   - random inputs (random bit patterns: NaN, Inf, denormals, huge): either
//     refused, or accepted and then everything the renderer derives from
//     them in float32 (camera matrices and their inverse, light strength and
//     radiance, camera-relative positions) is finite. Exact-size heap
//     buffers, so AddressSanitizer sees any read past an array.
#include "camera.h"
#include "scene_store.h"

#include <deferred/renderer.h>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

using namespace deferred;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// Runs `f`; returns the InvalidInput message, or "" if it was accepted.
std::string refusal(const std::function<void()>& f) {
    try {
        f();
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "";
}

#define EXPECT_REFUSED(call, needle)                                                        \
    do {                                                                                    \
        const std::string msg_ = refusal([&] { call; });                                    \
        EXPECT_FALSE(msg_.empty()) << #call << " was accepted";                             \
        EXPECT_NE(msg_.find(needle), std::string::npos) << #call << " -> \"" << msg_ << "\""; \
    } while (0)

#define EXPECT_ACCEPTED(call)                                                     \
    do {                                                                          \
        const std::string msg_ = refusal([&] { call; });                          \
        EXPECT_TRUE(msg_.empty()) << #call << " was refused: \"" << msg_ << "\""; \
    } while (0)

Mat4d translation(double x, double y, double z) {
    Mat4d m = identity_matrix();
    m[12] = x;
    m[13] = y;
    m[14] = z;
    return m;
}

struct OwnedMesh {
    std::vector<float> positions{0, 0, 0, 1, 0, 0, 0, 1, 0};
    std::vector<std::uint32_t> indices{0, 1, 2};
    std::vector<float> normals{0, 0, 1, 0, 0, 1, 0, 0, 1};
    std::vector<float> uvs{0, 0, 1, 0, 0, 1};
    std::vector<std::int32_t> mats{0};
    MeshData view() const {
        MeshData m;
        m.positions = positions.data();
        m.vertex_count = positions.size() / 3;
        m.indices = indices.data();
        m.triangle_count = indices.size() / 3;
        m.corner_normals = normals.data();
        m.corner_uvs = uvs.data();
        m.material_indices = mats.data();
        return m;
    }
};

// Finite once converted to float32 (checked in double: an out-of-range
// double -> float conversion is undefined behaviour).
bool float_finite(double v) { return std::isfinite(v) && std::abs(v) <= double(std::numeric_limits<float>::max()); }

}  // namespace

TEST(Validation, MeshErrorsNameTheArray) {
    OwnedMesh ok;
    EXPECT_ACCEPTED(validate_mesh(ok.view()));
    { OwnedMesh m = ok; m.positions[4] = kNaN; EXPECT_REFUSED(validate_mesh(m.view()), "positions: element 4"); }
    { OwnedMesh m = ok; m.positions[2] = -kInf; EXPECT_REFUSED(validate_mesh(m.view()), "positions"); }
    { OwnedMesh m = ok; m.positions[0] = 2e15f; EXPECT_REFUSED(validate_mesh(m.view()), "exceeds the limit"); }
    { OwnedMesh m = ok; m.indices[2] = 3; EXPECT_REFUSED(validate_mesh(m.view()), "indices: element 2 = 3 is out of range for 3 vertices"); }
    { OwnedMesh m = ok; m.indices[0] = 0xffffffffu; EXPECT_REFUSED(validate_mesh(m.view()), "indices"); }
    { OwnedMesh m = ok; m.normals[8] = kNaN; EXPECT_REFUSED(validate_mesh(m.view()), "corner_normals: element 8"); }
    { OwnedMesh m = ok; m.uvs[1] = kInf; EXPECT_REFUSED(validate_mesh(m.view()), "corner_uvs: element 1"); }
    { OwnedMesh m = ok; m.mats[0] = -1; EXPECT_REFUSED(validate_mesh(m.view()), "material_indices: element 0 = -1"); }
    {
        MeshData m = ok.view();
        m.positions = nullptr;
        EXPECT_REFUSED(validate_mesh(m), "required");
    }
    // Empty meshes are valid (nothing is drawn); degenerate triangles too.
    EXPECT_ACCEPTED(validate_mesh(MeshData{}));
    { OwnedMesh m = ok; m.indices = {0, 0, 0}; EXPECT_ACCEPTED(validate_mesh(m.view())); }
    { OwnedMesh m = ok; for (float& n : m.normals) n = 0; EXPECT_ACCEPTED(validate_mesh(m.view())); }
    { OwnedMesh m = ok; m.mats[0] = 7; EXPECT_EQ(validate_mesh(m.view()), 7); }
}

TEST(Validation, MaterialRanges) {
    EXPECT_ACCEPTED(validate_material(Material{}));
    Material edge;
    edge.base_color = {0, 1, 65504};
    edge.metallic = 1;
    edge.roughness = 0;
    edge.specular = 12;
    edge.specular_tint = 1;
    edge.sheen = 1;
    edge.sheen_tint = 0;
    edge.clearcoat = 1;
    edge.clearcoat_roughness = 0;
    edge.emission = {1e30f, 0, 0};
    edge.emission_strength = 1e30f;
    edge.alpha = 0;
    edge.pass_index = (1u << 24) - 1;
    EXPECT_ACCEPTED(validate_material(edge));
    auto with = [](auto set) { Material m; set(m); return m; };
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.roughness = kNaN; })), "roughness is NaN");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.roughness = -0.01f; })), "roughness = -0.01 is outside [0, 1]");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.metallic = 1.5f; })), "metallic");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.specular = 12.5f; })), "specular = 12.5 is outside [0, 12]");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.specular_tint = 2; })), "specular_tint");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.sheen = -1; })), "sheen");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.sheen_tint = kInf; })), "sheen_tint");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.clearcoat = 2; })), "clearcoat");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.clearcoat_roughness = -1; })), "clearcoat_roughness");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.alpha = 1.5f; })), "alpha");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.emission_strength = -1; })), "emission_strength");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.base_color[1] = -0.1f; })), "base_color component 1");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.base_color[2] = 70000; })), "outside [0, 65504]");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.base_color[0] = kNaN; })), "base_color must be finite");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.emission[0] = -1; })), "emission component 0");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.emission[2] = kInf; })), "emission must be finite");
    EXPECT_REFUSED(validate_material(with([](Material& m) { m.pass_index = 1u << 24; })), "pass_index");
}

TEST(Validation, LightRangesAndFallbacks) {
    EXPECT_ACCEPTED(validate_light(Light{}));
    auto with = [](auto set) { Light l; set(l); return l; };
    EXPECT_ACCEPTED(validate_light(with([](Light& l) { l.energy = -1e12f; })));  // negative: Blender allows it
    EXPECT_ACCEPTED(validate_light(with([](Light& l) { l.energy = 1e9f; l.radius = 0; })));
    EXPECT_ACCEPTED(validate_light(with([](Light& l) { l.spot_size = float(M_PI); l.spot_blend = 1; l.angle = float(M_PI); })));
    EXPECT_ACCEPTED(validate_light(with([](Light& l) { l.matrix = translation(1e15, -1e15, 0); })));
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.matrix[13] = std::nan(""); })), "matrix has NaN/Inf");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.matrix[12] = 2e15; })), "matrix element 12");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.energy = kInf; })), "energy is NaN or infinite");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.energy = 2e12f; })), "energy x colour");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.energy = 1e9f; l.color = {5000, 0, 0}; })), "exceeds the limit");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.color = {-1, 0, 0}; })), "color component 0");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.radius = -0.1f; })), "radius");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.radius = 1e7f; })), "radius");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.spot_size = 4; })), "spot_size");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.spot_blend = 1.5f; })), "spot_blend");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.angle = 7; })), "angle");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.size = -1; })), "size");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.size_y = kNaN; })), "size_y");
    EXPECT_REFUSED(validate_light(with([](Light& l) { l.type = LightType(7); })), "unknown type");

    // Fallbacks: tiny radius -> delta light; tiny area extents raised to 1e-6 m.
    EXPECT_EQ(sanitized_light(with([](Light& l) { l.radius = 1e-20f; })).radius, 0.0f);
    EXPECT_EQ(sanitized_light(with([](Light& l) { l.radius = 0.25f; })).radius, 0.25f);
    Light area = with([](Light& l) { l.type = LightType::Area; l.size = 1e-9f; });
    EXPECT_NEAR(sanitized_light(area).size, 1e-6f, 1e-11f);
    area.shape = AreaShape::Rectangle;
    area.size = 1.0f;
    area.size_y = 1e-12f;
    area.matrix[0] = 1e-3;  // X scale: extent 1e-3 m, fine
    const Light s = sanitized_light(area);
    EXPECT_EQ(s.size, 1.0f);
    EXPECT_NEAR(s.size_y, 1e-6f, 1e-11f);
    area.matrix[5] = 1e-30;  // a collapsed Y axis: no emitting surface
    EXPECT_EQ(sanitized_light(area).size_y, 0.0f);
}

TEST(Validation, WorldAndInstances) {
    EXPECT_ACCEPTED(validate_world(World{}));
    World w;
    w.color = {0, 0, 1e12f};
    EXPECT_ACCEPTED(validate_world(w));
    w.color = {0, kNaN, 0};
    EXPECT_REFUSED(validate_world(w), "world: color must be finite");
    w.color = {-1, 0, 0};
    EXPECT_REFUSED(validate_world(w), "world: color component 0");
    w.color = {2e12f, 0, 0};
    EXPECT_REFUSED(validate_world(w), "world: color");

    std::vector<double> m(32);
    Mat4d I = identity_matrix();
    std::copy(I.begin(), I.end(), m.begin());
    std::copy(I.begin(), I.end(), m.begin() + 16);
    EXPECT_ACCEPTED(validate_instances(m.data(), 2));
    EXPECT_ACCEPTED(validate_instances(nullptr, 0));
    EXPECT_REFUSED(validate_instances(nullptr, 1), "matrices are required");
    m[16 + 13] = std::nan("");
    EXPECT_REFUSED(validate_instances(m.data(), 2), "matrices: element 29 is NaN");
    m[16 + 13] = -3e15;
    EXPECT_REFUSED(validate_instances(m.data(), 2), "matrices: element 29");
}

TEST(Validation, CameraErrors) {
    EXPECT_ACCEPTED(build_camera(Camera{}, 640, 480));
    auto with = [](auto set) { Camera c; set(c); return c; };
    EXPECT_REFUSED(build_camera(Camera{}, 0, 480), "resolution");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.lens = 0; }), 64, 64), "lens");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.lens = kNaN; }), 64, 64), "lens");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.sensor_width = -1; }), 64, 64), "sensor");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.clip_end = c.clip_start; }), 64, 64), "clip_start < clip_end");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.clip_start = 1e-7f; }), 64, 64), "clip_start must be at least 1e-6");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.pixel_aspect_x = kInf; }), 64, 64), "pixel aspect");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.shift_x = kNaN; }), 64, 64), "shift");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.matrix[3] = std::nan(""); }), 64, 64), "matrix has NaN");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.matrix[0] = c.matrix[1] = c.matrix[2] = 0; }), 64, 64), "degenerate");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.matrix[4] = 1; c.matrix[5] = 0; }), 64, 64), "parallel");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.matrix[14] = 1e16; }), 64, 64), "farther than 1e15");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.lens = 1e-40f; }), 64, 64), "float32 cannot represent");
    EXPECT_ACCEPTED(build_camera(with([](Camera& c) { c.lens = 1e-30f; }), 64, 64));  // ~180 deg, still finite
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.shift_x = 1e30f; }), 64, 64), "viewplane is empty");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.clip_start = 1e-6f; c.clip_end = 1e38f; }), 64, 64),
                   "float32 cannot represent");
    EXPECT_REFUSED(build_camera(with([](Camera& c) { c.type = CameraType::Orthographic; c.ortho_scale = 1e-40f; }), 64, 64),
                   "ortho_scale");
    // Extreme but valid: Blender's lens range 1..5000 mm, 1e-6 clip start, 1e-4/1e5 clip, 16000 px.
    EXPECT_ACCEPTED(build_camera(with([](Camera& c) { c.lens = 1; }), 16000, 1));
    EXPECT_ACCEPTED(build_camera(with([](Camera& c) { c.lens = 5000; c.clip_start = 1e-6f; c.clip_end = 1e8f; }), 1, 1));
    EXPECT_ACCEPTED(build_camera(with([](Camera& c) { c.clip_start = 1e-4f; c.clip_end = 1e5f; c.matrix[12] = 1e6; }), 7, 3));
}

// Random bit patterns through every validator. Accepted input must give
// finite float32 values everywhere the renderer converts it.
TEST(Validation, RandomInputsAreRefusedOrSafe) {
    const char* env = std::getenv("DEFERRED_FUZZ_SEED");
    const std::uint64_t seed = env ? std::strtoull(env, nullptr, 0) : std::uint64_t(std::random_device{}());
    std::printf("validation fuzz: seed %llu (DEFERRED_FUZZ_SEED to override)\n", (unsigned long long)seed);
    std::mt19937_64 rng(seed);
    auto uni = [&] { return std::uniform_real_distribution<double>(0, 1)(rng); };
    // Floats from every class: ordinary, edge, tiny, huge, denormal, NaN, Inf, random bits.
    auto any_float = [&]() -> float {
        switch (int(uni() * 10)) {
            case 0: return 0.0f;
            case 1: return 1.0f;
            case 2: return float(uni());
            case 3: return float(std::pow(10.0, uni() * 80 - 40)) * (uni() < 0.3 ? -1.0f : 1.0f);
            case 4: return std::numeric_limits<float>::denorm_min() * float(1 + int(uni() * 1000));
            case 5: return uni() < 0.5 ? kNaN : (uni() < 0.5 ? kInf : -kInf);
            case 6: {
                std::uint32_t bits = std::uint32_t(rng());
                float f;
                std::memcpy(&f, &bits, 4);
                return f;
            }
            default: return float(uni() * 4 - 1);
        }
    };
    auto any_double = [&]() -> double {
        if (uni() < 0.05) return std::nan("");
        if (uni() < 0.1) return std::pow(10.0, uni() * 40 - 20) * (uni() < 0.5 ? -1 : 1);
        return double(any_float());
    };
    const int n = int(std::strtol(std::getenv("DEFERRED_VALIDATION_CASES") ? std::getenv("DEFERRED_VALIDATION_CASES") : "20000", nullptr, 10));
    int accepted[5] = {0, 0, 0, 0, 0}, problems = 0;
    auto problem = [&](const std::string& what) {
        if (++problems <= 10) ADD_FAILURE() << what;
    };
    for (int i = 0; i < n; ++i) {
        // Materials.
        Material m;
        float* mf[] = {&m.base_color[0], &m.base_color[1], &m.base_color[2], &m.metallic, &m.roughness, &m.specular,
                       &m.specular_tint, &m.sheen, &m.sheen_tint, &m.clearcoat, &m.clearcoat_roughness,
                       &m.emission[0], &m.emission[1], &m.emission[2], &m.emission_strength, &m.alpha};
        for (float* f : mf) if (uni() < 0.3) *f = any_float();
        if (refusal([&] { validate_material(m); }).empty()) {
            ++accepted[0];
            // What reaches the G-buffer (RGBA16F) and the emission product.
            for (float v : {m.base_color[0], m.base_color[1], m.base_color[2], m.specular})
                if (!(v <= 65504.0f)) problem("accepted material overflows half floats");
            const float e = m.emission[0] * m.emission_strength;
            if (std::isnan(e)) problem("accepted material gives NaN emission");
        }
        // Lights.
        Light l;
        l.type = LightType(int(uni() * 4));
        l.shape = AreaShape(int(uni() * 4));
        float* lf[] = {&l.color[0], &l.color[1], &l.color[2], &l.energy, &l.radius, &l.spot_size, &l.spot_blend,
                       &l.angle, &l.size, &l.size_y};
        for (float* f : lf) if (uni() < 0.3) *f = any_float();
        for (double& v : l.matrix) if (uni() < 0.1) v = any_double();
        Light s;
        if (refusal([&] { s = sanitized_light(l); }).empty()) {
            ++accepted[1];
            // The packed light (light_module.cpp): strength S, radiance of a
            // sphere disk S / (4 pi^2 R^2), area radiance S / (4 A), all float.
            const double smax = std::abs(double(s.energy)) * std::max({double(s.color[0]), double(s.color[1]), double(s.color[2])});
            if (!float_finite(smax)) problem("accepted light: S not finite in float");
            if (s.radius > 0) {
                const float r2 = s.radius * s.radius;
                if (!(r2 > 0) || !std::isfinite(float(smax) / (4.0f * 9.8696f * r2)))
                    problem("accepted light: sphere radiance overflows (radius " + std::to_string(s.radius) + ")");
            }
            if (s.type == LightType::Area && s.size > 0) {
                const bool sep = s.shape == AreaShape::Rectangle || s.shape == AreaShape::Ellipse;
                const glm::dvec3 x(s.matrix[0], s.matrix[1], s.matrix[2]), y(s.matrix[4], s.matrix[5], s.matrix[6]);
                const double hx = 0.5 * s.size * glm::length(x), hy = 0.5 * (sep ? s.size_y : s.size) * glm::length(y);
                const double area_d = 4.0 * hx * hy;
                if (!float_finite(area_d)) problem("accepted area light: area overflows float");
                const float area = float_finite(area_d) ? float(area_d) : 0.0f;
                if (area > 0 && !std::isfinite(float(smax) / (4.0f * area)))
                    problem("accepted area light: radiance overflows (area " + std::to_string(area) + ")");
            }
            // Camera-relative position in float (camera anywhere within the contract).
            for (int k = 12; k < 15; ++k)
                if (!float_finite(s.matrix[std::size_t(k)] - 1e15)) problem("accepted light: relative position overflows");
        }
        // World.
        World w;
        for (float& c : w.color) if (uni() < 0.5) c = any_float();
        if (refusal([&] { validate_world(w); }).empty()) ++accepted[2];
        // Camera.
        Camera c;
        c.type = uni() < 0.5 ? CameraType::Perspective : CameraType::Orthographic;
        c.sensor_fit = SensorFit(int(uni() * 3));
        float* cf[] = {&c.lens, &c.sensor_width, &c.sensor_height, &c.shift_x, &c.shift_y, &c.clip_start,
                       &c.clip_end, &c.ortho_scale, &c.pixel_aspect_x, &c.pixel_aspect_y};
        for (float* f : cf) if (uni() < 0.2) *f = any_float();
        for (double& v : c.matrix) if (uni() < 0.05) v = any_double();
        const int width = uni() < 0.1 ? int(uni() * 3) - 1 : 1 + int(uni() * 16000);
        const int height = uni() < 0.1 ? int(uni() * 3) - 1 : 1 + int(uni() * 16000);
        CameraMatrices cm;
        if (refusal([&] { cm = build_camera(c, width, height); }).empty()) {
            ++accepted[3];
            const glm::dmat4 inv = glm::inverse(cm.projection);
            for (int a = 0; a < 4; ++a)
                for (int b = 0; b < 4; ++b)
                    if (!float_finite(cm.projection[a][b]) || !float_finite(inv[a][b]))
                        problem("accepted camera: projection not finite in float");
            if (!float_finite(cm.position.x) || !float_finite(cm.position.y) || !float_finite(cm.position.z))
                problem("accepted camera: position not finite in float");
        }
        // Meshes: exact-size heap arrays (ASan catches any over-read).
        const std::size_t nv = std::size_t(uni() * 6), nt = std::size_t(uni() * 5);
        auto pos = std::make_unique<float[]>(nv * 3 + 1);
        auto idx = std::make_unique<std::uint32_t[]>(nt * 3 + 1);
        auto nrm = std::make_unique<float[]>(nt * 9 + 1);
        auto uvs = std::make_unique<float[]>(nt * 6 + 1);
        auto mat = std::make_unique<std::int32_t[]>(nt + 1);
        for (std::size_t k = 0; k < nv * 3; ++k) pos[k] = uni() < 0.02 ? any_float() : float(uni() * 10 - 5);
        for (std::size_t k = 0; k < nt * 3; ++k) idx[k] = uni() < 0.05 ? std::uint32_t(rng()) : std::uint32_t(uni() * double(nv));
        for (std::size_t k = 0; k < nt * 9; ++k) nrm[k] = uni() < 0.02 ? any_float() : float(uni());
        for (std::size_t k = 0; k < nt * 6; ++k) uvs[k] = uni() < 0.02 ? any_float() : float(uni());
        for (std::size_t k = 0; k < nt; ++k) mat[k] = uni() < 0.05 ? std::int32_t(rng()) : std::int32_t(uni() * 3);
        MeshData md;
        md.positions = nv ? pos.get() : nullptr;
        md.vertex_count = nv;
        md.indices = nt ? idx.get() : nullptr;
        md.triangle_count = nt;
        md.corner_normals = uni() < 0.5 ? nrm.get() : nullptr;
        md.corner_uvs = uni() < 0.5 ? uvs.get() : nullptr;
        md.material_indices = uni() < 0.5 ? mat.get() : nullptr;
        std::int32_t max_mat = 0;
        if (refusal([&] { max_mat = validate_mesh(md); }).empty()) {
            ++accepted[4];
            for (std::size_t k = 0; k < nt * 3; ++k)
                if (idx[k] >= nv) problem("accepted mesh with an index out of range");
            if (max_mat < 0) problem("negative max material index");
        }
    }
    std::printf("validation fuzz: %d random inputs of each kind; accepted: materials %d, lights %d, worlds %d, "
                "cameras %d, meshes %d; problems %d\n",
                n, accepted[0], accepted[1], accepted[2], accepted[3], accepted[4], problems);
    EXPECT_EQ(problems, 0) << "seed " << seed;
    // The generator must reach both sides of every validator.
    for (int k = 0; k < 5; ++k) {
        EXPECT_GT(accepted[k], 0);
        EXPECT_LT(accepted[k], n);
    }
}
