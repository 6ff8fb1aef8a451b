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
 * Bias, in shadow-map texels at the receiver's distance: normal offset of
 * 1.5 texels scaled by sin(theta) (theta between the normal and the light),
 * plus a slope-scaled depth bias of 1 + 2 tan(theta) texels clamped at 10. */

layout(std430, binding = SSBO_SHADOWS) readonly buffer Shadows { GpuShadow shadows[]; };
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

/* Orthographic map `m` (layer first + offset) along sh.point.xyz, the
 * direction the light travels: a sun cascade or the world's map. */
float ortho_visibility(GpuShadow sh, mat4 m, int offset, vec3 P, vec3 N) {
    vec3 axis = sh.point.xyz;
    float texel = 2.0 / (length(vec3(m[0][0], m[1][0], m[2][0])) * sh.params.y);
    float sin_t;
    float slope = shadow_bias_scale(N, -axis, sin_t);
    vec3 Pb = P + N * (1.5 * texel * sin_t);
    vec4 clip = m * vec4(Pb, 1.0);
    vec2 uv = clip.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;
    float stored = texture(shadow_maps, vec3(shadow_map_uv(sh, uv), sh.point.w + float(offset))).r;
    return dot(Pb, axis) - slope * texel <= stored ? 1.0 : 0.0;
}

#ifdef HAS_WORLD_OCCLUSION
layout(binding = TEX_WORLD_MAP) uniform sampler2DArray world_map; /* layer: the map's point.w */

/* 1 where P (normal N) sees the world along u = -side * axis (side +1: where
 * the map looks from, -1: the opposite direction), 0 where geometry blocks
 * it. The map holds (-nearest, farthest) depth along the axis. */
float world_visibility(GpuShadow sh, vec3 P, vec3 N, float side) {
    vec3 axis = sh.point.xyz;
    mat4 m = sh.cascade[0];
    float texel = 2.0 / (length(vec3(m[0][0], m[1][0], m[2][0])) * sh.params.y);
    float sin_t;
    float slope = shadow_bias_scale(N, -axis * side, sin_t);
    vec3 Pb = P + N * (1.5 * texel * sin_t);
    vec4 clip = m * vec4(Pb, 1.0);
    vec2 uv = clip.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;
    vec2 stored = texture(world_map, vec3(shadow_map_uv(sh, uv), sh.point.w)).rg;
    float d = dot(Pb, axis);
    return side > 0.0 ? (d - slope * texel <= -stored.r ? 1.0 : 0.0) : (d + slope * texel >= stored.g ? 1.0 : 0.0);
}
#endif

/* 1 where this sample's light point sees P (normal N), 0 in shadow. */
float shadow_visibility(int index, vec3 P, vec3 N) {
    GpuShadow sh = shadows[index];
    float res = sh.params.y;
    if (int(sh.params.x) == SHADOW_CASCADES) {
        float d = frame_view_depth(P);
        int c = d <= sh.cascade_split.x ? 0 : d <= sh.cascade_split.y ? 1 : d <= sh.cascade_split.z ? 2 : 3;
        return ortho_visibility(sh, sh.cascade[c], c, P, N);
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
    if (dist <= 0.0 || dot(N, v) >= 0.0) return 1.0;
    float texel = dist * sh.params.z;
    float sin_t;
    float slope = shadow_bias_scale(N, -v / dist, sin_t);
    vec3 Pb = P + N * (1.5 * texel * sin_t);
    vec3 vb = Pb - light_point;
    float fwd = max(dot(vb, F), 1e-20);
    vec2 uv = vec2(dot(vb, R), dot(vb, U)) / (fwd * SHADOW_CUBE_OVERLAP) * 0.5 + 0.5;
    float stored = texture(shadow_maps, vec3(shadow_map_uv(sh, uv), sh.point.w + float(face))).r;
    /* An emissive mesh's point lies on its own surface, which curves away
     * from it: the texels around its tangent plane see that surface at
     * almost no distance. Occluders nearer than cascade_split.z (a fraction
     * of the emitter's size; 0 for lights) are that surface, not a shadow. */
    return (length(vb) - slope * texel <= stored || stored < sh.cascade_split.z) ? 1.0 : 0.0;
}
