/* The Vector pass (motion_module.h): drawn against the G-buffer's depth with
 * an EQUAL test, so each fragment is the surface this film sample sees.
 * Cycles' primitive_motion_vector (kernel/geom/primitive.h): with raster(X)
 * the pixel position of X through a camera,
 *   xy = raster_previous(P_previous) - raster(P),
 *   zw = raster(P) - raster_next(P_next),
 * where P_previous / P_next are the same surface point moved by the object's
 * (and a deforming mesh's) motion, and raster_previous / raster_next use the
 * camera's matrices at those frames with this frame's projection. Raster
 * here is GL's window space (y up), the orientation of Blender's images,
 * as Cycles' raster rows are. Each fragment adds its motion and a count of
 * 1; the resolve divides (passes_comp.glsl RESOLVE_MOTION). */
#include "frame_lib.glsl"

in vec3 v_position;
in vec3 v_position_previous;
in vec3 v_position_next;

layout(binding = TEX_GBUF_EMISSION) uniform sampler2D gbuf_emission;
layout(location = 40) uniform mat4 raster_center;    /* camera-relative world -> clip, unjittered */
layout(location = 44) uniform mat4 raster_previous;  /* ... through the previous frame's camera */
layout(location = 48) uniform mat4 raster_next;

layout(location = 0) out vec4 out_motion;
layout(location = 1) out float out_count;

vec2 to_raster(mat4 to_clip, vec3 p) {
    vec4 clip = to_clip * vec4(p, 1.0);
    return (clip.xy / clip.w * 0.5 + 0.5) * frame.viewport.xy;
}

void main() {
    /* A holdout writes no data pass (emission.a 0, geometry_frag.glsl), as in
     * Cycles, where the holdout ends the path before film_write_data_passes. */
    if (texelFetch(gbuf_emission, ivec2(gl_FragCoord.xy), 0).a <= 0.0) discard;
    const vec2 center = to_raster(raster_center, v_position);
    out_motion = vec4(to_raster(raster_previous, v_position_previous) - center,
                      center - to_raster(raster_next, v_position_next));
    /* A fragment whose interpolants are not finite (a fuzzed scene: llvmpipe
     * rasterised a degenerate triangle at the near plane with NaN window
     * depth, which the depth clamp made equal to the G-buffer's) counts as
     * no sample, as a pixel that saw no surface: its motion would be NaN. */
    if (any(isnan(out_motion)) || any(isinf(out_motion))) discard;
    out_count = 1.0;
}
