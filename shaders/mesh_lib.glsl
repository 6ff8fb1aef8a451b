/* A mesh's buffers for vertex pulling (FrameScene::bind_mesh,
 * bind_attributes) and the fetches from them that the geometry pass's
 * vertex stage (geometry_vert.glsl) and the visibility buffer's resolve
 * (gbuffer_resolve_comp.glsl) share, so the two read a corner alike.
 * Positions are per vertex (through the index buffer), normals, UVs and
 * attributes per corner (Blender keeps split normals and UVs on loops). */
#ifndef MESH_LIB
#define MESH_LIB

layout(std430, binding = SSBO_POSITIONS) readonly buffer Positions { float positions[]; };
layout(std430, binding = SSBO_INDICES) readonly buffer Indices { uint indices[]; };
layout(std430, binding = SSBO_NORMALS) readonly buffer Normals { float corner_normals[]; };
layout(std430, binding = SSBO_UVS) readonly buffer Uvs { vec2 corner_uvs[]; };
/* A deforming mesh's previous then next vertex positions (mesh flag 8;
 * object space): the Vector pass reads them, motion blur interpolates them
 * at the sample's shutter time (frame.motion.w). */
layout(std430, binding = SSBO_MOTION_POSITIONS) readonly buffer MotionPositions { float motion_positions[]; };

vec3 mesh_position(uint vi) {  /* object space, as stored */
    return vec3(positions[3u * vi], positions[3u * vi + 1u], positions[3u * vi + 2u]);
}

vec3 motion_position(uint vi, uint step) {  /* step 0 previous, 1 next */
    const uint base = step * (uint(motion_positions.length()) / 2u) + 3u * vi;
    return vec3(motion_positions[base], motion_positions[base + 1u], motion_positions[base + 2u]);
}

/* Motion blur: the vertex at this sample's shutter time, linear between the
 * steps (Cycles' motion_triangle_verts_for_step); `flags` the mesh's. */
vec3 mesh_position_at_shutter(uint vi, uint flags) {
    vec3 p = mesh_position(vi);
    if ((flags & 8u) != 0u && frame.motion.w != 0.0) {
        const float r = frame.motion.w;
        p = mix(p, motion_position(vi, r < 0.0 ? 0u : 1u), abs(r));
    }
    return p;
}

vec3 mesh_corner_normal(uint corner) {
    return vec3(corner_normals[3u * corner], corner_normals[3u * corner + 1u], corner_normals[3u * corner + 2u]);
}

#ifdef MATERIAL_GRAPH
/* Node materials: the mesh's named per-corner attributes, one float array;
 * slot k of the material reads attribute_layout[k] = (offset in floats or -1
 * when the mesh lacks it, components). Values stay in object space. */
layout(std430, binding = SSBO_ATTRIBUTES) readonly buffer Attributes { float corner_attributes[]; };
layout(location = 3) uniform ivec4 attribute_layout[8];

/* Slot k's value at a corner: 0 where the mesh lacks it, else its
 * components with w 1; a float attribute fills every component. */
vec4 mesh_corner_attribute(int k, uint corner) {
    const ivec4 layout_k = attribute_layout[k];
    if (layout_k.x < 0) return vec4(0.0);
    vec4 a = vec4(0.0, 0.0, 0.0, 1.0);
    const int base = layout_k.x + int(corner) * layout_k.y;
    for (int c = 0; c < layout_k.y; ++c) a[c] = corner_attributes[base + c];
    if (layout_k.y == 1) a.xyz = vec3(a.x);
    return a;
}
#endif

#endif
