/* Image Texture and Environment Texture nodes, as Cycles 3.4 renders them on the CPU.
 *
 * Sources transcribed (Blender 3.4.1: the kernel files Blender ships in
 * scripts/addons/cycles/source/; the CPU interpolator, which Blender does not ship, is
 * intern/cycles/kernel/device/cpu/image.h of the 3.x series before 3.5 added the MIRROR
 * extension and reworked CLIP). Every mode below was compared with Blender 3.4.1's Cycles
 * (CPU) through shader AOVs at the coordinates Cycles used: Linear/Closest/Cubic/Smart x
 * REPEAT/EXTEND/CLIP, FLAT/BOX (blend 0, 0.25, 1)/SPHERE/TUBE, EQUIRECTANGULAR/
 * MIRROR_BALL, texture mapping, missing images; equal to ~1e-6.
 *   kernel/device/cpu/image.h  TextureInterpolator<T>: frac, wrap_periodic, wrap_clamp,
 *                              read (zero outside the image), interp_closest,
 *                              interp_linear, interp_cubic (uniform cubic B-spline,
 *                              SET_CUBIC_SPLINE_WEIGHTS), interp (anything that is not
 *                              Closest or Linear is Cubic: Smart renders as Cubic on CPU)
 *   kernel/svm/image.h         svm_image_texture (NODE_IMAGE_ALPHA_UNASSOCIATE, then
 *                              NODE_IMAGE_COMPRESS_AS_SRGB), svm_node_tex_image
 *                              (texco_remap_square, sphere/tube projection, UDIM tile
 *                              lookup), svm_node_tex_image_box, svm_node_tex_environment
 *   util/math.h                map_to_sphere, map_to_tube
 *   util/color.h               color_srgb_to_linear (scalar form; the SSE form differs
 *                              by a fast pow(x, 2.4) approximation of ~1e-7 relative)
 *   kernel/camera/projection.h direction_to_equirectangular(_range), direction_to_mirrorball
 *   util/math_float3.h         safe_normalize
 *
 * All filtering is done here with texelFetch (no GL sampler filtering, no mipmaps), in
 * Cycles' operation order, so the result does not depend on the GPU's filtering
 * precision. Texel (x, y) of the bound texture is Blender's pixel x of row y, row 0 the
 * bottom row (Blender's and Cycles' order); 8-bit textures read value/255 as Cycles'
 * uchar4 read does. Alpha association, sRGB storage and the other load-time steps of
 * Cycles' ImageManager are done in Python (materials/images.py), which also decides the
 * flags below.
 *
 * Compile-time ints (materials/nodes/image.py passes Blender's enum values, which are
 * Cycles' enum values):
 *   interpolation  0 Linear, 1 Closest, 2 Cubic, 3 Smart  (util/texture.h InterpolationType)
 *   extension      0 REPEAT, 1 EXTEND, 2 CLIP             (util/texture.h ExtensionType)
 *   projection     0 FLAT, 2 SPHERE, 3 TUBE; BOX has its own function
 *                                                         (kernel/svm/types.h NodeImageProjection)
 *   env projection 0 EQUIRECTANGULAR, 1 MIRROR_BALL       (NodeEnvironmentProjection)
 *   flags          IMG_FLAG_* bits below
 *   map_mode       texture mapping: 0 none, 1 affine, 2 affine + normalize (img_mapping_apply);
 *                  map_block is then the offset of its 12 constants
 */

#ifndef NODE_IMAGE_LIB
#define NODE_IMAGE_LIB

/* kernel/svm/types.h NODE_IMAGE_COMPRESS_AS_SRGB: the texels are sRGB-encoded; decode
 * after interpolation. */
#define IMG_FLAG_SRGB 1
/* kernel/svm/types.h NODE_IMAGE_ALPHA_UNASSOCIATE: divide the colour by alpha (the Alpha
 * output is linked and the image's alpha is not data/channel-packed/ignored). */
