/* Tiled light culling (Olsson & Assarsson 2011) with 2.5D depth masks
 * (Harada 2012), one TILE_SIZE^2 workgroup per screen tile.
 *
 * 1. The tile's depth bounds and a 32-bin occupancy mask come from the
 *    pixels of the tile widened by the pixel filter's reach (frame.tiles.w):
 *    a jittered film sample of a pixel sees what sample 0 sees up to that
 *    many pixels away.
 * 2. Every light whose influence sphere (GpuLight.params.z; suns: infinite)
 *    touches the tile's frustum between those depths, and whose depth range
 *    hits an occupied bin, is kept.
 * CULL_COUNT: counts the tile's lights and reserves room for them with one
 * atomicAdd on a global counter (the index buffer grows with the scene; there
 * is no per-tile cap). CULL_WRITE: runs the same test and writes the indices.
 * The lighting pass falls back to every light for a pixel whose depth is
 * outside its tile's bounds or bins, so the result never depends on culling
 * being conservative enough. */
#include "frame_lib.glsl"

layout(local_size_x = TILE_SIZE, local_size_y = TILE_SIZE) in;

layout(binding = TEX_DEPTH) uniform sampler2D gbuf_depth;
layout(std430, binding = SSBO_LIGHTS) readonly buffer Lights { GpuLight lights[]; };
layout(std430, binding = SSBO_TILES) buffer Tiles { GpuTile tiles[]; };
layout(std430, binding = SSBO_TILE_LIGHTS) buffer TileLights { uint tile_lights[]; };
layout(std430, binding = SSBO_CULL_COUNTER) buffer CullCounter { uint total_indices; uint capacity; };

shared uint s_min_depth, s_max_depth, s_mask, s_count, s_offset;

/* Positive view depth of a pixel of sample 0, or -1 for background. */
float pixel_view_depth(ivec2 p) {
    float depth = texelFetch(gbuf_depth, p, 0).r;
    if (depth <= 0.0) return -1.0;
    return frame_view_depth_from_buffer(p, depth);
}

/* Plane through the origin-side rays of two screen points (view space). */
vec3 view_ray(vec2 pixel_pos, float view_depth) {
    vec2 ndc = pixel_pos * frame.viewport.zw * 2.0 - 1.0;
    /* Any depth works: take the point on the ray at unit NDC depth, then scale. */
    vec4 a = frame.inv_projection * vec4(ndc, 0.5, 1.0);
    a /= a.w;
    vec4 b = frame.inv_projection * vec4(ndc, 0.25, 1.0);
    b /= b.w;
    /* Point of the ray a->b at view depth `view_depth` (-z). */
    float t = (view_depth + a.z) / (a.z - b.z);
    return a.xyz + (b.xyz - a.xyz) * t;
}

vec4 plane_from_points(vec3 p0, vec3 p1, vec3 p2, vec3 inside) {
    vec3 n = normalize(cross(p1 - p0, p2 - p0));
    vec4 plane = vec4(n, -dot(n, p0));
    if (dot(plane.xyz, inside) + plane.w < 0.0) plane = -plane;
    return plane;
}

