/* One render pass (PASS_ID, one of the PASS_* ids) from the G-buffer, with
 * Cycles' conventions (shared/REFERENCE.md): Depth is planar camera Z
 * (background 1e10), Position and Normal are world space (background 0),
 * DiffDir/GlossDir are light divided by their colour pass, Env is the world
 * where the background is seen. Combined is accumulated by the lighting pass.
 *
 * Variants: ACCUMULATE adds 1/samples of this sample's value to the pass
 * image (filtered passes, every sample); without it the value is written
 * once (Depth, Position, IndexOB, IndexMA: sample 0, the pixel centre, as
 * Cycles). DiffDir/GlossDir accumulate their colour during the samples and
 * RESOLVE_LIGHT divides the accumulated light by it at the end, as Cycles
 * divides the accumulated passes; RESOLVE_SHADOW turns the accumulated
 * shadowed/unshadowed luminance into the Shadow pass, RESOLVE_MOTION divides
 * the Vector pass's summed motion by its count (motion_module.h);
 * RESOLVE_CATCHER makes the Shadow Catcher pass from the catchers' light and
 * RESOLVE_CATCHER_COMBINED, without that pass, puts their shadow into
 * Combined (lighting_comp.glsl SHADOW_CATCHER). Compiled only for the passes
 * requested. */
#include "frame_lib.glsl"
#include "gbuffer_lib.glsl"
#include "bsdf_lib.glsl"
#ifdef HAS_WORLD_MAP
#include "world_lib.glsl"
#endif

layout(local_size_x = LIGHTING_GROUP_SIZE, local_size_y = LIGHTING_GROUP_SIZE) in;

layout(binding = TEX_DEPTH) uniform sampler2D gbuf_depth;
layout(binding = TEX_GBUF_EMISSION) uniform sampler2D gbuf_emission;
layout(binding = TEX_GBUF_BASE) uniform sampler2D gbuf_base;
layout(binding = TEX_GBUF_PARAMS0) uniform sampler2D gbuf_params0;
layout(binding = TEX_GBUF_NORMAL) uniform usampler2D gbuf_normal; /* packUnorm2x16 of the octahedral normal */
#ifdef GBUF_PARAMS1
layout(binding = TEX_GBUF_PARAMS1) uniform sampler2D gbuf_params1;
#endif
#ifdef GBUF_IDS
layout(binding = TEX_GBUF_IDS) uniform usampler2D gbuf_ids;
#endif
#ifdef GBUF_UV
layout(binding = TEX_GBUF_UV) uniform sampler2D gbuf_uv;
#endif
#ifdef RESOLVE_LIGHT
layout(binding = TEX_DIFF_LIGHT) uniform sampler2D diffuse_light;
layout(binding = TEX_GLOSS_LIGHT) uniform sampler2D glossy_light;
#endif
#ifdef RESOLVE_SHADOW
layout(binding = TEX_SHADOW_LIGHT) uniform sampler2D shadow_light;
#endif
#ifdef RESOLVE_MOTION
layout(binding = TEX_MOTION_WEIGHT) uniform sampler2D motion_count;
#endif
#if defined(RESOLVE_CATCHER) || defined(RESOLVE_CATCHER_COMBINED)
layout(binding = TEX_CATCHER_HIT) uniform sampler2D catcher_hit;
layout(binding = TEX_CATCHER_PASS) uniform sampler2D catcher_pass;
layout(binding = TEX_CATCHER_FILM) uniform sampler2D catcher_film;

/* Cycles' film_calculate_shadow_catcher (kernel/film/read.h): the catcher's
 * light with every shadow over its light with only catchers occluding, per
 * channel (safe_divide_shadow_catcher: 1 where the latter is 0), then
 * alpha-over on white with the Combined alpha (the samples that hit any
 * surface, the catcher's included); 1 where no sample hit a catcher. */
