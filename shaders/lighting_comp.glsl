/* Lighting pass: one invocation per pixel, every light (culling comes with
 * the many-lights work). Runs once per film sample (the projection is
 * jittered by the pixel filter, frame.sample_shift moves the light-shape
 * points) and adds 1/samples of (emission + direct light) to the Combined
 * accumulation; optionally accumulates the diffuse and glossy light apart
 * for the DiffDir/GlossDir passes. Variants: HAS_<TYPE>_LIGHTS for the
 * light types present, GBUF_PARAMS1, OUT_LIGHT_SPLIT; FORWARD_LAYER when
 * Blend-mode surfaces were drawn in front this sample (forward_module.h). */
#define LIGHTING_PASS
#include "lighting_lib.glsl"

layout(local_size_x = LIGHTING_GROUP_SIZE, local_size_y = LIGHTING_GROUP_SIZE) in;

/* This dispatch shades entries [x, y) of each pixel's light sequence (its
 * tile's list, or every light). The host splits the lights into batches so
 * no invocation runs more than a bounded number of loop iterations: Mesa's
 * llvmpipe silently ends every loop of an invocation after 65535 iterations
 * in total (LP_MAX_TGSI_LOOP_ITERATIONS), which would drop lights. Emission,
 * world light and background belong to the batch starting at 0. */
layout(location = 0) uniform uvec2 light_batch;

/* The batches after the first run only over the pixels that need them
 * (later_from_list): the first appends each pixel whose light sequence
 * goes on past it (not a background or holdout pixel, nor one whose tile
 * list fits the batch) to this list, with an indirect dispatch's group
 * counts (xyz; w the pixels; later_totals.x the pixels listed over the
 * frame's samples, FrameTimings::lighting_later_pixels): entry k is invocation k % 64 of group k / 64,
 * laid out LATER_GROUPS_PER_ROW groups a row (a dimension holds at least
 * 65535 groups), and later batches run one invocation per entry. A
 * dispatch over the whole image per batch cost llvmpipe ~25 ms at 480x270
 * however early each invocation returned (20 of them for 10 000 lights).
 * Without the list (an image whose list would not fit one storage block)
 * every batch covers the image. */
#define LATER_GROUPS_PER_ROW 1024u
layout(location = 2) uniform bool later_from_list;
layout(std430, binding = SSBO_LIGHTING_LATER) buffer LaterPixels {
    uvec4 later_dispatch;
    uvec4 later_totals;
    uint later_pixels[];
};

#ifdef LIGHT_SAMPLING
/* Stochastic light selection (RenderSettings::light_samples, the define's
 * value M): where a pixel's part of the batch holds more than M lights
 * (suns and emissive meshes apart, always shaded), each light i is shaded
 * this sample with probability p_i = min(1, M e_i / sum e) and weight 1 / p_i,
 * e_i its light_importance, so the sum's expectation is every light's sum
 * (unbiased, converging over the film's samples as Cycles' one light sample
 * per path does). The choice is systematic sampling along the running sum
 * of the p_i with one uniform per pixel and sample (Madow 1949): light i is
 * taken when that sum crosses an integer within its p_i, so each light has
 * exactly its probability, at most M (+ 1 from rounding) lights are taken,
 * and strong lights (p_i = 1) are shaded every sample. The chosen lights go to a short list
 * that the shading loop runs over: SIMD lanes (a GPU warp, llvmpipe's
 * vectors) run a loop as long as its longest lane, so skipping lights inside
 * the full loop would save nothing. */
#define LIGHT_SLOTS_ALWAYS 16
#define LIGHT_SLOTS (LIGHT_SAMPLING + 1 + LIGHT_SLOTS_ALWAYS)

/* A rough share of the light `light` gives P (normal N): radiant intensity
 * over squared distance, times how far it stands above P's horizon; never 0
 * for a light that can reach P (a floor of 5 % keeps the estimate unbiased
 * where the rough share is wrong: bumped or glossy lobes, spot cones seen
 * from within the light's radius). 0 for the lights shaded every sample. */