#define IMG_FLAG_UNASSOCIATE 2
/* A UDIM image with several tiles, of which only the first is bound, as tile 1001:
 * svm_node_tex_image's tile lookup, every other tile reads as missing (magenta). (A
 * one-tile UDIM is a plain image in Cycles: no flag.) */
#define IMG_FLAG_UDIM_1001 4
/* A single-channel image (IMAGE_DATA_TYPE_BYTE/USHORT/HALF/FLOAT): Cycles' CPU kernel
 * returns make_float4(f, f, f, 1.0f) for it, so alpha is 1 even outside a CLIP image. */
#define IMG_FLAG_ALPHA_ONE 8

#define IMG_INTERP_LINEAR 0
#define IMG_INTERP_CLOSEST 1
#define IMG_INTERP_CUBIC 2
#define IMG_INTERP_SMART 3

#define IMG_EXTENSION_REPEAT 0
#define IMG_EXTENSION_EXTEND 1
#define IMG_EXTENSION_CLIP 2

#define IMG_PROJ_FLAT 0
#define IMG_PROJ_BOX 1
#define IMG_PROJ_SPHERE 2
#define IMG_PROJ_TUBE 3

#define IMG_ENV_EQUIRECTANGULAR 0
#define IMG_ENV_MIRROR_BALL 1

/* util/texture.h TEX_IMAGE_MISSING_R/G/B/A */
#define IMG_MISSING_COLOR vec4(1.0, 0.0, 1.0, 1.0)

/* ------------------------------------------------------------------------------------ */
/* Helpers                                                                              */
/* ------------------------------------------------------------------------------------ */

/* kernel/device/cpu/image.h frac(): i = float_to_int(x) - (x < 0 ? 1 : 0), returns x - i.
 * float_to_int truncates like GLSL int(). (For a negative integer x this gives i = x - 1
 * and a fraction of 1.0, as Cycles does.) */
float img_frac(float x, out int ix)
{
  int i = int(x) - ((x < 0.0) ? 1 : 0);
  ix = i;
  return x - float(i);
}

/* wrap_periodic(): C's x % width (sign of x) plus width when negative. GLSL's % is
 * undefined for negative operands, so only non-negative ones are used. */
int img_wrap_periodic(int x, int width)
{
  if (x >= 0) {
    return x % width;
  }
  return width - 1 - ((-(x + 1)) % width);
}

/* wrap_clamp() */
int img_wrap_clamp(int x, int width)
{
  return clamp(x, 0, width - 1);
}

/* read(data, x, y, width, height): transparent black outside the image. */
vec4 img_read(sampler2D image, int x, int y, int width, int height)
{
  if (x < 0 || y < 0 || x >= width || y >= height) {
    return vec4(0.0);
  }
  return texelFetch(image, ivec2(x, y), 0);
}

/* SET_CUBIC_SPLINE_WEIGHTS(u, t): uniform cubic B-spline weights. */
vec4 img_cubic_weights(float t)
{
  vec4 u;
  u.x = (((-1.0 / 6.0) * t + 0.5) * t - 0.5) * t + (1.0 / 6.0);
  u.y = ((0.5 * t - 1.0) * t) * t + (2.0 / 3.0);
  u.z = ((-0.5 * t + 0.5) * t + 0.5) * t + (1.0 / 6.0);
  u.w = (1.0 / 6.0) * t * t * t;
  return u;
}

/* ------------------------------------------------------------------------------------ */
/* TextureInterpolator<T>::interp_closest / interp_linear / interp_cubic / interp        */
/* ------------------------------------------------------------------------------------ */

