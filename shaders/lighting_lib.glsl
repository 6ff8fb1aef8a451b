/* Direct light at one shading point: every light type, the world (map or
 * constant, with its occlusion maps), emissive meshes. Shared by the lighting
 * pass (lighting_comp.glsl, one invocation per G-buffer pixel) and the
 * forward pass (geometry_frag.glsl with FORWARD_PASS: Blend-mode surfaces
 * shaded where they are drawn), so both light a surface alike. */
#include "frame_lib.glsl"
#include "gbuffer_lib.glsl"
#include "light_lib.glsl"
#ifdef HAS_WORLD_MAP
#include "world_lib.glsl"
#endif

layout(std430, binding = SSBO_LIGHTS) readonly buffer Lights { GpuLight lights[]; };
/* The opaque surfaces' depth (screen-space visibility of sharp lobes). */
layout(binding = TEX_DEPTH) uniform sampler2D gbuf_depth;

/* Split-sum GGX directional albedo (F0 scale, bias) after Karis 2014. */
vec2 karis_env_brdf(float roughness, float NdotV) {
    const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
    const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
    vec4 k = roughness * c0 + c1;
    float a004 = min(k.x * k.x, exp2(-9.28 * max(NdotV, 0.0))) * k.x + k.y;
    return vec2(-1.04, 1.04) * a004 + k.zw;
}

/* World light at max_bounces 0: the world's radiance through the rays that
 * reach it, as the unoccluded integral minus what the scene blocks.
 *
 * Unoccluded part, a constant world Lw (no map): Lw times each lobe's
 *  directional albedo. Burley diffuse: closed form (principled_diffuse_albedo).
 *  Specular: E[F G1(L)] over GGX visible normals (f cos / pdf = F G1(L)), and
 *  sheen: E[pi (1 - L.H)^5] over cosine-distributed directions, 2 x 2
 *  stratified points per film sample placed at frame.sample_shift, so they
 *  converge over the samples to the integrals Cycles computes. A mirror lobe
 *  reflects the world with its Fresnel weight. Clearcoat: the split-sum fit
 *  of Karis 2014 ("Physically Based Shading on Mobile") at IOR 1.5, an
 *  approximation.
 * Unoccluded part, a world map (HAS_WORLD_MAP, world_map_unoccluded): Monte
 *  Carlo per pixel and film sample, WORLD_LIGHT_SAMPLES directions drawn from
 *  the map's density and as many from the BSDF, combined by the balance
 *  heuristic (Veach 1997) as Cycles combines its background light sample
 *  with its BSDF ray; mirror lobes look the map up along the reflection.
 *
 * Occlusion, Monte Carlo over the film's samples (HAS_WORLD_OCCLUSION): each
 *  sample has frame.world_occlusion.y directions w of the world (one,
 *  uniform on the sphere, for a constant world; several drawn by the map's
 *  density otherwise: WorldModule) and an orthographic map along each
 *  holding the nearest and farthest geometry, which gives the visibility
 *  along w and along -w; the one of the pair above the horizon, u, was
 *  drawn with density q = p(w) + p(-w) (the map's params.z; 1 / (2 pi) when
 *  uniform), and the maps' estimates are averaged. The light blocked is
 *  subtracted as a control variate: L(u) f(u) cos (1 - V(u)) / q has the
 *  expectation integral L f cos (1 - V), so the result's expectation is
 *  integral L f cos V, with no noise where nothing occludes. Ambient
 *  occlusion AO = 1 - cos(u) (1 - V(u)) / (pi q) (expectation: the
 *  cosine-weighted visible fraction, Cycles' AO pass). The glossy part of
 *  rough lobes takes the same control variate; for sharp lobes (alpha < 0.2)
 *  the occlusion directions would be fireflies, so each of their own
 *  directions (mirror, GGX and map samples) is occluded in screen space
 *  (screen_space_visibility), and AO scales what that cannot see: an
 *  approximation of the rays Cycles traces. */
/* Lobes at least this rough (alpha >= 0.2, roughness >= 0.45) take their
 * world occlusion from the occlusion maps; sharper ones in screen space. */
#define GLOSSY_OCCLUSION_MIN_ALPHA2 0.04

