/* Shadow lookups (maps rendered by shadow_frag.glsl, one set per film
 * sample, from this sample's point on the light; see ShadowModule).
 *
 * Soft shadows converge by sampling: each film sample renders the maps from
 * a new point on the light (sphere lights: per cube face, a point of the
 * disk perpendicular to the face's axis, which is the disk Cycles samples
 * for receivers on that axis; area lights: uniform on the surface; sun: the
 * same point of its disk the lighting uses), and the sample's unshadowed light is multiplied by that
 * point's visibility. Averaged over samples this is the light's unshadowed
 * integral times the fraction of the light's area that is visible, which is
 * Cycles' result when the light's contribution varies little across it
 * (the usual case; at grazing distances from large lights it is a bias).
 *
 * The comparison (receiver_plane_depth): a map stores, per texel, the
 * nearest caster's depth at the texel's centre. The receiver is compared
 * by the depth its own plane (through P, true normal Ng: the triangle
 * itself) has at that same centre (Isidoro 2006, "Shadow Mapping: GPU-based
 * Tips and Techniques": receiver plane depth bias), so a triangle never
 * shadows itself and the bias left is SHADOW_PLANE_BIAS texels: contact
 * shadows reach to a fraction of a texel of their caster. Where the plane
 * nearly contains the ray (|cos| < SHADOW_PLANE_MIN_COS) the old bias
 * stands: a normal offset of 1.5 texels x sin(theta) plus a slope-scaled
 * depth bias of 1 + 2 tan(theta) texels clamped at 10.
 *
 * Before the comparison the receiver moves by Cycles' shadow terminator
 * offset (shadow_ray_origin): smooth-shaded low-poly meshes shadow
 * themselves as Cycles' shadow rays do, with the object's Geometry Offset. */

/* Cycles 3.4's shadow_ray_offset (kernel/light/sample.h): the shadow ray's
 * origin for light direction L: P lifted by the terminator offset (the
 * G-buffer's, full amount) scaled by how close L is to the terminator,
 * offset_cutoff being the object's Geometry Offset:
 *   NL = |Ns.L|, NgL = Ng.L (Ng flipped to L's side when Ns.L < 0),
 *   amount = NL < cutoff ? clamp(2 - (NgL + NL) / cutoff) : clamp(1 - NgL / cutoff). */
vec3 shadow_ray_origin(SurfaceParams s, vec3 P, vec3 L) {
    if (!(s.terminator_cutoff > 0.0) || s.terminator == vec3(0.0)) return P;
    /* Cycles' sd->N: the interpolated normal, not a closure's bent one. */
    float NL = dot(s.Ns, L);
    vec3 Ng = NL < 0.0 ? -s.Ng : s.Ng;
    NL = abs(NL);
    float NgL = dot(Ng, L);
    float cutoff = s.terminator_cutoff;
    float amount = NL < cutoff ? clamp(2.0 - (NgL + NL) / cutoff, 0.0, 1.0) : clamp(1.0 - NgL / cutoff, 0.0, 1.0);
    return P + s.terminator * amount;
}

layout(std430, binding = SSBO_SHADOWS) readonly buffer Shadows { GpuShadow shadows[]; };

#ifdef SHADOW_RAYS
/* Shadow rays (settings.shadow_rays): visibility traced against the scene's
 * triangles (ray_lib.glsl) instead of looked up in maps; the lights' and
 * the world's sample directions are those the maps would use, so both
 * methods estimate the same integral, the rays without a map's resolution. */
#include "ray_lib.glsl"

/* Float precision around a camera-relative point: the depth buffer's
 * positions and the triangles' are good to about 1e-6 of their coordinates. */
float shadow_ray_epsilon(vec3 X) {
    return 2e-5 * max(max(abs(X.x), abs(X.y)), max(abs(X.z), 1e-2));
}

/* The light passing from surface point P (surface s) along unit L to the
 * point at distance `dist` (< 0: unbounded, a direction): the ray starts at
 * Cycles' shadow terminator origin, lifted off its own surface by
 * shadow_ray_epsilon, and (bounded) aims from there at the end point and
 * stops shadow_ray_epsilon short of it, as Cycles re-aims a shadow ray from
 * its offset origin (keeping the direction would cross a plane containing
 * the end point, such as an emitter's own triangle, up to eps / cos before
 * its end). */
