#include "shadow_module.h"

#include "../../shaders/shader_defines.h"

#include <deferred/renderer.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

namespace deferred {

namespace {

gpu::mat4 to_gpu_mat(const glm::dmat4& m) {
    gpu::mat4 r{};
    for (int c = 0; c < 4; ++c) r.cols[c] = {float(m[c][0]), float(m[c][1]), float(m[c][2]), float(m[c][3])};
    return r;
}

glm::dvec3 v3(const gpu::vec4& v) { return {v.x, v.y, v.z}; }

// The world's map is tested in every direction, grazing ones included,
// where the slope-scaled bias (up to 10 texels) hides occluders near the
// receiver: it gets 4x the texel density of the lights' maps (measured on
// the analytic scene against Cycles' AO pass, per object: at 1x our AO was
// up to 7.6 % too high, i.e. occlusion missed; at 4x within 1.2 %).
constexpr double kWorldQuality = 4.0;

// The most points receiver_points() keeps for one slice or volume.
constexpr std::size_t kMaxReceiverPoints = 1u << 20;

// The cube face basis of shadow_lib.glsl's cube_face(): forward F, right R, up U.
void face_basis(int face, glm::dvec3& F, glm::dvec3& R, glm::dvec3& U) {
    const int axis = face / 2;
    F = glm::dvec3(0.0);
    F[axis] = (face % 2 == 0) ? 1.0 : -1.0;
    const glm::dvec3 up = axis == 1 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
    R = glm::normalize(glm::cross(F, up));
    U = glm::cross(R, F);
}

// The cube faces' near plane (distance along the face's axis).
constexpr double kCubeNear = 1e-3;

// Camera-relative world -> clip for a (slightly wider than) 90 degree face from `origin`, reversed
// Z with an infinite far plane (depth = near / distance along F).
glm::dmat4 cube_face_matrix(int face, const glm::dvec3& origin) {
    glm::dvec3 F, R, U;
    face_basis(face, F, R, U);
    glm::dmat4 view(1.0);  // rows R, U, -F
    for (int c = 0; c < 3; ++c) {
        view[c][0] = R[c];
        view[c][1] = U[c];
        view[c][2] = -F[c];
    }
    view[3] = glm::dvec4(-glm::dot(R, origin), -glm::dot(U, origin), glm::dot(F, origin), 1.0);
    glm::dmat4 proj(0.0);
    proj[0][0] = 1.0 / SHADOW_CUBE_OVERLAP;
    proj[1][1] = 1.0 / SHADOW_CUBE_OVERLAP;
    proj[3][2] = kCubeNear;
    proj[2][3] = -1.0;
    return proj * view;
}

glm::dvec2 concentric_disk(double u1, double u2) {
    const double ox = 2 * u1 - 1, oy = 2 * u2 - 1;
    if (ox == 0 && oy == 0) return {0, 0};
    double r, t;
    if (std::abs(ox) > std::abs(oy)) { r = ox; t = M_PI / 4 * (oy / ox); }
    else { r = oy; t = M_PI / 2 - M_PI / 4 * (ox / oy); }
    return {r * std::cos(t), r * std::sin(t)};
}

// Where ortho_map's near plane lies along `axis`: casters up to max(far,
// 1 km) before the sphere.
double ortho_near(const glm::dvec3& axis, const glm::dvec3& center, double radius, double far) {
    return glm::dot(center, axis) - radius - std::max(far, 1000.0);
}

// Camera-relative world -> clip of an orthographic map along `axis` (the
// direction light travels) over the sphere (center, radius): x, y over the
// sphere, depth 1 nearest the light, with casters up to max(far, 1 km)
// beyond the sphere towards the light. `shift`: the texel grid moved by that
// fraction of a texel (of a map `resolution` texels wide) in x and y.
glm::dmat4 ortho_map(const glm::dvec3& axis, const glm::dvec3& center, double radius, double far,
                     const glm::dvec2& shift = glm::dvec2(0.0), int resolution = 1) {
    const glm::dvec3 R = glm::normalize(glm::cross(axis, std::abs(axis.z) < 0.999 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
    const glm::dvec3 U = glm::cross(R, axis);
    const double zmin = ortho_near(axis, center, radius, far), zmax = glm::dot(center, axis) + radius;
    glm::dmat4 m(0.0);  // rows: R/r, U/r, depth (1 nearest the light), w
    for (int c = 0; c < 3; ++c) {
        m[c][0] = R[c] / radius;
        m[c][1] = U[c] / radius;
        m[c][2] = -axis[c] / (zmax - zmin);
    }
    m[3][0] = -glm::dot(R, center) / radius + 2.0 * shift.x / resolution;
    m[3][1] = -glm::dot(U, center) / radius + 2.0 * shift.y / resolution;
    m[3][2] = zmax / (zmax - zmin);
    m[3][3] = 1.0;
    return m;
}

// Casters of a cube face from `origin`: spheres that reach into the face's
// frustum (tan <= SHADOW_CUBE_OVERLAP around F) within `reach`.
ShadowModule::CasterTest face_casters(int face, const glm::dvec3& origin, double reach) {
    glm::dvec3 F, R, U;
    face_basis(face, F, R, U);
    // Side planes of the frustum x <= k z: unit normal (1, -k)/sqrt(1 + k^2).
    const double k = SHADOW_CUBE_OVERLAP, inv = 1.0 / std::sqrt(1.0 + k * k);
    return [=](const glm::dvec3& c, double r) {
        const glm::dvec3 v = c - origin;
        const double z = glm::dot(v, F);
        if (z < -r || glm::length(v) - r > reach) return false;
        const double x = glm::dot(v, R), y = glm::dot(v, U);
        return (std::abs(x) - k * z) * inv <= r && (std::abs(y) - k * z) * inv <= r;
    };
}

// Casters of an orthographic map over the sphere (center, radius) along
// `axis`: spheres inside its square cross-section; `light_side_only`: only
// those before the sphere's far end along the axis (a one-sided map; the
// world's map keeps both sides).
ShadowModule::CasterTest ortho_casters(const glm::dvec3& axis, const glm::dvec3& center, double radius,
                                       bool light_side_only) {
    const glm::dvec3 R = glm::normalize(glm::cross(axis, std::abs(axis.z) < 0.999 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
    const glm::dvec3 U = glm::cross(R, axis);
    const double far_end = glm::dot(center, axis) + radius;
    return [=](const glm::dvec3& c, double r) {
        const glm::dvec3 v = c - center;
        if (std::abs(glm::dot(v, R)) > radius + r || std::abs(glm::dot(v, U)) > radius + r) return false;
        return !light_side_only || glm::dot(c, axis) - r <= far_end;
    };
}

// Casters of a sun's cascade whose shadow can fall on a lookup of its slice.
// A lookup at point Q reads the texel holding Q's place across the map,
// written by the casters covering that texel's centre before Q along the
// axis. Every Q lies within `reach` (metres, across the axis) of the
// slice's receivers, in the convex hull of `corners` (the slice's, or the
// receiver boxes' part of it: receiver_points), so its projection along the
// axis is within `reach` of the hull of the corners' projections; a caster
// (a sphere) whose projection keeps farther than that from it covers no
// texel any lookup reads. Nor does one that starts beyond every lookup's
// compared depth (`depth_reach` past the farthest corner): it can only be
// the stored depth where that depth is already lit. Each test is applied
// edge by edge, so the corners of the widened polygon are mitred: a few
// more casters are kept, never fewer. `square`: the map's own test.
ShadowModule::CasterTest slice_casters(const glm::dvec3& axis, const std::vector<glm::dvec3>& corners,
                                       double reach, double depth_reach, ShadowModule::CasterTest square) {
    // No lookup there (no receiver in the slice): no caster.
    if (corners.empty()) return [](const glm::dvec3&, double) { return false; };
    const glm::dvec3 R = glm::normalize(glm::cross(axis, std::abs(axis.z) < 0.999 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
    const glm::dvec3 U = glm::cross(R, axis);
    std::vector<glm::dvec2> across;
    across.reserve(corners.size());
    double far_end = -1e300;
    for (const glm::dvec3& c : corners) {
        across.emplace_back(glm::dot(c, R), glm::dot(c, U));
        far_end = std::max(far_end, glm::dot(c, axis));
    }
    far_end += depth_reach;
    const std::vector<glm::dvec2> hull = convex_hull(across);
    // Each edge's outward unit normal n and offset: outside by dot(n, q) - o.
    std::vector<glm::dvec3> edges;
    for (std::size_t i = 0; hull.size() >= 3 && i < hull.size(); ++i) {
        const glm::dvec2 e = hull[(i + 1) % hull.size()] - hull[i];
        const double len = glm::length(e);
        if (!(len > 0.0)) continue;
        const glm::dvec2 n(e.y / len, -e.x / len);
        edges.emplace_back(n.x, n.y, glm::dot(n, hull[i]) + reach);
    }
    return [=](const glm::dvec3& c, double r) {
        if (!square(c, r)) return false;
        if (glm::dot(c, axis) - r > far_end) return false;
        const glm::dvec2 q(glm::dot(c, R), glm::dot(c, U));
        for (const glm::dvec3& e : edges)
            if (e.x * q.x + e.y * q.y - e.z > r) return false;
        return true;
    };
}

// Casters of a cube face from `origin` whose shadow can reach a lookup of
// the view. A lookup at Q reads the texel holding Q's direction from the
// origin, written by the casters covering that texel's centre direction
// (at any distance: a caster beyond Q along it is still in the cone).
// Q lies within `lift` of the lookup volume (the convex hull of `corners`),
// and the centre direction within `spread` radians of Q's (the normal
// offset and half a texel's diagonal). So a caster counts only where its
// directions come within asin(lift / d) + spread of the cone the volume
// fills seen from the origin, d a lower bound of the origin's distance to
// the volume (`distance`); outside one of the cone's supporting planes by
// more than that, it covers no texel a lookup reads. Where the origin lies
// in the volume, or within `lift` of it, every caster counts. Planes are
// tested one at a time (mitred: a few more kept, never fewer). `face`: the
// face's own test.
ShadowModule::CasterTest cone_casters(const glm::dvec3& origin, const std::array<glm::dvec3, 8>& corners,
                                      double distance, double lift, double spread, ShadowModule::CasterTest face) {
    if (!(distance > lift)) return face;
    std::array<glm::dvec3, 8> w;
    for (std::size_t i = 0; i < 8; ++i) {
        const glm::dvec3 d = corners[i] - origin;
        const double len = glm::length(d);
        if (!(len > 0.0)) return face;
        w[i] = d / len;
    }
    // Outward unit normals of the planes through the origin and two
    // corners with every corner on one side.
    std::vector<glm::dvec3> planes;
    for (std::size_t i = 0; i < 8; ++i)
        for (std::size_t j = i + 1; j < 8; ++j) {
            glm::dvec3 n = glm::cross(w[i], w[j]);
            const double len = glm::length(n);
            if (!(len > 1e-12)) continue;
            n /= len;
            bool below = true, above = true;
            for (const glm::dvec3& v : w) {
                const double t = glm::dot(n, v);
                below = below && t <= 1e-12;
                above = above && t >= -1e-12;
            }
            if (above && !below) n = -n;
            if (above != below) planes.push_back(n);
        }
    if (planes.empty()) return face;
    const double margin = std::asin(std::min(lift / distance, 1.0)) + spread;
    return [=](const glm::dvec3& c, double r) {
        if (!face(c, r)) return false;
        const glm::dvec3 v = c - origin;
        const double dc = glm::length(v);
        if (dc <= r) return true;
        const double angle = std::asin(std::min(r / dc, 1.0)) + margin;
        if (angle >= M_PI / 2) return true;
        const double limit = std::sin(angle) * dc;
        for (const glm::dvec3& n : planes)
            if (glm::dot(n, v) > limit) return false;
        return true;
    };
}

// Where a light with a cube map shines. An area light lights only what lies
// in front of its plane (one-sided, light_lib.glsl); a spot only its cone
// (Cycles 3.4's spot_attenuation is 0 at and beyond cos = cos(spot_size / 2)),
// taken from any point of its disk of radius r, so every lit receiver lies
// in the cone from the centre widened by r, and the segment from a light
// point (within r of the centre) to it lies there too: the widened cone is
// convex (spot_size <= 180 degrees) and holds both ends. A caster outside
// the region therefore blocks no lit receiver: its texels are looked up by
// no receiver the light reaches (they get no light whatever the map says),
// and not rasterising it saves the fill, the stage a GPU is bound by here
// (bench/gpu/results: 14 Gpixel/s of depth on an H200).
//   clip: half-spaces dot(xyz, x) + w >= 0 (camera-relative world) the casters
//         are clipped to (geometry_vert.glsl gl_ClipDistance), (0, 0, 0, 1) unused;
//   cones: where the planes contain the light point itself (an area light's
//         plane, a spot without radius): unit g with dot(d, g) >= 0 for every
//         direction d that point lights, which bound each face's image
//         (face_image_bounds) and leave out faces it never looks through.
// `pad`: an angle every bound is widened by (two texels: a lit receiver's
// lookup lands within half a texel of its direction, and its nearest texel
// centre may lie just outside), `far`: the farthest receiver's distance.
struct LitRegion {
    std::array<glm::dvec4, SHADOW_CLIP_PLANES> clip;
    int planes = 0;  // clip[0, planes) are used (GL_CLIP_DISTANCEi enabled only for them)
    std::vector<glm::dvec3> cones;
};

// No bound: every plane keeps everything (points, mesh lights, cascades).
LitRegion everywhere() {
    LitRegion r;
    r.clip.fill(glm::dvec4(0.0, 0.0, 0.0, 1.0));
    return r;
}

LitRegion lit_region(const gpu::GpuLight& l, const glm::dvec3& p, double pad, double far) {
    LitRegion r = everywhere();
    const int type = int(l.position_type.w);
    if (type != LIGHT_AREA && type != LIGHT_SPOT) return r;
    const glm::dvec3 centre = v3(l.position_type), axis = glm::normalize(v3(l.direction));
    // Float precision of camera-relative positions (~1e-7 of the coordinates).
    const double eps = 1e-5 * (glm::length(centre) + 1.0);
    if (type == LIGHT_AREA) {
        // Widened by `pad` at the farthest receiver: a plane offset behind p.
        // A sheared light's points leave the plane through p normal to its
        // direction (its axes are the matrix's columns): each point lights
        // what lies in front of its own, so the plane moves back by the
        // light's depth along the direction, and bounds no face's image.
        const double depth = 2.0 * (std::abs(glm::dot(axis, v3(l.axis_x))) + std::abs(glm::dot(axis, v3(l.axis_y))));
        const double offset = eps + far * std::sin(pad) + depth;
        r.clip[0] = glm::dvec4(axis, -glm::dot(axis, p) + offset);
        r.planes = 1;
        if (depth <= eps) r.cones.push_back(axis);
    } else if (type == LIGHT_SPOT) {
        const double half = std::acos(std::clamp(double(l.direction.w), -1.0, 1.0));
        const double radius = std::max(double(l.strength.w), 0.0);
        const double wide = half + pad;
        if (wide < M_PI / 2 - 1e-3) {
            // The square pyramid around the cone: planes through the centre
            // with outward normals m = e cos - axis sin (e = +-t, +-b), a cone
            // direction u at angle phi <= wide from the axis has
            // dot(u, m) <= sin(phi - wide) <= 0; widened by the radius.
            const glm::dvec3 t = glm::normalize(glm::cross(axis, std::abs(axis.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
            const glm::dvec3 b = glm::cross(axis, t);
            const glm::dvec3 sides[4] = {t, -t, b, -b};
            for (int i = 0; i < 4; ++i) {
                const glm::dvec3 m = sides[i] * std::cos(wide) - axis * std::sin(wide);
                r.clip[std::size_t(i)] = glm::dvec4(-m, radius + eps + glm::dot(m, centre));
                if (radius == 0.0) r.cones.push_back(-(sides[i] * std::cos(half) - axis * std::sin(half)));
            }
            r.planes = 4;
        } else {
            // A cone of nearly 180 degrees: the half-space in front of it.
            r.clip[0] = glm::dvec4(axis, -glm::dot(axis, centre) + radius + eps + far * std::sin(pad));
            r.planes = 1;
            if (radius == 0.0) r.cones.push_back(axis);
        }
    }
    return r;
}

// The texels of a cube face (basis F, R, U; `resolution` texels a side) a
// light point looks through towards the directions `cones` allow, widened by
// `pad`: the scissor box {x, y, width, height}, width 0 where it looks
// through none. The face's image (x, y) in [-1, 1]^2 is the direction
// F + k x R + k y U (k = SHADOW_CUBE_OVERLAP); each cone bounds it by the
// half-plane dot(d, g) >= -sin(pad) |d|, with |d| <= sqrt(1 + 2 k^2).
std::array<int, 4> face_image_bounds(const glm::dvec3& F, const glm::dvec3& R, const glm::dvec3& U,
                                     const std::vector<glm::dvec3>& cones, double pad, int resolution) {
    const double k = SHADOW_CUBE_OVERLAP;
    std::vector<glm::dvec2> poly = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (const glm::dvec3& g : cones) {
        // a + b x + c y >= 0 (Sutherland-Hodgman against one half-plane).
        const double a = glm::dot(F, g) + std::sin(pad) * std::sqrt(1.0 + 2.0 * k * k);
        const double b = k * glm::dot(R, g), c = k * glm::dot(U, g);
        std::vector<glm::dvec2> out;
        for (std::size_t i = 0; i < poly.size(); ++i) {
            const glm::dvec2 &p0 = poly[i], &p1 = poly[(i + 1) % poly.size()];
            const double s0 = a + b * p0.x + c * p0.y, s1 = a + b * p1.x + c * p1.y;
            if (s0 >= 0) out.push_back(p0);
            if ((s0 >= 0) != (s1 >= 0)) out.push_back(p0 + (p1 - p0) * (s0 / (s0 - s1)));
        }
        poly.swap(out);
        if (poly.empty()) return {0, 0, 0, 0};
    }
    glm::dvec2 lo(1.0), hi(-1.0);
    for (const glm::dvec2& v : poly) {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
    }
    // Texel i covers x in [2 i / res - 1, 2 (i + 1) / res - 1]; one texel more each side.
    auto texel = [&](double x) { return (x + 1.0) * 0.5 * resolution; };
    const int x0 = std::clamp(int(std::floor(texel(lo.x))) - 1, 0, resolution);
    const int y0 = std::clamp(int(std::floor(texel(lo.y))) - 1, 0, resolution);
    const int x1 = std::clamp(int(std::ceil(texel(hi.x))) + 1, 0, resolution);
    const int y1 = std::clamp(int(std::ceil(texel(hi.y))) + 1, 0, resolution);
    if (x1 <= x0 || y1 <= y0) return {0, 0, 0, 0};
    return {x0, y0, x1 - x0, y1 - y0};
}

}  // namespace

void ShadowModule::begin_frame(const CameraMatrices& camera, int max_resolution, float quality,
                              std::size_t memory_budget, bool rays, bool count_fragments) {
    camera_ = camera;
    rays_ = rays;
    split_near_ = camera.clip_start;
    split_far_ = camera.clip_end;
    resolution_ = std::clamp(max_resolution, 32, 8192);
    quality_ = quality;
    budget_ = memory_budget;
    // DEFERRED_SHADOW_LIT_REGION=off draws every face whole (the tests'
    // reference for what lit_region leaves out).
    const char* lit = std::getenv("DEFERRED_SHADOW_LIT_REGION");
    lit_region_enabled_ = !(lit && std::string(lit) == "off");
    // DEFERRED_SHADOW_RECEIVER_CULLING=off: each cascade draws every caster
    // in its square (the tests' reference for what slice_casters leaves out).
    const char* receiver = std::getenv("DEFERRED_SHADOW_RECEIVER_CULLING");
    receiver_culling_enabled_ = !(receiver && std::string(receiver) == "off");
    // DEFERRED_DENSE_CASCADES=off: a sun's cascades take the receivers'
    // need alone, however dense the casters (the tests' reference).
    const char* dense = std::getenv("DEFERRED_DENSE_CASCADES");
    dense_cascades_enabled_ = !(dense && std::string(dense) == "off");
    by_vertex_enabled_ = draw_by_vertex_enabled();
    face_culling_enabled_ = face_culling_enabled();
    count_fragments_ = count_fragments &&
                       (epoxy_gl_version() >= 46 || epoxy_has_gl_extension("GL_ARB_pipeline_statistics_query"));
    entries_.clear();
    layers_ = 0;
    world_index_ = -1;
    world_count_ = 0;
}

void ShadowModule::offer_world(int maps) {
    // Offered before any light and kept in order by the stable sort of
    // allocate(): the world's maps get consecutive shadow indices.
    for (int k = 0; k < maps; ++k) {
        Entry e;
        e.world = true;
        e.priority = 1e300;
        e.light_index = std::size_t(-1);
        entries_.push_back(e);
    }
}

bool ShadowModule::offer(std::size_t light_index, const Light& light, const gpu::GpuLight& packed) {
    if (!light.cast_shadow || light.energy == 0.0f) return false;
    const bool sun = light.type == LightType::Sun;
    if (!sun) {
        // Only lights whose influence sphere reaches the view frustum.
        const double radius = packed.params.z;
        if (radius >= 0.0) {
            const glm::dvec3 c = glm::dmat3(camera_.view) * v3(packed.position_type);
            const double depth = -c.z;
            if (depth + radius < camera_.clip_start || depth - radius > camera_.clip_end) return false;
            const glm::dvec4& vp = camera_.viewplane;  // l r b t, in tan units (persp) or metres (ortho)
            auto side = [&](double lo, double hi, double x) {
                const double scale = camera_.orthographic ? 1.0 : std::max(depth, 0.0);
                return x + radius >= lo * scale - radius * 2.0 && x - radius <= hi * scale + radius * 2.0;
            };
            if (depth > 0 && (!side(vp.x, vp.y, c.x) || !side(vp.z, vp.w, c.y))) return false;
        }
    }
    Entry e;
    e.light = packed;
    e.sun = sun;
    e.light_index = light_index;
    e.fixed_point = light.type == LightType::Sun ? !(light.angle > 0.0f)
                                                 : light.type != LightType::Area && !(light.radius > 0.0f);
    const double S = std::abs(double(light.energy)) * std::max({light.color[0], light.color[1], light.color[2]});
    const double d2 = glm::dot(v3(packed.position_type), v3(packed.position_type));
    e.priority = sun ? 1e300 : S / std::max(d2, 1.0);
    entries_.push_back(e);
    return true;
}

bool ShadowModule::offer_mesh(std::size_t light_index, const gpu::GpuLight& packed, double power) {
    if (!(power > 0.0)) return false;
    Entry e;
    e.light = packed;
    e.light_index = light_index;
    e.fixed_point = false;
    const double d2 = glm::dot(v3(packed.position_type), v3(packed.position_type));
    e.priority = power / std::max(d2, 1.0);
    entries_.push_back(e);
    return true;
}

void ShadowModule::update_light(std::size_t light_index, const gpu::GpuLight& packed) {
    for (Entry& e : entries_)
        if (!e.world && e.light_index == light_index) e.light = packed;
}

std::vector<int> ShadowModule::allocate(std::size_t light_count) {
    std::vector<int> index(light_count, -1);
    dropped_ = 0;
    if (entries_.empty()) return index;
    GLint max_layers = 256;
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    std::stable_sort(entries_.begin(), entries_.end(),
                     [](const Entry& a, const Entry& b) { return a.priority > b.priority; });
    // Keep lights while their layers fit the array; lower the resolution (down
    // to 256) to fit the memory budget, then drop the least important.
    auto layers_of = [](const Entry& e) { return e.world ? 0 : e.sun ? SHADOW_CASCADE_COUNT : 6; };
    std::size_t kept = 0;
    layers_ = 0;
    if (rays_) {
        kept = entries_.size();  // no maps: nothing to fit
    } else {
        for (const Entry& e : entries_) {
            if (layers_ + layers_of(e) > max_layers) break;
            layers_ += layers_of(e);
            ++kept;
        }
        while (resolution_ > 256 && std::size_t(layers_) * resolution_ * resolution_ * 4 > budget_) resolution_ /= 2;
        while (kept > 0 && std::size_t(layers_) * resolution_ * resolution_ * 4 > budget_)
            layers_ -= layers_of(entries_[--kept]);
    }
    dropped_ = entries_.size() - kept;
    entries_.resize(kept);
    int layer = 0;
    for (std::size_t i = 0; i < entries_.size(); ++i) {
        entries_[i].first_layer = layer;
        layer += layers_of(entries_[i]);
        if (entries_[i].world) {
            if (world_index_ < 0) world_index_ = int(i);
            ++world_count_;
        } else {
            index[entries_[i].light_index] = int(i);
        }
    }
    return index;
}

std::pair<double, double> ShadowModule::slice_depths(const Cascades& cs, int k) const {
    // A float view depth against the double splits: 1e-4 of slack each side.
    const double near = k == 0 ? lookups_.depths.x : cs.split[k] * (1.0 - 1e-4);
    const double far = k == SHADOW_CASCADE_COUNT - 1 ? lookups_.depths.y : cs.split[k + 1] * (1.0 + 1e-4);
    return {near, std::max(far, near)};
}

std::array<glm::dvec3, 8> ShadowModule::slice_corners(const Cascades& cs, int k) const {
    const auto [near, far] = slice_depths(cs, k);
    return lookup_corners(near, far);
}

std::vector<glm::dvec3> ShadowModule::receiver_points(double near, double far) const {
    // In view space (x right, y up, depth -z): the volume's six half-spaces
    // and its corners (frustum_corners' order: depth, then x, then y).
    const glm::dmat3 to_view(camera_.view), from_view = glm::transpose(to_view);
    const glm::dvec4& vp = lookups_.viewplane;
    std::vector<HalfSpace> volume = {{{0, 0, 1}, -near}, {{0, 0, -1}, far}};
    if (camera_.orthographic) {
        volume.push_back({{-1, 0, 0}, -vp.x});
        volume.push_back({{1, 0, 0}, vp.y});
        volume.push_back({{0, -1, 0}, -vp.z});
        volume.push_back({{0, 1, 0}, vp.w});
    } else {
        // x >= l d with d = -z: -x - l z <= 0, and so on.
        volume.push_back({{-1, 0, -vp.x}, 0.0});
        volume.push_back({{1, 0, vp.y}, 0.0});
        volume.push_back({{0, -1, -vp.z}, 0.0});
        volume.push_back({{0, 1, vp.w}, 0.0});
    }
    std::array<glm::dvec3, 8> corners;
    std::size_t ci = 0;
    for (double depth : {near, far})
        for (double x : {vp.x, vp.y})
            for (double y : {vp.z, vp.w}) {
                const double s = camera_.orthographic ? 1.0 : depth;
                corners[ci++] = glm::dvec3(x * s, y * s, -depth);
            }
    std::vector<glm::dvec3> points;
    for (const Box& b : lookups_.boxes) {
        Box v;
        v.center = to_view * b.center;
        for (std::size_t i = 0; i < 3; ++i) v.half[i] = to_view * b.half[i];
        const std::size_t before = points.size();
        box_in_volume(v, volume, corners, points);
        for (std::size_t i = before; i < points.size(); ++i) points[i] = from_view * points[i];
        // Memory and each sample's hull stay bounded (a million points,
        // 24 MB): past that, the volume's own corners.
        if (points.size() > kMaxReceiverPoints) {
            const std::array<glm::dvec3, 8> whole = lookup_corners(near, far);
            return {whole.begin(), whole.end()};
        }
    }
    return points;
}

double ShadowModule::lookup_distance(const glm::dvec3& p) const {
    // The largest of its signed distances to the volume's six planes (view
    // space: the camera's rotation only), at most its distance to the volume.
    const glm::dvec3 v = glm::dmat3(camera_.view) * p;
    const double d = -v.z;
    const glm::dvec4& vp = lookups_.viewplane;
    double out = std::max(lookups_.depths.x - d, d - lookups_.depths.y);
    if (camera_.orthographic)
        return std::max({out, vp.x - v.x, v.x - vp.y, vp.z - v.y, v.y - vp.w});
    // Side planes x = l d (and the others): unit normals (1, 0, l) / sqrt(1 + l^2)...
    return std::max({out, (vp.x * d - v.x) / std::sqrt(1.0 + vp.x * vp.x),
                     (v.x - vp.y * d) / std::sqrt(1.0 + vp.y * vp.y),
                     (vp.z * d - v.y) / std::sqrt(1.0 + vp.z * vp.z),
                     (v.y - vp.w * d) / std::sqrt(1.0 + vp.w * vp.w)});
}

std::array<glm::dvec3, 8> ShadowModule::lookup_corners(double near, double far) const {
    return frustum_corners(lookups_.viewplane, near, far);
}

std::array<glm::dvec3, 8> ShadowModule::frustum_corners(const glm::dvec4& vp, double near, double far) const {
    std::array<glm::dvec3, 8> corners;
    std::size_t ci = 0;
    for (double depth : {near, far})
        for (double x : {vp.x, vp.y})
            for (double y : {vp.z, vp.w}) {
                const double s = camera_.orthographic ? 1.0 : depth;
                corners[ci++] = camera_.rotation * glm::dvec3(x * s, y * s, -depth);
            }
    return corners;
}

ShadowModule::Cascades ShadowModule::cascades() const {
    Cascades c{};
    // Practical split scheme (Zhang et al. 2006), lambda 0.75, over the
    // depths the view sees (fit).
    const double n = split_near_, f = split_far_;
    for (int k = 0; k <= SHADOW_CASCADE_COUNT; ++k) {
        const double t = double(k) / SHADOW_CASCADE_COUNT;
        c.split[k] = 0.75 * n * std::pow(f / n, t) + 0.25 * (n + (f - n) * t);
    }
    for (int k = 0; k < SHADOW_CASCADE_COUNT; ++k) {
        // Bounding sphere of the frustum slice (camera-relative).
        const std::array<glm::dvec3, 8> corners = frustum_corners(camera_.viewplane, c.split[k], c.split[k + 1]);
        glm::dvec3 center(0.0);
        for (auto& p : corners) center += p / 8.0;
        double radius = 0;
        for (auto& p : corners) radius = std::max(radius, glm::length(p - center));
        c.center[k] = center;
        c.radius[k] = radius * 1.02;
    }
    return c;
}

void ShadowModule::fit(const std::vector<Receiver>& receivers, std::pair<double, double> visible_depths,
                       const LookupVolume* lookups, const CasterTriangles& caster_triangles) {
    lookups_known_ = lookups != nullptr && receiver_culling_enabled_;
    if (lookups) lookups_ = *lookups;
    if (entries_.empty()) return;
    split_near_ = camera_.clip_start;
    split_far_ = camera_.clip_end;
    auto [near, far] = visible_depths;
    if (far > near && near > 0.0) {
        // A margin for what later, jittered samples see beyond sample 0's
        // pixel centres (up to the filter's reach across an edge): 5 % of
        // the range and 1 % of the depth each side. A pixel beyond the last
        // cascade would find no map (lit), before the first the same.
        const double margin = 0.05 * (far - near);
        split_near_ = std::max(camera_.clip_start, near * 0.99 - margin);
        split_far_ = std::min(camera_.clip_end, far * 1.01 + margin);
        if (!(split_far_ > split_near_)) {
            split_near_ = camera_.clip_start;
            split_far_ = camera_.clip_end;
        }
    }
    const Cascades cs = cascades();
    layers_rendered_ = 0;
    texels_rendered_ = 0;
    receiver_points_known_ = lookups_known_ && !lookups_.boxes.empty() && !rays_;
    for (auto& points : slice_points_) points.clear();
    volume_points_.clear();
    if (receiver_points_known_) {
        const bool sun = std::any_of(entries_.begin(), entries_.end(), [](const Entry& e) { return e.sun; });
        const bool world = std::any_of(entries_.begin(), entries_.end(), [](const Entry& e) { return e.world; });
        for (int k = 0; sun && k < SHADOW_CASCADE_COUNT; ++k) {
            const auto [near_k, far_k] = slice_depths(cs, k);
            slice_points_[std::size_t(k)] = receiver_points(near_k, far_k);
        }
        if (world) volume_points_ = receiver_points(lookups_.depths.x, lookups_.depths.y);
    }
    receivers_center_ = glm::dvec3(0.0);
    receivers_radius_ = 0.0;
    for (const Receiver& p : receivers) receivers_center_ += p.position / double(receivers.size());
    for (const Receiver& p : receivers)
        receivers_radius_ = std::max(receivers_radius_, glm::length(p.position - receivers_center_));
    receivers_radius_ = std::max(receivers_radius_ * 1.02, 1e-3);
    std::vector<double> need;
    need.reserve(receivers.size());
    int array_resolution = 32;
    for (Entry& e : entries_) {
        need.clear();
        const gpu::GpuLight& l = e.light;
        if (e.world) {
            // One map over the receivers' bounding sphere.
            for (const Receiver& p : receivers) need.push_back(kWorldQuality * quality_ * 2.0 * receivers_radius_ / p.footprint);
        } else if (e.sun) {
            // A cascade of radius r spans 2r over `resolution` texels.
            for (const Receiver& p : receivers) {
                int k = 0;
                while (k < SHADOW_CASCADE_COUNT - 1 && p.depth > cs.split[k + 1]) ++k;
                need.push_back(quality_ * 2.0 * cs.radius[k] / p.footprint);
            }
        } else {
            // A cube face's texel at distance d from the light spans
            // d * 2 * overlap / resolution (at the face's centre).
            const glm::dvec3 lp = v3(l.position_type);
            const double reach = l.params.z >= 0.0f ? double(l.params.z) : 1e300;
            const bool area = int(l.position_type.w) == LIGHT_AREA;
            for (const Receiver& p : receivers) {
                const glm::dvec3 v = p.position - lp;
                const double d = glm::length(v);
                if (d > reach || (area && glm::dot(v, v3(l.direction)) <= 0.0)) continue;
                need.push_back(quality_ * 2.0 * SHADOW_CUBE_OVERLAP * d / p.footprint);
            }
        }
        double r = 32.0;
        if (!need.empty()) {
            const std::size_t k = std::min(need.size() - 1, need.size() * 9 / 10);
            std::nth_element(need.begin(), need.begin() + long(k), need.end());
            r = need[k];
        }
        if (e.sun && caster_triangles && dense_cascades_enabled_ && !need.empty()) {
            // Dense casters: up to one texel per triangle of the fullest
            // cascade (fit() in shadow_module.h), at most kDenseCascades
            // times the need.
            const glm::dvec3 axis = glm::normalize(v3(l.direction));
            std::uint64_t most = 0;
            for (int k = 0; k < SHADOW_CASCADE_COUNT; ++k)
                most = std::max(most, caster_triangles(ortho_casters(axis, cs.center[k], cs.radius[k], true)));
            r = std::clamp(std::sqrt(double(most)), r, kDenseCascades * r);
        }
        e.resolution = std::clamp(int(std::ceil(std::min(r, 1e6) / 32.0)) * 32, 32, resolution_);
        e.rendered = false;
        if (rays_) continue;  // no maps
        if (e.world) {
            if (e.resolution != world_allocated_ || world_count_ != world_layers_) {
                GLuint id = 0;
                glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &id);
                world_map_ = Texture(id);
                glTextureStorage3D(id, 1, GL_RG32F, e.resolution, e.resolution, world_count_);
                glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
                glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
                glTextureParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
                glTextureParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
                GLuint fbo = 0;
                glCreateFramebuffers(1, &fbo);
                world_fbo_ = Framebuffer(fbo);
                world_allocated_ = e.resolution;
                world_layers_ = world_count_;
            }
            continue;
        }
        array_resolution = std::max(array_resolution, e.resolution);
    }
    resolution_ = array_resolution;
    if (rays_) {
        bytes_ = 0;
        shadow_buffer_ = make_storage_buffer(nullptr, entries_.size() * sizeof(gpu::GpuShadow), "shadows");
        return;
    }
    bytes_ = (layers_ > 0 ? (std::size_t(layers_) + 1) * resolution_ * resolution_ * 4 : 0) +
              std::size_t(world_allocated_) * world_allocated_ * 8 * std::size_t(world_layers_);
    if (layers_ > 0 && (layers_ != allocated_layers_ || resolution_ != allocated_resolution_)) {
        GLuint id = 0;
        glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &id);
        maps_ = Texture(id);
        glTextureStorage3D(id, 1, GL_R32F, resolution_, resolution_, layers_);
        glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTextureParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTextureParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        depth_ = make_texture_2d(GL_DEPTH_COMPONENT32F, resolution_, resolution_, "shadow depth");
        GLuint fbo = 0;
        glCreateFramebuffers(1, &fbo);
        fbo_ = Framebuffer(fbo);
        glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth_.get(), 0);
        allocated_layers_ = layers_;
        allocated_resolution_ = resolution_;
        check_gl("allocating shadow maps");
    }
    shadow_buffer_ = make_storage_buffer(nullptr, entries_.size() * sizeof(gpu::GpuShadow), "shadows");
}

std::vector<int> ShadowModule::resolutions() const {
    std::vector<int> r;
    for (const Entry& e : entries_)
        if (!e.world) r.push_back(e.resolution);
    return r;
}

void ShadowModule::render_sample(ShaderLibrary& shaders, const std::array<float, 2>& u,
                                 const std::array<float, 2>& grid, const std::vector<glm::dvec4>& world_dirs,
                                 const DrawCasters& draw_casters, const std::vector<std::string>& caster_defines,
                                 bool casters_vary) {
    // Orthographic maps drawn again this sample move their texel grid by a
    // new fraction of a texel: an edge's position in a map is quantised to
    // its texels, and moving the grid over the samples averages that out (a
    // 1-texel box filter instead of a fixed staircase; Suzanne under a 1
    // degree sun against Cycles, shadow quality 1: see README).
    // Maps drawn once (a light without size) keep an unshifted grid. The
    // shifted ones span a texel more, so no receiver leaves the map.
    const glm::dvec2 shift(double(grid[0]) - 0.5, double(grid[1]) - 0.5);
    auto padded = [](double radius, int resolution) { return radius * (1.0 + 2.0 / double(resolution)); };
    if (entries_.empty()) return;
    // Opaque casters are drawn by vertex and, where closed, front faces only
    // (draw_style.h); partly transparent ones (SCENE_ALPHA: each triangle
    // kept by chance, seen through) need every corner's triangle and both
    // sides. Where the scene has both, the opaque ones keep the plain
    // program and the transparent constant materials' slots take
    // `alpha_program` (GeometryStage::draw_casters): with SCENE_ALPHA every
    // fragment of every caster ran its discard test, the transparency
    // sample's floor among them (its maps 2.3x as slow on llvmpipe).
    const bool alpha = std::find(caster_defines.begin(), caster_defines.end(), "SCENE_ALPHA") != caster_defines.end();
    const bool apart = alpha && alpha_apart_enabled();
    ShaderVariant variant, alpha_variant;
    for (const std::string& d : caster_defines)
        if (!apart || d != "SCENE_ALPHA") variant.defines.push_back(d);
    variant.defines.push_back("SHADOW_PASS");
    alpha_variant = variant;
    alpha_variant.defines.push_back("SCENE_ALPHA");
    DrawStyle style;
    style.by_vertex = by_vertex_enabled_ && !(alpha && !apart);
    style.cull_faces = face_culling_enabled_ && !(alpha && !apart);
    if (style.by_vertex) variant.defines.push_back("INDEXED_DRAW");
    GLuint alpha_program = 0;
    if (!rays_) {
        const GLuint program = shaders.graphics_program("geometry_vert.glsl", "shadow_frag.glsl", variant);
        if (apart) alpha_program = shaders.graphics_program("geometry_vert.glsl", "shadow_frag.glsl", alpha_variant);
        glUseProgram(program);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_GREATER);
        glDepthMask(GL_TRUE);
        glDisable(GL_CULL_FACE);
    }

    std::vector<gpu::GpuShadow> shadows(entries_.size());
    const LitRegion unbounded = everywhere();
    // A layer: cleared over the light's corner (`whole`), drawn inside
    // `scissor` (nothing where it is empty). Texels outside the scissor read
    // as unoccluded, not as an earlier sample's map: a receiver the light
    // reaches looks them up only where the shadow test moves its point
    // (the terminator offset) across the lit region's edge, where the
    // light is about 0 (an area light's plane) or a spot's cone ends.
    auto draw_layer = [&](int layer, const glm::dmat4& view_projection, const glm::dvec3& origin, int kind,
                          const glm::dvec3& axis, const CasterTest& casts, const std::array<int, 4>& whole,
                          const std::array<int, 4>& scissor, const LitRegion& region, const FaceCulling& faces) {
        if (rays_) return;
        glNamedFramebufferTextureLayer(fbo_.get(), GL_COLOR_ATTACHMENT0, maps_.get(), 0, layer);
        const GLenum draw = GL_COLOR_ATTACHMENT0;
        glNamedFramebufferDrawBuffers(fbo_.get(), 1, &draw);
        const float far_away[4] = {3.0e38f, 0, 0, 0};
        const float depth_far = 0.0f;
        glScissor(whole[0], whole[1], whole[2], whole[3]);
        glClearNamedFramebufferfv(fbo_.get(), GL_COLOR, 0, far_away);
        if (scissor[2] <= 0 || scissor[3] <= 0) return;
        glScissor(scissor[0], scissor[1], scissor[2], scissor[3]);
        glClearNamedFramebufferfv(fbo_.get(), GL_DEPTH, 0, &depth_far);
        texels_rendered_ += std::uint64_t(scissor[2]) * std::uint64_t(scissor[3]);
        float clip[4 * SHADOW_CLIP_PLANES];
        for (int i = 0; i < SHADOW_CLIP_PLANES; ++i)
            for (int c = 0; c < 4; ++c) clip[4 * i + c] = float(region.clip[std::size_t(i)][c]);
        glUniform4fv(LOC_SHADOW_CLIP, SHADOW_CLIP_PLANES, clip);
        // Only the planes in use: llvmpipe clips every triangle of a draw
        // with any clip distance enabled (the shadow stage took ~25 % longer
        // for 800k triangles with four unused planes on).
        for (int i = 0; i < SHADOW_CLIP_PLANES; ++i) {
            if (i < region.planes) glEnable(GL_CLIP_DISTANCE0 + GLenum(i));
            else glDisable(GL_CLIP_DISTANCE0 + GLenum(i));
        }
        const gpu::mat4 m = to_gpu_mat(view_projection);
        glUniformMatrix4fv(2, 1, GL_FALSE, &m.cols[0].x);
        glUniform4f(3, float(origin.x), float(origin.y), float(origin.z), float(kind));
        glUniform3f(4, float(axis.x), float(axis.y), float(axis.z));
        begin_fragment_count();
        draw_casters(casts, false, style, style.cull_faces ? &faces : nullptr, alpha_program);
        end_fragment_count();
        ++layers_rendered_;
    };

    if (!rays_) glEnable(GL_SCISSOR_TEST);
    const Cascades cs = cascades();
    const std::array<glm::dvec3, 8> view_corners = lookup_corners(lookups_.depths.x, lookups_.depths.y);
    std::vector<glm::dvec3> world_axes(std::size_t(world_count_), glm::dvec3(0.0));
    std::vector<glm::dmat4> world_matrices(std::size_t(world_count_), glm::dmat4(0.0));
    for (std::size_t i = 0; i < entries_.size(); ++i) {
        Entry& e = entries_[i];
        gpu::GpuShadow& g = shadows[i];
        const gpu::GpuLight& l = e.light;
        // Maps of a light without size are the same every sample (unless
        // transparent casters are drawn stochastically): keep them.
        const bool draw = !(e.fixed_point && e.rendered && !casters_vary);
        e.rendered = true;
        if (!rays_) glViewport(0, 0, e.resolution, e.resolution);
        const std::array<int, 4> whole = {0, 0, e.resolution, e.resolution};  // only the corner in use
        const float uv_scale = float(e.resolution) / float(resolution_);
        if (e.world) {
            // This sample's k-th direction of the world (the map also
            // answers for the opposite one); light from it travels along
            // `axis`. Layer k of the world's array, the pair's density in params.z.
            const std::size_t k = i - std::size_t(world_index_);
            const glm::dvec4 d = k < world_dirs.size() ? world_dirs[k] : glm::dvec4(0.0, 0.0, 1.0, 0.5 / M_PI);
            const glm::dvec3 axis = -glm::dvec3(d);
            const glm::dmat4 m = ortho_map(axis, receivers_center_, padded(receivers_radius_, e.resolution),
                                           camera_.clip_end, shift, e.resolution);
            g.cascade[0] = to_gpu_mat(m);
            g.point = {float(axis.x), float(axis.y), float(axis.z), float(k)};
            g.params = {float(SHADOW_WORLD), float(e.resolution), float(d.w), 1.0f};
            world_axes[k] = axis;
            world_matrices[k] = m;
            continue;
        }
        if (e.sun) {
            // The same point of the sun's disk the lighting uses this sample.
            glm::dvec3 axis = glm::normalize(v3(l.direction));
            const double tan_r = std::tan(double(l.strength.w));
            if (tan_r > 0) {
                glm::dvec3 t = glm::normalize(glm::cross(std::abs(axis.z) < 0.999 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0), -axis));
                glm::dvec3 b = glm::cross(-axis, t);
                const glm::dvec2 d = concentric_disk(u[0], u[1]) * tan_r;
                axis = -glm::normalize(-axis + t * d.x + b * d.y);
            }
            for (int k = 0; k < SHADOW_CASCADE_COUNT; ++k) {
                const bool shifted = !(e.fixed_point && !casters_vary);
                const glm::dmat4 m =
                    shifted ? ortho_map(axis, cs.center[k], padded(cs.radius[k], e.resolution), camera_.clip_end,
                                        shift, e.resolution)
                            : ortho_map(axis, cs.center[k], cs.radius[k], camera_.clip_end);
                g.cascade[k] = to_gpu_mat(m);
                FaceCulling faces;
                faces.perspective = false;
                faces.axis = axis;
                faces.near = ortho_near(axis, cs.center[k], shifted ? padded(cs.radius[k], e.resolution) : cs.radius[k],
                                        camera_.clip_end);
                faces.facing_ccw = facing_is_ccw(m, cs.center[k], -axis);
                if (draw) {
                    CasterTest casts = ortho_casters(axis, cs.center[k], cs.radius[k], true);
                    if (lookups_known_) {
                        // Along the axis, the plane's depth at a texel's
                        // centre can lie 0.71 texel / SHADOW_PLANE_MIN_COS
                        // beyond the lookup's point, the slope bias 10
                        // texels before it.
                        const double texel = 2.0 * (shifted ? padded(cs.radius[k], e.resolution) : cs.radius[k]) /
                                             double(e.resolution);
                        const double slack = 1e-5 * (glm::length(cs.center[k]) + cs.radius[k]);
                        const double depth_reach = lookups_.lift + (3.0 + 1.0 / SHADOW_PLANE_MIN_COS) * texel + slack;
                        // Both branches lvalues: the points are not copied.
                        const std::array<glm::dvec3, 8> corners = slice_corners(cs, k);
                        const std::vector<glm::dvec3> whole_slice =
                            receiver_points_known_ ? std::vector<glm::dvec3>()
                                                   : std::vector<glm::dvec3>(corners.begin(), corners.end());
                        casts = slice_casters(axis,
                                              receiver_points_known_ ? slice_points_[std::size_t(k)] : whole_slice,
                                              lookup_reach(texel, slack), depth_reach, casts);
                    }
                    draw_layer(e.first_layer + k, m, glm::dvec3(0.0), SHADOW_CASCADES, axis, casts, whole, whole,
                               unbounded, faces);
                }
            }
            g.point = {float(axis.x), float(axis.y), float(axis.z), float(e.first_layer)};
            g.params = {float(SHADOW_CASCADES), float(e.resolution), 0.0f, uv_scale};
            g.cascade_split = {float(cs.split[1]), float(cs.split[2]), float(cs.split[3]), float(cs.split[4])};
        } else {
            // This sample's point on the light. Area lights: uniform on the
            // surface. Sphere lights: Cycles samples a disk facing each
            // shading point; a face of the cube sees receivers around its
            // axis, so each face uses the point of the disk perpendicular to
            // that axis (the same disk coordinates for all six faces).
            glm::dvec3 p = v3(l.position_type);
            glm::dvec2 disk(0.0);
            const int type = int(l.position_type.w);
            if (type == LIGHT_MESH) {
                p = v3(l.axis_x);  // the sample's shared point on the emitting surface
            } else if (type == LIGHT_AREA) {
                const glm::dvec2 xy = int(l.axis_y.w) == AREA_ELLIPSE ? concentric_disk(u[0], u[1])
                                                                      : glm::dvec2(2 * u[0] - 1, 2 * u[1] - 1);
                p += v3(l.axis_x) * xy.x + v3(l.axis_y) * xy.y;
            } else if (l.strength.w > 0) {
                disk = concentric_disk(u[0], u[1]) * double(l.strength.w);
            }
            // A caster between the light and a receiver it reaches is nearer
            // than the receiver: nothing beyond the influence radius casts.
            const double reach = l.params.z >= 0.0f ? double(l.params.z) : 1e300;
            // Only where the light shines (lit_region): two texels' angle
            // (at a face's centre) of margin, out to the farthest receiver.
            const double pad = 4.0 * SHADOW_CUBE_OVERLAP / e.resolution;
            const double far = std::min(glm::length(p - receivers_center_) + receivers_radius_, reach);
            const LitRegion region = lit_region_enabled_ ? lit_region(l, p, pad, far) : unbounded;
            for (int face = 0; face < 6 && draw; ++face) {
                glm::dvec3 F, R, U;
                face_basis(face, F, R, U);
                const glm::dvec3 pf = p + R * disk.x + U * disk.y;
                // Faces no lit direction passes through are only cleared.
                const std::array<int, 4> scissor = face_image_bounds(F, R, U, region.cones, pad, e.resolution);
                const glm::dmat4 m = cube_face_matrix(face, pf);
                // Nothing within the near plane's corners (< 2 near) of pf is clipped.
                FaceCulling faces;
                faces.origin = pf;
                faces.near = 2.0 * kCubeNear;
                faces.facing_ccw = facing_is_ccw(m, pf + F, -F);
                CasterTest casts = face_casters(face, pf, reach);
                if (lookups_known_) {
                    // Directions: 1.5 texels of normal offset (shadow_lib.glsl's
                    // Pb) and 0.71 to the texel's centre, rounded up to 3,
                    // a texel spanning at most 2 overlap / resolution radians.
                    const double slack = 1e-5 * (glm::length(pf) + 1.0);
                    casts = cone_casters(pf, view_corners, lookup_distance(pf), lookups_.lift + slack,
                                         3.0 * 2.0 * SHADOW_CUBE_OVERLAP / e.resolution, casts);
                }
                draw_layer(e.first_layer + face, m, pf, SHADOW_CUBE, glm::dvec3(0.0), casts, whole, scissor, region,
                           faces);
            }
            g.point = {float(p.x), float(p.y), float(p.z), float(e.first_layer)};
            g.params = {float(SHADOW_CUBE), float(e.resolution), float(2.0 * SHADOW_CUBE_OVERLAP / e.resolution),
                        uv_scale};
            // A mesh light's own surface within 2 % of its size around the
            // point is not a shadow (shadow_lib.glsl).
            const float near_ignore = type == LIGHT_MESH ? 0.02f * l.direction.w : 0.0f;
            g.cascade_split = {float(disk.x), float(disk.y), near_ignore, 0.0f};
        }
    }
    glNamedBufferSubData(shadow_buffer_.get(), 0, GLsizeiptr(shadows.size() * sizeof(gpu::GpuShadow)), shadows.data());
    if (rays_) {
        check_gl("shadow entries");
        return;
    }
    glDisable(GL_SCISSOR_TEST);
    for (int i = 0; i < SHADOW_CLIP_PLANES; ++i) glDisable(GL_CLIP_DISTANCE0 + GLenum(i));
    if (world_index_ >= 0) {
        // Nearest and farthest geometry along the axis in one pass: MAX
        // blending of (-depth, depth), no depth test; depth clamping keeps
        // casters beyond the map's depth range (the far side serves the
        // opposite direction), the stored value is the exact depth anyway.
        ShaderVariant world_variant = variant, world_alpha_variant = alpha_variant;
        world_variant.defines.push_back("WORLD_MAP");
        world_alpha_variant.defines.push_back("WORLD_MAP");
        const GLuint world_program = shaders.graphics_program("geometry_vert.glsl", "shadow_frag.glsl", world_variant);
        const GLuint world_alpha_program =
            apart ? shaders.graphics_program("geometry_vert.glsl", "shadow_frag.glsl", world_alpha_variant) : 0;
        glBindFramebuffer(GL_FRAMEBUFFER, world_fbo_.get());
        glViewport(0, 0, world_allocated_, world_allocated_);
        glDisable(GL_DEPTH_TEST);
        glEnable(GL_DEPTH_CLAMP);
        glEnable(GL_BLEND);
        glBlendEquation(GL_MAX);
        for (int k = 0; k < world_count_; ++k) {
            glUseProgram(world_program);  // draw_casters may leave another bound
            glNamedFramebufferTextureLayer(world_fbo_.get(), GL_COLOR_ATTACHMENT0, world_map_.get(), 0, k);
            const float lowest[4] = {-3.0e38f, -3.0e38f, 0, 0};
            glClearNamedFramebufferfv(world_fbo_.get(), GL_COLOR, 0, lowest);
            const gpu::mat4 m = to_gpu_mat(world_matrices[std::size_t(k)]);
            const glm::dvec3& axis = world_axes[std::size_t(k)];
            glUniformMatrix4fv(2, 1, GL_FALSE, &m.cols[0].x);
            glUniform4f(3, 0.0f, 0.0f, 0.0f, float(SHADOW_CASCADES));
            glUniform3f(4, float(axis.x), float(axis.y), float(axis.z));
            // Both sides: the map keeps the farthest surface too. Casters
            // whose projection keeps clear of the whole lookup volume's
            // are read by no lookup (slice_casters, without its depth
            // test: the far side serves the opposite direction).
            CasterTest casts = ortho_casters(axis, receivers_center_, receivers_radius_, false);
            if (lookups_known_) {
                const double texel = 2.0 * padded(receivers_radius_, world_allocated_) / double(world_allocated_);
                const double slack = 1e-5 * (glm::length(receivers_center_) + receivers_radius_);
                const std::array<glm::dvec3, 8> corners = lookup_corners(lookups_.depths.x, lookups_.depths.y);
                const std::vector<glm::dvec3> whole_volume =
                    receiver_points_known_ ? std::vector<glm::dvec3>()
                                           : std::vector<glm::dvec3>(corners.begin(), corners.end());
                casts = slice_casters(axis, receiver_points_known_ ? volume_points_ : whole_volume,
                                      lookup_reach(texel, slack), 1e300, casts);
            }
            begin_fragment_count();
            draw_casters(casts, true, style, nullptr, world_alpha_program);
            end_fragment_count();
            ++layers_rendered_;
            texels_rendered_ += std::uint64_t(world_allocated_) * std::uint64_t(world_allocated_);
        }
        glDisable(GL_BLEND);
        glDisable(GL_DEPTH_CLAMP);
        glBlendEquation(GL_FUNC_ADD);
        glEnable(GL_DEPTH_TEST);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("shadow maps");
}

// Around each layer's draws only: a driver may clear a scissored region by
// drawing it (llvmpipe does), which the statistic would count too.
void ShadowModule::begin_fragment_count() {
    if (!count_fragments_) return;
    query_active_ = true;
    if (free_queries_.empty()) {
        free_queries_.emplace_back();
        glGenQueries(1, &free_queries_.back());
    }
    fragment_queries_.push_back(free_queries_.back());
    free_queries_.pop_back();
    glBeginQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB, fragment_queries_.back());
}

void ShadowModule::end_fragment_count() {
    if (!query_active_) return;
    glEndQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB);
    query_active_ = false;
}

void ShadowModule::abandon_frame() {
    end_fragment_count();
    free_queries_.insert(free_queries_.end(), fragment_queries_.begin(), fragment_queries_.end());
    fragment_queries_.clear();
    for (int i = 0; i < SHADOW_CLIP_PLANES; ++i) glDisable(GL_CLIP_DISTANCE0 + GLenum(i));
}

std::uint64_t ShadowModule::collect_fragments() {
    std::uint64_t sum = 0;
    for (GLuint q : fragment_queries_) {
        GLuint64 n = 0;
        glGetQueryObjectui64v(q, GL_QUERY_RESULT, &n);
        sum += n;
        free_queries_.push_back(q);
    }
    fragment_queries_.clear();
    return sum;
}

void ShadowModule::bind() const {
    if (entries_.empty()) return;
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_SHADOWS, shadow_buffer_.get());
    if (rays_) return;
    glBindTextureUnit(TEX_SHADOW_MAPS, maps_.get());
    if (world_index_ >= 0) glBindTextureUnit(TEX_WORLD_MAP, world_map_.get());
}

}  // namespace deferred