/* Three numbers in [0, 1) for direction k of a strategy at this pixel and
 * film sample: the R3 low-discrepancy sequence (Roberts 2018, the
 * generalised golden ratio of x^4 = x + 1) over the pixel's samples,
 * stratifying them as Cycles' sampling patterns do, shifted per pixel and
 * strategy by a pcg4d hash (Cranley-Patterson rotation; see
 * transparency_random). In 32-bit fixed point, so the sequence stays exact
 * at any sample count. */
vec3 world_sequence(ivec2 pixel, uint strategy, uint k) {
    uvec4 v = uvec4(uvec2(pixel), strategy * 0x9E3779B9u + 0x85EBCA6Bu, 0x27d4eb2du);
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    uint n = uint(frame.sample_shift.w) * uint(WORLD_LIGHT_SAMPLES) + k;
    uvec3 x = v.xyz + n * uvec3(0xd1b54a32u, 0xabc98388u, 0x8cb92ba7u);
    return vec3(x >> 8u) * (1.0 / 16777216.0);
}

/* Screen-space visibility of the world along unit L from P, for sharp
 * glossy lobes, which the occlusion maps' few directions per sample cannot
 * serve (their light comes from a narrow cone): the ray is marched through
 * the depth buffer (SS_TRACE_STEPS points, quadratically spaced up to four
 * times P's view depth, jittered per sample). It is blocked (0) where a
 * step lies behind a surface the camera sees; free (1) where it runs its
 * whole length in view and in front of what the camera sees; unknown (-1)
 * where it leaves the view first, and the caller falls back to AO. An
 * approximation of Cycles' ray: occluders the camera does not see are
 * missed, and a ray passing behind an object counts as blocked. */
#define SS_TRACE_STEPS 24
float screen_space_visibility(vec3 P, vec3 N, vec3 L, float jitter) {
    float view_d = max(frame_view_depth(P), 1e-4);
    float texel = 2.0 / (abs(frame.projection[1][1]) * frame.viewport.y); /* a pixel at unit view depth */
    float pixel = frame_is_ortho() ? texel : texel * view_d;
    vec3 origin = P + N * (2.0 * pixel);
    float max_t = 4.0 * view_d;
    vec4 start = frame.projection * (frame.view * vec4(P, 1.0));
    vec2 start_xy = (start.xy / start.w * 0.5 + 0.5) * frame.viewport.xy;
    for (int i = 0; i < SS_TRACE_STEPS; ++i) {
        float x = (float(i) + jitter) / float(SS_TRACE_STEPS);
        float t = max_t * x * x + pixel;
        vec3 X = origin + L * t;
        vec3 view = (frame.view * vec4(X, 1.0)).xyz;
        if (!frame_is_ortho() && view.z >= -1e-6) return -1.0; /* behind the camera */
        vec4 clip = frame.projection * vec4(view, 1.0);
        vec2 ndc = clip.xy / clip.w;
        if (any(greaterThan(abs(ndc), vec2(1.0)))) return -1.0;
        vec2 xy = (ndc * 0.5 + 0.5) * frame.viewport.xy;
        ivec2 px = clamp(ivec2(xy), ivec2(0), ivec2(frame.viewport.xy) - 1);
        float ray = -view.z;
        float d = texelFetch(gbuf_depth, px, 0).r;
        /* Within two pixels of the start the depth buffer is the surface
         * itself, whose slope at grazing angles outruns any bias. */
        if (d > 0.0 && dot(xy - start_xy, xy - start_xy) > 4.0) {
            /* Blocked where the step lies behind the surface seen at its
             * pixel: it crossed that surface, or it passes behind an object
             * nearer the camera, whose thickness the camera does not see:
             * taken as hitting its hidden side (a ray passing behind it is
             * wrongly dark; the other choice makes the reflection of the
             * world behind an object a firefly, and AO cannot catch it). */
            float scene = frame_view_depth_from_buffer(px, d);
            float bias = 2.0 * (frame_is_ortho() ? texel : texel * scene);
            if (ray > scene + bias) return 0.0;
        }
    }
    return 1.0;
}

/* Sharp glossy light along L: added with its screen-space visibility where
 * that is known, kept apart for AO otherwise. */