float light_importance(GpuLight light, vec3 P, vec3 N) {
    const int type = int(light.position_type.w);
    if (type == LIGHT_SUN || type == LIGHT_MESH) return 0.0;
    vec3 d = light.position_type.xyz - P;
    float d2 = dot(d, d);
    float inv_d = inversesqrt(max(d2, 1e-20));
    float size2 = type == LIGHT_AREA ? dot(light.axis_x.xyz, light.axis_x.xyz) + dot(light.axis_y.xyz, light.axis_y.xyz)
                                     : light.strength.w * light.strength.w;
    float sin_r = min(sqrt(size2) * inv_d, 1.0); /* ~ sine of the light's angular radius */
    float facing = clamp(dot(N, d) * inv_d + sin_r, 0.0, 1.0);
    float power = max(dot(light.strength.rgb, vec3(0.2126729, 0.7151522, 0.0721750)), 0.0);
    /* Radiant intensity towards P: a point or spot light's power over 4 pi,
     * a one-sided area light's over pi times its cosine. */
    float intensity = power * (0.25 * M_1_PI_F);
    if (type == LIGHT_AREA) intensity = power * M_1_PI_F * max(-dot(light.direction.xyz, d) * inv_d + sin_r, 0.05);
    if (type == LIGHT_SPOT && -dot(light.direction.xyz, d) * inv_d + sin_r < light.direction.w) intensity *= 0.05;
    return max(intensity * (0.05 + facing) / max(d2 + size2, 1e-20), 1e-30);
}

/* One number in [0, 1) per pixel, film sample and batch: the first
 * dimension of the R3 sequence over the samples (stratified; Roberts 2018,
 * alpha = 1/phi3), rotated per pixel and batch. Not the golden-ratio step:
 * the Mix Shader's choice (sample_shift.z) steps by it, and a selection
 * shifted from it by a constant per pixel would take each light only with
 * one of the mix's alternatives, a bias per pixel. */
float light_selection_offset(ivec2 pixel) {
    uvec4 v = uvec4(uvec2(pixel), light_batch.x * 0x9E3779B9u + 0x68E31DA4u, 0xB5297A4Du);
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    uint x = v.x + uint(frame.sample_shift.w) * 0xD1B54A32u;
    return float(x >> 8u) * (1.0 / 16777216.0);
}
#endif

#ifdef LIGHT_CULLING
layout(std430, binding = SSBO_TILES) readonly buffer Tiles { GpuTile tiles[]; };
layout(std430, binding = SSBO_TILE_LIGHTS) readonly buffer TileLights { uint tile_lights[]; };
#endif

/* Entry k of the pixel's light sequence: its tile's list (from `first`),
 * or every light. */
uint light_entry(uint k, bool from_list, uint first) {
#ifdef LIGHT_CULLING
    return from_list ? tile_lights[first + k] : k;
#else
    return k;
#endif
}

layout(binding = TEX_GBUF_EMISSION) uniform sampler2D gbuf_emission;
layout(binding = TEX_GBUF_BASE) uniform sampler2D gbuf_base;
layout(binding = TEX_GBUF_PARAMS0) uniform sampler2D gbuf_params0;
layout(binding = TEX_GBUF_NORMAL) uniform usampler2D gbuf_normal; /* packUnorm2x16 of the octahedral normal */
#ifdef GBUF_PARAMS1
layout(binding = TEX_GBUF_PARAMS1) uniform sampler2D gbuf_params1;
#endif
#ifdef GBUF_GEOMETRY
layout(binding = TEX_GBUF_GEOMETRY) uniform usampler2D gbuf_geometry;
#endif
#ifdef FORWARD_LAYER
/* This sample's Blend-mode layers over the pixel: rgb their light
 * (premultiplied, composited back to front), a the transmittance left for
 * what is behind them. */
layout(binding = TEX_FORWARD_LAYER) uniform sampler2D forward_layer;
#endif

#ifdef LIGHT_GROUPS
/* Light groups (LIGHT_GROUPS of them): each light's, each emissive
 * surface's and the world's light also goes to its group's layer (Cycles'
 * Combined_<group> passes; the groups' sum is Combined where every source
 * has a group). */
layout(std430, binding = SSBO_LIGHT_GROUPS) readonly buffer LightGroups { uint light_groups[]; };
layout(std430, binding = SSBO_INSTANCE_GROUPS) readonly buffer InstanceGroups { uint instance_groups[]; };
layout(binding = TEX_GBUF_IDS) uniform usampler2D gbuf_ids; /* z: instance (GBUF_INSTANCE_IDS) */
layout(binding = IMG_LIGHT_GROUPS, rgba32f) uniform image2DArray group_images;
layout(location = 1) uniform uint world_group;
vec3 group_sums[LIGHT_GROUPS];
void add_to_group(uint group, vec3 value) {
    if (group > 0u && group <= uint(LIGHT_GROUPS)) group_sums[group - 1u] += value;
}
/* This invocation's group sums added to the layers, seen through the Blend
 * layers in front (their own light is in no group). */
