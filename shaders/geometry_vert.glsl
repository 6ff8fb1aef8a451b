/* Geometry pass, vertex stage: vertex pulling. Triangle t, corner c is vertex
 * 3t + c of a glDrawArraysInstanced call; positions are fetched through the
 * index buffer, per-corner normals and UVs directly (Blender keeps split
 * normals and UVs on loops). No vertex arrays; one draw per mesh, or per
 * material slot range when node materials are drawn. */
#include "frame_lib.glsl"

#include "mesh_lib.glsl"
layout(std430, binding = SSBO_MATERIAL_INDICES) readonly buffer MaterialIndices { int material_indices[]; };
layout(std430, binding = SSBO_INSTANCES) readonly buffer Instances { GpuInstance instances[]; };
layout(std430, binding = SSBO_MATERIAL_SLOTS) readonly buffer Slots { uint material_slots[]; };

layout(location = 0) uniform uint instance_offset;
layout(location = 1) uniform uint mesh_flags;  /* 1: normals, 2: uvs, 4: material indices */
/* Only the instances that can be seen (by the camera, or cast into the
 * shadow map being drawn) are drawn, listed in instance_remap from
 * instance_offset on. */
layout(std430, binding = SSBO_INSTANCE_REMAP) readonly buffer Remap { uint instance_remap[]; };
#ifdef SHADOW_PASS
/* Shadow maps (shadow_frag.glsl): camera-relative world -> the face's clip space. */
layout(location = 2) uniform mat4 shadow_view_projection;
/* Casters are kept where dot(xyz, x) + w >= 0 for each plane: the region
 * where the light shines (ShadowModule's lit_region: in front of an area
 * light, inside a spot's cone); (0, 0, 0, 1) keeps everything. Unset
 * uniforms are 0, which keeps everything too. */
layout(location = LOC_SHADOW_CLIP) uniform vec4 shadow_clip[SHADOW_CLIP_PLANES];
#endif
#ifdef MOTION_PASS
/* The Vector pass (motion_module.h): each instance's previous and next model
 * matrix (camera-relative to this frame's camera). */
layout(std430, binding = SSBO_INSTANCE_MOTION) readonly buffer InstanceMotion { mat4 instance_motion[]; };
out vec3 v_position_previous;  /* camera-relative world, this frame's camera */
out vec3 v_position_next;
#endif
#ifdef EMISSION_BAKE
/* Textured emission (emitter_module.h): each emitting triangle is drawn into
 * its own T x T tile of the bake target, corners 0, 1, 2 at the tile's
 * (0, 0), (T + 1/2, 0), (0, T + 1/2), so exactly the texels (i, j) with
 * i + j <= T - 1 are covered (their centres' sums are whole numbers, the
 * edge's is T + 1/2) and texel (i, j) holds the surface at barycentric
 * weights ((i + 1/2), (j + 1/2)) / (T + 1/2) of corners 1 and 2.
 * Tile of triangle t: bake_tile_offset + (t - bake_first_triangle). */
layout(location = 30) uniform int bake_tile_offset;
layout(location = 31) uniform uint bake_first_triangle;
layout(location = 32) uniform ivec4 bake_layout;  /* tile size T, tiles per row, target width, height */
#endif

#ifdef MATERIAL_GRAPH
/* Node materials: the mesh's attribute slots (mesh_lib.glsl). */
out vec3 v_object_position;
out vec3 v_object_normal;
flat out vec3 v_true_normal;  /* world, from the triangle's three vertices (Cycles' Ng) */
out vec2 v_barycentric;       /* weights of the triangle's corners 0 and 1 */
#if MATERIAL_ATTRIBUTE_COUNT > 0
out vec4 v_attr[MATERIAL_ATTRIBUTE_COUNT];
#endif
#ifdef MATERIAL_FLAT_ATTRIBUTE
flat out vec4 v_attr_flat; /* that slot, constant per triangle: not interpolated */
#endif
#endif

#ifdef GBUF_GEOMETRY
/* The shadow terminator offset (geometry_frag.glsl terminator_offset), per
 * triangle: Cycles' terms dot(V_j - V_i, N_i) in object space (V the
 * corners' positions, N their normals), the interpolated object normal as
 * a world direction (object_dir_transform), the corner weights, and the
 * object's Geometry Offset (0 without normals: a flat surface). */