void add_sharp_glossy(inout vec3 known, inout vec3 unknown, vec3 value, SurfaceParams s, vec3 P, vec3 N, vec3 L,
                      float jitter) {
    if (value == vec3(0.0)) return;
#ifdef SHADOW_RAYS
    /* Shadow rays: the direction's own ray, as Cycles traces it. */
    known += value * shadow_ray(s, P, L, -1.0);
    return;
#endif
    float v = screen_space_visibility(P, N, L, jitter);
    if (v < 0.0) unknown += value;
    else known += value * v;
}

/* The world's radiance for light arriving from direction d. */
vec3 world_radiance_from(vec3 d) {
#ifdef HAS_WORLD_MAP
    return world_light_radiance(d);
#else
    return frame.world_color.rgb;
#endif
}

LightContribution world_constant_unoccluded(PrincipledWeights w, SurfaceParams s, vec3 P, vec3 N, vec3 V,
                                            float jitter, inout vec3 sharp_unknown) {
    LightContribution r;
    vec3 Lw = frame.world_color.rgb;
    float NdotV = dot(N, V);
    bool sharp = w.alpha2 < GLOSSY_OCCLUSION_MIN_ALPHA2;
    r.diffuse = w.diffuse * diffuse_lobe_albedo(s, NdotV);
    r.glossy = vec3(0.0);
    add_sharp_glossy(r.glossy, sharp_unknown, principled_mirror_weight(w, N, V) * Lw, s, P, N, reflect(-V, N), jitter);
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
                    vec3 value = pdf > 0.0 ? principled_specular(w, N, V, L) * (0.25 / pdf) * Lw : vec3(0.0);
                    if (sharp) add_sharp_glossy(r.glossy, sharp_unknown, value, s, P, N, L, jitter);
                    else r.glossy += value;
                }
                if (w.sheen != vec3(0.0)) {
                    /* Cosine-distributed: f cos / pdf = pi (1 - L.H)^5. */
                    vec2 d = concentric_disk(u);
                    vec3 L = T * d.x + B * d.y + N * sqrt(max(1.0 - dot(d, d), 0.0));
                    r.diffuse += w.sheen * (0.25 * M_PI_F * principled_sheen_factor(N, V, L) / max(dot(N, L), 1e-8));
                }
            }
    }
    vec3 clearcoat = vec3(0.0);
    if (w.clearcoat > 0.0) {
        vec2 AB = karis_env_brdf(sqrt(w.cc_alpha), NdotV);
        clearcoat = vec3(0.25 * w.clearcoat * (0.04 * AB.x + AB.y)) * Lw;
    }
    /* The split-sum clearcoat has no direction: AO occludes it when sharp. */
    if (sharp) sharp_unknown += clearcoat;
    else r.glossy += clearcoat;
    r.diffuse *= Lw;
    return r;
}

#ifdef HAS_WORLD_MAP
/* The BSDF's sampling strategies for the world's light: cosine-weighted
 * (diffuse and sheen), GGX visible normals (specular), GTR1 half vectors
 * (clearcoat, as Cycles samples it), chosen with probabilities by each
 * lobe's weight; mirror lobes are not sampled (looked up along R). */
struct BsdfChoice {
    float diffuse, specular, clearcoat;
};

BsdfChoice world_bsdf_choice(PrincipledWeights w) {
    const vec3 lum = vec3(0.2126729, 0.7151522, 0.0721750);
    BsdfChoice c;
    c.diffuse = dot(principled_diffuse_color(w), lum);
    c.specular = (w.specular != 0.0 && w.alpha2 > 1e-7) ? max(dot(w.cspec0, lum), 0.1) : 0.0;
    c.clearcoat = (w.clearcoat > 0.0 && w.cc_alpha * w.cc_alpha > 1e-7) ? 0.25 * w.clearcoat : 0.0;
    float total = c.diffuse + c.specular + c.clearcoat;
    if (total <= 0.0) {
        c.diffuse = c.specular = c.clearcoat = 0.0;
        return c;
    }
    c.diffuse /= total;
    c.specular /= total;
    c.clearcoat /= total;
    return c;
}

/* GTR1 (Burley 2012): cos(theta_h)^2 = (1 - a^(2(1 - u))) / (1 - a^2),
 * pdf(h) = D(h) cos(theta_h), per incident direction / (4 L.H). */
