// Randomised scenes through the native API (issue 7, "Process").
//
// Thousands of small random scenes (random meshes, instances, materials,
// lights, world, camera, passes; parameters drawn from both ordinary and
// extreme values) go through ONE Renderer (clear_scene() between scenes, so
// renderer reuse is exercised too), at tiny resolutions with 1-2 samples.
// Invariants, per scene:
//   - the library never crashes and only ever throws deferred::InvalidInput
//     (a GL error or any other exception fails the test);
//   - input inside the documented contract (README, "Hard cases and bad
//     input") is accepted; input outside it is refused with InvalidInput
//     (the generator knows which of its choices leave the contract);
//   - every pass of an accepted scene is finite (no NaN, no Inf).
//
// The base seed is printed; DEFERRED_FUZZ_SEED=<seed> reproduces a run and
// DEFERRED_FUZZ_SCENES=<n> sets the number of scenes (default 3000). Scene i
// uses seed + i, so one failing scene reruns alone with
// DEFERRED_FUZZ_SEED=<seed + i> DEFERRED_FUZZ_SCENES=1 (DEFERRED_FUZZ_VERBOSE=1
// prints every scene).
#include "robustness_helpers.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <vector>

using namespace deferred;
using namespace deferred::robustness;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// One random scene: the arrays it owns and the calls it makes.
class SceneGen {
public:
    explicit SceneGen(std::uint64_t seed) : rng_(seed) {}

    std::mt19937_64 rng_;
    std::ostringstream log;     // what was generated (printed on failure)
    bool invalid = false;       // some input is outside the documented contract
    std::string invalid_why;

    double uni(double a = 0, double b = 1) { return std::uniform_real_distribution<double>(a, b)(rng_); }
    int pick(int n) { return int(std::uniform_int_distribution<int>(0, n - 1)(rng_)); }
    bool chance(double p) { return uni() < p; }

    void mark_invalid(const std::string& why) {
        if (!invalid) invalid_why = why;
        invalid = true;
        log << " [INVALID: " << why << "]";
    }

    // A value in [lo, hi] that favours the end points and the extremes.
    float unit_param(float lo = 0, float hi = 1) {
        switch (pick(6)) {
            case 0: return lo;
            case 1: return hi;
            case 2: return lo + (hi - lo) * 1e-7f;
            case 3: return hi - (hi - lo) * 1e-7f;
            default: return float(uni(lo, hi));
        }
    }
    // Finite magnitude from tiny to huge (log-uniform), sometimes exactly 0.
    double magnitude(double lo_exp = -30, double hi_exp = 30) {
        if (chance(0.1)) return 0.0;
        return std::pow(10.0, uni(lo_exp, hi_exp));
    }
    // Rarely a non-finite value (then the input is invalid).
    float maybe_poison(float v, const char* what, double p = 0.004) {
        if (!chance(p)) return v;
        mark_invalid(std::string(what) + " non-finite");
        return chance(0.5) ? kNaN : (chance(0.5) ? kInf : -kInf);
    }

    Material material() {
        Material m;
        const int kind = pick(4);
        if (kind == 0) {  // ordinary
            m.base_color = {float(uni()), float(uni()), float(uni())};
            m.metallic = float(uni());
            m.roughness = float(uni());
        } else {          // every parameter at an end point or extreme
            const float c = chance(0.5) ? unit_param() : float(uni(0, 10));
            m.base_color = {c, unit_param(), unit_param()};
            m.metallic = unit_param();
            m.roughness = unit_param();
            m.specular = chance(0.2) ? float(uni(0, kMaxSpecular)) : unit_param();
            m.specular_tint = unit_param();
            m.sheen = chance(0.3) ? unit_param() : 0.0f;
            m.sheen_tint = unit_param();
            m.clearcoat = chance(0.3) ? unit_param() : 0.0f;
            m.clearcoat_roughness = unit_param();
            m.alpha = unit_param();
            if (chance(0.3)) {
                m.emission = {unit_param(), unit_param(), unit_param()};
                m.emission_strength = float(magnitude(-10, 38));
            }
        }
        m.pass_index = std::uint32_t(pick(1000));
        // Outside the contract.
        if (chance(0.005)) { m.roughness = -0.5f; mark_invalid("roughness < 0"); }
        if (chance(0.005)) { m.metallic = 1.5f; mark_invalid("metallic > 1"); }
        if (chance(0.005)) { m.specular = 12.5f + float(uni(0, 100)); mark_invalid("specular > max"); }
        if (chance(0.005)) { m.base_color[1] = -0.1f; mark_invalid("negative base colour"); }
        if (chance(0.005)) { m.base_color[2] = 1e6f; mark_invalid("base colour > half max"); }
        if (chance(0.005)) { m.emission_strength = -1.0f; mark_invalid("negative emission"); }
        m.roughness = maybe_poison(m.roughness, "roughness");
        m.base_color[0] = maybe_poison(m.base_color[0], "base_color");
        log << " mat(base " << m.base_color[0] << "," << m.base_color[1] << "," << m.base_color[2] << " m "
            << m.metallic << " r " << m.roughness << " s " << m.specular << " st " << m.specular_tint << " sh "
            << m.sheen << " cc " << m.clearcoat << "/" << m.clearcoat_roughness << " em " << m.emission[0] << "x"
            << m.emission_strength << ")";
        return m;
    }

