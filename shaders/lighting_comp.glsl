/* Lighting pass: one invocation per pixel, every light (culling comes with
 * the many-lights work). Runs once per film sample (the projection is
 * jittered by the pixel filter, frame.sample_shift moves the light-shape
 * points) and adds 1/samples of (emission + direct light) to the Combined
 * accumulation; optionally accumulates the diffuse and glossy light apart
 * for the DiffDir/GlossDir passes. Variants: HAS_<TYPE>_LIGHTS for the
 * light types present, GBUF_PARAMS1, OUT_LIGHT_SPLIT. */
#include "frame_lib.glsl"
#include "gbuffer_lib.glsl"
#include "light_lib.glsl"

layout(local_size_x = LIGHTING_GROUP_SIZE, local_size_y = LIGHTING_GROUP_SIZE) in;

/* This dispatch shades entries [x, y) of each pixel's light sequence (its
 * tile's list, or every light). The host splits the lights into batches so
 * no invocation runs more than a bounded number of loop iterations: Mesa's
 * llvmpipe silently ends every loop of an invocation after 65535 iterations
 * in total (LP_MAX_TGSI_LOOP_ITERATIONS), which would drop lights. Emission,
 * world light and background belong to the batch starting at 0. */
layout(location = 0) uniform uvec2 light_batch;

layout(std430, binding = SSBO_LIGHTS) readonly buffer Lights { GpuLight lights[]; };
#ifdef LIGHT_CULLING
layout(std430, binding = SSBO_TILES) readonly buffer Tiles { GpuTile tiles[]; };
layout(std430, binding = SSBO_TILE_LIGHTS) readonly buffer TileLights { uint tile_lights[]; };
#endif

layout(binding = TEX_DEPTH) uniform sampler2D gbuf_depth;
layout(binding = TEX_GBUF_EMISSION) uniform sampler2D gbuf_emission;
layout(binding = TEX_GBUF_BASE) uniform sampler2D gbuf_base;
layout(binding = TEX_GBUF_PARAMS0) uniform sampler2D gbuf_params0;
layout(binding = TEX_GBUF_NORMAL) uniform sampler2D gbuf_normal;
#ifdef GBUF_PARAMS1
layout(binding = TEX_GBUF_PARAMS1) uniform sampler2D gbuf_params1;
#endif
#ifdef GBUF_SMOOTH_NORMAL
layout(binding = TEX_GBUF_SMOOTH_NORMAL) uniform sampler2D gbuf_smooth_normal;
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

/* Split-sum GGX directional albedo (F0 scale, bias) after Karis 2014. */
vec2 karis_env_brdf(float roughness, float NdotV) {
    const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
    const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
    vec4 k = roughness * c0 + c1;
    float a004 = min(k.x * k.x, exp2(-9.28 * max(NdotV, 0.0))) * k.x + k.y;
    return vec2(-1.04, 1.04) * a004 + k.zw;
}

/* World light at max_bounces 0: the constant world colour Lw through the
 * rays that reach it.
 *  Unoccluded part: Lw times each lobe's directional albedo. Burley diffuse:
 *  closed form (principled_diffuse_albedo). Specular: E[F G1(L)] over GGX
 *  visible normals (f cos / pdf = F G1(L)), and sheen: E[pi (1 - L.H)^5]
 *  over cosine-distributed directions, 2 x 2 stratified points per film
 *  sample placed at frame.sample_shift, so they converge over the samples to
 *  the integrals Cycles computes. A mirror lobe reflects the world with its
 *  Fresnel weight. Clearcoat: the split-sum fit of Karis 2014 ("Physically
 *  Based Shading on Mobile") at IOR 1.5, an approximation.
 *  Occlusion, Monte Carlo over the film's samples (HAS_WORLD_OCCLUSION): each
 *  sample has one direction w of the sphere (uniform) and an orthographic
 *  map along it holding the nearest and farthest geometry, which gives the
 *  visibility of the world along w and along -w; the one of the pair above
 *  the horizon, u, is a uniform sample of the hemisphere (pdf 1/(2 pi)).
 *  The diffuse light blocked is subtracted as a control variate:
 *  Lw [A - 2 pi f(u) cos (1 - V(u))] has the expectation
 *  Lw [A - integral f cos (1 - V)] = Lw integral f cos V where A is the
 *  unoccluded albedo above, and no noise where nothing occludes. Ambient occlusion
 *  AO = 1 - 2 cos(u) (1 - V(u)) (expectation: the cosine-weighted visible
 *  fraction, Cycles' AO pass). The glossy part of rough lobes takes the same
 *  control variate; for sharp lobes (alpha < 0.2) uniform directions would
 *  be fireflies, so AO scales them: specular occlusion from AO, an
 *  approximation (Cycles traces the lobe's own directions). */