flat out vec3 v_term_a;  /* G01, G02, G10 with Gij = dot(V_j - V_i, N_i) */
flat out vec3 v_term_b;  /* G12, G20, G21 */
out vec3 v_term_dir;
out vec2 v_term_bary;    /* weights of corners 0 and 1 */
flat out float v_term_cutoff;
#endif

/* The same depth from every geometry program: node materials test for equal
 * depth against the depth pre-pass drawn with the constant-material program. */
invariant gl_Position;

out vec3 v_position;  /* camera-relative world */
out vec3 v_normal;    /* world, unnormalised */
out vec2 v_uv;
flat out uint v_material;
flat out uint v_object_index;
flat out uint v_mirrored;
flat out uint v_instance;  /* the instance drawn (transparency_random, node materials) */
flat out uint v_triangle;  /* the triangle of the mesh (transparency_random) */
#ifdef VISIBILITY_PASS
/* The visibility buffer (visibility_frag.glsl): the batch's slot-table
 * entry (instance ids.y + slot) the triangle is drawn with, which names its
 * mesh and material for the resolve (visibility_stage.h). */
flat out uint v_slot_key;
#endif

#ifdef SHADOW_PASS
/* A caster's vertex in the map being drawn, and its distances to the lit
 * region's planes. */
void shadow_map_position(vec4 world) {
    gl_Position = shadow_view_projection * world;
    gl_ClipDistance[0] = dot(shadow_clip[0].xyz, world.xyz) + shadow_clip[0].w;
    gl_ClipDistance[1] = dot(shadow_clip[1].xyz, world.xyz) + shadow_clip[1].w;
    gl_ClipDistance[2] = dot(shadow_clip[2].xyz, world.xyz) + shadow_clip[2].w;
    gl_ClipDistance[3] = dot(shadow_clip[3].xyz, world.xyz) + shadow_clip[3].w;
}
#endif