    static constexpr float kMaxSpecular = 12.0f;

    struct Mesh {
        std::vector<float> positions, normals, uvs;
        std::vector<std::uint32_t> indices;
        std::vector<std::int32_t> material_indices;
        bool with_normals = false, with_uvs = false, with_mat = false;
        MeshData view() const {
            MeshData m;
            m.positions = positions.data();
            m.vertex_count = positions.size() / 3;
            m.indices = indices.data();
            m.triangle_count = indices.size() / 3;
            m.corner_normals = with_normals ? normals.data() : nullptr;
            m.corner_uvs = with_uvs ? uvs.data() : nullptr;
            m.material_indices = with_mat ? material_indices.data() : nullptr;
            return m;
        }
    };

    Mesh mesh(int slot_count) {
        Mesh m;
        const int kind = pick(8);
        const int nv = kind == 0 ? 0 : 3 + pick(10);
        const double size = chance(0.8) ? uni(0.1, 3) : magnitude(-12, 12);
        log << " mesh(kind " << kind << " nv " << nv << " size " << size;
        for (int i = 0; i < nv; ++i) {
            float p[3];
            for (float& c : p) c = float(uni(-size, size));
            if (kind == 1) p[2] = 0;                          // flat
            if (kind == 2) { p[1] = p[0] * 2; p[2] = p[0]; }  // collinear: zero-area triangles
            if (kind == 3 && i > 0) for (int k = 0; k < 3; ++k) p[k] = m.positions[k];  // one repeated point
            if (kind == 4) p[1] *= 1e-7f;                     // needle-thin
            m.positions.insert(m.positions.end(), p, p + 3);
        }
        if (!m.positions.empty()) m.positions[0] = maybe_poison(m.positions[0], "position");
        const int nt = nv == 0 ? (chance(0.9) ? 0 : 1) : 1 + pick(12);
        for (int t = 0; t < nt; ++t)
            for (int c = 0; c < 3; ++c) m.indices.push_back(nv ? std::uint32_t(pick(nv)) : 0u);
        if (nv == 0 && nt > 0) mark_invalid("indices without vertices");
        if (nv > 0 && chance(0.01)) {
            m.indices[std::size_t(pick(int(m.indices.size())))] = std::uint32_t(nv + pick(3));
            mark_invalid("index out of range");
        }
        m.with_normals = chance(0.7);
        if (m.with_normals) {
            const int nk = pick(5);
            for (int i = 0; i < nt * 3; ++i) {
                float n[3] = {float(uni(-1, 1)), float(uni(-1, 1)), float(uni(-1, 1))};
                if (nk == 0) n[0] = n[1] = n[2] = 0;        // zero-length normals
                if (nk == 1) { n[0] = n[1] = 0; n[2] = -1; }  // facing away
                if (nk == 2) for (float& c : n) c *= 1e-30f;  // denormal-ish
                if (nk == 3) for (float& c : n) c *= 1e30f;   // huge
                m.normals.insert(m.normals.end(), n, n + 3);
            }
            if (!m.normals.empty()) m.normals[0] = maybe_poison(m.normals[0], "normal");
            log << " normals " << nk;
        }
        m.with_uvs = chance(0.5);
        if (m.with_uvs) {
            const double uv_scale = magnitude(-5, 30);
            for (int i = 0; i < nt * 3 * 2; ++i) m.uvs.push_back(float(uni(-uv_scale, uv_scale)));
            if (!m.uvs.empty()) m.uvs[0] = maybe_poison(m.uvs[0], "uv");
        }
        m.with_mat = chance(0.4);
        if (m.with_mat) {
            for (int t = 0; t < nt; ++t) m.material_indices.push_back(pick(slot_count));
            if (nt > 0 && chance(0.02)) {
                m.material_indices[0] = chance(0.5) ? -1 : slot_count + pick(3);
                mark_invalid("material index out of range");
            }
        }
        log << " nt " << nt << ")";
        return m;
    }