vec4 img_interp_closest(int extension, sampler2D image, float x, float y)
{
  ivec2 size = textureSize(image, 0);
  int width = size.x;
  int height = size.y;
  int ix, iy;
  img_frac(x * float(width), ix);
  img_frac(y * float(height), iy);
  if (extension == IMG_EXTENSION_REPEAT) {
    ix = img_wrap_periodic(ix, width);
    iy = img_wrap_periodic(iy, height);
  }
  else {
    if (extension == IMG_EXTENSION_CLIP) {
      if (x < 0.0 || y < 0.0 || x > 1.0 || y > 1.0) {
        return vec4(0.0);
      }
    }
    /* CLIP falls through to EXTEND. */
    ix = img_wrap_clamp(ix, width);
    iy = img_wrap_clamp(iy, height);
  }
  return texelFetch(image, ivec2(ix, iy), 0);
}

vec4 img_interp_linear(int extension, sampler2D image, float x, float y)
{
  ivec2 size = textureSize(image, 0);
  int width = size.x;
  int height = size.y;
  int ix, iy, nix, niy;
  float tx = img_frac(x * float(width) - 0.5, ix);
  float ty = img_frac(y * float(height) - 0.5, iy);
  if (extension == IMG_EXTENSION_REPEAT) {
    ix = img_wrap_periodic(ix, width);
    iy = img_wrap_periodic(iy, height);
    nix = img_wrap_periodic(ix + 1, width);
    niy = img_wrap_periodic(iy + 1, height);
  }
  else if (extension == IMG_EXTENSION_CLIP) {
    /* Texels outside the image read as zero (read()). */
    nix = ix + 1;
    niy = iy + 1;
  }
  else {
    nix = img_wrap_clamp(ix + 1, width);
    niy = img_wrap_clamp(iy + 1, height);
    ix = img_wrap_clamp(ix, width);
    iy = img_wrap_clamp(iy, height);
  }
  return (1.0 - ty) * (1.0 - tx) * img_read(image, ix, iy, width, height) +
         (1.0 - ty) * tx * img_read(image, nix, iy, width, height) +
         ty * (1.0 - tx) * img_read(image, ix, niy, width, height) +
         ty * tx * img_read(image, nix, niy, width, height);
}

vec4 img_interp_cubic(int extension, sampler2D image, float x, float y)
{
  ivec2 size = textureSize(image, 0);
  int width = size.x;
  int height = size.y;
  int ix, iy, nix, niy, pix, piy, nnix, nniy;
  float tx = img_frac(x * float(width) - 0.5, ix);
  float ty = img_frac(y * float(height) - 0.5, iy);
  if (extension == IMG_EXTENSION_REPEAT) {
    ix = img_wrap_periodic(ix, width);
    iy = img_wrap_periodic(iy, height);
    pix = img_wrap_periodic(ix - 1, width);
    piy = img_wrap_periodic(iy - 1, height);
    nix = img_wrap_periodic(ix + 1, width);
    niy = img_wrap_periodic(iy + 1, height);
    nnix = img_wrap_periodic(ix + 2, width);
    nniy = img_wrap_periodic(iy + 2, height);
  }
  else if (extension == IMG_EXTENSION_CLIP) {
    pix = ix - 1;
    piy = iy - 1;
    nix = ix + 1;
    niy = iy + 1;
    nnix = ix + 2;
    nniy = iy + 2;
  }
  else {
    pix = img_wrap_clamp(ix - 1, width);
    piy = img_wrap_clamp(iy - 1, height);
    nix = img_wrap_clamp(ix + 1, width);
    niy = img_wrap_clamp(iy + 1, height);
    nnix = img_wrap_clamp(ix + 2, width);
    nniy = img_wrap_clamp(iy + 2, height);
    ix = img_wrap_clamp(ix, width);
    iy = img_wrap_clamp(iy, height);
  }
  ivec4 xc = ivec4(pix, ix, nix, nnix);
  ivec4 yc = ivec4(piy, iy, niy, nniy);
  vec4 u = img_cubic_weights(tx);
  vec4 v = img_cubic_weights(ty);
  /* TERM(0) + TERM(1) + TERM(2) + TERM(3), TERM(col) = v[col] * (u[0] * DATA(0, col) +
   * u[1] * DATA(1, col) + u[2] * DATA(2, col) + u[3] * DATA(3, col)). */
  vec4 r = vec4(0.0);
  for (int col = 0; col < 4; col++) {
    int yy = yc[col];
    r += v[col] * (u.x * img_read(image, xc.x, yy, width, height) +
                   u.y * img_read(image, xc.y, yy, width, height) +
                   u.z * img_read(image, xc.z, yy, width, height) +
                   u.w * img_read(image, xc.w, yy, width, height));
  }
  return r;
}

