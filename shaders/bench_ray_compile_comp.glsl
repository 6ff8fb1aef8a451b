/* Benchmark (bench/bench_ray_compile.cpp): what a program with shadow rays
 * costs the driver to compile, against the number of places that call the
 * traversal. GLSL has no calls that stay calls: a compiler inlines
 * ray_transmittance at every call site, and the lighting program calls it
 * from up to ten (light_lib.glsl). RAY_SITES sites here, each in its own
 * branch so no two can be merged; with RAY_SUBROUTINE each calls through
 * ray_lib.glsl's subroutine uniform instead, as the engine's programs do (a
 * call the compiler cannot resolve at compile time, so it may keep one copy
 * of the traversal). */
#include "ray_lib.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Rays { vec4 rays[]; }; /* (origin, tmax), (dir, 0) */
layout(std430, binding = 1) writeonly buffer Transmittance { float transmittance[]; };

#define SITE(k)                                                                     \
    if (((i >> uint(k)) & 1u) != 0u)                                                \
        T += ray_transmittance(o.xyz + vec3(float(k) * 1e-3), d.xyz, o.w) * float(k + 1);

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (2u * i + 1u >= uint(rays.length())) return;
    vec4 o = rays[2u * i], d = rays[2u * i + 1u];
    float T = 0.0;
    SITE(0)
#if RAY_SITES > 1
    SITE(1)
#endif
#if RAY_SITES > 2
    SITE(2)
    SITE(3)
#endif
#if RAY_SITES > 4
    SITE(4)
    SITE(5)
    SITE(6)
    SITE(7)
#endif
#if RAY_SITES > 8
    SITE(8)
    SITE(9)
    SITE(10)
    SITE(11)
    SITE(12)
    SITE(13)
    SITE(14)
    SITE(15)
#endif
    transmittance[i] = T;
}
