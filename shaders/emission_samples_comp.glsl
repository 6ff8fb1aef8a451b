/* An emission sub-sample (native/src/emission_samples.h): the directly seen
 * emission of the G-buffer just drawn at the sub-sample's jitter, its share
 * 1 / (samples K) (frame.jitter.w = 1/K), added to Combined's target and,
 * with OUT_EMIT, the Emit pass's; the film splats them with the taps for the
 * sub-sample's offset. Directly seen emission, as the lighting pass scales
 * it: a surface's (not the background's), not a holdout's (emission.a 0)
 * nor a shadow catcher's (emission.a 2), whose paths keep their own. */
#include "frame_lib.glsl"

layout(local_size_x = LIGHTING_GROUP_SIZE, local_size_y = LIGHTING_GROUP_SIZE) in;

layout(binding = TEX_DEPTH) uniform sampler2D gbuf_depth;
layout(binding = TEX_GBUF_EMISSION) uniform sampler2D gbuf_emission;
layout(binding = IMG_FILM, rgba32f) uniform image2D film;
#ifdef OUT_EMIT
layout(binding = IMG_PASS_OUT, rgba32f) uniform image2D emit_pass;
#endif

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, ivec2(frame.viewport.xy)))) return;
    if (texelFetch(gbuf_depth, pixel, 0).r <= 0.0) return;
    vec4 emission = texelFetch(gbuf_emission, pixel, 0);
    if (!directly_seen_emission(emission) || emission.rgb == vec3(0.0)) return;
    vec4 value = vec4(emission.rgb * (directly_seen_emission_share(emission) / float(max(frame.counts.w, 1u))), 0.0);
    imageStore(film, pixel, imageLoad(film, pixel) + value);
#ifdef OUT_EMIT
    imageStore(emit_pass, pixel, imageLoad(emit_pass, pixel) + value);
#endif
}