vec4 img_interp(int interpolation, int extension, sampler2D image, float x, float y)
{
  if (interpolation == IMG_INTERP_CLOSEST) {
    return img_interp_closest(extension, image, x, y);
  }
  if (interpolation == IMG_INTERP_LINEAR) {
    return img_interp_linear(extension, image, x, y);
  }
  /* Cubic, and Smart (CPU: interp() sends every other type to interp_cubic). */
  return img_interp_cubic(extension, image, x, y);
}

/* util/color.h color_srgb_to_linear */
float img_srgb_to_linear(float c)
{
  if (c < 0.04045) {
    return (c < 0.0) ? 0.0 : c * (1.0 / 12.92);
  }
  return pow((c + 0.055) * (1.0 / 1.055), 2.4);
}

/* kernel/svm/image.h svm_image_texture (for a found image). */
vec4 img_texture(int interpolation, int extension, int flags, sampler2D image, float x, float y)
{
  vec4 r = img_interp(interpolation, extension, image, x, y);
  if ((flags & IMG_FLAG_ALPHA_ONE) != 0) {
    r.w = 1.0;
  }
  float alpha = r.w;
  if ((flags & IMG_FLAG_UNASSOCIATE) != 0 && alpha != 1.0 && alpha != 0.0) {
    r /= alpha;
    r.w = alpha;
  }
  if ((flags & IMG_FLAG_SRGB) != 0) {
    r = vec4(img_srgb_to_linear(r.x), img_srgb_to_linear(r.y), img_srgb_to_linear(r.z), r.w);
  }
  return r;
}

/* C's atan2f(): GLSL's atan(y, x) is undefined at x == y == 0, where C gives +-0 or +-pi;
 * the callers reach the origin only as direction_to_equirectangular of a vertical
 * direction, where C's atan2f(+-0, +0) is +-0. */
float img_atan2f(float y, float x)
{
  if (x == 0.0 && y == 0.0) {
    return 0.0;
  }
  return atan(y, x);
}

/* util/math.h safe_acosf */
float img_safe_acosf(float a)
{
  return acos(clamp(a, -1.0, 1.0));
}

/* kernel/svm/image.h texco_remap_square */
vec3 img_texco_remap_square(vec3 co)
{
  return (co - vec3(0.5, 0.5, 0.5)) * 2.0;
}

/* util/math.h map_to_tube (3.4) */
vec2 img_map_to_tube(vec3 co)
{
  float u, v;
  float len = sqrt(co.x * co.x + co.y * co.y);
  if (len > 0.0) {
    u = (1.0 - (img_atan2f(co.x / len, co.y / len) / 3.14159265358979323846)) * 0.5;
    v = (co.z + 1.0) * 0.5;
  }
  else {
    u = v = 0.0;
  }
  return vec2(u, v);
}

/* util/math.h map_to_sphere (3.4: l = dot(co, co), M_1_2PI_F, M_1_PI_F) */
vec2 img_map_to_sphere(vec3 co)
{
  float l = dot(co, co);
  float u, v;
  if (l > 0.0) {
    if (co.x == 0.0 && co.y == 0.0) {
      u = 0.0; /* Otherwise domain error. */
    }
    else {
      u = (0.5 - img_atan2f(co.x, co.y) * 0.15915494309189533577);
    }
    v = 1.0 - img_safe_acosf(co.z / sqrt(l)) * 0.31830988618379067154;
  }
  else {
    u = v = 0.0;
  }
  return vec2(u, v);
}

