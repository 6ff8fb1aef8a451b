/* What the shadow maps are sized for (renderer.cpp visible_receivers), from
 * sample 0's depth, so that only this comes back to the CPU instead of the
 * whole depth buffer (8 MB at 1920x1080, a wait on the GPU and a CPU loop
 * over every pixel, each frame):
 *   - the nearest and the farthest stored depth of the pixels that see a
 *     surface (reversed Z: the largest and the smallest value above 0;
 *     positive floats order as their bits, so atomicMax / atomicMin on the
 *     bits find them; one atomic per workgroup after a shared-memory pass);
 *   - the depth at the points of the receiver grid: every `step`-th pixel
 *     from step / 2 in x and y, row-major (grid.x points a row).
 * near_bits starts at 0 (0.0) and far_bits at the bits of 2.0, as the CPU
 * loop did: no surface leaves them there. */
#include "shader_defines.h"

layout(local_size_x = 16, local_size_y = 16) in;

layout(binding = TEX_DEPTH) uniform sampler2D gbuf_depth;
layout(std430, binding = SSBO_RECEIVERS) buffer Receivers {
    uint near_bits;
    uint far_bits;
    uint pad0, pad1;
    float grid_depth[];
};
layout(location = 0) uniform ivec4 u_grid;  /* width, height, step, points per grid row */

shared uint s_near, s_far;

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        s_near = 0u;
        s_far = floatBitsToUint(2.0);
    }
    barrier();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    int step = u_grid.z;
    if (p.x < u_grid.x && p.y < u_grid.y) {
        float z = texelFetch(gbuf_depth, p, 0).r;
        if (z > 0.0) {
            atomicMax(s_near, floatBitsToUint(z));
            atomicMin(s_far, floatBitsToUint(z));
        }
        if (p.x % step == step / 2 && p.y % step == step / 2)
            grid_depth[(p.y / step) * u_grid.w + p.x / step] = z;
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_near != 0u) {
        atomicMax(near_bits, s_near);
        atomicMin(far_bits, s_far);
    }
}