void main() {
    const uvec2 tile_id = gl_WorkGroupID.xy;
    const uint tile_index = tile_id.y * frame.tiles.x + tile_id.x;
    const int reach = int(frame.tiles.w);
    const ivec2 size = ivec2(frame.viewport.xy);
    if (gl_LocalInvocationIndex == 0u) {
#ifdef CULL_WRITE
        /* The count pass stored the bounds and mask: no need to read depth again. */
        GpuTile t = tiles[tile_index];
        s_min_depth = floatBitsToUint(t.depth.x);
        s_max_depth = floatBitsToUint(t.depth.y);
        s_mask = t.list.z;
        if (t.list.w == 0u) { s_min_depth = 0x7f7fffffu; s_max_depth = 0u; }
#else
        s_min_depth = 0x7f7fffffu; /* FLT_MAX bits: positive floats order like uints */
        s_max_depth = 0u;
        s_mask = 0u;
#endif
        s_count = 0u;
    }
    barrier();

#ifdef CULL_COUNT
    /* 1. Depth bounds over the widened tile. */
    ivec2 lo = ivec2(tile_id) * TILE_SIZE - reach;
    ivec2 hi = min(ivec2(tile_id + 1u) * TILE_SIZE + reach, size);
    lo = max(lo, ivec2(0));
    for (int y = lo.y + int(gl_LocalInvocationID.y); y < hi.y; y += TILE_SIZE)
        for (int x = lo.x + int(gl_LocalInvocationID.x); x < hi.x; x += TILE_SIZE) {
            float d = pixel_view_depth(ivec2(x, y));
            if (d >= 0.0) {
                atomicMin(s_min_depth, floatBitsToUint(d));
                atomicMax(s_max_depth, floatBitsToUint(d));
            }
        }
    barrier();
    {
        const bool any = s_max_depth != 0u || s_min_depth != 0x7f7fffffu;
        const float lo_d = uintBitsToFloat(s_min_depth), hi_d = uintBitsToFloat(s_max_depth);
        if (any) {
            for (int y = lo.y + int(gl_LocalInvocationID.y); y < hi.y; y += TILE_SIZE)
                for (int x = lo.x + int(gl_LocalInvocationID.x); x < hi.x; x += TILE_SIZE) {
                    float d = pixel_view_depth(ivec2(x, y));
                    if (d >= 0.0) atomicOr(s_mask, 1u << depth_bin(d, lo_d, hi_d));
                }
        }
    }
    barrier();
#endif
    const bool has_geometry = s_max_depth != 0u || s_min_depth != 0x7f7fffffu;
    const float dmin = uintBitsToFloat(s_min_depth), dmax = uintBitsToFloat(s_max_depth);

    /* 2. The tile's frustum: four side planes through the widened tile's
     * corner rays (valid for perspective and orthographic cameras). */
    vec2 c0 = vec2(ivec2(tile_id) * TILE_SIZE - reach);
    vec2 c1 = vec2(ivec2(tile_id + 1u) * TILE_SIZE + reach);
    vec3 n00 = view_ray(vec2(c0.x, c0.y), 1.0), f00 = view_ray(vec2(c0.x, c0.y), 2.0);
    vec3 n10 = view_ray(vec2(c1.x, c0.y), 1.0), f10 = view_ray(vec2(c1.x, c0.y), 2.0);
    vec3 n11 = view_ray(vec2(c1.x, c1.y), 1.0), f11 = view_ray(vec2(c1.x, c1.y), 2.0);
    vec3 n01 = view_ray(vec2(c0.x, c1.y), 1.0), f01 = view_ray(vec2(c0.x, c1.y), 2.0);
    vec3 inside = 0.25 * (n00 + n10 + n11 + n01);
    vec4 planes[4];
    planes[0] = plane_from_points(n00, f00, n01, inside);
    planes[1] = plane_from_points(n10, f10, n11, inside);
    planes[2] = plane_from_points(n00, f00, n10, inside);
    planes[3] = plane_from_points(n01, f01, n11, inside);
    const uint mask = s_mask;

#ifdef CULL_WRITE
    const uint offset = tiles[tile_index].list.x;
#endif
    if (has_geometry) {
        for (uint i = gl_LocalInvocationIndex; i < frame.counts.x; i += uint(TILE_SIZE * TILE_SIZE)) {
            GpuLight light = lights[i];
            float radius = light.params.z;
            bool keep = true;
            if (radius >= 0.0) {
                vec3 c = (frame.view * vec4(light.position_type.xyz, 1.0)).xyz;
                float d = -c.z;
                keep = d + radius >= dmin && d - radius <= dmax;
                for (int k = 0; k < 4 && keep; ++k) keep = dot(planes[k].xyz, c) + planes[k].w >= -radius;
                if (keep) {
                    uint b0 = depth_bin(d - radius, dmin, dmax), b1 = depth_bin(d + radius, dmin, dmax);
                    uint light_mask = (b1 >= 31u ? 0xffffffffu : ((1u << (b1 + 1u)) - 1u)) & ~((1u << b0) - 1u);
                    keep = (light_mask & mask) != 0u;
                }
            }
            if (keep) {
                uint slot = atomicAdd(s_count, 1u);
#ifdef CULL_WRITE
                if (offset + slot < capacity) tile_lights[offset + slot] = i;
#endif
            }
        }
    }
    barrier();
#ifdef CULL_COUNT
    if (gl_LocalInvocationIndex == 0u) {
        uint reserved = atomicAdd(total_indices, s_count);
        tiles[tile_index].list = uvec4(reserved, s_count, mask, has_geometry ? 1u : 0u);
        tiles[tile_index].depth = vec4(dmin, dmax, 0.0, 0.0);
    }
#endif
}