/* The 1x1 magenta texture Cycles' ImageManager substitutes for an image that fails to
 * load (device_load_image), filtered like any other texture, without a sampler: every
 * texel read inside the image is IMG_MISSING_COLOR, so the result is the colour times the
 * summed weights of the in-image texels (separable in x and y). */
float img_missing_weight_1d(int interpolation, int extension, float x, bool clip_closest_out)
{
  if (extension != IMG_EXTENSION_CLIP) {
    return 1.0; /* REPEAT/EXTEND map every texel index to the single texel. */
  }
  int ix;
  if (interpolation == IMG_INTERP_CLOSEST) {
    return clip_closest_out ? 0.0 : 1.0;
  }
  float t = img_frac(x - 0.5, ix);
  if (interpolation == IMG_INTERP_LINEAR) {
    return ((ix == 0) ? (1.0 - t) : 0.0) + ((ix + 1 == 0) ? t : 0.0);
  }
  vec4 u = img_cubic_weights(t);
  return ((ix - 1 == 0) ? u.x : 0.0) + ((ix == 0) ? u.y : 0.0) + ((ix + 1 == 0) ? u.z : 0.0) +
         ((ix + 2 == 0) ? u.w : 0.0);
}

vec4 img_texture_missing(int interpolation, int extension, int flags, float x, float y)
{
  bool out_of_range = (x < 0.0 || y < 0.0 || x > 1.0 || y > 1.0);
  float w = img_missing_weight_1d(interpolation, extension, x, out_of_range) *
            img_missing_weight_1d(interpolation, extension, y, out_of_range);
  vec4 r = w * IMG_MISSING_COLOR;
  float alpha = r.w;
  if ((flags & IMG_FLAG_UNASSOCIATE) != 0 && alpha != 1.0 && alpha != 0.0) {
    r /= alpha;
    r.w = alpha;
  }
  /* sRGB decoding leaves 0 and 1 unchanged; the weights make other values only in
   * CLIP borders, where Cycles decodes them too. */
  if ((flags & IMG_FLAG_SRGB) != 0) {
    r = vec4(img_srgb_to_linear(r.x), img_srgb_to_linear(r.y), img_srgb_to_linear(r.z), r.w);
  }
  return r;
}

/* svm_node_tex_image's coordinate step: projection, then the UDIM tile lookup (tile 1001
 * only; any other tile is reported as missing through `missing`). */
vec2 img_tex_co(int projection, int flags, vec3 co, out bool missing)
{
  vec2 tex_co;
  if (projection == IMG_PROJ_SPHERE) {
    tex_co = img_map_to_sphere(img_texco_remap_square(co));
  }
  else if (projection == IMG_PROJ_TUBE) {
    tex_co = img_map_to_tube(img_texco_remap_square(co));
  }
  else {
    tex_co = co.xy;
  }
  missing = false;
  if ((flags & IMG_FLAG_UDIM_1001) != 0) {
    /* int tx = (int)tex_co.x, ty likewise; tile 1001 + 10 ty + tx when tx >= 0, ty >= 0,
     * tx < 10; the UVs are then made tile-relative (unchanged for tile 1001). */
    int tx = int(tex_co.x);
    int ty = int(tex_co.y);
    missing = !(tx == 0 && ty == 0);
  }
  return tex_co;
}

/* util/math_float3.h safe_normalize: a * (1 / len) when len != 0. */
vec3 img_safe_normalize(vec3 a)
{
  float t = sqrt(dot(a, a));
  return (t != 0.0) ? a * (1.0 / t) : a;
}

