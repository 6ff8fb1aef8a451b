/* GPU unit test (tests/native/test_rays.cpp): the transmittance of a buffer
 * of rays through ray_lib.glsl's traversal of a RayScene buffer. */
#include "ray_lib.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Rays { vec4 rays[]; }; /* (origin, tmax), (dir, 0) */
layout(std430, binding = 1) writeonly buffer Transmittance { float transmittance[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (2u * i + 1u >= uint(rays.length())) return;
    vec4 o = rays[2u * i], d = rays[2u * i + 1u];
    transmittance[i] = ray_transmittance(o.xyz, d.xyz, o.w);
}