float gtr1_D(float a, float cosH) {
    if (a >= 1.0) return M_1_PI_F;
    float a2 = a * a;
    return (a2 - 1.0) / (M_PI_F * log(a2) * (1.0 + (a2 - 1.0) * cosH * cosH));
}

vec3 sample_gtr1(vec3 N, vec3 V, float a, vec2 u) {
    float a2 = min(a * a, 0.9999);
    float cos2 = (1.0 - pow(a2, 1.0 - u.x)) / (1.0 - a2);
    float cos_h = sqrt(clamp(cos2, 0.0, 1.0)), sin_h = sqrt(max(1.0 - cos2, 0.0));
    float phi = 2.0 * M_PI_F * u.y;
    vec3 T, B;
    make_basis(N, T, B);
    vec3 H = T * (sin_h * cos(phi)) + B * (sin_h * sin(phi)) + N * cos_h;
    return reflect(-V, H);
}

float gtr1_pdf(vec3 N, vec3 V, float a, vec3 L) {
    vec3 H = normalize(L + V);
    float cosH = dot(N, H), LdotH = dot(L, H);
    if (cosH <= 0.0 || LdotH <= 0.0) return 0.0;
    return gtr1_D(a, cosH) * cosH / (4.0 * LdotH);
}

float world_bsdf_pdf(BsdfChoice c, PrincipledWeights w, vec3 N, vec3 V, vec3 L) {
    float NdotL = dot(N, L);
    if (NdotL <= 0.0) return 0.0;
    float p = c.diffuse * NdotL * M_1_PI_F;
    if (c.specular > 0.0) p += c.specular * principled_specular_pdf(w, N, V, L);
    if (c.clearcoat > 0.0) p += c.clearcoat * gtr1_pdf(N, V, w.cc_alpha, L);
    return p;
}

vec3 world_bsdf_sample(BsdfChoice c, PrincipledWeights w, vec3 N, vec3 V, vec3 r) {
    if (r.z < c.diffuse) {
        vec3 T, B;
        make_basis(N, T, B);
        vec2 d = concentric_disk(r.xy);
        return T * d.x + B * d.y + N * sqrt(max(1.0 - dot(d, d), 0.0));
    }
    if (r.z < c.diffuse + c.specular) return sample_ggx_vndf(N, V, sqrt(w.alpha2), r.xy);
    return sample_gtr1(N, V, w.cc_alpha, r.xy);
}

/* f cos L / (p_map + p_bsdf) for one direction (the balance heuristic's
 * share of either strategy's sample); a sharp lobe's glossy part with its
 * screen-space visibility. */
void world_map_add(inout LightContribution r, inout vec3 sharp_unknown, PrincipledWeights w, SurfaceParams s,
                   vec3 P, vec3 N, vec3 V, vec3 L, float p_sum, float jitter) {
    if (dot(N, L) <= 0.0 || !(p_sum > 0.0)) return;
    vec3 Le = world_light_radiance(L) * (1.0 / (p_sum * float(WORLD_LIGHT_SAMPLES)));
    LobeEval e = principled_eval(s, w, N, V, L);
    r.diffuse += e.diffuse * Le;
    vec3 glossy = e.glossy * (Le * smooth_side(s, L));
    if (w.alpha2 < GLOSSY_OCCLUSION_MIN_ALPHA2) add_sharp_glossy(r.glossy, sharp_unknown, glossy, s, P, N, L, jitter);
    else r.glossy += glossy;
}

