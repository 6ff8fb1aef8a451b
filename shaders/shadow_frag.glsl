/* Shadow maps: stores, per texel, the distance from the light's sample point
 * (SHADOW_CUBE) or the depth along the sun's direction (SHADOW_CASCADES) of
 * the nearest surface, as a float (R32F). Depth testing uses its own
 * reversed-Z float buffer; the stored value is linear so the lookup compares
 * distances in metres.
 * WORLD_MAP: the world's occlusion map stores (-min, max) of the depth along
 * its axis through MAX blending (no depth test), so one map answers for the
 * direction it looks along and for the opposite one.
 * SCENE_ALPHA: partly transparent casters are kept with probability alpha
 * (transparency_random), so the maps of many samples converge to Cycles'
 * transparent shadows. */
#include "frame_lib.glsl"

in vec3 v_position;
#ifdef SCENE_ALPHA
flat in uint v_material;
flat in uint v_instance;
flat in uint v_triangle;
layout(std430, binding = SSBO_MATERIALS) readonly buffer Materials { GpuMaterial materials[]; };

#include "material_alpha_lib.glsl"
#endif
layout(location = 3) uniform vec4 shadow_origin; /* xyz: light point (cube) or a point up-sun (cascades); w: kind */
layout(location = 4) uniform vec3 shadow_axis;   /* sun direction (cascades) */
#ifdef WORLD_MAP
layout(location = 0) out vec2 out_depths;
#else
layout(location = 0) out float out_distance;
#endif

void main() {
#ifdef SCENE_ALPHA
    if (transparency_random(uvec2(gl_FragCoord.xy), v_instance, v_triangle) >= material_chain_alpha(v_material)) discard;
#endif
    float d = caster_depth(v_position, shadow_origin, shadow_axis);
#ifdef WORLD_MAP
    out_depths = vec2(-d, d);
#else
    out_distance = d;
#endif
}
