/* The visibility buffer's classification (visibility_stage.h): the covered
 * pixels grouped by slot key (one mesh batch's slot: its mesh and material),
 * so that the resolve runs one indirect dispatch per key over exactly its
 * pixels, with the mesh's buffers and the material's program bound.
 *   VIS_COUNT    each key's pixel count
 *   VIS_SCAN     each key's first index (an exclusive prefix sum, one
 *                workgroup) and its indirect dispatch
 *   VIS_SCATTER  each pixel's index into its key's range
 * A workgroup first aggregates its 64 pixels' keys in shared memory (a small
 * open-addressing table), so a large surface costs one global atomic per
 * workgroup, not per pixel. The order within a key is not deterministic; the
 * resolve writes each pixel by itself, so the image is. */
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
        key_data[base + 0u] = (n + uint(VIS_RESOLVE_SIZE) - 1u) / uint(VIS_RESOLVE_SIZE);
        key_data[base + 1u] = 1u;
        key_data[base + 2u] = 1u;
        key_data[base + VIS_KEY_OFFSET] = offset;
        key_data[base + VIS_KEY_CURSOR] = 0u;
        offset += n;
    }
}
#else
layout(local_size_x = VIS_CLASSIFY_SIZE, local_size_y = VIS_CLASSIFY_SIZE) in;
layout(binding = TEX_VISIBILITY) uniform usampler2D visibility;
#ifdef VIS_SCATTER
layout(std430, binding = SSBO_VIS_PIXELS) writeonly buffer VisPixels { uint vis_pixels[]; };
shared uint s_base[VIS_CLASSIFY_SIZE * VIS_CLASSIFY_SIZE];
#endif
#define TABLE_SIZE (VIS_CLASSIFY_SIZE * VIS_CLASSIFY_SIZE)
shared uint s_keys[TABLE_SIZE];   /* key + 1, 0: empty */
shared uint s_counts[TABLE_SIZE];

void main() {
    const uint t = gl_LocalInvocationIndex;
    s_keys[t] = 0u;
    s_counts[t] = 0u;
    barrier();
    const ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    const ivec2 size = textureSize(visibility, 0);
    uint key = 0u;
    if (all(lessThan(pixel, size))) key = texelFetch(visibility, pixel, 0).z;
    if (key > key_count) key = 0u;  /* never written by the raster; a guard only */
    uint slot = 0u, local = 0u;
    if (key != 0u) {
        /* At most 64 distinct keys in 64 slots: the probe always ends. */
        slot = key % uint(TABLE_SIZE);
        for (int i = 0; i < TABLE_SIZE; ++i) {
            const uint previous = atomicCompSwap(s_keys[slot], 0u, key);
            if (previous == 0u || previous == key) break;
            slot = (slot + 1u) % uint(TABLE_SIZE);
        }
        local = atomicAdd(s_counts[slot], 1u);
    }
    barrier();
#ifdef VIS_COUNT
    if (s_keys[t] != 0u) atomicAdd(key_data[(s_keys[t] - 1u) * VIS_KEY_STRIDE + VIS_KEY_COUNT], s_counts[t]);
#else
    if (s_keys[t] != 0u)
        s_base[t] = atomicAdd(key_data[(s_keys[t] - 1u) * VIS_KEY_STRIDE + VIS_KEY_CURSOR], s_counts[t]);
    barrier();
    if (key != 0u) {
        const uint base = (key - 1u) * VIS_KEY_STRIDE;
        vis_pixels[key_data[base + VIS_KEY_OFFSET] + s_base[slot] + local] = uint(pixel.x) | (uint(pixel.y) << 16u);
    }
#endif
}
#endif
