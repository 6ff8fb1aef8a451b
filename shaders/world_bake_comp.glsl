/* Bakes the world's node tree into an equirectangular map (world_lib.glsl's
 * mapping): each texel evaluates the generated graph for the direction
 * through its centre and stores the background closure's radiance (the
 * Background nodes' colour x strength, mixed as the graph mixes them).
 * Variants: WORLD_LIGHTING (Light Path answers for light samples, not
 * camera rays), MATERIAL_IMAGE_COUNT.
 *
 * The shading point of a background, as Cycles' shader_setup_from_background
 * sets it (kernel/geom/shader_data.h): P = D (the ray direction, so
 * Generated, Object and UV coordinates and the Environment Texture's
 * default vector are D), N = Ng = I = -D; Camera coordinates are D in the
 * camera's frame, Window its raster position (the frame block carries the
 * unjittered camera). */
#include "frame_lib.glsl"
#include "world_lib.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(location = 0) uniform int constants_offset;
layout(binding = IMG_WORLD_BAKE, rgba32f) writeonly uniform image2D bake;
#if MATERIAL_IMAGE_COUNT > 0
layout(binding = TEX_MATERIAL_IMAGE0) uniform sampler2D material_images[MATERIAL_IMAGE_COUNT];
#endif
/* Generated: includes material_lib.glsl and nodes/node_lib.glsl, then the graph. */
#include "material_graph.glsl"

void main() {
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(bake);
    if (any(greaterThanEqual(texel, size))) return;
    vec3 D = world_uv_to_direction((vec2(texel) + 0.5) / vec2(size));
    g_sd.P = D;
    g_sd.N = -D;
    g_sd.Ng = -D;
    g_sd.I = -D;
    g_sd.generated = D;
    g_sd.uv = D;
    g_sd.N_object = -D;
    g_sd.P_object = D;
    g_sd.N_object_smooth = -D;
    g_sd.object_location = vec3(0.0);
    g_sd.object_color = vec4(0.0);
    g_sd.object_index = 0.0;
    g_sd.material_index = 0.0;
    g_sd.object_random = 0.0;
    g_sd.backfacing = 0.0;
    g_sd.view_distance = 0.0;
    g_sd.view_depth = 0.0;
    g_sd.dPdx = vec3(0.0);
    g_sd.dPdy = vec3(0.0);
    vec3 view = mat3(frame.view) * D;
    g_sd.P_view = vec3(view.xy, -view.z);
    /* Window: Cycles' camera_world_to_ndc of P (svm_node_tex_coord), the
     * frame's raster position of the direction: a perspective camera adds
     * its position to P = D (so D's point at infinity projects where the
     * camera sees D); an orthographic one projects the point D itself (what
     * light samples see; its camera rays use their own origin, which a
     * per-direction map cannot hold: the add-on warns). The projection
     * divides by w whatever its sign, as transform_perspective does. */
    {
        vec3 P = frame.camera_position.w > 0.5 ? D - frame.camera_position.xyz : D;
        vec4 clip = frame.projection * (frame.view * vec4(P, 1.0));
        g_sd.window = clip.w != 0.0 ? clip.xy / clip.w * 0.5 + 0.5 : vec2(0.0);
    }
    g_sd.barycentric = vec2(0.0);
    g_sd.normal_to_world = mat3(1.0);
    g_sd.object_to_world = mat3(1.0);
    for (int k = 0; k < 8; ++k) g_sd.attr[k] = vec4(0.0);
    g_sd.bump_dP = 0.0;
    g_const_base = constants_offset;
    g_mix_u = 0.5;
    Closure c;
    material_graph_eval(c);
    /* Radiance is finite and not negative (a graph can make NaN or negative
     * values; negative light is not sampled): clamped as the constant world
     * colour is (scene_store.h kMaxWorld). */
    vec3 L = c.emission * c.alpha;
    L = vec3(isnan(L.x) ? 0.0 : L.x, isnan(L.y) ? 0.0 : L.y, isnan(L.z) ? 0.0 : L.z);
    imageStore(bake, texel, vec4(clamp(L, vec3(0.0), vec3(1e12)), 1.0));
}