void store_groups(ivec2 pixel, float share) {
    float T = 1.0;
#ifdef FORWARD_LAYER
    T = texelFetch(forward_layer, pixel, 0).a;
#endif
    for (int g = 0; g < LIGHT_GROUPS; ++g) {
        if (group_sums[g] == vec3(0.0)) continue;
        ivec3 at = ivec3(pixel, g);
        imageStore(group_images, at, imageLoad(group_images, at) + vec4(group_sums[g] * (T * share), 0.0));
    }
}
#endif

layout(binding = IMG_FILM, rgba32f) uniform image2D film;
#ifdef OUT_SHADOW
layout(binding = IMG_SHADOW, rgba32f) uniform image2D shadow_light;
#endif
#ifdef OUT_AO
layout(binding = IMG_AO, rgba32f) uniform image2D ao_image;
#endif
#ifdef OUT_LIGHT_SPLIT
layout(binding = IMG_DIFF_LIGHT, rgba32f) uniform image2D diffuse_light;
layout(binding = IMG_GLOSS_LIGHT, rgba32f) uniform image2D glossy_light;
#endif
#ifdef SHADOW_CATCHER
/* Cycles' shadow catcher (kernel/integrator/shadow_catcher.h): a camera ray's
 * first hit on a catcher splits the path. The matte path goes on as if the
 * catcher were transparent: Combined (Blender's, the matte pass) gets a hole
 * there. The hit path shades the catcher with every shadow, the pass path
 * with only catchers occluding; the Shadow Catcher pass is their ratio
 * (passes_comp.glsl RESOLVE_CATCHER). Here the pass path's light is the
 * unshadowed light (the catcher's own shadows on itself are not kept apart
 * from the others'). */
layout(binding = IMG_CATCHER_HIT, rgba32f) uniform image2D catcher_hit;
layout(binding = IMG_CATCHER_PASS, rgba32f) uniform image2D catcher_pass;
#endif

/* What this sample shows of `value` (the opaque surface or the background)
 * through the Blend-mode layers in front of it, plus the layers themselves
 * (added once, with the first light batch): value T + layer, alpha
 * a T + (1 - T). Without such layers, the value. */
vec4 behind_forward_layer(ivec2 pixel, vec4 value, bool first_batch) {
#ifdef FORWARD_LAYER
    vec4 layer = texelFetch(forward_layer, pixel, 0);
    return value * layer.a + (first_batch ? vec4(layer.rgb, 1.0 - layer.a) : vec4(0.0));
#else
    return value;
#endif
}

/* Light i's shadowed light this sample and its unshadowed light (the
 * Shadow pass's denominator, the catchers' unshadowed light), added to the
 * pixel's sums. */
void add_to_sums(uint i, LightContribution shadowed, LightContribution unshadowed, inout LightContribution total,
                 inout float lum_shadowed, inout float lum_unshadowed, inout vec3 catcher_unshadowed) {
    const vec3 luminance = vec3(0.2126729, 0.7151522, 0.0721750);
    total.diffuse += shadowed.diffuse;
    total.glossy += shadowed.glossy;
#ifdef LIGHT_GROUPS
    add_to_group(light_groups[i], shadowed.diffuse + shadowed.glossy);
#endif
#ifdef OUT_SHADOW
    lum_unshadowed += dot(unshadowed.diffuse + unshadowed.glossy, luminance);
    lum_shadowed += dot(shadowed.diffuse + shadowed.glossy, luminance);
#endif
#ifdef SHADOW_CATCHER
    catcher_unshadowed += unshadowed.diffuse + unshadowed.glossy;
#endif
}

/* Light i's contribution this sample, times `weight` (the inverse of its
 * selection probability), added to the pixel's sums; `kind` a literal (only
 * that kind's code) or LIGHT_ANY_KIND. */
void add_light(int kind, uint i, float weight, SurfaceParams s, PrincipledWeights w, vec3 P, vec3 N, vec3 V,
               inout LightContribution total, inout float lum_shadowed, inout float lum_unshadowed,
               inout vec3 catcher_unshadowed) {
    float visible;
#ifdef MESH_RAY_POOL
    mesh_ray_pool_light = i;
    mesh_ray_pool_weight = weight;
#endif
    LightContribution c = shade_light_kind(kind, lights[i], s, w, P, N, V, visible);
    c.diffuse = c.diffuse * weight * visible;
    c.glossy = c.glossy * weight * visible;
    last_unshadowed.diffuse *= weight;
    last_unshadowed.glossy *= weight;
    add_to_sums(i, c, last_unshadowed, total, lum_shadowed, lum_unshadowed, catcher_unshadowed);
}