float shadow_ray(SurfaceParams s, vec3 P, vec3 L, float dist) {
    vec3 O = shadow_ray_origin(s, P, L);
    vec3 Ng = dot(s.Ng, L) < 0.0 ? -s.Ng : s.Ng;
    O += Ng * shadow_ray_epsilon(O);
    vec3 dir = L;
    float tmax = 1e30;
    if (dist >= 0.0) {
        vec3 X = P + L * dist;
        vec3 D = X - O;
        float len = length(D);
        tmax = len - shadow_ray_epsilon(X);
        if (!(tmax > 0.0)) return 1.0;
        dir = D / len;
    }
    /* One call site: the traversal is inlined wherever this is. */
    return ray_transmittance(O, dir, tmax);
}

#ifdef HAS_WORLD_OCCLUSION
/* 1 where P sees the world along u = -side * axis, 0 where geometry blocks
 * it (the map-based version below). */
float world_visibility(GpuShadow sh, vec3 P, SurfaceParams s, float side) {
    return shadow_ray(s, P, -sh.point.xyz * side, -1.0);
}
#endif

#else /* shadow maps */

/* A cube face's ray from the light point `origin` along `dir`: the
 * parameter t where it meets the receiver's own plane (through P, normal
 * Ng), with ok = false where the plane nearly contains the ray or lies
 * behind the light point. */
float receiver_plane_hit(vec3 P, vec3 Ng, vec3 origin, vec3 dir, out bool ok) {
    float c = dot(dir, Ng);
    float t = dot(P - origin, Ng) / c;
    ok = abs(c) >= SHADOW_PLANE_MIN_COS * length(dir) && t > 0.0 && !isinf(t) && !isnan(t);
    return t;
}

layout(binding = TEX_SHADOW_MAPS) uniform sampler2DArray shadow_maps;

/* The cube face of direction v (+X -X +Y -Y +Z -Z) and its basis: forward F,
 * right R, up U, as ShadowModule builds the face's view matrix. */
int cube_face(vec3 v, out vec3 F, out vec3 R, out vec3 U) {
    vec3 a = abs(v);
    int face;
    if (a.x >= a.y && a.x >= a.z) { face = v.x >= 0.0 ? 0 : 1; F = vec3(v.x >= 0.0 ? 1.0 : -1.0, 0.0, 0.0); }
    else if (a.y >= a.z) { face = v.y >= 0.0 ? 2 : 3; F = vec3(0.0, v.y >= 0.0 ? 1.0 : -1.0, 0.0); }
    else { face = v.z >= 0.0 ? 4 : 5; F = vec3(0.0, 0.0, v.z >= 0.0 ? 1.0 : -1.0); }
    vec3 up = abs(F.y) > 0.5 ? vec3(0.0, 0.0, 1.0) : vec3(0.0, 1.0, 0.0);
    R = normalize(cross(F, up));
    U = cross(R, F);
    return face;
}

float shadow_bias_scale(vec3 N, vec3 L, out float sin_t) {
    float cos_t = clamp(dot(N, L), 1e-3, 1.0);
    sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    return min(1.0 + 2.0 * sin_t / cos_t, 10.0);
}

/* A map's [0, 1]^2 coordinates -> the array layer's: the light's maps fill
 * the lower-left resolution^2 corner (params.y texels, params.w of the
 * layer); the last texel is clamped so nearest filtering stays inside. */
vec2 shadow_map_uv(GpuShadow sh, vec2 uv) {
    return clamp(uv, vec2(0.0), vec2(1.0 - 0.5 / sh.params.y)) * sh.params.w;
}

/* An orthographic map (rows r0, r1 of its matrix; light travelling along
 * `axis`): the depth along the axis that the receiver's own plane (through
 * P, normal Ng) has on the line through the centre of the texel holding uv
 * (uv = 0.5 (r.X + m[3]) + 0.5), with ok = false where the plane nearly
 * contains the axis. */
