/* The visibility buffer's classification (visibility_stage.h): the screen's
 * 8 x 8 tiles listed by slot key (one mesh batch's slot: its mesh and
 * material), so that the resolve runs one indirect dispatch per key over
 * exactly the tiles where it appears, with the mesh's buffers and the
 * material's program bound; a tile two keys share is in both lists, and
 * each dispatch resolves its own key's pixels there.
 *   VIS_COUNT    each key's tile count
 *   VIS_SCAN     each key's first index (an exclusive prefix sum, one
 *                workgroup) and its indirect dispatch
 *   VIS_SCATTER  each (tile, key) pair into its key's range
 * The first pixel of each distinct key in a tile does one global atomic
 * for it: a surface's interior costs one atomic per 64 pixels. Per-pixel atomics cost more than the
 * raster on llvmpipe (about 35 ns each). The order of a key's tiles is not
 * deterministic; each pixel is resolved by itself, so the image is. */
#include "shader_defines.h"

layout(std430, binding = SSBO_VIS_KEYS) coherent buffer VisKeys { uint key_data[]; };
layout(location = LOC_VIS_KEY_COUNT) uniform uint key_count;

#ifdef VIS_SCAN
layout(local_size_x = VIS_SCAN_SIZE) in;
shared uint s_sums[VIS_SCAN_SIZE];

void main() {
    const uint t = gl_LocalInvocationID.x;
    const uint chunk = (key_count + uint(VIS_SCAN_SIZE) - 1u) / uint(VIS_SCAN_SIZE);
    const uint first = min(t * chunk, key_count), last = min(first + chunk, key_count);
    uint sum = 0u;
    for (uint k = first; k < last; ++k) sum += key_data[k * VIS_KEY_STRIDE + VIS_KEY_COUNT];
    s_sums[t] = sum;
    barrier();
    /* Inclusive scan of the chunks' sums (Hillis and Steele). */
    for (uint d = 1u; d < uint(VIS_SCAN_SIZE); d <<= 1u) {
        uint add = t >= d ? s_sums[t - d] : 0u;
        barrier();
        s_sums[t] += add;
        barrier();
    }
    uint offset = s_sums[t] - sum;
    for (uint k = first; k < last; ++k) {
        const uint base = k * VIS_KEY_STRIDE, n = key_data[base + VIS_KEY_COUNT];
        /* One workgroup per tile, rows of VIS_DISPATCH_ROW (a dimension's
         * count may be as small as 65535: an 8K image has 518 400 tiles). */
        key_data[base + 0u] = min(n, uint(VIS_DISPATCH_ROW));
        key_data[base + 1u] = (n + uint(VIS_DISPATCH_ROW) - 1u) / uint(VIS_DISPATCH_ROW);
        key_data[base + 2u] = 1u;
        key_data[base + VIS_KEY_OFFSET] = offset;
        key_data[base + VIS_KEY_CURSOR] = 0u;
        offset += n;
    }
}
#else
layout(local_size_x = VIS_TILE, local_size_y = VIS_TILE) in;
layout(binding = TEX_VISIBILITY) uniform usampler2D visibility;
#ifdef VIS_SCATTER
layout(std430, binding = SSBO_VIS_TILES) writeonly buffer VisTiles { uint vis_tiles[]; };
#endif
shared uint s_keys[VIS_TILE * VIS_TILE]; /* key + 1, 0: none */

void main() {
    const uint t = gl_LocalInvocationIndex;
    const ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    const ivec2 size = textureSize(visibility, 0);
    uint key = 0u;
    if (all(lessThan(pixel, size))) key = texelFetch(visibility, pixel, 0).z;
    s_keys[t] = key <= key_count ? key : 0u; /* larger: never written by the raster; a guard only */
    barrier();
    /* The first pixel of each distinct key in the tile leads it: one global
     * atomic per (tile, key). Most tiles see one key, so most pixels stop
     * at the first comparison. (Without shared memory, each pixel fetching
     * the others' keys, llvmpipe took 60 ms more at 1080p.) */
    if (key == 0u || key > key_count) return;
    if (t != 0u && key == s_keys[0]) return;
    for (uint u = 1u; u < t; ++u)
        if (s_keys[u] == key) return;
    const uint base = (key - 1u) * VIS_KEY_STRIDE;
#ifdef VIS_COUNT
    atomicAdd(key_data[base + VIS_KEY_COUNT], 1u);
#else
    const uint at = key_data[base + VIS_KEY_OFFSET] + atomicAdd(key_data[base + VIS_KEY_CURSOR], 1u);
    vis_tiles[at] = gl_WorkGroupID.x | (gl_WorkGroupID.y << 16u);
#endif
}
#endif