    Mat4d matrix() {
        Mat4d m = identity_matrix();
        const int kind = pick(7);
        const double angle = uni(0, 6.3);
        m = rotation_z(angle);
        double s[3] = {1, 1, 1};
        if (kind == 1) s[0] = s[1] = s[2] = uni(0.1, 3);
        if (kind == 2) { s[0] = uni(-3, 3); s[1] = uni(0.01, 3); s[2] = -uni(0.01, 3); }  // non-uniform, mirrored
        if (kind == 3) s[pick(3)] = 0;                                               // degenerate
        if (kind == 4) s[0] = s[1] = s[2] = magnitude(-20, 10);
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) m[std::size_t(c * 4 + r)] *= s[c];
        if (kind == 5) {  // tilted: a rotation about X as well
            const double b = uni(0, 6.3);
            Mat4d rx = identity_matrix();
            rx[5] = std::cos(b); rx[6] = std::sin(b); rx[9] = -std::sin(b); rx[10] = std::cos(b);
            m = multiply(m, rx);
        }
        const double spread = chance(0.8) ? 2.0 : magnitude(-3, 7);
        m[12] = uni(-spread, spread);
        m[13] = uni(-spread, spread);
        m[14] = uni(-spread, spread);
        log << " M(kind " << kind << " t " << m[12] << "," << m[13] << "," << m[14] << ")";
        return m;
    }

    static Mat4d multiply(const Mat4d& a, const Mat4d& b) {
        Mat4d r{};
        for (int c = 0; c < 4; ++c)
            for (int row = 0; row < 4; ++row) {
                double s = 0;
                for (int k = 0; k < 4; ++k) s += a[std::size_t(k * 4 + row)] * b[std::size_t(c * 4 + k)];
                r[std::size_t(c * 4 + row)] = s;
            }
        return r;
    }

    // Shader variants are compiled per combination of light types present,
    // G-buffer features, passes, culling and shadows (thousands of
    // combinations, 1-2 s each to compile on llvmpipe the first time). So a
    // scene with lights has all four types (`carrier` lights that the light
    // module cannot drop come first), and passes come from two sets: a cold
    // run (no Mesa shader cache) stays within a few minutes, and every light
    // type, feature and pass is still exercised in every run.
    Light light(int carrier_type = -1) {
        Light l;
        l.type = carrier_type >= 0 ? LightType(carrier_type) : LightType(pick(4));
        l.matrix = matrix();
        if (chance(0.2)) { l.matrix[12] = l.matrix[13] = 0; l.matrix[14] = uni(-1e-3, 1e-3); }  // touching a surface
        l.color = {float(uni()), float(uni()), float(uni())};
        switch (pick(7)) {
            case 0: l.energy = 0; break;
            case 1: l.energy = -float(uni(0, 100)); break;        // negative (Blender allows it)
            case 2: l.energy = 1e9f; break;                      // huge
            case 3: l.energy = float(magnitude(-30, 12)); break;
            default: l.energy = float(uni(0, 1000)); break;
        }
        l.radius = chance(0.3) ? 0.0f : float(chance(0.5) ? uni(0, 2) : magnitude(-30, 4));
        l.spot_size = chance(0.2) ? (chance(0.5) ? 0.0f : float(M_PI)) : float(uni(0, M_PI));
        l.spot_blend = unit_param();
        l.angle = chance(0.2) ? (chance(0.5) ? 0.0f : float(M_PI)) : float(uni(0, M_PI));
        l.shape = AreaShape(pick(4));
        l.size = chance(0.2) ? 0.0f : float(chance(0.5) ? uni(0, 3) : magnitude(-20, 4));
        l.size_y = chance(0.2) ? 0.0f : float(chance(0.5) ? uni(0, 3) : magnitude(-20, 4));
        if (carrier_type >= 0) {  // never dropped by the light module (zero power or area)
            if (l.energy == 0) l.energy = 1e-3f;
            l.color[1] = std::max(l.color[1], 0.01f);
            l.size = std::max(l.size, 1e-3f);
            l.size_y = std::max(l.size_y, 1e-3f);
            l.matrix = rotation_z(uni(0, 6.3), uni(-2, 2), uni(-2, 2), uni(0.1, 3));
        }
        if (chance(0.004)) { l.radius = -1; mark_invalid("negative radius"); }
        if (chance(0.004)) { l.spot_size = 4; mark_invalid("spot_size > pi"); }
        if (chance(0.004)) { l.angle = 7; mark_invalid("sun angle > pi"); }
        l.cast_shadow = chance(0.7);
        l.energy = maybe_poison(l.energy, "energy", 0.002);
        log << " light(type " << int(l.type) << " E " << l.energy << " R " << l.radius << " spot " << l.spot_size
            << "/" << l.spot_blend << " angle " << l.angle << " shape " << int(l.shape) << " size " << l.size << "x"
            << l.size_y << " at " << l.matrix[12] << "," << l.matrix[13] << "," << l.matrix[14] << ")";
        return l;
    }

    Camera camera() {
        Camera c;
        c.type = chance(0.7) ? CameraType::Perspective : CameraType::Orthographic;
        const double dist = chance(0.8) ? uni(2, 20) : magnitude(-3, 6);
        const double eye[3] = {uni(-1, 1) * dist, uni(-1, 1) * dist, uni(0.2, 1) * dist};
        const double target[3] = {uni(-0.5, 0.5), uni(-0.5, 0.5), 0};
        c.matrix = tools::look_at(eye, target);
        if (chance(0.1)) {  // far from the origin, scene not
            c.matrix[12] += 1e5;
        }
        c.lens = chance(0.8) ? float(uni(10, 200)) : (chance(0.5) ? 1.0f : 5000.0f);
        c.sensor_fit = SensorFit(pick(3));
        c.shift_x = chance(0.8) ? 0.0f : float(uni(-2, 2));
        c.shift_y = chance(0.8) ? 0.0f : float(uni(-2, 2));
        c.clip_start = chance(0.5) ? 0.1f : float(chance(0.5) ? 1e-4 : 1e-6);
        c.clip_end = chance(0.5) ? 1000.0f : float(chance(0.5) ? 1e4 : 1e8);
        c.ortho_scale = float(chance(0.8) ? uni(0.5, 30) : magnitude(-3, 6));
        if (c.ortho_scale == 0) c.ortho_scale = 1;
        c.pixel_aspect_x = chance(0.8) ? 1.0f : float(uni(1, 200));
        c.pixel_aspect_y = chance(0.8) ? 1.0f : float(uni(1, 200));
        if (chance(0.01)) { c.clip_end = c.clip_start; mark_invalid("clip_end == clip_start"); }
        if (chance(0.01)) { c.lens = 0; mark_invalid("lens 0"); }
        log << " cam(type " << int(c.type) << " eye " << eye[0] << "," << eye[1] << "," << eye[2] << " lens "
            << c.lens << " clip " << c.clip_start << ".." << c.clip_end << " ortho " << c.ortho_scale << " shift "
            << c.shift_x << "," << c.shift_y << " aspect " << c.pixel_aspect_x << "/" << c.pixel_aspect_y << ")";
        return c;
    }

    RenderSettings settings() {
        RenderSettings s;
        const int kind = pick(10);
        s.width = kind == 0 ? 1 : kind == 1 ? 7 : 8;
        s.height = kind == 0 ? 1 : kind == 1 ? 3 : 8;
        s.samples = chance(0.8) ? 1 : 2;
        s.filter_width = chance(0.9) ? 1.5f : float(uni(0.01, 10));
        s.film_transparent = chance(0.3);
        if (chance(0.5))
            s.passes = all_passes();
        else
            s.passes = {Pass::Combined, Pass::Depth, Pass::Mist, Pass::Position, Pass::Normal, Pass::DiffCol,
                        Pass::GlossCol, Pass::Emit, Pass::Env};
        s.mist.start = float(uni(-5, 50));
        s.mist.depth = float(chance(0.9) ? uni(0.01, 100) : magnitude(-10, 10));
        s.mist.falloff = MistFalloff(pick(3));
        s.shadows = chance(0.7);
        const int shadow_sizes[] = {1, 16, 64, 256};
        s.shadow_resolution = shadow_sizes[pick(4)];
        s.light_culling = chance(0.7);
        const float thresholds[] = {0.0f, 1e-6f, 1e-3f, 0.1f, 10.0f};
        s.light_threshold = thresholds[pick(5)];
        s.visibility_buffer = chance(0.3);  // the G-buffer in compute (visibility_module.h)
        log << " settings(" << s.width << "x" << s.height << " spp " << s.samples << " passes " << s.passes.bits()
            << " shadows " << s.shadows << "/" << s.shadow_resolution << " culling " << s.light_culling << "/"
            << s.light_threshold << " visibility buffer " << s.visibility_buffer << ")";
        return s;
    }
};

