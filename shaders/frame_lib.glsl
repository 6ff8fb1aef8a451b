/* Per-frame constants and the scene buffers every pass may read. */
#include "shader_shared.h"
#include "shader_defines.h"

layout(std140, binding = UBO_FRAME) uniform FrameBlock { FrameConstants frame; };

bool frame_is_ortho() { return frame.camera_position.w > 0.5; }

/* A surface's emission (the G-buffer's emission target) that the film
 * sample's own pixel shares with the emission sub-samples
 * (native/src/emission_samples.h): not a holdout's (a 0) nor a shadow
 * catcher's (a 2). The sample adds frame.jitter.w (1/K) of it. */
bool directly_seen_emission(vec4 emission) { return emission.a > 0.0 && emission.a < 1.5; }
float directly_seen_emission_share(vec4 emission) { return directly_seen_emission(emission) ? frame.jitter.w : 1.0; }

/* Direction towards the viewer from a camera-relative position. */
vec3 frame_view_vector(vec3 P) {
    if (frame_is_ortho()) return normalize(frame.inv_view[2].xyz);
    return normalize(frame.motion.xyz - P);
}

/* Distance from this sample's camera (at the origin but under motion blur). */
float frame_eye_distance(vec3 P) { return length(P - frame.motion.xyz); }

/* Camera-relative world position of a pixel from its reversed-Z depth. */
vec3 frame_position_from_depth(ivec2 pixel, float depth) {
    vec2 ndc = (vec2(pixel) + 0.5) * frame.viewport.zw * 2.0 - 1.0;
    vec4 view = frame.inv_projection * vec4(ndc, depth, 1.0);
    view /= view.w;
    return (frame.inv_view * vec4(view.xyz, 1.0)).xyz;
}

/* Positive camera-space Z (Cycles' Depth pass) of a camera-relative position. */
float frame_view_depth(vec3 P) { return -(frame.view * vec4(P, 1.0)).z; }

/* Positive view depth of a pixel straight from its depth-buffer value: two
 * rows of the inverse projection instead of rebuilding the position (the
 * culling passes run this for every pixel). */
float frame_view_depth_from_buffer(ivec2 pixel, float depth) {
    vec4 ndc = vec4((vec2(pixel) + 0.5) * frame.viewport.zw * 2.0 - 1.0, depth, 1.0);
    mat4 m = frame.inv_projection;
    float z = m[0][2] * ndc.x + m[1][2] * ndc.y + m[2][2] * ndc.z + m[3][2];
    float w = m[0][3] * ndc.x + m[1][3] * ndc.y + m[2][3] * ndc.z + m[3][3];
    return -z / w;
}

/* Bin of view depth d in a tile's [dmin, dmax] (2.5D culling masks); the
 * culling and lighting passes must agree bit for bit, hence one function. */
uint depth_bin(float d, float dmin, float dmax) {
    float t = (d - dmin) / max(dmax - dmin, 1e-30);
    return uint(clamp(t * float(DEPTH_BINS), 0.0, float(DEPTH_BINS - 1)));
}

/* What a shadow-map caster stores for camera-relative position P: the
 * distance from the light's point (cube maps) or the depth along the sun's
 * axis (cascades, and the world's map, whose origin.w is SHADOW_CASCADES).
 * shadow_frag.glsl and the node-material casters (geometry_frag.glsl). */
float caster_depth(vec3 P, vec4 origin, vec3 axis) {
    vec3 v = P - origin.xyz;
    return int(origin.w) == SHADOW_CASCADES ? dot(v, axis) : length(v);
}

/* Burley 2020, "Practical Hash-based Owen Scrambling" (JCGT 9(4)): the
 * Laine-Karras permutation of a bit-reversed integer, and nested uniform
 * (Owen) scrambling of an integer's bits from the top, by `seed`. */
uint laine_karras_permutation(uint x, uint seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}
uint nested_uniform_scramble(uint x, uint seed) {
    return bitfieldReverse(laine_karras_permutation(bitfieldReverse(x), seed));
}

/* Stochastic transparency: Cycles renders a surface of alpha a (Principled
 * Alpha, a Transparent BSDF mixed in) as covering a fraction a of what is
 * behind it, for camera and shadow rays alike. A fragment is kept when this
 * number is below a. It is uniform for each film sample, and independent
 * across pixels (of the camera or of a shadow map) and surfaces (instance,
 * triangle), so a stack of layers converges to the product of their
 * (1 - a). Over one pixel's and surface's samples it is stratified: sample s
 * takes point s of the van der Corput sequence with its index shuffled and
 * its value Owen-scrambled, both seeded per pixel and surface (Burley 2020,
 * sections 3-4: the shuffle keeps two surfaces' sequences from pairing up,
 * which with a shared sequence would freeze a pixel's see-through fraction
 * of a stack at a wrong value). The first 2^k samples then hold one point in
 * each 1/2^k of [0, 1): a surface of alpha a is kept in N a samples out of
 * N, give or take one, where independent numbers give it +-sqrt(N a (1 - a))
 * (4 samples at alpha 0.3: the kept fraction's RMS error 0.1 against 0.23).
 * The seed: pcg4d (Jarzynski and Olano 2020, "Hash Functions for GPU
 * Rendering") of the pixel and surface. */
float transparency_random(uvec2 pixel, uint instance, uint triangle) {
    uvec4 v = uvec4(pixel, instance * 0x9E3779B9u ^ triangle, 0x2545F491u);
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    uint index = nested_uniform_scramble(uint(frame.sample_shift.w), v.x);
    uint x = nested_uniform_scramble(bitfieldReverse(index), v.y);
    return float(x >> 8u) * (1.0 / 16777216.0);
}
