/* The visibility buffer's raster half (visibility_stage.h): depth, and per
 * pixel the instance, the triangle and the slot-table entry it is drawn
 * with, plus one (0: no surface). Nothing is shaded here: the G-buffer is
 * written by gbuffer_resolve_comp.glsl from these ids, in compute, where a
 * data-centre GPU runs per-pixel work many times faster than in its
 * fragment stage (bench/gpu/results/nvidia_h200_2026-11-26: 32x). */
#include "frame_lib.glsl"

flat in uint v_instance;
#ifdef INDEXED_DRAW
/* Drawn by vertex (draw_style.h): the vertex stage knows no triangle, the
 * primitive's number in the drawn range does (it counts from 0 for each
 * instance), and the slot key follows from it as geometry_vert.glsl's
 * does from its corner's triangle. */
layout(location = 1) uniform uint mesh_flags;
layout(location = LOC_FIRST_TRIANGLE) uniform uint first_triangle;
layout(std430, binding = SSBO_INSTANCES) readonly buffer Instances { GpuInstance instances[]; };
layout(std430, binding = SSBO_MATERIAL_INDICES) readonly buffer MaterialIndices { int material_indices[]; };
#else
flat in uint v_triangle;
flat in uint v_slot_key;
#endif

layout(location = 0) out uvec4 out_visibility;

void main() {
#ifdef INDEXED_DRAW
    const uint triangle = first_triangle + uint(gl_PrimitiveID);
    const uvec4 ids = instances[v_instance].ids;
    const int slot = (mesh_flags & 4u) != 0u ? material_indices[triangle] : 0;
    const uint slot_key = ids.y + min(uint(max(slot, 0)), max(ids.z, 1u) - 1u);
    out_visibility = uvec4(v_instance, triangle, slot_key + 1u, 0u);
#else
    out_visibility = uvec4(v_instance, v_triangle, v_slot_key + 1u, 0u);
#endif
}
