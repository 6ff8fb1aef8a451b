/* Cryptomatte accumulation, once per film sample (cryptomatte_module.h):
 * the surface this sample sees at each pixel adds 1/samples of coverage to
 * its id in each layer's slots (object, material, asset): the slot that
 * already holds the id, else the first empty one; with every slot taken by
 * other ids, the last slot (Cycles' film_write_cryptomatte_slots: the
 * coverage still adds up to 1, credited to that slot's id). Cycles 3.4 has
 * no other mode: its Accurate Mode's unbounded per-pixel map is no longer
 * built, and the switch renders the same. As in Cycles, the pixel filter is in the jittered sample
 * positions, so every sample weighs the same; background adds nothing.
 * Defines: CRYPTO_LEVELS, CRYPTO_LAYERS and CRYPTO_KIND_<i> (0 object,
 * 1 material, 2 asset) for each layer i. */
#include "frame_lib.glsl"

layout(local_size_x = LIGHTING_GROUP_SIZE, local_size_y = LIGHTING_GROUP_SIZE) in;

layout(location = 0) uniform float sample_weight; /* 1 / samples */

layout(binding = TEX_DEPTH) uniform sampler2D gbuf_depth;
layout(binding = TEX_GBUF_IDS) uniform usampler2D gbuf_ids; /* z: instance, w: material id (GBUF_INSTANCE_IDS) */
layout(std430, binding = SSBO_CRYPTO_INSTANCES) readonly buffer CryptoInstances { uint crypto_instances[]; };
layout(std430, binding = SSBO_CRYPTO_MATERIALS) readonly buffer CryptoMaterials { uint crypto_materials[]; };
layout(std430, binding = SSBO_CRYPTO_SLOTS) buffer CryptoSlots { uvec2 slots[]; }; /* (id, coverage bits) */

uint layer_id(int kind, uvec4 ids) {
    if (kind == 1) return crypto_materials[ids.w];
    return crypto_instances[2u * ids.z + (kind == 2 ? 1u : 0u)];
}

void add_coverage(uint base, uint id) {
    for (uint k = 0u; k < uint(CRYPTO_LEVELS); ++k) {
        uvec2 s = slots[base + k];
        if (s.y == 0u) { /* empty: coverage 0.0 */
            slots[base + k] = uvec2(id, floatBitsToUint(sample_weight));
            return;
        }
        if (s.x == id || k == uint(CRYPTO_LEVELS) - 1u) {
            slots[base + k].y = floatBitsToUint(uintBitsToFloat(s.y) + sample_weight);
            return;
        }
    }
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, ivec2(frame.viewport.xy)))) return;
    if (texelFetch(gbuf_depth, pixel, 0).r <= 0.0) return;
    uvec4 ids = texelFetch(gbuf_ids, pixel, 0);
    uint pixel_index = uint(pixel.y) * uint(frame.viewport.x) + uint(pixel.x);
    const int kinds[3] = int[3](CRYPTO_KIND_0, CRYPTO_KIND_1, CRYPTO_KIND_2);
    for (int layer = 0; layer < CRYPTO_LAYERS; ++layer)
        add_coverage((pixel_index * uint(CRYPTO_LAYERS) + uint(layer)) * uint(CRYPTO_LEVELS),
                     layer_id(kinds[layer], ids));
}