/* scene/shader_nodes.cpp TextureMapping::compile_begin: when TextureMapping::skip() is
 * false, NODE_TEXTURE_MAPPING (kernel/svm/mapping.h svm_node_texture_mapping) applies
 * transform_point() with TextureMapping::compute_transform() (rows x, y, z of the 3x4
 * Transform in a constant block of 12 floats, computed in image.py); type NORMAL then
 * normalizes (NODE_VECTOR_MATH_NORMALIZE: safe_normalize). map_mode: 0 none, 1 affine,
 * 2 affine then normalize. */
vec3 img_mapping_apply(int map_mode, int map_block, vec3 a)
{
  if (map_mode == 0) {
    return a;
  }
  int o = map_block;
  vec3 c = vec3(a.x * mat_const(o + 0) + a.y * mat_const(o + 1) + a.z * mat_const(o + 2) +
                    mat_const(o + 3),
                a.x * mat_const(o + 4) + a.y * mat_const(o + 5) + a.z * mat_const(o + 6) +
                    mat_const(o + 7),
                a.x * mat_const(o + 8) + a.y * mat_const(o + 9) + a.z * mat_const(o + 10) +
                    mat_const(o + 11));
  if (map_mode == 2) {
    c = img_safe_normalize(c);
  }
  return c;
}

/* ------------------------------------------------------------------------------------ */
/* Nodes                                                                                */
/* ------------------------------------------------------------------------------------ */

/* Image Texture, projection FLAT / SPHERE / TUBE: kernel/svm/image.h svm_node_tex_image. */
void node_tex_image(int interpolation,
                    int extension,
                    int projection,
                    int flags,
                    int map_mode,
                    int map_block,
                    sampler2D image,
                    vec3 co,
                    out vec3 color,
                    out float alpha)
{
  co = img_mapping_apply(map_mode, map_block, co);
  bool missing;
  vec2 tex_co = img_tex_co(projection, flags, co, missing);
  vec4 f = missing ? IMG_MISSING_COLOR :
                     img_texture(interpolation, extension, flags, image, tex_co.x, tex_co.y);
  color = f.xyz;
  alpha = f.w;
}

/* Image Texture with no image: Cycles loads an empty file name, which fails, and binds
 * its 1x1 magenta texture (scene/image.cpp device_load_image). */
void node_tex_image_missing(int interpolation,
                            int extension,
                            int projection,
                            int flags,
                            int map_mode,
                            int map_block,
                            vec3 co,
                            out vec3 color,
                            out float alpha)
{
  co = img_mapping_apply(map_mode, map_block, co);
  bool missing;
  vec2 tex_co = img_tex_co(projection, 0, co, missing);
  vec4 f = img_texture_missing(interpolation, extension, flags, tex_co.x, tex_co.y);
  color = f.xyz;
  alpha = f.w;
}

/* Box-projection weights of kernel/svm/image.h svm_node_tex_image_box, from the
 * object-space normal N_object (Cycles: sd->N through object_inverse_normal_transform;
 * its length does not matter here). */
vec3 img_box_weights(vec3 N_object, float blend, out vec3 signed_N)
{
  vec3 N = N_object;
  signed_N = N;
  N = abs(N);
  N /= (N.x + N.y + N.z);

  vec3 weight = vec3(0.0);
  float limit = 0.5 * (1.0 + blend);

  if (N.x > limit * (N.x + N.y) && N.x > limit * (N.x + N.z)) {
    weight.x = 1.0;
  }
  else if (N.y > limit * (N.x + N.y) && N.y > limit * (N.y + N.z)) {
    weight.y = 1.0;
  }
  else if (N.z > limit * (N.x + N.z) && N.z > limit * (N.y + N.z)) {
    weight.z = 1.0;
  }
  else if (blend > 0.0) {
    if (N.z < (1.0 - limit) * (N.y + N.x)) {
      weight.x = N.x / (N.x + N.y);
      weight.x = clamp((weight.x - 0.5 * (1.0 - blend)) / blend, 0.0, 1.0);
      weight.y = 1.0 - weight.x;
    }
    else if (N.x < (1.0 - limit) * (N.y + N.z)) {
      weight.y = N.y / (N.y + N.z);
      weight.y = clamp((weight.y - 0.5 * (1.0 - blend)) / blend, 0.0, 1.0);
      weight.z = 1.0 - weight.y;
    }
    else if (N.y < (1.0 - limit) * (N.x + N.z)) {
      weight.x = N.x / (N.x + N.z);
      weight.x = clamp((weight.x - 0.5 * (1.0 - blend)) / blend, 0.0, 1.0);
      weight.z = 1.0 - weight.x;
    }
    else {
      weight.x = ((2.0 - limit) * N.x + (limit - 1.0)) / (2.0 * limit - 1.0);
      weight.y = ((2.0 - limit) * N.y + (limit - 1.0)) / (2.0 * limit - 1.0);
      weight.z = ((2.0 - limit) * N.z + (limit - 1.0)) / (2.0 * limit - 1.0);
    }
  }
  else {
    /* Desperate mode, no valid choice anyway, fallback to one side. */
    weight.x = 1.0;
  }
  return weight;
}