/* Lobes at least this rough (alpha >= 0.2, roughness >= 0.45) take their
 * world occlusion from the sampled direction; sharper ones from AO. */
#define GLOSSY_OCCLUSION_MIN_ALPHA2 0.04

LightContribution world_light(PrincipledWeights w, SurfaceParams s, vec3 P, vec3 N, vec3 V, out float ao) {
    LightContribution r;
    vec3 Lw = frame.world_color.rgb;
    float NdotV = dot(N, V);
    r.diffuse = w.diffuse * diffuse_lobe_albedo(s, NdotV);
    r.glossy = principled_mirror_weight(w, N, V);
    bool spec_lobe = w.specular != 0.0 && w.alpha2 > 1e-7;
    if (spec_lobe || w.sheen != vec3(0.0)) {
        vec3 T, B;
        make_basis(N, T, B);
        float alpha = sqrt(w.alpha2);
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) {
                vec2 u = (vec2(i, j) + frame.sample_shift.xy) * 0.5;
                if (spec_lobe) {
                    vec3 L = sample_ggx_vndf(N, V, alpha, u);
                    float pdf = principled_specular_pdf(w, N, V, L);
                    if (pdf > 0.0) r.glossy += principled_specular(w, N, V, L) * (0.25 / pdf);
                }
                if (w.sheen != vec3(0.0)) {
                    /* Cosine-distributed: f cos / pdf = pi (1 - L.H)^5. */
                    vec2 d = concentric_disk(u);
                    vec3 L = T * d.x + B * d.y + N * sqrt(max(1.0 - dot(d, d), 0.0));
                    r.diffuse += w.sheen * (0.25 * M_PI_F * principled_sheen_factor(N, V, L) / max(dot(N, L), 1e-8));
                }
            }
    }
    if (w.clearcoat > 0.0) {
        vec2 AB = karis_env_brdf(sqrt(w.cc_alpha), NdotV);
        r.glossy += vec3(0.25 * w.clearcoat * (0.04 * AB.x + AB.y));
    }
    r.diffuse *= Lw;
    r.glossy *= Lw;
    ao = 1.0;
#ifdef HAS_WORLD_OCCLUSION
    GpuShadow sh = shadows[int(frame.world_occlusion.x)];
    float c = -dot(N, sh.point.xyz); /* cos to the map's world direction */
    float side = c >= 0.0 ? 1.0 : -1.0;
    vec3 u = -sh.point.xyz * side; /* whichever of the pair is above the horizon */
    float cos_u = abs(c);
    if (cos_u > 0.0) {
        float blocked = 1.0 - world_visibility(sh, P, N, side);
        /* The analytic albedo above has no bump shadowing term: the sampled
         * direction removes what the term takes, 1 - t, with what is blocked:
         * f (1 - (1 - blocked) t) (exact in expectation; t = 1 without bump). */
        float t = bump_shadowing_term(s.Ns, N, u);
        r.diffuse -= Lw * (2.0 * M_PI_F) * principled_eval_diffuse_unbumped(s, w, N, V, u) *
                     (1.0 - (1.0 - blocked) * t);
        ao = 1.0 - 2.0 * cos_u * blocked;
        if (w.alpha2 >= GLOSSY_OCCLUSION_MIN_ALPHA2) {
            /* A rough lobe: the same control variate (its f stays small). */
            vec3 f = principled_specular(w, N, V, u) + vec3(principled_clearcoat(w, N, V, u));
            r.glossy -= Lw * (2.0 * M_PI_F) * f * blocked;
        } else {
            /* A sharp lobe would make uniform directions fireflies: AO as
             * its occlusion. */
            r.glossy *= ao;
        }
    }