LightContribution world_map_unoccluded(PrincipledWeights w, SurfaceParams s, vec3 P, vec3 N, vec3 V, ivec2 pixel,
                                       float jitter, inout vec3 sharp_unknown) {
    LightContribution r;
    r.diffuse = vec3(0.0);
    r.glossy = vec3(0.0);
    BsdfChoice c = world_bsdf_choice(w);
    bool sample_bsdf = c.diffuse + c.specular + c.clearcoat > 0.0;
    for (int k = 0; k < WORLD_LIGHT_SAMPLES; ++k) {
        float p_map;
        vec3 L = world_sample(world_sequence(pixel, 0u, uint(k)), p_map);
        world_map_add(r, sharp_unknown, w, s, P, N, V, L, p_map + world_bsdf_pdf(c, w, N, V, L), jitter);
        if (sample_bsdf) {
            vec3 Lb = world_bsdf_sample(c, w, N, V, world_sequence(pixel, 1u, uint(k)));
            world_map_add(r, sharp_unknown, w, s, P, N, V, Lb, world_pdf(Lb) + world_bsdf_pdf(c, w, N, V, Lb),
                          jitter);
        }
    }
    vec3 R = reflect(-V, N);
    add_sharp_glossy(r.glossy, sharp_unknown, principled_mirror_weight(w, N, V) * world_light_radiance(R), s, P, N, R,
                     jitter);
    return r;
}
#endif

/* The world's light before any occlusion (world_light sets it): what a
 * shadow catcher gets without the other objects. */
LightContribution last_world_unoccluded;

LightContribution world_light(PrincipledWeights w, SurfaceParams s, vec3 P, vec3 N, vec3 V, ivec2 pixel,
                              out float ao) {
    /* Sharp glossy light whose screen-space visibility is unknown: AO below. */
    vec3 sharp_unknown = vec3(0.0);
    float jitter = world_sequence(pixel, 2u, 0u).x;
#ifdef HAS_WORLD_MAP
    LightContribution r = world_map_unoccluded(w, s, P, N, V, pixel, jitter, sharp_unknown);
#else
    LightContribution r = world_constant_unoccluded(w, s, P, N, V, jitter, sharp_unknown);
#endif
    last_world_unoccluded = r;
    last_world_unoccluded.glossy += sharp_unknown;
    ao = 1.0;
#ifdef HAS_WORLD_OCCLUSION
    /* The sample's maps, each a direction pair with its own density; their
     * estimates are averaged. */
    const int maps = int(frame.world_occlusion.y);
    const float share = 1.0 / float(maps);
    float ao_sum = 0.0;
    for (int k = 0; k < maps; ++k) {
        GpuShadow sh = shadows[int(frame.world_occlusion.x) + k];
        float c = -dot(N, sh.point.xyz); /* cos to the map's world direction */
        float side = c >= 0.0 ? 1.0 : -1.0;
        vec3 u = -sh.point.xyz * side; /* whichever of the pair is above the horizon */
        float cos_u = abs(c);
        float inv_q = share / sh.params.z; /* 1 / the pair's density, this map's share */
        if (cos_u <= 0.0) continue;
        float blocked = 1.0 - world_visibility(sh, P, s, side);
        vec3 Lu = world_radiance_from(u) * inv_q;
#ifdef HAS_WORLD_MAP
        r.diffuse -= Lu * principled_eval_diffuse(s, w, N, V, u) * blocked;
#else
        /* The analytic albedo above has no bump shadowing term: the sampled
         * direction removes what the term takes, 1 - t, with what is blocked:
         * f (1 - (1 - blocked) t) (exact in expectation; t = 1 without bump). */
        float t = bump_shadowing_term(s.Ns, N, u);
        r.diffuse -= Lu * principled_eval_diffuse_unbumped(s, w, N, V, u) * (1.0 - (1.0 - blocked) * t);
#endif
        ao_sum += cos_u * blocked * inv_q * M_1_PI_F;
        if (w.alpha2 >= GLOSSY_OCCLUSION_MIN_ALPHA2) {
            /* A rough lobe: the same control variate (its f stays small). */
            vec3 f = principled_specular(w, N, V, u) + vec3(principled_clearcoat(w, N, V, u));
#ifdef HAS_WORLD_MAP
            f *= smooth_side(s, u);
#endif
            r.glossy -= Lu * f * blocked;
        }
    }
    ao = 1.0 - ao_sum;
    /* A sharp lobe would make the occlusion directions fireflies: its light
     * was occluded in screen space, and AO occludes what that could not see
     * (clamped to [0, 1]: with importance-sampled directions one sample's AO
     * can fall below 0). */
    if (w.alpha2 < GLOSSY_OCCLUSION_MIN_ALPHA2) sharp_unknown *= clamp(ao, 0.0, 1.0);
#endif
    r.glossy += sharp_unknown;
    return r;
}

