/* The visibility buffer's raster half (visibility_stage.h): depth, and per
 * pixel the instance, the triangle and the slot-table entry it is drawn
 * with, plus one (0: no surface). Nothing is shaded here: the G-buffer is
 * written by gbuffer_resolve_comp.glsl from these ids, in compute, where a
 * data-centre GPU runs per-pixel work many times faster than in its
 * fragment stage (bench/gpu/results/nvidia_h200_2026-11-26: 32x). */
#include "frame_lib.glsl"

flat in uint v_instance;
flat in uint v_triangle;
flat in uint v_slot_key;

layout(location = 0) out uvec4 out_visibility;

void main() {
    out_visibility = uvec4(v_instance, v_triangle, v_slot_key + 1u, 0u);
}
