/* The visibility buffer's resolve (visibility_module.h): the G-buffer
 * written in compute. One dispatch per slot key (a mesh batch's material
 * slot), a workgroup per screen tile where the classification found the key
 * (visibility_classify_comp.glsl), an invocation per pixel of the tile that
 * sees the key; each
 * rebuilds what the geometry pass's vertex stage and rasteriser would have
 * handed its fragment (geometry_vert.glsl), from the instance and triangle
 * the visibility buffer holds:
 *   - the barycentric weights where the pixel's ray (through its centre,
 *     under this sample's jittered projection) meets the triangle's plane
 *     (Moeller and Trumbore 1997): the rasteriser's perspective-correct
 *     interpolation is that same point;
 *   - every varying as those weights of the corners' values, fetched from
 *     the mesh's buffers as the vertex stage fetches them;
 *   - their screen derivatives from the right and upper neighbours' rays
 *     met on the same plane (the quad's dFdxFine, without the quad);
 *   - the facing from the winding in clip space, as the rasteriser decides
 *     it (the sign of the homogeneous 2D determinant, Olano and Greer 1997).
 * Then geometry_frag.glsl's own surface code runs (GBUFFER_RESOLVE) and its
 * outputs are stored into the G-buffer's images. */
#define GBUFFER_RESOLVE
#include "geometry_frag.glsl"

layout(local_size_x = VIS_TILE, local_size_y = VIS_TILE) in;

#include "mesh_lib.glsl"
layout(std430, binding = SSBO_MATERIAL_SLOTS) readonly buffer Slots { uint material_slots[]; };
#ifndef MATERIAL_GRAPH
layout(std430, binding = SSBO_INSTANCES) readonly buffer Instances { GpuInstance instances[]; };
#endif
layout(std430, binding = SSBO_VIS_KEYS) readonly buffer VisKeys { uint key_data[]; };
layout(std430, binding = SSBO_VIS_TILES) readonly buffer VisTiles { uint vis_tiles[]; };
layout(binding = TEX_VISIBILITY) uniform usampler2D visibility;
layout(location = 1) uniform uint mesh_flags;  /* geometry_vert.glsl's */
layout(location = LOC_VIS_KEY) uniform uint resolve_key;

layout(binding = OUT_EMISSION, rgba32f) writeonly uniform image2D img_emission;
layout(binding = OUT_BASE, rgba16f) writeonly uniform image2D img_base;
layout(binding = OUT_PARAMS0, rgba16f) writeonly uniform image2D img_params0;
layout(binding = OUT_NORMAL, r32ui) writeonly uniform uimage2D img_normal;
#ifdef GBUF_PARAMS1
layout(binding = OUT_PARAMS1, rgba16f) writeonly uniform image2D img_params1;
#endif
#ifdef GBUF_INSTANCE_IDS
layout(binding = OUT_IDS, rgba32ui) writeonly uniform uimage2D img_ids;
#elif defined(GBUF_IDS)
layout(binding = OUT_IDS, rg32ui) writeonly uniform uimage2D img_ids;
#endif
#ifdef GBUF_UV
layout(binding = OUT_UV, rg32f) writeonly uniform image2D img_uv;
#endif
#ifdef GEOMETRY_OUT
layout(binding = OUT_GEOMETRY, rgba32ui) writeonly uniform uimage2D img_geometry;
#endif

/* The pixel's ray met on the triangle's plane, in double precision: in
 * float the weights lose bits to cancellation, since the ray's origin and
 * the corner are as far apart as the camera is from the surface while the
 * weights resolve offsets within the triangle (about 1e-6 of the view's
 * extent: the node probes' Degrees case, whose input is x57 its UV, erred
 * 1.2e-4 in float where the raster erred 3e-5). The corners stay the float
 * positions the vertex stage computes, so both paths meet the same
 * triangle. On NVIDIA's data-centre GPUs doubles run at half the float
 * rate; the resolve does three of these per pixel. */

/* Camera-relative world point of window position `frag` (pixels) at depth d. */
dvec3 window_point(dvec2 frag, double d) {
    const dvec4 view = dmat4(frame.inv_projection) * dvec4(frag / dvec2(frame.viewport.xy) * 2.0 - 1.0, d, 1.0);
    return (dmat4(frame.inv_view) * dvec4(view.xyz / view.w, 1.0)).xyz;
}

/* Weights of corners 1 and 2 where the ray through window position `frag`
 * meets the plane of (p0, p1, p2) (Moeller-Trumbore, unclamped). */