void main() {
#ifdef INDEXED_DRAW
    /* Drawn by vertex (glDrawElementsInstanced over the index buffer,
     * draw_style.h): gl_VertexID is the vertex itself, which a vertex cache
     * shades once for the triangles sharing it. Only the position (and the
     * instance): an opaque caster (shadow_frag.glsl without SCENE_ALPHA)
     * reads nothing else, the visibility buffer's one raster program
     * (visibility_frag.glsl) takes the rest from gl_PrimitiveID. */
#if !defined(SHADOW_PASS) && !defined(VISIBILITY_PASS)
#error "INDEXED_DRAW draws shadow casters and the visibility buffer only"
#endif
    {
        const uint instance = instance_remap[instance_offset + uint(gl_InstanceID)];
        const vec4 world = instances[instance].model * vec4(mesh_position_at_shutter(uint(gl_VertexID), mesh_flags), 1.0);
        v_position = world.xyz;
#ifdef SHADOW_PASS
        shadow_map_position(world);
#else
        gl_Position = frame.projection * (frame.view * world);
        v_instance = instance;
#endif
        return;
    }
#endif
    const uint corner = uint(gl_VertexID);
    const uint triangle = corner / 3u;
    const uint instance = instance_remap[instance_offset + uint(gl_InstanceID)];
    GpuInstance inst = instances[instance];

    const uint vi = indices[corner];
#ifdef MOTION_PASS
    const vec3 p = mesh_position(vi);
#else
    const vec3 p = mesh_position_at_shutter(vi, mesh_flags);
#endif
    vec4 world = inst.model * vec4(p, 1.0);
    v_position = world.xyz;
#ifdef MOTION_PASS
    {
        vec3 p_previous = p, p_next = p;
        if ((mesh_flags & 8u) != 0u) {
            p_previous = motion_position(vi, 0u);
            p_next = motion_position(vi, 1u);
        }
        v_position_previous = (instance_motion[2u * instance] * vec4(p_previous, 1.0)).xyz;
        v_position_next = (instance_motion[2u * instance + 1u] * vec4(p_next, 1.0)).xyz;
    }
#endif
#ifdef SHADOW_PASS
    shadow_map_position(world);
#elif defined(EMISSION_BAKE)
    {
        const int tile = bake_tile_offset + int(triangle - bake_first_triangle);
        const float T = float(bake_layout.x);
        vec2 at = vec2(float(tile % bake_layout.y), float(tile / bake_layout.y)) * T;
        const uint c = corner % 3u;
        at += c == 1u ? vec2(T + 0.5, 0.0) : c == 2u ? vec2(0.0, T + 0.5) : vec2(0.0);
        gl_Position = vec4(at / vec2(bake_layout.zw) * 2.0 - 1.0, 0.0, 1.0);
    }
#else
    gl_Position = frame.projection * (frame.view * world);
#endif

    v_normal = vec3(0.0);
    vec3 n = vec3(0.0);
    if ((mesh_flags & 1u) != 0u) {
        n = mesh_corner_normal(corner);
        v_normal = mat3(inst.normal_matrix) * n;
#ifdef MATERIAL_GRAPH
        /* Cycles applies a single user's transform to the mesh and normalises
         * each vertex normal there, before interpolation: under non-uniform
         * scale that changes the interpolated direction (Texture Coordinate
         * Normal measured 3.3e-3 off without it). */
        v_normal = normalize(v_normal);
#endif
    }
#ifdef MATERIAL_GRAPH
    {
        const uint t0 = indices[3u * triangle], t1 = indices[3u * triangle + 1u], t2 = indices[3u * triangle + 2u];
        const vec3 p0 = mesh_position(t0), p1 = mesh_position(t1), p2 = mesh_position(t2);
        v_true_normal = mat3(inst.normal_matrix) * cross(p1 - p0, p2 - p0);
    }
    v_barycentric = vec2(corner % 3u == 0u ? 1.0 : 0.0, corner % 3u == 1u ? 1.0 : 0.0);
    v_object_position = p;
    v_object_normal = n;
#if MATERIAL_ATTRIBUTE_COUNT > 0
    for (int k = 0; k < MATERIAL_ATTRIBUTE_COUNT; ++k) v_attr[k] = mesh_corner_attribute(k, corner);
#endif
#ifdef MATERIAL_FLAT_ATTRIBUTE
    v_attr_flat = v_attr[MATERIAL_FLAT_ATTRIBUTE];
#endif
#endif
    v_uv = (mesh_flags & 2u) != 0u ? corner_uvs[corner] : vec2(0.0);
#ifdef GBUF_GEOMETRY
    {
        vec3 V[3], Nc[3];
        for (uint k = 0u; k < 3u; ++k) {
            const uint ck = 3u * triangle + k, vk = indices[ck];
            V[k] = mesh_position(vk);
            Nc[k] = (mesh_flags & 1u) != 0u ? mesh_corner_normal(ck) : vec3(0.0);
        }
        v_term_a = vec3(dot(V[1] - V[0], Nc[0]), dot(V[2] - V[0], Nc[0]), dot(V[0] - V[1], Nc[1]));
        v_term_b = vec3(dot(V[2] - V[1], Nc[1]), dot(V[0] - V[2], Nc[2]), dot(V[1] - V[2], Nc[2]));
        v_term_dir = mat3(inst.model) * n;
        v_term_bary = vec2(corner % 3u == 0u ? 1.0 : 0.0, corner % 3u == 1u ? 1.0 : 0.0);
        v_term_cutoff = (mesh_flags & 1u) != 0u ? inst.info.y : 0.0;
    }
#endif

    /* Slot -> material id through the instance's slot map; out-of-range slots
     * were rejected on upload, the clamp only guards against driver surprises. */
    int slot = (mesh_flags & 4u) != 0u ? material_indices[triangle] : 0;
    uint s = min(uint(max(slot, 0)), max(inst.ids.z, 1u) - 1u);
    v_material = material_slots[inst.ids.y + s];
#ifdef VISIBILITY_PASS
    v_slot_key = inst.ids.y + s;
#endif
    v_object_index = inst.ids.x;
    v_mirrored = inst.ids.w;
    v_instance = instance;
    v_triangle = triangle;
}