/* Image Texture, projection BOX: kernel/svm/image.h svm_node_tex_image_box. Tiles play
 * no part (Cycles culls a box-projected UDIM image to tile 1001). */
void node_tex_image_box(int interpolation,
                        int extension,
                        int flags,
                        int map_mode,
                        int map_block,
                        sampler2D image,
                        vec3 co,
                        vec3 N_object,
                        float blend,
                        out vec3 color,
                        out float alpha)
{
  co = img_mapping_apply(map_mode, map_block, co);
  vec3 signed_N;
  vec3 weight = img_box_weights(N_object, blend, signed_N);
  vec4 f = vec4(0.0);
  /* Map so that no textures are flipped, rotation is somewhat arbitrary. */
  if (weight.x > 0.0) {
    vec2 uv = vec2((signed_N.x < 0.0) ? 1.0 - co.y : co.y, co.z);
    f += weight.x * img_texture(interpolation, extension, flags, image, uv.x, uv.y);
  }
  if (weight.y > 0.0) {
    vec2 uv = vec2((signed_N.y > 0.0) ? 1.0 - co.x : co.x, co.z);
    f += weight.y * img_texture(interpolation, extension, flags, image, uv.x, uv.y);
  }
  if (weight.z > 0.0) {
    vec2 uv = vec2((signed_N.z > 0.0) ? 1.0 - co.y : co.y, co.x);
    f += weight.z * img_texture(interpolation, extension, flags, image, uv.x, uv.y);
  }
  color = f.xyz;
  alpha = f.w;
}

/* Box projection with no image: as above with the 1x1 magenta texture. */
void node_tex_image_box_missing(int interpolation,
                                int extension,
                                int flags,
                                int map_mode,
                                int map_block,
                                vec3 co,
                                vec3 N_object,
                                float blend,
                                out vec3 color,
                                out float alpha)
{
  co = img_mapping_apply(map_mode, map_block, co);
  vec3 signed_N;
  vec3 weight = img_box_weights(N_object, blend, signed_N);
  vec4 f = vec4(0.0);
  if (weight.x > 0.0) {
    vec2 uv = vec2((signed_N.x < 0.0) ? 1.0 - co.y : co.y, co.z);
    f += weight.x * img_texture_missing(interpolation, extension, flags, uv.x, uv.y);
  }
  if (weight.y > 0.0) {
    vec2 uv = vec2((signed_N.y > 0.0) ? 1.0 - co.x : co.x, co.z);
    f += weight.y * img_texture_missing(interpolation, extension, flags, uv.x, uv.y);
  }
  if (weight.z > 0.0) {
    vec2 uv = vec2((signed_N.z > 0.0) ? 1.0 - co.y : co.y, co.x);
    f += weight.z * img_texture_missing(interpolation, extension, flags, uv.x, uv.y);
  }
  color = f.xyz;
  alpha = f.w;
}

