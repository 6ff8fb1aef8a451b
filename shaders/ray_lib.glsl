/* Shadow rays traced against the scene's two-level bounding volume
 * hierarchy (ray_scene.h builds it and documents the buffer's layout; its
 * trace_transmittance is this traversal on the CPU). */
#ifndef RAY_LIB
#define RAY_LIB

#include "shader_defines.h"

layout(std430, binding = SSBO_RAY_SCENE) readonly buffer RayScene { uvec4 ray_scene[]; };

vec3 ray_safe_inverse(vec3 d) {
    return vec3(abs(d.x) > 1e-30 ? 1.0 / d.x : (d.x < 0.0 ? -1e30 : 1e30),
                abs(d.y) > 1e-30 ? 1.0 / d.y : (d.y < 0.0 ? -1e30 : 1e30),
                abs(d.z) > 1e-30 ? 1.0 / d.z : (d.z < 0.0 ? -1e30 : 1e30));
}

/* Slab test over t in [0, tmax]. */
bool ray_box(uvec4 a, uvec4 b, vec3 o, vec3 inv, float tmax) {
    vec3 t0 = (uintBitsToFloat(a.xyz) - o) * inv, t1 = (uintBitsToFloat(b.xyz) - o) * inv;
    vec3 tn = min(t0, t1), tf = max(t0, t1);
    float enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float leave = min(min(tf.x, tf.y), min(tf.z, tmax));
    return enter <= leave;
}

/* The fraction of light that passes from `origin` along `dir` (not
 * necessarily unit) over t in (0, tmax): 0 at an opaque surface, the product
 * of 1 - alpha over partly transparent ones (Cycles' transparent shadows),
 * 1 where nothing is hit. Any hit ends an opaque ray, so the children are
 * visited in stored order.
 * RAY_SUBROUTINE (ray_scene.h, add_ray_traversal_define): called through a
 * subroutine uniform. GLSL compilers inline a function at every call site,
 * and the lighting program calls this from up to ten (light_lib.glsl); a
 * subroutine call is resolved only when the program runs, so the compiler
 * can keep one copy (bench/bench_ray_compile.cpp measures what that saves
 * on a driver). The program's user selects it (use_ray_traversal). */
#ifdef RAY_SUBROUTINE
subroutine float RayTransmittance(vec3 origin, vec3 dir, float tmax);
subroutine uniform RayTransmittance ray_transmittance;
subroutine(RayTransmittance) float ray_transmittance_bvh(vec3 origin, vec3 dir, float tmax) {
#else
float ray_transmittance(vec3 origin, vec3 dir, float tmax) {
#endif
    uvec4 header = ray_scene[0];
    if (header.z == 0u) return 1.0;
    float T = 1.0;
    vec3 inv = ray_safe_inverse(dir);
    uint stack[RAY_MAX_DEPTH];
    uint inner[RAY_MAX_DEPTH];
    int sp = 0;
    uint node = 0u;
    int steps = 0;
    for (;;) {
        if (++steps > RAY_MAX_STEPS) return T;
        uvec4 a = ray_scene[header.x + 2u * node], b = ray_scene[header.x + 2u * node + 1u];
        if (ray_box(a, b, origin, inv, tmax)) {
            if (b.w == 0u) {
                stack[sp++] = a.w + 1u;
                node = a.w;
                continue;
            }
            for (uint i = a.w; i < a.w + b.w; ++i) {
                /* Into the instance's mesh: the affine map keeps t. */
                uint r = header.y + 4u * i;
                vec4 m0 = uintBitsToFloat(ray_scene[r]), m1 = uintBitsToFloat(ray_scene[r + 1u]),
                     m2 = uintBitsToFloat(ray_scene[r + 2u]);
                uvec4 info = ray_scene[r + 3u]; /* node base, triangle base, alpha base */
                vec3 o = vec3(dot(m0.xyz, origin) + m0.w, dot(m1.xyz, origin) + m1.w, dot(m2.xyz, origin) + m2.w);
                vec3 d = vec3(dot(m0.xyz, dir), dot(m1.xyz, dir), dot(m2.xyz, dir));
                vec3 dinv = ray_safe_inverse(d);
                /* Hits nearer than the float precision of the object-space
                 * origin (1e-6 of its largest coordinate) are the ray's own
                 * surface: a mesh far from its object's origin has coarser
                 * floats there than the camera-relative lift allows for. */
                float tmin = 1e-6 * max(max(abs(o.x), abs(o.y)), abs(o.z)) * inversesqrt(dot(d, d));
                int isp = 0;
                uint n = 0u;
                for (;;) {
                    if (++steps > RAY_MAX_STEPS) return T;
                    uvec4 na = ray_scene[info.x + 2u * n], nb = ray_scene[info.x + 2u * n + 1u];
                    if (ray_box(na, nb, o, dinv, tmax)) {
                        if (nb.w == 0u) {
                            inner[isp++] = na.w + 1u;
                            n = na.w;
                            continue;
                        }
                        for (uint t = na.w; t < na.w + nb.w; ++t) {
                            uint k = info.y + 3u * t;
                            uvec4 t0 = ray_scene[k];
                            vec3 v0 = uintBitsToFloat(t0.xyz), e1 = uintBitsToFloat(ray_scene[k + 1u].xyz),
                                 e2 = uintBitsToFloat(ray_scene[k + 2u].xyz);
                            /* Moller-Trumbore. */
                            vec3 p = cross(d, e2);
                            float det = dot(e1, p);
                            if (det == 0.0) continue;
                            float inv_det = 1.0 / det;
                            vec3 s = o - v0;
                            float u = dot(s, p) * inv_det;
                            if (u < 0.0 || u > 1.0) continue;
                            vec3 q = cross(s, e1);
                            float v = dot(d, q) * inv_det;
                            if (v < 0.0 || u + v > 1.0) continue;
                            float th = dot(e2, q) * inv_det;
                            if (!(th > tmin && th < tmax)) continue;
                            if (info.z == 0u) return 0.0;
                            T *= 1.0 - uintBitsToFloat(ray_scene[info.z + t0.w / 4u][t0.w % 4u]);
                            if (T <= 0.0) return 0.0;
                        }
                    }
                    if (isp == 0) break;
                    n = inner[--isp];
                }
            }
        }
        if (sp == 0) break;
        node = stack[--sp];
    }
    return T;
}

#endif