void main() {
    const bool first_batch = light_batch.x == 0u;
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (!first_batch && later_from_list) {
        const uint group = gl_WorkGroupID.y * LATER_GROUPS_PER_ROW + gl_WorkGroupID.x;
        const uint entry = group * uint(LIGHTING_GROUP_SIZE * LIGHTING_GROUP_SIZE) + gl_LocalInvocationIndex;
        if (entry >= later_dispatch.w) return;
        const uint entry_pixel = later_pixels[entry];
        pixel = ivec2(entry_pixel & 0xffffu, entry_pixel >> 16u);
    }
    if (any(greaterThanEqual(pixel, ivec2(frame.viewport.xy)))) return;
    lighting_pixel = uvec2(pixel);
#ifdef LIGHT_GROUPS
    for (int g = 0; g < LIGHT_GROUPS; ++g) group_sums[g] = vec3(0.0);
#endif

    /* Each sample adds its share (1/samples) to the accumulations. */
    float share = 1.0 / float(max(frame.counts.w, 1u));
    float depth = texelFetch(gbuf_depth, pixel, 0).r;
    if (depth <= 0.0) {
        if (!first_batch) return;
        /* Background: the world along this sample's ray through the pixel
         * (the pixel filter's jitter is in the projection), or transparent
         * (Cycles film_transparent). */
        bool transparent = frame.world_color.w > 0.5;
#ifdef HAS_WORLD_MAP
        vec3 world = world_camera_radiance(-frame_view_vector(frame_position_from_depth(pixel, 0.5)));
#else
        vec3 world = frame.world_color.rgb;
#endif
        vec4 bg = transparent ? vec4(0.0) : vec4(world, 1.0);
        imageStore(film, pixel, imageLoad(film, pixel) + behind_forward_layer(pixel, bg, true) * share);
#ifdef LIGHT_GROUPS
        add_to_group(world_group, bg.rgb);
        store_groups(pixel, share);
#endif
        return;
    }

    /* A holdout (geometry_frag.glsl writes emission.a 0): a hole, black with
     * alpha 0 behind whatever Blend-mode layers lie in front of it. */
    vec4 emission = texelFetch(gbuf_emission, pixel, 0);
    if (emission.a <= 0.0) {
        if (first_batch)
            imageStore(film, pixel, imageLoad(film, pixel) + behind_forward_layer(pixel, vec4(0.0), true) * share);
        return;
    }

    /* The tile's list when this sample's point lies inside the depth range
     * and occupied bins the list was culled for, every light otherwise (a
     * jittered sample can see a sliver no pixel centre saw). */
    uint first = 0u, count = frame.counts.x;
    bool from_list = false;
#ifdef LIGHT_CULLING
    GpuTile tile = tiles[(uint(pixel.y) / uint(TILE_SIZE)) * frame.tiles.x + uint(pixel.x) / uint(TILE_SIZE)];
    float d = frame_view_depth_from_buffer(pixel, depth);
    if (tile.list.w != 0u && d >= tile.depth.x && d <= tile.depth.y &&
        ((tile.list.z >> depth_bin(d, tile.depth.x, tile.depth.y)) & 1u) != 0u) {
        first = tile.list.x;
        count = tile.list.y;
        from_list = true;
    }
#endif
    if (first_batch && later_from_list && count > light_batch.y) {
        const uint entry = atomicAdd(later_dispatch.w, 1u);
        later_pixels[entry] = uint(pixel.x) | (uint(pixel.y) << 16u);
        atomicAdd(later_totals.x, 1u);
        const uint group = entry / uint(LIGHTING_GROUP_SIZE * LIGHTING_GROUP_SIZE);
        if (entry % uint(LIGHTING_GROUP_SIZE * LIGHTING_GROUP_SIZE) == 0u) {
            atomicMax(later_dispatch.x, min(group + 1u, LATER_GROUPS_PER_ROW));
            atomicMax(later_dispatch.y, group / LATER_GROUPS_PER_ROW + 1u);
        }
    }
    if (!first_batch && light_batch.x >= min(count, light_batch.y)) return;

    vec4 params1 = vec4(0.0);
#ifdef GBUF_PARAMS1
    params1 = texelFetch(gbuf_params1, pixel, 0);
#endif
    SurfaceParams s = gbuffer_unpack(texelFetch(gbuf_base, pixel, 0), texelFetch(gbuf_params0, pixel, 0), params1,
                                     unpackUnorm2x16(texelFetch(gbuf_normal, pixel, 0).r));
#ifdef GBUF_GEOMETRY
    gbuffer_unpack_geometry(s, texelFetch(gbuf_geometry, pixel, 0));
#endif
    PrincipledWeights w = principled_weights(s);
    vec3 P = frame_position_from_depth(pixel, depth);
    vec3 V = frame_view_vector(P);
    vec3 N = s.N;

    LightContribution total;
    total.diffuse = vec3(0.0);
    total.glossy = vec3(0.0);
    float ao = 1.0;
    if (first_batch) total = world_light(w, s, P, N, V, pixel, ao);
#ifdef LIGHT_GROUPS
    if (first_batch) add_to_group(world_group, total.diffuse + total.glossy);
#endif
#ifdef OUT_AO
    if (first_batch) imageStore(ao_image, pixel, imageLoad(ao_image, pixel) + vec4(vec3(ao), 0.0) * share);
#endif
    float lum_shadowed = 0.0, lum_unshadowed = 0.0;
    vec3 catcher_unshadowed = vec3(0.0);
#ifdef MESH_RAY_POOL
    mesh_ray_pool_start();
#endif
#ifdef SHADOW_CATCHER
    const bool catcher = emission.a > 1.5;
    if (catcher && first_batch) catcher_unshadowed = last_world_unoccluded.diffuse + last_world_unoccluded.glossy;
#endif
    const uint end = min(count, light_batch.y);
    uint iterations = end > light_batch.x ? end - light_batch.x : 0u;
#ifdef LIGHT_SAMPLING
    uint chosen[LIGHT_SLOTS];
    float chosen_weight[LIGHT_SLOTS];
    float importance_sum = 0.0;
    uint candidates = 0u, always = 0u;
    /* A pixel whose part of the batch holds no more lights than the budget
     * shades them all: no pass over them to sum. */
    for (uint k = light_batch.x; iterations > uint(LIGHT_SAMPLING) && k < end; ++k) {
        uint i = light_entry(k, from_list, first);
        float e = light_importance(lights[i], P, N);
        importance_sum += e;
        if (e > 0.0) ++candidates;
        else ++always;
    }
    /* Too many lights shaded every sample for the list, or an importance
     * that is not finite: every light. */
    const bool selecting = candidates > uint(LIGHT_SAMPLING) && always <= uint(LIGHT_SLOTS_ALWAYS) &&
                           !isinf(importance_sum) && !isnan(importance_sum);
    if (selecting) {
        /* The running sum in fixed point (2^22 per unit; at most 512 units):
         * each light's probability is its quantised q / 2^22 (at least one
         * step, never 0) and its weight exactly the inverse, so the rounding
         * of a float sum cannot bias the lights with tiny p. */
        const float unit = 4194304.0;
        const float budget_scale = float(LIGHT_SAMPLING) / importance_sum;
        const uint comb = uint(light_selection_offset(pixel) * unit);
        uint running = 0u;
        uint n = 0u;
        for (uint k = light_batch.x; k < end && n < uint(LIGHT_SLOTS); ++k) {
            uint i = light_entry(k, from_list, first);
            float e = light_importance(lights[i], P, N);
            float weight = 1.0;
            if (e > 0.0) {
                uint q = max(uint(min(e * budget_scale, 1.0) * unit + 0.5), 1u);
                uint before = (running + comb) >> 22u;
                running += q;
                weight = ((running + comb) >> 22u) != before ? unit / float(q) : 0.0; /* 0: not this sample */
            }
            if (weight > 0.0) {
                chosen[n] = i;
                chosen_weight[n] = weight;
                ++n;
            }
        }
        iterations = n;
    }
#endif
#ifdef LIGHT_SAMPLING
#define SEQUENCE_LIGHT(j) (selecting ? chosen[j] : light_entry(light_batch.x + (j), from_list, first))
#define SEQUENCE_WEIGHT(j) (selecting ? chosen_weight[j] : 1.0)
#else
#define SEQUENCE_LIGHT(j) light_entry(light_batch.x + (j), from_list, first)
#define SEQUENCE_WEIGHT(j) 1.0
#endif
    /* LIGHT_KIND_LOOPS (LightingStage::Config::kind_loops, llvmpipe): one
     * loop per light kind, its body holding only that kind's code
     * (shade_light_kind with a literal kind), over the sequence LightModule
     * packs in kind order; a kind's loop ends at the first entry of another
     * kind. On llvmpipe a loop body costs all the code it holds, whatever
     * branch a light takes (light_lib.glsl, is_kind): one loop over every
     * kind's code cost the showcase's seven lights 765 ms at 320x180 and 4
     * samples, of which 620 ms remained with every light returning at once.
     * A GPU skips the branches its lanes do not take: one loop. */
#define SHADE_KIND(KIND) \
    for (; j < iterations; ++j) { \
        const uint i = SEQUENCE_LIGHT(j); \
        if (light_kind(int(lights[i].position_type.w)) != KIND) break; \
        add_light(KIND, i, SEQUENCE_WEIGHT(j), s, w, P, N, V, total, lum_shadowed, lum_unshadowed, catcher_unshadowed); \
    }
    uint j = 0u;
#ifdef LIGHT_KIND_LOOPS
#if defined(HAS_POINT_LIGHTS) || defined(HAS_SPOT_LIGHTS)
    SHADE_KIND(LIGHT_POINT)
#endif
#ifdef HAS_SUN_LIGHTS
    SHADE_KIND(LIGHT_SUN)
#endif
#ifdef HAS_AREA_LIGHTS
    SHADE_KIND(LIGHT_AREA)
#endif
#ifdef HAS_MESH_LIGHTS
    SHADE_KIND(LIGHT_MESH)
#endif
#else
    /* Every light with every kind's code (GPUs, and culled frames, whose
     * tile lists come in the culling's atomic order, kinds mixed). */
    for (; j < iterations; ++j)
        add_light(LIGHT_ANY_KIND, SEQUENCE_LIGHT(j), SEQUENCE_WEIGHT(j), s, w, P, N, V, total, lum_shadowed,
                  lum_unshadowed, catcher_unshadowed);
#endif
#ifdef MESH_RAY_POOL
    {
        /* The mesh lights' one ray (light_lib.glsl): their traced light, to
         * the picked candidate's light group; as every mesh light's, its
         * unshadowed light for the Shadow pass is the shadowed. */
        const LightContribution m = reservoir_trace(mesh_ray_pool, s, P);
        add_to_sums(mesh_ray_pool.owner, m, m, total, lum_shadowed, lum_unshadowed, catcher_unshadowed);
    }
#endif

    if (!first_batch) emission = vec4(0.0);
#ifdef SHADOW_CATCHER
    if (catcher) {
        /* Both split paths shade the catcher's emission too. Its light
         * reaches no light pass and no light group, as in Cycles. */
        const vec3 shadowed = emission.rgb + total.diffuse + total.glossy;
        imageStore(catcher_hit, pixel, imageLoad(catcher_hit, pixel) +
                                           vec4(shadowed, first_batch ? 1.0 : 0.0) * share);
        imageStore(catcher_pass, pixel, imageLoad(catcher_pass, pixel) +
                                            vec4(emission.rgb + catcher_unshadowed, 0.0) * share);
        if (first_batch)
            imageStore(film, pixel, imageLoad(film, pixel) + behind_forward_layer(pixel, vec4(0.0), true) * share);
        return;
    }
#endif
#ifdef LIGHT_GROUPS
    add_to_group(instance_groups[texelFetch(gbuf_ids, pixel, 0).z], emission.rgb);
    store_groups(pixel, share);
#endif
    /* Emission sub-samples (emission_samples.h) add the rest of it. */
    vec4 sample_value = vec4(emission.rgb * directly_seen_emission_share(emission) + total.diffuse + total.glossy,
                             emission.a);
    imageStore(film, pixel, imageLoad(film, pixel) + behind_forward_layer(pixel, sample_value, first_batch) * share);
#ifdef OUT_SHADOW
    imageStore(shadow_light, pixel, imageLoad(shadow_light, pixel) + vec4(lum_shadowed, lum_unshadowed, 0.0, 0.0) * share);
#endif
#ifdef OUT_LIGHT_SPLIT
    imageStore(diffuse_light, pixel, imageLoad(diffuse_light, pixel) + vec4(total.diffuse * share, 0.0));
    imageStore(glossy_light, pixel, imageLoad(glossy_light, pixel) + vec4(total.glossy * share, 0.0));
#endif
}