#endif
    return r;
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, ivec2(frame.viewport.xy)))) return;

    /* Each sample adds its share (1/samples) to the accumulations. */
    float share = 1.0 / float(max(frame.counts.w, 1u));
    float depth = texelFetch(gbuf_depth, pixel, 0).r;
    const bool first_batch = light_batch.x == 0u;
    if (depth <= 0.0) {
        if (!first_batch) return;
        /* Background: the world colour, or transparent (Cycles film_transparent). */
        bool transparent = frame.world_color.w > 0.5;
        vec4 bg = transparent ? vec4(0.0) : vec4(frame.world_color.rgb, 1.0);
        imageStore(film, pixel, imageLoad(film, pixel) + bg * share);
        return;
    }

    vec4 params1 = vec4(0.0);
#ifdef GBUF_PARAMS1
    params1 = texelFetch(gbuf_params1, pixel, 0);
#endif
    SurfaceParams s = gbuffer_unpack(texelFetch(gbuf_base, pixel, 0), texelFetch(gbuf_params0, pixel, 0), params1,
                                     texelFetch(gbuf_normal, pixel, 0).rg);
#ifdef GBUF_SMOOTH_NORMAL
    s.Ns = octahedral_decode(texelFetch(gbuf_smooth_normal, pixel, 0).rg);
#endif
    PrincipledWeights w = principled_weights(s);
    vec3 P = frame_position_from_depth(pixel, depth);
    vec3 V = frame_view_vector(P);
    vec3 N = s.N;

    LightContribution total;
    total.diffuse = vec3(0.0);
    total.glossy = vec3(0.0);
    float ao = 1.0;
    if (first_batch) total = world_light(w, s, P, N, V, ao);
#ifdef OUT_AO
    if (first_batch) imageStore(ao_image, pixel, imageLoad(ao_image, pixel) + vec4(vec3(ao), 0.0) * share);
#endif
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
    float lum_shadowed = 0.0, lum_unshadowed = 0.0;
    const vec3 luminance = vec3(0.2126729, 0.7151522, 0.0721750);
    const uint end = min(count, light_batch.y);
    if (!first_batch && light_batch.x >= end) return;
    for (uint k = light_batch.x; k < end; ++k) {
#ifdef LIGHT_CULLING
        uint i = from_list ? tile_lights[first + k] : k;
#else
        uint i = k;
#endif
        float visible;
        LightContribution c = shade_light(lights[i], s, w, P, N, V, visible);
        total.diffuse += c.diffuse * visible;
        total.glossy += c.glossy * visible;
#ifdef OUT_SHADOW
        float lum = dot(c.diffuse + c.glossy, luminance);
        lum_unshadowed += lum;
        lum_shadowed += lum * visible;
#endif
    }

    vec4 emission = first_batch ? texelFetch(gbuf_emission, pixel, 0) : vec4(0.0);
    vec4 sample_value = vec4(emission.rgb + total.diffuse + total.glossy, emission.a);
    imageStore(film, pixel, imageLoad(film, pixel) + sample_value * share);
#ifdef OUT_SHADOW
    imageStore(shadow_light, pixel, imageLoad(shadow_light, pixel) + vec4(lum_shadowed, lum_unshadowed, 0.0, 0.0) * share);
#endif
#ifdef OUT_LIGHT_SPLIT
    imageStore(diffuse_light, pixel, imageLoad(diffuse_light, pixel) + vec4(total.diffuse * share, 0.0));
    imageStore(glossy_light, pixel, imageLoad(glossy_light, pixel) + vec4(total.glossy * share, 0.0));
#endif
}