/* kernel/camera/projection.h direction_to_equirectangular: the range
 * (-2 pi, pi, -pi, pi), so u = (atan2(y, x) - pi) / -2pi, v = (acos(z / |d|) - pi) / -pi. */
vec2 img_direction_to_equirectangular(vec3 dir)
{
  if (dir.x == 0.0 && dir.y == 0.0 && dir.z == 0.0) {
    return vec2(0.0);
  }
  float u = (img_atan2f(dir.y, dir.x) - 3.14159265358979323846) / -6.28318530717958647692;
  /* acos(z / |d|) as atan2(|d.xy|, z): the same angle, but GPU acos (llvmpipe's
   * especially) is far less accurate than atan, and an error of 1e-4 rad is
   * a 50th of a 1024-wide map's texel: visible on a sharp HDRI. */
  float v = (atan(length(dir.xy), dir.z) - 3.14159265358979323846) / -3.14159265358979323846;
  return vec2(u, v);
}

/* kernel/camera/projection.h direction_to_mirrorball */
vec2 img_direction_to_mirrorball(vec3 dir)
{
  dir.y -= 1.0;
  float div = 2.0 * sqrt(max(-0.5 * dir.y, 0.0));
  if (div > 0.0) {
    dir /= div;
  }
  float u = 0.5 * (dir.x + 1.0);
  float v = 0.5 * (dir.z + 1.0);
  return vec2(u, v);
}

vec2 img_env_uv(int projection, vec3 direction)
{
  vec3 co = img_safe_normalize(direction);
  return (projection == IMG_ENV_EQUIRECTANGULAR) ? img_direction_to_equirectangular(co) :
                                                   img_direction_to_mirrorball(co);
}

/* Environment Texture lookup: kernel/svm/image.h svm_node_tex_environment, returning
 * colour and alpha. Extension is always REPEAT (EnvironmentTextureNode::image_params);
 * only IMG_FLAG_SRGB and IMG_FLAG_ALPHA_ONE apply (the colour stays associated: Cycles'
 * environment node never unassociates). `direction` is the Vector input after the
 * texture mapping; unlinked it is the position, which for a world is the ray direction. */
vec4 img_environment(int interpolation, int projection, int flags, sampler2D image, vec3 direction)
{
  vec2 uv = img_env_uv(projection, direction);
  return img_texture(interpolation,
                     IMG_EXTENSION_REPEAT,
                     flags & (IMG_FLAG_SRGB | IMG_FLAG_ALPHA_ONE),
                     image,
                     uv.x,
                     uv.y);
}

/* The Environment Texture node (Blender 3.4's node has a Color output only). */
void node_tex_environment(int interpolation,
                          int projection,
                          int flags,
                          int map_mode,
                          int map_block,
                          sampler2D image,
                          vec3 direction,
                          out vec3 color)
{
  vec4 f = img_environment(
      interpolation, projection, flags, image, img_mapping_apply(map_mode, map_block, direction));
  color = f.xyz;
}

/* The same with Cycles' alpha too (EnvironmentTextureNode has an Alpha socket that
 * Blender does not show), for callers outside node trees such as the world. */
void node_tex_environment_rgba(int interpolation,
                               int projection,
                               int flags,
                               int map_mode,
                               int map_block,
                               sampler2D image,
                               vec3 direction,
                               out vec3 color,
                               out float alpha)
{
  vec4 f = img_environment(
      interpolation, projection, flags, image, img_mapping_apply(map_mode, map_block, direction));
  color = f.xyz;
  alpha = f.w;
}

/* Environment Texture with no image: the 1x1 magenta texture with REPEAT, i.e. magenta. */
void node_tex_environment_missing(int interpolation,
                                  int projection,
                                  int flags,
                                  int map_mode,
                                  int map_block,
                                  vec3 direction,
                                  out vec3 color)
{
  color = IMG_MISSING_COLOR.xyz;
}

#endif /* NODE_IMAGE_LIB */