float ortho_plane_depth(vec3 P, vec3 Ng, vec3 axis, vec3 r0, vec3 r1, vec2 uv, float res, out bool ok) {
    vec2 centre = (floor(uv * res) + 0.5) / res;
    vec3 line = P + r0 * (2.0 * (centre.x - uv.x) / dot(r0, r0)) + r1 * (2.0 * (centre.y - uv.y) / dot(r1, r1));
    float c = dot(axis, Ng);
    ok = abs(c) >= SHADOW_PLANE_MIN_COS;
    return dot(line, axis) + (ok ? dot(P - line, Ng) / c : 0.0);
}

/* Orthographic map `m` (layer first + offset) along sh.point.xyz, the
 * direction the light travels: a sun cascade or the world's map. */
float ortho_visibility(GpuShadow sh, mat4 m, int offset, vec3 P, SurfaceParams s) {
    vec3 axis = sh.point.xyz;
    float res = sh.params.y;
    vec3 r0 = vec3(m[0][0], m[1][0], m[2][0]), r1 = vec3(m[0][1], m[1][1], m[2][1]);
    float texel = 2.0 / (length(r0) * res);
    P = shadow_ray_origin(s, P, -axis);
    vec4 clip = m * vec4(P, 1.0);
    vec2 uv = clip.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;
    float stored = texture(shadow_maps, vec3(shadow_map_uv(sh, uv), sh.point.w + float(offset))).r;
    bool ok;
    float d = ortho_plane_depth(P, s.Ng, axis, r0, r1, uv, res, ok);
    if (ok) return d - SHADOW_PLANE_BIAS * texel <= stored ? 1.0 : 0.0;
    float sin_t;
    float slope = shadow_bias_scale(s.N, -axis, sin_t);
    vec3 Pb = P + s.N * (1.5 * texel * sin_t);
    stored = texture(shadow_maps, vec3(shadow_map_uv(sh, (m * vec4(Pb, 1.0)).xy * 0.5 + 0.5),
                                       sh.point.w + float(offset))).r;
    return dot(Pb, axis) - slope * texel <= stored ? 1.0 : 0.0;
}

#ifdef HAS_WORLD_OCCLUSION
layout(binding = TEX_WORLD_MAP) uniform sampler2DArray world_map; /* layer: the map's point.w */

/* 1 where P (surface s) sees the world along u = -side * axis (side +1: where
 * the map looks from, -1: the opposite direction), 0 where geometry blocks
 * it. The map holds (-nearest, farthest) depth along the axis. */
float world_visibility(GpuShadow sh, vec3 P, SurfaceParams s, float side) {
    vec3 axis = sh.point.xyz;
    mat4 m = sh.cascade[0];
    float res = sh.params.y;
    vec3 r0 = vec3(m[0][0], m[1][0], m[2][0]), r1 = vec3(m[0][1], m[1][1], m[2][1]);
    float texel = 2.0 / (length(r0) * res);
    P = shadow_ray_origin(s, P, -axis * side);
    vec4 clip = m * vec4(P, 1.0);
    vec2 uv = clip.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;
    vec2 stored = texture(world_map, vec3(shadow_map_uv(sh, uv), sh.point.w)).rg;
    /* The plane's depth along the axis at the texel's centre (either side). */
    bool ok;
    float d = ortho_plane_depth(P, s.Ng, axis, r0, r1, uv, res, ok);
    if (ok) {
        float bias = SHADOW_PLANE_BIAS * texel;
        return side > 0.0 ? (d - bias <= -stored.r ? 1.0 : 0.0) : (d + bias >= stored.g ? 1.0 : 0.0);
    }
    float sin_t;
    float slope = shadow_bias_scale(s.N, -axis * side, sin_t);
    vec3 Pb = P + s.N * (1.5 * texel * sin_t);
    stored = texture(world_map, vec3(shadow_map_uv(sh, (m * vec4(Pb, 1.0)).xy * 0.5 + 0.5), sh.point.w)).rg;
    d = dot(Pb, axis);
    return side > 0.0 ? (d - slope * texel <= -stored.r ? 1.0 : 0.0) : (d + slope * texel >= stored.g ? 1.0 : 0.0);
}
#endif

