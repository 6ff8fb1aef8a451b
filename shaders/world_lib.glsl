/* The world as an environment map (HAS_WORLD_MAP): the world's node tree
 * baked into an equirectangular map (world_bake_comp.glsl), looked up along
 * a direction and importance-sampled by luminance.
 *
 * Mapping: Cycles' direction_to_equirectangular (kernel/camera/projection.h,
 * range (-2 pi, pi, -pi, pi)): u = (atan2(y, x) - pi) / -2pi,
 * v = (acos(z) - pi) / -pi, so v = 1 is straight up. Texel (i, j) of a W x H
 * map is centred at ((i + 0.5) / W, (j + 0.5) / H), as the texels of an
 * environment image of that size: a bilinear lookup of the bake is then
 * Cycles' Linear lookup of the image itself. Both axes repeat, as
 * Cycles' environment lookup does (IMG_EXTENSION_REPEAT).
 *
 * Sampling density (per solid angle), with f = WORLD_UNIFORM_FRACTION:
 *   p(w) = f / (4 pi) + (1 - f) P(texel) W H / (2 pi^2 sin(theta)),
 * P(texel) = P(row) P(column | row) from the CDFs below, built on the CPU
 * from luminance x sin(theta) of each texel (native/src/world_module.cpp);
 * inside a texel the point is uniform in (u, v), whence the 1 / sin(theta)
 * of the (u, v) -> solid-angle Jacobian 2 pi^2 sin(theta).
 *
 * world_cdf: the H + 1 row CDF values (0 .. 1), then per row j the W + 1
 * values of the column CDF inside that row, at H + 1 + j (W + 1). */
#ifndef WORLD_LIB
#define WORLD_LIB

/* A name of its own: the node library declares M_PI_F locally. */
#define WORLD_PI 3.14159265358979

layout(binding = TEX_WORLD_RADIANCE) uniform sampler2D world_radiance;
layout(binding = TEX_WORLD_CAMERA) uniform sampler2D world_camera;
layout(std430, binding = SSBO_WORLD_CDF) readonly buffer WorldCdf { float world_cdf[]; };

vec2 world_direction_to_uv(vec3 d) {
    float u = (atan(d.y, d.x) - WORLD_PI) / (-2.0 * WORLD_PI);
    /* acos(z) as atan2(|d.xy|, z): GPU acos is far less accurate (see
     * img_direction_to_equirectangular). */
    float v = (atan(length(d.xy), d.z) - WORLD_PI) / -WORLD_PI;
    return vec2(u, v);
}

vec3 world_uv_to_direction(vec2 uv) {
    float phi = WORLD_PI - 2.0 * WORLD_PI * uv.x;
    float theta = WORLD_PI * (1.0 - uv.y); /* from +Z */
    float s = sin(theta);
    return vec3(s * cos(phi), s * sin(phi), cos(theta));
}

/* Bilinear lookup with both axes repeating, weights in float: the
 * fixed-point weights of texture filtering (8 bits of sub-texel precision
 * are allowed, and llvmpipe uses them) would miss Cycles' Linear lookup by
 * up to 1/256 of a texel's contrast. */
vec3 world_lookup(sampler2D map, vec3 d) {
    ivec2 size = textureSize(map, 0);
    vec2 uv = world_direction_to_uv(d);
    vec2 x = uv * vec2(size) - 0.5;
    vec2 f = x - floor(x);
    ivec2 i0 = ivec2(floor(x));
    ivec2 i1 = i0 + 1;
    i0 = (i0 % size + size) % size;
    i1 = (i1 % size + size) % size;
    vec3 a = texelFetch(map, ivec2(i0.x, i0.y), 0).rgb, b = texelFetch(map, ivec2(i1.x, i0.y), 0).rgb;
    vec3 c = texelFetch(map, ivec2(i0.x, i1.y), 0).rgb, e = texelFetch(map, ivec2(i1.x, i1.y), 0).rgb;
    return mix(mix(a, b, f.x), mix(c, e, f.x), f.y);
}

/* Radiance of the world along unit direction d (towards the world). */
vec3 world_light_radiance(vec3 d) { return world_lookup(world_radiance, d); }
vec3 world_camera_radiance(vec3 d) { return world_lookup(world_camera, d); }

ivec2 world_map_size() { return ivec2(frame.world_occlusion.zw); }

/* The largest k in [0, n) with cdf[base + k] <= x (cdf[base] = 0 <= x < 1 = cdf[base + n]). */
int world_cdf_find(int base, int n, float x) {
    int lo = 0, hi = n;
    while (hi - lo > 1) {
        int mid = (lo + hi) >> 1;
        if (world_cdf[base + mid] <= x) lo = mid; else hi = mid;
    }
    return lo;
}

/* Luminance part of the density at direction d (per solid angle). */
float world_luminance_pdf(vec3 d) {
    ivec2 size = world_map_size();
    vec2 uv = world_direction_to_uv(d);
    int i = clamp(int(fract(uv.x) * float(size.x)), 0, size.x - 1);
    int j = clamp(int(uv.y * float(size.y)), 0, size.y - 1);
    float p_row = world_cdf[j + 1] - world_cdf[j];
    int row = size.y + 1 + j * (size.x + 1);
    float p_col = world_cdf[row + i + 1] - world_cdf[row + i];
    float s = sqrt(max(1.0 - d.z * d.z, 0.0));
    if (s <= 0.0) return 0.0;
    return p_row * p_col * float(size.x) * float(size.y) / (2.0 * WORLD_PI * WORLD_PI * s);
}

float world_pdf(vec3 d) {
    return WORLD_UNIFORM_FRACTION / (4.0 * WORLD_PI) + (1.0 - WORLD_UNIFORM_FRACTION) * world_luminance_pdf(d);
}

/* A direction with density world_pdf() from three uniform numbers. */
vec3 world_sample(vec3 r, out float pdf) {
    vec3 d;
    if (r.z < WORLD_UNIFORM_FRACTION) {
        float z = 1.0 - 2.0 * r.x, phi = 2.0 * WORLD_PI * r.y;
        float s = sqrt(max(1.0 - z * z, 0.0));
        d = vec3(s * cos(phi), s * sin(phi), z);
    } else {
        ivec2 size = world_map_size();
        int j = world_cdf_find(0, size.y, r.y);
        float y0 = world_cdf[j], y1 = world_cdf[j + 1];
        float fy = y1 > y0 ? clamp((r.y - y0) / (y1 - y0), 0.0, 1.0) : 0.5;
        int row = size.y + 1 + j * (size.x + 1);
        int i = world_cdf_find(row, size.x, r.x);
        float x0 = world_cdf[row + i], x1 = world_cdf[row + i + 1];
        float fx = x1 > x0 ? clamp((r.x - x0) / (x1 - x0), 0.0, 1.0) : 0.5;
        d = world_uv_to_direction(vec2((float(i) + fx) / float(size.x), (float(j) + fy) / float(size.y)));
    }
    pdf = world_pdf(d);
    return d;
}

#endif /* WORLD_LIB */
