/* The film's filter splatting (film.h PixelFilter::splat_taps): adds to
 * each pixel's accumulation the weighted samples of its neighbours, this
 * film sample's values (a scratch image the sample's passes added to,
 * cleared before it). The weights are separable, f(d - o) / F(-o) per axis
 * for the sample's jitter o, and sum to 1, so the accumulation converges to
 * the same filtered pixel as each pixel's own sample (Cycles' filter
 * importance sampling) with less variance where the filter's tail reaches a
 * small bright feature. Pixels within the margin of the image's edge keep
 * their own sample (their neighbours' are not rendered). SPLAT_LAYERS: the
 * light groups' array, one layer per z. */
#include "shader_defines.h"

layout(local_size_x = LIGHTING_GROUP_SIZE, local_size_y = LIGHTING_GROUP_SIZE) in;

#ifdef SPLAT_LAYERS
layout(binding = IMG_SPLAT_SAMPLE, rgba32f) uniform readonly image2DArray sample_image;
layout(binding = IMG_SPLAT_FILM, rgba32f) uniform image2DArray film;
#define AT(p) ivec3(p, layer)
#else
layout(binding = IMG_SPLAT_SAMPLE, rgba32f) uniform readonly image2D sample_image;
layout(binding = IMG_SPLAT_FILM, rgba32f) uniform image2D film;
#define AT(p) (p)
#endif

layout(location = LOC_SPLAT_TAPS) uniform ivec4 taps; /* first x, first y, count x, count y */
layout(location = LOC_SPLAT_MARGIN) uniform int margin;
layout(location = LOC_SPLAT_WEIGHTS_X) uniform float weight_x[SPLAT_MAX_TAPS];
layout(location = LOC_SPLAT_WEIGHTS_Y) uniform float weight_y[SPLAT_MAX_TAPS];

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(film).xy;
    if (any(greaterThanEqual(pixel, size))) return;
    int layer = int(gl_GlobalInvocationID.z);
    vec4 value;
    if (all(greaterThanEqual(pixel, ivec2(margin))) && all(lessThan(pixel, size - margin))) {
        value = vec4(0.0);
        for (int j = 0; j < taps.w; ++j) {
            vec4 row = vec4(0.0);
            for (int i = 0; i < taps.z; ++i)
                row += weight_x[i] * imageLoad(sample_image, AT(pixel + ivec2(taps.x + i, taps.y + j)));
            value += weight_y[j] * row;
        }
    } else {
        value = imageLoad(sample_image, AT(pixel));
    }
    imageStore(film, AT(pixel), imageLoad(film, AT(pixel)) + value);
}