/* 1 where this sample's light point sees P (surface s), 0 in shadow. */
/* `kind` the light's (light_lib.glsl's light kinds; negative: read from the
 * map): a sun's maps are cascades, every other light's a cube, so a literal
 * kind leaves the other lookup out of the caller's code. */
float shadow_visibility_kind(int kind, int index, vec3 P, SurfaceParams s) {
    GpuShadow sh = shadows[index];
    if (kind < 0 ? int(sh.params.x) == SHADOW_CASCADES : kind == LIGHT_SUN) {
        float d = frame_view_depth(P);
        int c = d <= sh.cascade_split.x ? 0 : d <= sh.cascade_split.y ? 1 : d <= sh.cascade_split.z ? 2 : 3;
        return ortho_visibility(sh, sh.cascade[c], c, P, s);
    }
    /* The face from the light's centre; its light point is on the disk
     * perpendicular to the face's axis (sh.cascade_split.xy, see ShadowModule). */
    vec3 F, R, U;
    int face = cube_face(P - sh.point.xyz, F, R, U);
    vec3 light_point = sh.point.xyz + R * sh.cascade_split.x + U * sh.cascade_split.y;
    /* Near a face border P may lie in the next face as seen from this face's
     * point: switch once (faces also overlap by SHADOW_CUBE_OVERLAP). */
    vec3 F2, R2, U2;
    int face2 = cube_face(P - light_point, F2, R2, U2);
    if (face2 != face) {
        face = face2;
        F = F2;
        R = R2;
        U = U2;
        light_point = sh.point.xyz + R * sh.cascade_split.x + U * sh.cascade_split.y;
    }
    vec3 v = P - light_point;
    float dist = length(v);
    /* A light point below the receiver's horizon: the unshadowed term already
     * left that part of the light out (horizon clipping), and the receiver's
     * own surface is no shadow; only occlusion by other geometry counts. */
    if (dist <= 0.0 || dot(s.N, v) >= 0.0) return 1.0;
    P = shadow_ray_origin(s, P, -v / dist);
    v = P - light_point;
    dist = length(v);
    float texel = dist * sh.params.z;
    float res = sh.params.y;
    float fwd = max(dot(v, F), 1e-20);
    vec2 uv = vec2(dot(v, R), dot(v, U)) / (fwd * SHADOW_CUBE_OVERLAP) * 0.5 + 0.5;
    float stored = texture(shadow_maps, vec3(shadow_map_uv(sh, uv), sh.point.w + float(face))).r;
    /* An emissive mesh's point lies on its own surface, which curves away
     * from it: the texels around its tangent plane see that surface at
     * almost no distance. Occluders nearer than cascade_split.z (a fraction
     * of the emitter's size; 0 for lights) are that surface, not a shadow. */
    if (stored < sh.cascade_split.z) return 1.0;
    /* The ray through the texel's centre, and the receiver's plane on it. */
    vec2 centre = (floor(uv * res) + 0.5) / res;
    vec2 xy = (2.0 * centre - 1.0) * SHADOW_CUBE_OVERLAP;
    vec3 dir = F + R * xy.x + U * xy.y;
    bool ok;
    float t = receiver_plane_hit(P, s.Ng, light_point, dir, ok);
    if (ok) return t * length(dir) - SHADOW_PLANE_BIAS * texel <= stored ? 1.0 : 0.0;
    float sin_t;
    float slope = shadow_bias_scale(s.N, -v / dist, sin_t);
    vec3 Pb = P + s.N * (1.5 * texel * sin_t);
    vec3 vb = Pb - light_point;
    fwd = max(dot(vb, F), 1e-20);
    uv = vec2(dot(vb, R), dot(vb, U)) / (fwd * SHADOW_CUBE_OVERLAP) * 0.5 + 0.5;
    stored = texture(shadow_maps, vec3(shadow_map_uv(sh, uv), sh.point.w + float(face))).r;
    return (length(vb) - slope * texel <= stored || stored < sh.cascade_split.z) ? 1.0 : 0.0;
}

float shadow_visibility(int index, vec3 P, SurfaceParams s) { return shadow_visibility_kind(-1, index, P, s); }
#endif /* SHADOW_RAYS */