struct Outcome {
    enum Kind { Rendered, Refused, NonFinite, WrongRefusal, AcceptedInvalid, OtherError } kind;
    std::string detail;
};

Outcome run_scene(Renderer& r, std::uint64_t seed, std::string* description, double* coverage = nullptr,
                  double* pixels = nullptr) {
    SceneGen g(seed);
    r.clear_scene();
    try {
        const int n_materials = 1 + g.pick(3);
        std::vector<std::uint32_t> mats;
        for (int i = 0; i < n_materials; ++i) mats.push_back(r.add_material(g.material()));
        const int n_meshes = 1 + g.pick(3);
        for (int i = 0; i < n_meshes; ++i) {
            SceneGen::Mesh m = g.mesh(n_materials);
            const std::uint32_t id = r.add_mesh(m.view());
            const int n_inst = g.pick(4);
            std::vector<double> matrices;
            std::vector<std::uint32_t> ids;
            for (int k = 0; k < n_inst; ++k) {
                Mat4d mm = g.matrix();
                if (g.chance(0.01)) {
                    mm[g.pick(16)] = g.chance(0.5) ? std::nan("") : HUGE_VAL;
                    g.mark_invalid("matrix non-finite");
                }
                matrices.insert(matrices.end(), mm.begin(), mm.end());
                ids.push_back(std::uint32_t(g.pick(100)));
            }
            std::vector<std::uint32_t> slots;
            if (g.chance(0.7)) slots = mats;  // else: empty map = every material in order
            r.add_instances(id, matrices.data(), std::size_t(n_inst), g.chance(0.5) ? ids.data() : nullptr, slots);
        }
        if (g.chance(0.5)) {  // a floor at z = 0 that lights can touch
            static const tools::MeshArrays floor = tools::make_plane(3.0f, 2);
            const std::uint32_t id = r.add_mesh(floor.view());
            const Mat4d I = identity_matrix();
            r.add_instances(id, I.data(), 1, nullptr, {mats[0]});
            g.log << " floor";
        }
        // None, a few (one of each type first), or >= 8 (the culled path).
        const int n_lights = g.chance(0.15) ? 0 : g.chance(0.8) ? 4 + g.pick(3) : 8 + g.pick(17);
        for (int i = 0; i < n_lights; ++i) {
            Light l = g.light(i < 4 ? i : -1);
            if (g.chance(0.3)) {  // on, just above or just below the floor
                const double heights[] = {0.0, 1e-7, -1e-7, 1e-4, -1e-4, 1e-2};
                l.matrix[14] = heights[g.pick(6)];
                l.matrix[12] = g.uni(-2, 2);
                l.matrix[13] = g.uni(-2, 2);
                g.log << " (moved to z " << l.matrix[14] << ")";
            }
            r.add_light(l);
        }
        World w;
        const int wk = g.pick(4);
        w.color = wk == 0 ? Vec3{0, 0, 0} : wk == 1 ? Vec3{1e4f, 1e4f, 1e4f} : Vec3{float(g.uni()), 0.05f, 0.05f};
        r.set_world(w);
        const Camera cam = g.camera();
        const RenderSettings s = g.settings();
        FrameResult f = r.render(cam, s);
        *description = g.log.str();
        if (g.invalid) return {Outcome::AcceptedInvalid, g.invalid_why};
        FiniteReport rep = check_finite(f);
        if (!rep.ok()) return {Outcome::NonFinite, std::to_string(rep.bad) + " values, first " + rep.first};
        if (coverage) {
            const PassImage& c = *f.find(Pass::Combined);
            for (std::size_t i = 3; i < c.pixels.size(); i += 4) *coverage += c.pixels[i] > 0 ? 1 : 0;
            *pixels += c.pixels.size() / 4;
        }
        if (g.chance(0.2)) {  // the same scene again at another size: targets reallocated, scene reused
            const RenderSettings s2 = g.settings();
            FrameResult f2 = r.render(cam, s2);
            *description = g.log.str();
            rep = check_finite(f2);
            if (!rep.ok()) return {Outcome::NonFinite, "second render: " + std::to_string(rep.bad) + " values, first " + rep.first};
        }
        return {Outcome::Rendered, ""};
    } catch (const InvalidInput& e) {
        *description = g.log.str();
        if (!g.invalid) return {Outcome::WrongRefusal, e.what()};
        return {Outcome::Refused, e.what()};
    } catch (const std::exception& e) {
        *description = g.log.str();
        return {Outcome::OtherError, e.what()};
    }
}

}  // namespace