vec3 shadow_catcher(ivec2 pixel, float matte_alpha) {
    vec4 hit = texelFetch(catcher_hit, pixel, 0);
    if (hit.a <= 0.0) return vec3(1.0);
    vec3 pass = texelFetch(catcher_pass, pixel, 0).rgb;
    vec3 ratio = vec3(pass.r != 0.0 ? hit.r / pass.r : 1.0, pass.g != 0.0 ? hit.g / pass.g : 1.0,
                      pass.b != 0.0 ? hit.b / pass.b : 1.0);
    float alpha = clamp(matte_alpha + hit.a, 0.0, 1.0);
    return (1.0 - alpha) + alpha * ratio;
}
#endif

layout(binding = IMG_PASS_OUT, rgba32f) uniform image2D pass_out;

SurfaceParams load_surface(ivec2 pixel) {
    vec4 params1 = vec4(0.0);
#ifdef GBUF_PARAMS1
    params1 = texelFetch(gbuf_params1, pixel, 0);
#endif
    return gbuffer_unpack(texelFetch(gbuf_base, pixel, 0), texelFetch(gbuf_params0, pixel, 0), params1,
                          unpackUnorm2x16(texelFetch(gbuf_normal, pixel, 0).r));
}

vec3 safe_divide(vec3 a, vec3 b) {
    return vec3(b.x != 0.0 ? a.x / b.x : 0.0, b.y != 0.0 ? a.y / b.y : 0.0, b.z != 0.0 ? a.z / b.z : 0.0);
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, ivec2(frame.viewport.xy)))) return;

#if defined(RESOLVE_CATCHER)
    /* The Shadow Catcher pass. */
    imageStore(pass_out, pixel, vec4(shadow_catcher(pixel, texelFetch(catcher_film, pixel, 0).a), 0.0));
#elif defined(RESOLVE_CATCHER_COMBINED)
    /* Combined without the Shadow Catcher pass asked for: Cycles' approximate
     * shadow catcher (film_calculate_shadow_catcher_matte_with_shadow): the
     * matte with the shadow in its alpha, A = (1 - a)(1 - shadow) + a; with an
     * opaque film, the world behind the catcher seen through 1 - A of it. */
    vec4 matte = imageLoad(pass_out, pixel);
    vec3 sc = shadow_catcher(pixel, matte.a);
    float A = (1.0 - matte.a) * (1.0 - clamp((sc.r + sc.g + sc.b) * (1.0 / 3.0), 0.0, 1.0)) + matte.a;
    if (frame.world_color.w > 0.5) {
        imageStore(pass_out, pixel, vec4(matte.rgb, A));
    } else {
#ifdef HAS_WORLD_MAP
        vec3 world = world_camera_radiance(-frame_view_vector(frame_position_from_depth(pixel, 0.5)));
#else
        vec3 world = frame.world_color.rgb;
#endif
        float behind = texelFetch(catcher_hit, pixel, 0).a;  /* the samples whose world the catcher hid */
        imageStore(pass_out, pixel, vec4(matte.rgb + world * behind * (1.0 - A), 1.0));
    }
#elif defined(RESOLVE_MOTION)
    /* Vector: the motion summed over the samples that saw a surface, divided
     * by their count (Cycles' pass_motion_weight); 0 where none did. */
    float n = texelFetch(motion_count, pixel, 0).r;
    imageStore(pass_out, pixel, n > 0.0 ? imageLoad(pass_out, pixel) / n : vec4(0.0));
#elif defined(RESOLVE_SHADOW)
    /* Shadow: shadowed over unshadowed direct-light luminance, 1 where no light arrives. */
    vec2 l = texelFetch(shadow_light, pixel, 0).xy;
    imageStore(pass_out, pixel, vec4(vec3(l.y > 0.0 ? l.x / l.y : 1.0), 0.0));
#elif defined(RESOLVE_LIGHT)
#if PASS_ID == PASS_DIFF_DIR
    vec3 light = texelFetch(diffuse_light, pixel, 0).rgb;
#else
    vec3 light = texelFetch(glossy_light, pixel, 0).rgb;
#endif
    imageStore(pass_out, pixel, vec4(safe_divide(light, imageLoad(pass_out, pixel).rgb), 0.0));
#else
    float depth = texelFetch(gbuf_depth, pixel, 0).r;
    bool background = depth <= 0.0;
