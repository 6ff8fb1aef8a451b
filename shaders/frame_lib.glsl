/* Per-frame constants and the scene buffers every pass may read. */
#include "shader_shared.h"
#include "shader_defines.h"

layout(std140, binding = UBO_FRAME) uniform FrameBlock { FrameConstants frame; };

bool frame_is_ortho() { return frame.camera_position.w > 0.5; }

/* Direction towards the viewer from a camera-relative position. */
vec3 frame_view_vector(vec3 P) {
    if (frame_is_ortho()) return normalize(frame.inv_view[2].xyz);
    return normalize(-P);
}

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