TEST(Fuzz, ThousandsOfRandomSmallScenes) {
    const std::uint64_t seed = env_u64("DEFERRED_FUZZ_SEED", std::uint64_t(std::random_device{}()));
    const std::uint64_t scenes = env_u64("DEFERRED_FUZZ_SCENES", 3000);
    const bool verbose = env_u64("DEFERRED_FUZZ_VERBOSE", 0) != 0;
    std::printf("fuzz: seed %llu, %llu scenes (DEFERRED_FUZZ_SEED / DEFERRED_FUZZ_SCENES to override)\n",
                (unsigned long long)seed, (unsigned long long)scenes);
    std::fflush(stdout);
    Renderer r;
    std::map<int, int> counts;
    std::map<std::string, int> refusals;
    int failures = 0;
    double covered = 0, pixels = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (std::uint64_t i = 0; i < scenes; ++i) {
        std::string desc;
        const Outcome o = run_scene(r, seed + i, &desc, &covered, &pixels);
        counts[o.kind]++;
        if (verbose) std::printf("scene seed %llu: kind %d %s\n   %s\n", (unsigned long long)(seed + i), o.kind,
                                 o.detail.c_str(), desc.c_str());
        if (verbose && (i + 1) % 100 == 0)
            std::printf("fuzz: %llu scenes, %.1f s\n", (unsigned long long)(i + 1),
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        if (o.kind == Outcome::Refused) refusals[o.detail.substr(0, o.detail.find(':'))]++;
        if (o.kind != Outcome::Rendered && o.kind != Outcome::Refused) {
            ++failures;
            if (failures <= int(env_u64("DEFERRED_FUZZ_MAX_REPORTS", 20)))
                ADD_FAILURE() << "scene seed " << seed + i << " (rerun: DEFERRED_FUZZ_SEED=" << seed + i
                              << " DEFERRED_FUZZ_SCENES=1): "
                              << (o.kind == Outcome::NonFinite         ? "non-finite pass: "
                                  : o.kind == Outcome::WrongRefusal    ? "valid input refused: "
                                  : o.kind == Outcome::AcceptedInvalid ? "invalid input accepted: "
                                                                       : "unexpected error: ")
                              << o.detail << "\n  scene:" << desc;
        }
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("fuzz: %llu scenes in %.1f s: %d rendered finite, %d refused (InvalidInput), %d failures\n",
                (unsigned long long)scenes, secs, counts[Outcome::Rendered], counts[Outcome::Refused], failures);
    std::printf("fuzz: %.0f%% of the rendered pixels show geometry (the rest is background)\n",
                100.0 * covered / std::max(pixels, 1.0));
    for (auto& [what, n] : refusals) std::printf("  refused %4d x %s\n", n, what.c_str());
    EXPECT_EQ(failures, 0) << "seed " << seed;
}