#if PASS_ID >= PASS_DEPTH && PASS_ID <= PASS_INDEX_MA
    /* A holdout surface (emission.a 0, geometry_frag.glsl) writes no data
     * pass, as in Cycles, where the holdout ends the path before them. */
    if (!background && texelFetch(gbuf_emission, pixel, 0).a <= 0.0) background = true;
#endif
    vec4 value = vec4(0.0);
    vec3 P = background ? vec3(0.0) : frame_position_from_depth(pixel, depth);

#if PASS_ID == PASS_DEPTH
    value = vec4(background ? 1e10 : frame_view_depth(P));
#elif PASS_ID == PASS_MIST
    /* Cycles: distance along the ray (planar for orthographic cameras),
     * mapped by start/depth and the falloff exponent; background 1. */
    float dist = frame_is_ortho() ? frame_view_depth(P) : frame_eye_distance(P);
    float mist = clamp((dist - frame.mist.x) * frame.mist.y, 0.0, 1.0);
    int falloff = int(frame.mist.z);
    if (falloff == 0) mist = mist * mist;
    else if (falloff == 2) mist = sqrt(mist);
    value = vec4(background ? 1.0 : mist);
#elif PASS_ID == PASS_POSITION
    value = background ? vec4(0.0) : vec4(P + frame.camera_position.xyz, 0.0);
#elif PASS_ID == PASS_NORMAL
    value = background ? vec4(0.0) : vec4(octahedral_decode(unpackUnorm2x16(texelFetch(gbuf_normal, pixel, 0).r)), 0.0);
#elif PASS_ID == PASS_UV
    value = background ? vec4(0.0) : vec4(texelFetch(gbuf_uv, pixel, 0).rg, 1.0, 0.0);
#elif PASS_ID == PASS_INDEX_OB
    value = vec4(background ? 0.0 : float(texelFetch(gbuf_ids, pixel, 0).x));
#elif PASS_ID == PASS_INDEX_MA
    value = vec4(background ? 0.0 : float(texelFetch(gbuf_ids, pixel, 0).y));
#elif PASS_ID == PASS_DIFF_COL || PASS_ID == PASS_DIFF_DIR
    if (!background) value = vec4(principled_diffuse_color(principled_weights(load_surface(pixel))), 0.0);
#elif PASS_ID == PASS_GLOSS_COL || PASS_ID == PASS_GLOSS_DIR
    if (!background) value = vec4(principled_glossy_color(principled_weights(load_surface(pixel))), 0.0);
#elif PASS_ID == PASS_EMIT
    if (!background) {
        /* The emission sub-samples (emission_samples.h) add the rest of it. */
        vec4 emission = texelFetch(gbuf_emission, pixel, 0);
        value = vec4(emission.rgb * directly_seen_emission_share(emission), 0.0);
    }
#elif PASS_ID == PASS_ENV
#ifdef HAS_WORLD_MAP
    /* The world map along this sample's ray through the pixel (as camera rays see it). */
    value = background ? vec4(world_camera_radiance(-frame_view_vector(frame_position_from_depth(pixel, 0.5))), 0.0)
                       : vec4(0.0);
#else
    value = background ? vec4(frame.world_color.rgb, 0.0) : vec4(0.0);
#endif
#elif PASS_ID == PASS_SHADOW
    value = vec4(1.0); /* written by the RESOLVE_SHADOW variant */
#elif PASS_ID == PASS_AO
    value = vec4(1.0); /* accumulated by the lighting pass */
#elif PASS_ID == PASS_VECTOR
    value = vec4(0.0); /* drawn by the motion module, divided by RESOLVE_MOTION */
#elif PASS_ID == PASS_SHADOW_CATCHER
    value = vec4(1.0); /* written by RESOLVE_CATCHER */
#else
#error "passes_comp.glsl: unknown PASS_ID"
#endif
#ifdef ACCUMULATE
    value = imageLoad(pass_out, pixel) + value * (1.0 / float(max(frame.counts.w, 1u)));
#endif
    imageStore(pass_out, pixel, value);
#endif
}