dvec2 plane_weights(dvec2 frag, dvec3 p0, dvec3 e1, dvec3 e2) {
    const dvec3 o = window_point(frag, 1.0);            /* the near plane (reversed Z) */
    const dvec3 d = window_point(frag, 0.5) - o;        /* further along the same ray */
    const dvec3 pvec = cross(d, e2);
    const double det = dot(e1, pvec);
    if (abs(det) < 1e-300 || isnan(det)) return dvec2(1.0 / 3.0);  /* edge-on: the centroid */
    const dvec3 tvec = o - p0;
    const dvec3 qvec = cross(tvec, e1);
    return dvec2(dot(tvec, pvec), dot(d, qvec)) / det;
}

void main() {
    const uint base = resolve_key * VIS_KEY_STRIDE;
    const uint index = gl_WorkGroupID.y * uint(VIS_DISPATCH_ROW) + gl_WorkGroupID.x;
    if (index >= key_data[base + VIS_KEY_COUNT]) return;
    const uint tile = vis_tiles[key_data[base + VIS_KEY_OFFSET] + index];
    const ivec2 pixel = ivec2(tile & 0xFFFFu, tile >> 16u) * VIS_TILE + ivec2(gl_LocalInvocationID.xy);
    if (any(greaterThanEqual(pixel, textureSize(visibility, 0)))) return;
    const uvec4 vis = texelFetch(visibility, pixel, 0);
    if (vis.z != resolve_key + 1u) return;  /* another key's pixel of a shared tile, or none */
    const uint instance = vis.x, triangle = vis.y;
    const GpuInstance inst = instances[instance];

    uint vi[3];
    vec3 object_p[3], world[3];
    for (uint k = 0u; k < 3u; ++k) {
        vi[k] = indices[3u * triangle + k];
        object_p[k] = mesh_position_at_shutter(vi[k], mesh_flags);
        world[k] = (inst.model * vec4(object_p[k], 1.0)).xyz;
    }
    /* Facing as the rasteriser saw it: counter-clockwise in the window is
     * front (glFrontFace's default). */
    {
        /* In the vertex stage's order of operations, so a near-degenerate
         * triangle's sign is the one the rasteriser saw. */
        vec4 c0 = frame.projection * (frame.view * vec4(world[0], 1.0));
        vec4 c1 = frame.projection * (frame.view * vec4(world[1], 1.0));
        vec4 c2 = frame.projection * (frame.view * vec4(world[2], 1.0));
        g_front_facing = determinant(mat3(c0.xyw, c1.xyw, c2.xyw)) > 0.0;
    }
    const vec2 frag = vec2(pixel) + 0.5;
    g_frag_coord = vec4(frag, 0.0, 1.0);
    g_triangle_normal = cross(world[1] - world[0], world[2] - world[0]);
    const dvec3 p0 = dvec3(world[0]), e1 = dvec3(world[1]) - p0, e2 = dvec3(world[2]) - p0;
    const dvec2 w12_d = plane_weights(dvec2(frag), p0, e1, e2);
    const vec2 w12 = vec2(w12_d);
    const vec2 w12_dx = vec2(plane_weights(dvec2(frag) + dvec2(1.0, 0.0), p0, e1, e2) - w12_d);
    const vec2 w12_dy = vec2(plane_weights(dvec2(frag) + dvec2(0.0, 1.0), p0, e1, e2) - w12_d);
    const vec3 b = vec3(1.0 - w12.x - w12.y, w12);
    const vec3 db_dx = vec3(-w12_dx.x - w12_dx.y, w12_dx), db_dy = vec3(-w12_dy.x - w12_dy.y, w12_dy);

    v_position = b.x * world[0] + b.y * world[1] + b.z * world[2];
    g_dposition_dx = db_dx.x * world[0] + db_dx.y * world[1] + db_dx.z * world[2];
    g_dposition_dy = db_dy.x * world[0] + db_dy.y * world[1] + db_dy.z * world[2];

    const uint c0 = 3u * triangle;
    vec3 n[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    v_normal = vec3(0.0);
    if ((mesh_flags & 1u) != 0u) {
        for (uint k = 0u; k < 3u; ++k) {
            n[k] = mesh_corner_normal(c0 + k);
            vec3 world_n = mat3(inst.normal_matrix) * n[k];
#ifdef MATERIAL_GRAPH
            world_n = normalize(world_n);  /* as geometry_vert.glsl, per vertex */
#endif
            v_normal += b[k] * world_n;
        }
    }
    v_uv = vec2(0.0);
    if ((mesh_flags & 2u) != 0u) {
        const vec2 uv0 = corner_uvs[c0], uv1 = corner_uvs[c0 + 1u], uv2 = corner_uvs[c0 + 2u];
        v_uv = b.x * uv0 + b.y * uv1 + b.z * uv2;
        g_duv_dx = db_dx.x * uv0 + db_dx.y * uv1 + db_dx.z * uv2;
        g_duv_dy = db_dy.x * uv0 + db_dy.y * uv1 + db_dy.z * uv2;
    } else {
        g_duv_dx = g_duv_dy = vec2(0.0);
    }
    v_material = material_slots[resolve_key];
    v_object_index = inst.ids.x;
    v_mirrored = inst.ids.w;
    v_instance = instance;
    v_triangle = triangle;
#ifdef MATERIAL_GRAPH
    {
        /* The undeformed corners, as the vertex stage's true normal. */
        vec3 q[3];
        for (uint k = 0u; k < 3u; ++k) q[k] = mesh_position(vi[k]);
        v_true_normal = mat3(inst.normal_matrix) * cross(q[1] - q[0], q[2] - q[0]);
    }
    v_barycentric = b.xy;
    v_object_position = b.x * object_p[0] + b.y * object_p[1] + b.z * object_p[2];
    g_dobject_dx = db_dx.x * object_p[0] + db_dx.y * object_p[1] + db_dx.z * object_p[2];
    g_dobject_dy = db_dy.x * object_p[0] + db_dy.y * object_p[1] + db_dy.z * object_p[2];
    v_object_normal = b.x * n[0] + b.y * n[1] + b.z * n[2];
    for (int k = 0; k < 8; ++k) g_dattr_dx[k] = g_dattr_dy[k] = vec4(0.0);
#if MATERIAL_ATTRIBUTE_COUNT > 0
    for (int k = 0; k < MATERIAL_ATTRIBUTE_COUNT; ++k) {
        vec4 a[3];
        for (uint j = 0u; j < 3u; ++j) a[j] = mesh_corner_attribute(k, c0 + j);
        v_attr[k] = b.x * a[0] + b.y * a[1] + b.z * a[2];
        g_dattr_dx[k] = db_dx.x * a[0] + db_dx.y * a[1] + db_dx.z * a[2];
        g_dattr_dy[k] = db_dy.x * a[0] + db_dy.y * a[1] + db_dy.z * a[2];
#ifdef MATERIAL_FLAT_ATTRIBUTE
        /* Flat: the provoking (last) corner's value, exactly. */
        if (k == MATERIAL_FLAT_ATTRIBUTE) v_attr_flat = a[2];
#endif
    }
#endif
#endif
#ifdef GEOMETRY_OUT
    {
        /* geometry_vert.glsl's terminator terms, from the undeformed corners. */
        vec3 V[3];
        for (uint k = 0u; k < 3u; ++k) V[k] = mesh_position(vi[k]);
        v_term_a = vec3(dot(V[1] - V[0], n[0]), dot(V[2] - V[0], n[0]), dot(V[0] - V[1], n[1]));
        v_term_b = vec3(dot(V[2] - V[1], n[1]), dot(V[0] - V[2], n[2]), dot(V[1] - V[2], n[2]));
        v_term_dir = mat3(inst.model) * (b.x * n[0] + b.y * n[1] + b.z * n[2]);
        v_term_bary = b.xy;
        v_term_cutoff = (mesh_flags & 1u) != 0u ? inst.info.y : 0.0;
    }
#endif

    geometry_surface();

    imageStore(img_emission, pixel, out_emission);
    imageStore(img_base, pixel, out_base);
    imageStore(img_params0, pixel, out_params0);
    imageStore(img_normal, pixel, uvec4(out_normal));
#ifdef GBUF_PARAMS1
    imageStore(img_params1, pixel, out_params1);
#endif
#ifdef GBUF_INSTANCE_IDS
    imageStore(img_ids, pixel, out_ids);
#elif defined(GBUF_IDS)
    imageStore(img_ids, pixel, uvec4(out_ids, 0u, 0u));
#endif
#ifdef GBUF_UV
    imageStore(img_uv, pixel, vec4(out_uv, 0.0, 0.0));
#endif
#ifdef GEOMETRY_OUT
    imageStore(img_geometry, pixel, out_geometry);
#endif
}
