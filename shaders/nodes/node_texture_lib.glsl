/* Procedural texture nodes, computed as Cycles 3.4 computes them.
 *
 * Source read: the Cycles kernel that Blender 3.4.1 ships (and compiles for GPUs) in
 * scripts/addons/cycles/source/ (kernel/svm/{noise,fractal_noise,noisetex,voronoi,
 * musgrave,wave,checker,brick,gradient,magic,white_noise,mapping}.h, util/{hash,math,
 * math_float2,math_float3,math_float4,transform}.h), plus intern/cycles/blender/shader.cpp
 * and intern/cycles/scene/shader_nodes.cpp of the 3.x series for how node properties and
 * the texture mapping reach the kernel. Each function below names the Cycles function it
 * transcribes. Where Cycles has an SSE/AVX variant (perlin_2d/3d/4d, float3 dot/len) the
 * scalar variant is followed: it is what Cycles' GPU kernels run, and what these sources hold.
 *
 * Float arithmetic is written in Cycles' operation order with Cycles' own helpers
 * (mix = a + t * (b - a), smoothstep, safe_divide, float2/float4 division by a scalar as a
 * multiply by its reciprocal, len = sqrt(dot), ...) rather than GLSL builtins whose
 * definitions differ. Integer hashes are exact (uint wraps like C). Where a GLSL compiler
 * may legally round differently from C, the code pins the rounding down:
 *  - `precise` on the expressions a compiler would otherwise rewrite (Mesa turns
 *    a * (1 - t) + b * t into other lerp forms and reassociates constants; NVIDIA contracts
 *    a * b + c into fma), so they round as the C code does;
 *  - double precision (core in GLSL 4.50) for C's sinf/cosf (Wave, Magic), powf (Musgrave),
 *    fmodf (Magic), atan2f (Gradient RADIAL) and a correctly rounded division (Wave), which
 *    GLSL's sin/cos/pow/atan/mod do not give;
 *  - -0 canonicalised before Voronoi hashes a cell coordinate (see tex_cell()).
 * Checked by running this file on Mesa llvmpipe against these Cycles sources compiled as C++
 * (scalar path, no fp contraction) on random inputs: the hashes, Perlin/fractal noise, Noise,
 * Voronoi, Wave, Checker, Brick, Gradient, White Noise and the mapping are bit-exact except
 * Voronoi MINKOWSKI with exponents other than 0.5, 1, 2 (GLSL pow per cell), and libm's own
 * sinf/powf/atan2f roundings (not always correctly rounded) leave Musgrave, Gradient RADIAL,
 * Wave SIN 1-ulp differences in a few percent of points and Magic a few ulps (amplified by
 * its iterations) in ~5 %. A GPU's float sqrt and division may still be a few ulps off.
 *
 * Enum values (compile-time ints; texture.py holds the same tables):
 *   dimensions               1 = 1D, 2 = 2D, 3 = 3D, 4 = 4D
 *   Voronoi feature          0 F1, 1 F2, 2 SMOOTH_F1, 3 DISTANCE_TO_EDGE, 4 N_SPHERE_RADIUS
 *   Voronoi metric           0 EUCLIDEAN, 1 MANHATTAN, 2 CHEBYCHEV, 3 MINKOWSKI
 *   Musgrave type            0 MULTIFRACTAL, 1 FBM, 2 HYBRID_MULTIFRACTAL,
 *                            3 RIDGED_MULTIFRACTAL, 4 HETERO_TERRAIN
 *   Wave type                0 BANDS, 1 RINGS
 *   Wave bands direction     0 X, 1 Y, 2 Z, 3 DIAGONAL
 *   Wave rings direction     0 X, 1 Y, 2 Z, 3 SPHERICAL
 *   Wave profile             0 SIN, 1 SAW, 2 TRI
 *   Gradient type            0 LINEAR, 1 QUADRATIC, 2 EASING, 3 DIAGONAL, 4 RADIAL,
 *                            5 QUADRATIC_SPHERE, 6 SPHERICAL
 *   Texture mapping mode     0 none (identity: Cycles' TextureMapping::skip()),
 *                            1 affine 3x4 transform in a constant block of 12 floats
 *                              (rows x, y, z of Cycles' Transform), 2 the same then
 *                              safe_normalize (TextureMapping type NORMAL)
 *
 * (kernel/svm/types.h: NodeVoronoiFeature, NodeVoronoiDistanceMetric, NodeMusgraveType,
 * NodeWaveType, NodeWaveBandsDirection, NodeWaveRingsDirection, NodeWaveProfile,
 * NodeGradientType; Blender's RNA enum values are the same numbers, and
 * blender/shader.cpp casts them straight across.) */

#ifndef NODE_TEXTURE_LIB
#define NODE_TEXTURE_LIB

#include "nodes/hash_lib.glsl"

/* ==================================================================================== */
/* Helpers: Cycles' util/math*.h semantics                                              */
/* ==================================================================================== */

/* util/math.h: mix(float, float, float) and its float2/3/4 overloads: a + t * (b - a). */
float tex_mix(float a, float b, float t)
{
  precise float r = a + t * (b - a);
  return r;
}
vec2 tex_mix(vec2 a, vec2 b, float t)
{
  precise vec2 r = a + t * (b - a);
  return r;
}
vec3 tex_mix(vec3 a, vec3 b, float t)
{
  precise vec3 r = a + t * (b - a);
  return r;
}
vec4 tex_mix(vec4 a, vec4 b, float t)
{
  precise vec4 r = a + t * (b - a);
  return r;
}

/* util/math.h: smoothstep() (not GLSL's: no clamp, defined for any edges). */
float tex_smoothstep(float edge0, float edge1, float x)
{
  float result;
  if (x < edge0) {
    result = 0.0;
  }
  else if (x >= edge1) {
    result = 1.0;
  }
  else {
    precise float t = (x - edge0) / (edge1 - edge0);
    precise float r = (3.0 - 2.0 * t) * (t * t);
    result = r;
  }
  return result;
}

/* util/math.h: smoothstepf() */
float tex_smoothstepf(float f)
{
  precise float ff = f * f;
  precise float r = (3.0 * ff - 2.0 * ff * f);
  return r;
}

/* util/math.h: floorfrac(): float_to_int() is a C (int) cast, i.e. truncation, of floorf(x). */
float tex_floorfrac(float x, out int i)
{
  float f = floor(x);
  i = int(f);
  return x - f;
}

/* util/math.h: ensure_finite() (isfinite_safe() tests the bits, so fast math cannot drop it). */
float tex_ensure_finite(float v)
{
  return ((floatBitsToUint(v) & 0x7f800000u) == 0x7f800000u) ? 0.0 : v;
}

/* util/math.h: safe_divide(float, float) */
float tex_safe_divide(float a, float b)
{
  return (b != 0.0) ? a / b : 0.0;
}

/* Cycles' vector-by-scalar division differs by type (scalar kernel, util/math_float2/3/4.h):
 * float2 / f and float4 / f multiply by 1.0f / f; float3 / f divides each component. */
vec2 tex_div_vs(vec2 a, float f)
{
  precise float invf = 1.0 / f;
  precise vec2 r = a * invf;
  return r;
}
vec3 tex_div_vs(vec3 a, float f)
{
  return vec3(a.x / f, a.y / f, a.z / f);
}
vec4 tex_div_vs(vec4 a, float f)
{
  precise float invf = 1.0 / f;
  precise vec4 r = a * invf;
  return r;
}

/* util/math_float2.h: safe_divide_float2_float(); math_float3.h / math_float4.h:
 * safe_divide(float3/float4, float). */
vec2 tex_safe_divide(vec2 a, float b)
{
  return (b != 0.0) ? tex_div_vs(a, b) : vec2(0.0);
}
vec3 tex_safe_divide(vec3 a, float b)
{
  return (b != 0.0) ? tex_div_vs(a, b) : vec3(0.0);
}
vec4 tex_safe_divide(vec4 a, float b)
{
  return (b != 0.0) ? tex_div_vs(a, b) : vec4(0.0);
}

/* util/math_float2/3/4.h: dot() (scalar versions; float4 sums in pairs). */
float tex_dot(vec2 a, vec2 b)
{
  precise float r = a.x * b.x + a.y * b.y;
  return r;
}
float tex_dot(vec3 a, vec3 b)
{
  precise float r = a.x * b.x + a.y * b.y + a.z * b.z;
  return r;
}
float tex_dot(vec4 a, vec4 b)
{
  precise float r = (a.x * b.x + a.y * b.y) + (a.z * b.z + a.w * b.w);
  return r;
}

/* util/math_float2/3/4.h: len() = sqrtf(dot(a, a)). */
float tex_len(vec2 a)
{
  return sqrt(tex_dot(a, a));
}
float tex_len(vec3 a)
{
  return sqrt(tex_dot(a, a));
}
float tex_len(vec4 a)
{
  return sqrt(tex_dot(a, a));
}

/* util/math_float2/3/4.h: distance(a, b) = len(a - b); for floats, Cycles writes fabsf(a - b). */
float tex_distance(float a, float b)
{
  return abs(a - b);
}
float tex_distance(vec2 a, vec2 b)
{
  return tex_len(a - b);
}
float tex_distance(vec3 a, vec3 b)
{
  return tex_len(a - b);
}
float tex_distance(vec4 a, vec4 b)
{
  return tex_len(a - b);
}

/* util/math_float2/3/4.h: normalize() = a / len(a) (with the division of each type). */
vec2 tex_normalize(vec2 a)
{
  return tex_div_vs(a, tex_len(a));
}
vec3 tex_normalize(vec3 a)
{
  return tex_div_vs(a, tex_len(a));
}
vec4 tex_normalize(vec4 a)
{
  return tex_div_vs(a, tex_len(a));
}

/* util/math_float3.h: safe_normalize() */
vec3 tex_safe_normalize(vec3 a)
{
  float t = tex_len(a);
  return (t != 0.0) ? a * (1.0 / t) : a;
}

/* powf() for a >= 0, as Voronoi's Minkowski metric uses it (per cell and axis, so the double
 * tex_powf() would be too slow on GPUs with slow doubles). The exponents 1, 2 and 0.5 (the
 * node's default) and their reciprocals are computed exactly as a correctly rounded powf
 * gives them (a, a * a, sqrt(a)); other exponents use GLSL's pow(), a few ulps from libm.
 * GLSL's pow() is undefined at 0, C's powf(0, b) is 1 for b == 0, 0 for b > 0, +inf for
 * b < 0. */
float tex_powf_nonneg(float a, float b)
{
  if (b == 0.0) {
    return 1.0;
  }
  if (a == 0.0) {
    return (b > 0.0) ? 0.0 : uintBitsToFloat(0x7f800000u);
  }
  if (b == 1.0) {
    return a;
  }
  if (b == 2.0) {
    precise float r = a * a;
    return r;
  }
  if (b == 0.5) {
    return sqrt(a);
  }
  return pow(a, b);
}

/* C's powf(a, b) for a > 0 (Musgrave's powf(lacunarity, -H)): GLSL's pow() is exp2(b * log2(a))
 * in float, several ulps off. Here exp(b * log(a)) in double: log by the atanh series on a
 * mantissa in [sqrt(1/2), sqrt(2)), exp by Taylor after reduction by ln 2 (ln 2 split so
 * that n * ln2_hi is exact); relative error ~1e-14, so the float result is correctly rounded
 * but for rare ties, as libm's powf is (glibc: < 0.82 ulp). Other a, b: GLSL's pow(). */
double tex_log_d(double x)
{
  int e;
  double m = frexp(x, e); /* x = m * 2^e, m in [0.5, 1) */
  if (m < 0.7071067811865476lf) {
    m *= 2.0lf;
    e -= 1;
  }
  precise double s = (m - 1.0lf) / (m + 1.0lf);
  precise double s2 = s * s;
  precise double p = 0.043478260869565216lf;
  p = p * s2 + 0.047619047619047616lf;
  p = p * s2 + 0.05263157894736842lf;
  p = p * s2 + 0.058823529411764705lf;
  p = p * s2 + 0.06666666666666667lf;
  p = p * s2 + 0.07692307692307693lf;
  p = p * s2 + 0.09090909090909091lf;
  p = p * s2 + 0.1111111111111111lf;
  p = p * s2 + 0.14285714285714285lf;
  p = p * s2 + 0.2lf;
  p = p * s2 + 0.3333333333333333lf;
  precise double r = double(e) * 0.6931471805599453lf + 2.0lf * s * (1.0lf + s2 * p);
  return r;
}

double tex_exp_d(double t)
{
  precise double n = floor(t * 1.4426950408889634lf + 0.5lf);
  precise double r = (t - n * 0.6931471803691238lf) - n * 1.9082149292705877e-10lf;
  precise double p = 1.6059043836821613e-10lf;
  p = p * r + 2.08767569878681e-09lf;
  p = p * r + 2.505210838544172e-08lf;
  p = p * r + 2.755731922398589e-07lf;
  p = p * r + 2.7557319223985893e-06lf;
  p = p * r + 2.48015873015873e-05lf;
  p = p * r + 0.0001984126984126984lf;
  p = p * r + 0.001388888888888889lf;
  p = p * r + 0.008333333333333333lf;
  p = p * r + 0.041666666666666664lf;
  p = p * r + 0.16666666666666666lf;
  p = p * r + 0.5lf;
  p = p * r + 1.0lf;
  p = p * r + 1.0lf;
  return ldexp(p, int(n));
}

float tex_powf(float a, float b)
{
  bool finite_args = ((floatBitsToUint(a) & 0x7f800000u) != 0x7f800000u) &&
                     ((floatBitsToUint(b) & 0x7f800000u) != 0x7f800000u);
  if (!(a > 0.0) || !finite_args) {
    return pow(a, b);
  }
  if (b == 0.0 || a == 1.0) {
    return 1.0;
  }
  precise double t = double(b) * tex_log_d(double(a));
  if (t > 89.0lf) {
    return uintBitsToFloat(0x7f800000u); /* overflows float */
  }
  if (t < -110.0lf) {
    return 0.0;
  }
  return float(tex_exp_d(t));
}

/* C's fmodf(a, b): truncated quotient, the result has the sign of a (GLSL's mod() floors
 * instead), and it is exact. In double: while |a / b| < 2^24 the double quotient cannot round
 * across an integer, q * b is exact (48 bits) and a - q * b is the exact, float-representable
 * remainder. */
float tex_fmodf(float a, float b)
{
  precise double da = double(a);
  precise double db = double(b);
  precise double q = trunc(da / db);
  precise double r = da - q * db;
  float fr = float(r);
  if (fr == 0.0) {
    fr = uintBitsToFloat(floatBitsToUint(a) & 0x80000000u); /* fmodf keeps the sign of a */
  }
  return fr;
}

/* atan(t) for 0 <= t <= 1 in double: t > tan(pi/8) is moved by pi/4, the angle halved once
 * (atan u = 2 atan(u / (1 + sqrt(1 + u^2)))), then the series to degree 23 (|v| <= tan(pi/16)). */
double tex_atan01_d(double t)
{
  precise double base = 0.0lf;
  precise double u = t;
  if (t > 0.41421356237309503lf) {
    u = (t - 1.0lf) / (t + 1.0lf);
    base = 0.7853981633974483lf;
  }
  precise double v = u / (1.0lf + sqrt(1.0lf + u * u));
  precise double v2 = v * v;
  precise double p = -0.043478260869565216lf;
  p = p * v2 + 0.047619047619047616lf;
  p = p * v2 + -0.05263157894736842lf;
  p = p * v2 + 0.058823529411764705lf;
  p = p * v2 + -0.06666666666666667lf;
  p = p * v2 + 0.07692307692307693lf;
  p = p * v2 + -0.09090909090909091lf;
  p = p * v2 + 0.1111111111111111lf;
  p = p * v2 + -0.14285714285714285lf;
  p = p * v2 + 0.2lf;
  p = p * v2 + -0.3333333333333333lf;
  precise double r = base + 2.0lf * (v + v * v2 * p);
  return r;
}

/* C's atan2f() (Gradient RADIAL, once per shading point): computed in double and rounded,
 * i.e. correctly rounded but for rare ties (libm's atan2f is within an ulp of that); GLSL's
 * atan(y, x) is a few ulps off and undefined at x == y == 0, where C gives +-0 or +-pi. */
float tex_atan2f(float y, float x)
{
  bool y_neg = (floatBitsToUint(y) & 0x80000000u) != 0u;
  if (x == 0.0 && y == 0.0) {
    bool x_neg = (floatBitsToUint(x) & 0x80000000u) != 0u;
    float r = x_neg ? 3.1415926535897932 : 0.0;
    return y_neg ? -r : r;
  }
  if (((floatBitsToUint(x) & 0x7f800000u) == 0x7f800000u) ||
      ((floatBitsToUint(y) & 0x7f800000u) == 0x7f800000u)) {
    return atan(y, x); /* inf or NaN */
  }
  double ax = abs(double(x));
  double ay = abs(double(y));
  bool swap = ay > ax;
  precise double a = tex_atan01_d(swap ? ax / ay : ay / ax);
  if (swap) {
    a = 1.5707963267948966lf - a;
  }
  if (x < 0.0) {
    a = 3.141592653589793lf - a;
  }
  return float(y_neg ? -a : a);
}

/* Voronoi hashes the cell coordinate cellPosition + cellOffset. In C that sum is never -0
 * (float(0) is +0 and -0 + +0 == +0), but GLSL compilers may fold `x + 0.0` to `x` and keep
 * a -0 from floor(-0.0): the hash would see different bits. Canonicalising -0 to +0 gives
 * Cycles' value whatever the compiler does. */
float tex_cell(float x)
{
  uint u = floatBitsToUint(x);
  return uintBitsToFloat(u == 0x80000000u ? 0u : u);
}
vec2 tex_cell(vec2 x)
{
  return vec2(tex_cell(x.x), tex_cell(x.y));
}
vec3 tex_cell(vec3 x)
{
  return vec3(tex_cell(x.x), tex_cell(x.y), tex_cell(x.z));
}
vec4 tex_cell(vec4 x)
{
  return vec4(tex_cell(x.x), tex_cell(x.y), tex_cell(x.z), tex_cell(x.w));
}

/* C's sinf()/cosf(), correctly rounded but for rare ties, for |x| < 65536: GLSL's sin()/cos()
 * have no precision requirement and drift from libm for arguments of a few hundred radians,
 * which Wave (n = 20 * coordinate) and Magic (iterated sin/cos) reach. The argument is reduced
 * by pi/2 in double precision (pi/2 in three parts, the first two with 36 significant bits so
 * that j * part is exact), and the Taylor series to degree 11/12 is evaluated in double
 * (truncation error < 1e-11 on [-pi/4, pi/4]). GLSL 4.50 core has double precision. */
double tex_sincos_reduce(float x, out int quadrant)
{
  precise double dx = double(x);
  precise double j = floor(dx * 0.6366197723675814lf + 0.5lf); /* round(x / (pi / 2)) */
  precise double r = ((dx - j * 1.5707963267923333lf) - j * 2.5633441515839558e-12lf) -
                     j * 1.0562999066987428e-23lf;
  quadrant = int(j);
  return r;
}

/* sin(r + quadrant * pi / 2) for |r| <= pi / 4 (a little more is fine). */
float tex_sincos_poly(double r, int quadrant)
{
  precise double z = r * r;
  precise double s =
      r + r * z *
              (-0.16666666666666666lf +
               z * (0.008333333333333333lf +
                    z * (-0.0001984126984126984lf +
                         z * (2.7557319223985893e-06lf + z * -2.505210838544172e-08lf))));
  precise double c =
      1.0lf +
      z * (-0.5lf +
           z * (0.041666666666666664lf +
                z * (-0.001388888888888889lf +
                     z * (2.48015873015873e-05lf +
                          z * (-2.755731922398589e-07lf + z * 2.08767569878681e-09lf)))));
  int q = quadrant & 3;
  double v = (q == 0) ? s : (q == 1) ? c : (q == 2) ? -s : -c;
  return float(v);
}

float tex_sinf(float x)
{
  if (!(abs(x) < 65536.0)) {
    return sin(x); /* huge, inf or NaN: not worth exactness */
  }
  int q;
  double r = tex_sincos_reduce(x, q);
  return tex_sincos_poly(r, q);
}

float tex_cosf(float x)
{
  if (!(abs(x) < 65536.0)) {
    return cos(x);
  }
  int q;
  double r = tex_sincos_reduce(x, q);
  return tex_sincos_poly(r, q + 1);
}

/* a / b correctly rounded, as C divides, where a GLSL implementation may compute
 * a * (1 / b) or divide to 2.5 ulp: the double quotient rounded to float is the correctly
 * rounded float quotient (53 >= 2 * 24 + 2 bits, so the double rounding is innocuous). */
float tex_div(float a, float b)
{
  return float(double(a) / double(b));
}

/* ==================================================================================== */
/* Texture mapping                                                                      */
/* ==================================================================================== */

/* scene/shader_nodes.cpp: TextureMapping::compile_begin() puts NODE_TEXTURE_MAPPING in front
 * of a texture node when TextureMapping::skip() is false; kernel/svm/mapping.h:
 * svm_node_texture_mapping() applies transform_point() (util/transform.h, scalar) with the
 * Transform from TextureMapping::compute_transform() (computed in texture.py), then for type
 * NORMAL a NODE_VECTOR_MATH normalize (safe_normalize). Min/max is never enabled from
 * Blender (blender/shader.cpp: get_tex_mapping() does not set use_minmax). */
vec3 tex_mapping_apply(int map_mode, int map_block, vec3 a)
{
  if (map_mode == 0) {
    return a;
  }
  int o = map_block;
  precise vec3 c = vec3(a.x * mat_const(o + 0) + a.y * mat_const(o + 1) + a.z * mat_const(o + 2) +
                    mat_const(o + 3),
                a.x * mat_const(o + 4) + a.y * mat_const(o + 5) + a.z * mat_const(o + 6) +
                    mat_const(o + 7),
                a.x * mat_const(o + 8) + a.y * mat_const(o + 9) + a.z * mat_const(o + 10) +
                    mat_const(o + 11));
  if (map_mode == 2) {
    c = tex_safe_normalize(c);
  }
  return c;
}

/* ==================================================================================== */
/* Perlin noise: kernel/svm/noise.h (the standard, non-SSE implementation)              */
/* ==================================================================================== */

/* noise.h: fade() */
float tex_fade(float t)
{
  precise float r = t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
  return r;
}

/* noise.h: negate_if() */
float tex_negate_if(float val, int condition)
{
  return (condition != 0) ? -val : val;
}

/* noise.h: grad1() */
float perlin_grad1(int hash, float x)
{
  int h = hash & 15;
  float g = float(1 + (h & 7));
  return tex_negate_if(g, h & 8) * x;
}

/* noise.h: perlin_1d() */
float perlin_1d(float x)
{
  int X;
  float fx = tex_floorfrac(x, X);
  float u = tex_fade(fx);

  return tex_mix(perlin_grad1(int(hash_uint(uint(X))), fx),
                 perlin_grad1(int(hash_uint(uint(X + 1))), fx - 1.0),
                 u);
}

/* noise.h: bi_mix() */
float perlin_bi_mix(float v0, float v1, float v2, float v3, float x, float y)
{
  precise float x1 = 1.0 - x;
  precise float r = (1.0 - y) * (v0 * x1 + v1 * x) + y * (v2 * x1 + v3 * x);
  return r;
}

/* noise.h: tri_mix() */
float perlin_tri_mix(float v0,
                     float v1,
                     float v2,
                     float v3,
                     float v4,
                     float v5,
                     float v6,
                     float v7,
                     float x,
                     float y,
                     float z)
{
  precise float x1 = 1.0 - x;
  precise float y1 = 1.0 - y;
  precise float z1 = 1.0 - z;
  precise float r = z1 * (y1 * (v0 * x1 + v1 * x) + y * (v2 * x1 + v3 * x)) +
                    z * (y1 * (v4 * x1 + v5 * x) + y * (v6 * x1 + v7 * x));
  return r;
}

/* noise.h: quad_mix() */
float perlin_quad_mix(float v0,
                      float v1,
                      float v2,
                      float v3,
                      float v4,
                      float v5,
                      float v6,
                      float v7,
                      float v8,
                      float v9,
                      float v10,
                      float v11,
                      float v12,
                      float v13,
                      float v14,
                      float v15,
                      float x,
                      float y,
                      float z,
                      float w)
{
  return tex_mix(perlin_tri_mix(v0, v1, v2, v3, v4, v5, v6, v7, x, y, z),
                 perlin_tri_mix(v8, v9, v10, v11, v12, v13, v14, v15, x, y, z),
                 w);
}

/* noise.h: grad2() */
float perlin_grad2(int hash, float x, float y)
{
  int h = hash & 7;
  float u = h < 4 ? x : y;
  float v = 2.0 * (h < 4 ? y : x);
  return tex_negate_if(u, h & 1) + tex_negate_if(v, h & 2);
}

/* noise.h: grad3() */
float perlin_grad3(int hash, float x, float y, float z)
{
  int h = hash & 15;
  float u = h < 8 ? x : y;
  float vt = ((h == 12) || (h == 14)) ? x : z;
  float v = h < 4 ? y : vt;
  return tex_negate_if(u, h & 1) + tex_negate_if(v, h & 2);
}

/* noise.h: grad4() */
float perlin_grad4(int hash, float x, float y, float z, float w)
{
  int h = hash & 31;
  float u = h < 24 ? x : y;
  float v = h < 16 ? y : z;
  float s = h < 8 ? z : w;
  return tex_negate_if(u, h & 1) + tex_negate_if(v, h & 2) + tex_negate_if(s, h & 4);
}

/* hash_uint2/3/4 of int cell coordinates, as an int (the C code passes the uint result
 * to an `int hash` parameter). */
int perlin_hash2(int x, int y)
{
  return int(hash_uint2(uint(x), uint(y)));
}
int perlin_hash3(int x, int y, int z)
{
  return int(hash_uint3(uint(x), uint(y), uint(z)));
}
int perlin_hash4(int x, int y, int z, int w)
{
  return int(hash_uint4(uint(x), uint(y), uint(z), uint(w)));
}

/* noise.h: perlin_2d() */
float perlin_2d(float x, float y)
{
  int X;
  int Y;

  float fx = tex_floorfrac(x, X);
  float fy = tex_floorfrac(y, Y);

  float u = tex_fade(fx);
  float v = tex_fade(fy);

  float r = perlin_bi_mix(perlin_grad2(perlin_hash2(X, Y), fx, fy),
                          perlin_grad2(perlin_hash2(X + 1, Y), fx - 1.0, fy),
                          perlin_grad2(perlin_hash2(X, Y + 1), fx, fy - 1.0),
                          perlin_grad2(perlin_hash2(X + 1, Y + 1), fx - 1.0, fy - 1.0),
                          u,
                          v);

  return r;
}

/* noise.h: perlin_3d() */
float perlin_3d(float x, float y, float z)
{
  int X;
  int Y;
  int Z;

  float fx = tex_floorfrac(x, X);
  float fy = tex_floorfrac(y, Y);
  float fz = tex_floorfrac(z, Z);

  float u = tex_fade(fx);
  float v = tex_fade(fy);
  float w = tex_fade(fz);

  float r = perlin_tri_mix(
      perlin_grad3(perlin_hash3(X, Y, Z), fx, fy, fz),
      perlin_grad3(perlin_hash3(X + 1, Y, Z), fx - 1.0, fy, fz),
      perlin_grad3(perlin_hash3(X, Y + 1, Z), fx, fy - 1.0, fz),
      perlin_grad3(perlin_hash3(X + 1, Y + 1, Z), fx - 1.0, fy - 1.0, fz),
      perlin_grad3(perlin_hash3(X, Y, Z + 1), fx, fy, fz - 1.0),
      perlin_grad3(perlin_hash3(X + 1, Y, Z + 1), fx - 1.0, fy, fz - 1.0),
      perlin_grad3(perlin_hash3(X, Y + 1, Z + 1), fx, fy - 1.0, fz - 1.0),
      perlin_grad3(perlin_hash3(X + 1, Y + 1, Z + 1), fx - 1.0, fy - 1.0, fz - 1.0),
      u,
      v,
      w);
  return r;
}

/* noise.h: perlin_4d() */
float perlin_4d(float x, float y, float z, float w)
{
  int X;
  int Y;
  int Z;
  int W;

  float fx = tex_floorfrac(x, X);
  float fy = tex_floorfrac(y, Y);
  float fz = tex_floorfrac(z, Z);
  float fw = tex_floorfrac(w, W);

  float u = tex_fade(fx);
  float v = tex_fade(fy);
  float t = tex_fade(fz);
  float s = tex_fade(fw);

  float r = perlin_quad_mix(
      perlin_grad4(perlin_hash4(X, Y, Z, W), fx, fy, fz, fw),
      perlin_grad4(perlin_hash4(X + 1, Y, Z, W), fx - 1.0, fy, fz, fw),
      perlin_grad4(perlin_hash4(X, Y + 1, Z, W), fx, fy - 1.0, fz, fw),
      perlin_grad4(perlin_hash4(X + 1, Y + 1, Z, W), fx - 1.0, fy - 1.0, fz, fw),
      perlin_grad4(perlin_hash4(X, Y, Z + 1, W), fx, fy, fz - 1.0, fw),
      perlin_grad4(perlin_hash4(X + 1, Y, Z + 1, W), fx - 1.0, fy, fz - 1.0, fw),
      perlin_grad4(perlin_hash4(X, Y + 1, Z + 1, W), fx, fy - 1.0, fz - 1.0, fw),
      perlin_grad4(perlin_hash4(X + 1, Y + 1, Z + 1, W), fx - 1.0, fy - 1.0, fz - 1.0, fw),
      perlin_grad4(perlin_hash4(X, Y, Z, W + 1), fx, fy, fz, fw - 1.0),
      perlin_grad4(perlin_hash4(X + 1, Y, Z, W + 1), fx - 1.0, fy, fz, fw - 1.0),
      perlin_grad4(perlin_hash4(X, Y + 1, Z, W + 1), fx, fy - 1.0, fz, fw - 1.0),
      perlin_grad4(perlin_hash4(X + 1, Y + 1, Z, W + 1), fx - 1.0, fy - 1.0, fz, fw - 1.0),
      perlin_grad4(perlin_hash4(X, Y, Z + 1, W + 1), fx, fy, fz - 1.0, fw - 1.0),
      perlin_grad4(perlin_hash4(X + 1, Y, Z + 1, W + 1), fx - 1.0, fy, fz - 1.0, fw - 1.0),
      perlin_grad4(perlin_hash4(X, Y + 1, Z + 1, W + 1), fx, fy - 1.0, fz - 1.0, fw - 1.0),
      perlin_grad4(
          perlin_hash4(X + 1, Y + 1, Z + 1, W + 1), fx - 1.0, fy - 1.0, fz - 1.0, fw - 1.0),
      u,
      v,
      t,
      s);

  return r;
}

/* noise.h: noise_scale1..4(): remap to about [-1, 1] (constants from OSL).
 * noise.h: snoise_1d..4d() (signed) and noise_1d..4d() (unsigned, [0, 1]).
 * (3.4 has no precision correction of large coordinates: that came with 4.0.) */
float snoise_1d(float p)
{
  return 0.2500 * tex_ensure_finite(perlin_1d(p));
}
float noise_1d(float p)
{
  precise float r = 0.5 * snoise_1d(p) + 0.5;
  return r;
}
float snoise_2d(vec2 p)
{
  return 0.6616 * tex_ensure_finite(perlin_2d(p.x, p.y));
}
float noise_2d(vec2 p)
{
  precise float r = 0.5 * snoise_2d(p) + 0.5;
  return r;
}
float snoise_3d(vec3 p)
{
  return 0.9820 * tex_ensure_finite(perlin_3d(p.x, p.y, p.z));
}
float noise_3d(vec3 p)
{
  precise float r = 0.5 * snoise_3d(p) + 0.5;
  return r;
}
float snoise_4d(vec4 p)
{
  return 0.8344 * tex_ensure_finite(perlin_4d(p.x, p.y, p.z, p.w));
}
float noise_4d(vec4 p)
{
  precise float r = 0.5 * snoise_4d(p) + 0.5;
  return r;
}

/* ==================================================================================== */
/* Fractal noise: kernel/svm/fractal_noise.h                                            */
/* ==================================================================================== */

/* fractal_noise.h: fractal_noise_1d() */
float fractal_noise_1d(float p, float octaves, float roughness)
{
  float fscale = 1.0;
  precise float amp = 1.0;
  precise float maxamp = 0.0;
  precise float sum = 0.0;
  octaves = clamp(octaves, 0.0, 15.0);
  int n = int(octaves);
  for (int i = 0; i <= n; i++) {
    float t = noise_1d(fscale * p);
    sum += t * amp;
    maxamp += amp;
    amp *= clamp(roughness, 0.0, 1.0);
    fscale *= 2.0;
  }
  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    float t = noise_1d(fscale * p);
    precise float sum2 = sum + t * amp;
    sum /= maxamp;
    sum2 /= maxamp + amp;
    precise float r = (1.0 - rmd) * sum + rmd * sum2;
    return r;
  }
  else {
    return sum / maxamp;
  }
}

/* fractal_noise.h: fractal_noise_2d() */
float fractal_noise_2d(vec2 p, float octaves, float roughness)
{
  float fscale = 1.0;
  precise float amp = 1.0;
  precise float maxamp = 0.0;
  precise float sum = 0.0;
  octaves = clamp(octaves, 0.0, 15.0);
  int n = int(octaves);
  for (int i = 0; i <= n; i++) {
    float t = noise_2d(fscale * p);
    sum += t * amp;
    maxamp += amp;
    amp *= clamp(roughness, 0.0, 1.0);
    fscale *= 2.0;
  }
  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    float t = noise_2d(fscale * p);
    precise float sum2 = sum + t * amp;
    sum /= maxamp;
    sum2 /= maxamp + amp;
    precise float r = (1.0 - rmd) * sum + rmd * sum2;
    return r;
  }
  else {
    return sum / maxamp;
  }
}

/* fractal_noise.h: fractal_noise_3d() */
float fractal_noise_3d(vec3 p, float octaves, float roughness)
{
  float fscale = 1.0;
  precise float amp = 1.0;
  precise float maxamp = 0.0;
  precise float sum = 0.0;
  octaves = clamp(octaves, 0.0, 15.0);
  int n = int(octaves);
  for (int i = 0; i <= n; i++) {
    float t = noise_3d(fscale * p);
    sum += t * amp;
    maxamp += amp;
    amp *= clamp(roughness, 0.0, 1.0);
    fscale *= 2.0;
  }
  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    float t = noise_3d(fscale * p);
    precise float sum2 = sum + t * amp;
    sum /= maxamp;
    sum2 /= maxamp + amp;
    precise float r = (1.0 - rmd) * sum + rmd * sum2;
    return r;
  }
  else {
    return sum / maxamp;
  }
}

/* fractal_noise.h: fractal_noise_4d() */
float fractal_noise_4d(vec4 p, float octaves, float roughness)
{
  float fscale = 1.0;
  precise float amp = 1.0;
  precise float maxamp = 0.0;
  precise float sum = 0.0;
  octaves = clamp(octaves, 0.0, 15.0);
  int n = int(octaves);
  for (int i = 0; i <= n; i++) {
    float t = noise_4d(fscale * p);
    sum += t * amp;
    maxamp += amp;
    amp *= clamp(roughness, 0.0, 1.0);
    fscale *= 2.0;
  }
  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    float t = noise_4d(fscale * p);
    precise float sum2 = sum + t * amp;
    sum /= maxamp;
    sum2 /= maxamp + amp;
    precise float r = (1.0 - rmd) * sum + rmd * sum2;
    return r;
  }
  else {
    return sum / maxamp;
  }
}

/* ==================================================================================== */
/* Noise Texture: kernel/svm/noisetex.h                                                 */
/* ==================================================================================== */

/* 100.0f + h * 100.0f, unfused. */
float noise_offset_of(float h)
{
  precise float r = 100.0 + h * 100.0;
  return r;
}

/* noisetex.h: random_float_offset() .. random_float4_offset(): seeds in [100, 200]. */
float noise_random_float_offset(float seed)
{
  return noise_offset_of(hash_float_to_float(seed));
}

vec2 noise_random_float2_offset(float seed)
{
  return vec2(noise_offset_of(hash_float2_to_float(vec2(seed, 0.0))),
              noise_offset_of(hash_float2_to_float(vec2(seed, 1.0))));
}

vec3 noise_random_float3_offset(float seed)
{
  return vec3(noise_offset_of(hash_float2_to_float(vec2(seed, 0.0))),
              noise_offset_of(hash_float2_to_float(vec2(seed, 1.0))),
              noise_offset_of(hash_float2_to_float(vec2(seed, 2.0))));
}

vec4 noise_random_float4_offset(float seed)
{
  return vec4(noise_offset_of(hash_float2_to_float(vec2(seed, 0.0))),
              noise_offset_of(hash_float2_to_float(vec2(seed, 1.0))),
              noise_offset_of(hash_float2_to_float(vec2(seed, 2.0))),
              noise_offset_of(hash_float2_to_float(vec2(seed, 3.0))));
}

/* noisetex.h: noise_texture_1d() */
void noise_texture_1d(float co,
                      float detail,
                      float roughness,
                      float distortion,
                      bool color_is_needed,
                      out float value,
                      out vec3 color)
{
  precise float p = co;
  if (distortion != 0.0) {
    p += snoise_1d(p + noise_random_float_offset(0.0)) * distortion;
  }

  value = fractal_noise_1d(p, detail, roughness);
  color = vec3(0.0);
  if (color_is_needed) {
    color = vec3(value,
                 fractal_noise_1d(p + noise_random_float_offset(1.0), detail, roughness),
                 fractal_noise_1d(p + noise_random_float_offset(2.0), detail, roughness));
  }
}

/* noisetex.h: noise_texture_2d() */
void noise_texture_2d(vec2 co,
                      float detail,
                      float roughness,
                      float distortion,
                      bool color_is_needed,
                      out float value,
                      out vec3 color)
{
  precise vec2 p = co;
  if (distortion != 0.0) {
    p += vec2(snoise_2d(p + noise_random_float2_offset(0.0)) * distortion,
              snoise_2d(p + noise_random_float2_offset(1.0)) * distortion);
  }

  value = fractal_noise_2d(p, detail, roughness);
  color = vec3(0.0);
  if (color_is_needed) {
    color = vec3(value,
                 fractal_noise_2d(p + noise_random_float2_offset(2.0), detail, roughness),
                 fractal_noise_2d(p + noise_random_float2_offset(3.0), detail, roughness));
  }
}

/* noisetex.h: noise_texture_3d() */
void noise_texture_3d(vec3 co,
                      float detail,
                      float roughness,
                      float distortion,
                      bool color_is_needed,
                      out float value,
                      out vec3 color)
{
  precise vec3 p = co;
  if (distortion != 0.0) {
    p += vec3(snoise_3d(p + noise_random_float3_offset(0.0)) * distortion,
              snoise_3d(p + noise_random_float3_offset(1.0)) * distortion,
              snoise_3d(p + noise_random_float3_offset(2.0)) * distortion);
  }

  value = fractal_noise_3d(p, detail, roughness);
  color = vec3(0.0);
  if (color_is_needed) {
    color = vec3(value,
                 fractal_noise_3d(p + noise_random_float3_offset(3.0), detail, roughness),
                 fractal_noise_3d(p + noise_random_float3_offset(4.0), detail, roughness));
  }
}

/* noisetex.h: noise_texture_4d() */
void noise_texture_4d(vec4 co,
                      float detail,
                      float roughness,
                      float distortion,
                      bool color_is_needed,
                      out float value,
                      out vec3 color)
{
  precise vec4 p = co;
  if (distortion != 0.0) {
    p += vec4(snoise_4d(p + noise_random_float4_offset(0.0)) * distortion,
              snoise_4d(p + noise_random_float4_offset(1.0)) * distortion,
              snoise_4d(p + noise_random_float4_offset(2.0)) * distortion,
              snoise_4d(p + noise_random_float4_offset(3.0)) * distortion);
  }

  value = fractal_noise_4d(p, detail, roughness);
  color = vec3(0.0);
  if (color_is_needed) {
    color = vec3(value,
                 fractal_noise_4d(p + noise_random_float4_offset(4.0), detail, roughness),
                 fractal_noise_4d(p + noise_random_float4_offset(5.0), detail, roughness));
  }
}

/* Noise Texture node (ShaderNodeTexNoise): noisetex.h: svm_node_tex_noise().
 * color_needed: whether the Color output is linked (Cycles: stack_valid(color_stack_offset));
 * the Fac output is the same either way. */
void node_tex_noise(int dimensions,
                    int color_needed,
                    int map_mode,
                    int map_block,
                    vec3 vector_in,
                    float w,
                    float scale,
                    float detail,
                    float roughness,
                    float distortion,
                    out float fac,
                    out vec3 color)
{
  vec3 vector = tex_mapping_apply(map_mode, map_block, vector_in);
  vector *= scale;
  w *= scale;

  bool color_is_needed = color_needed != 0;
  float value = 0.0;
  vec3 col = vec3(0.0);
  if (dimensions == 1) {
    noise_texture_1d(w, detail, roughness, distortion, color_is_needed, value, col);
  }
  else if (dimensions == 2) {
    noise_texture_2d(vec2(vector.x, vector.y), detail, roughness, distortion, color_is_needed,
                     value, col);
  }
  else if (dimensions == 3) {
    noise_texture_3d(vector, detail, roughness, distortion, color_is_needed, value, col);
  }
  else {
    noise_texture_4d(vec4(vector.x, vector.y, vector.z, w), detail, roughness, distortion,
                     color_is_needed, value, col);
  }
  fac = value;
  color = col;
}

/* ==================================================================================== */
/* Voronoi Texture: kernel/svm/voronoi.h                                                */
/* ==================================================================================== */

/* The feature point of a cell, relative to cellPosition (voronoi.h writes it inline:
 * cellOffset + hash_floatN_to_floatN(cellPosition + cellOffset) * randomness). */
float voronoi_point(float cellPosition, float cellOffset, float randomness)
{
  precise float r = cellOffset + hash_float_to_float(tex_cell(cellPosition + cellOffset)) *
                                     randomness;
  return r;
}
vec2 voronoi_point(vec2 cellPosition, vec2 cellOffset, float randomness)
{
  precise vec2 r = cellOffset + hash_float2_to_float2(tex_cell(cellPosition + cellOffset)) *
                                    randomness;
  return r;
}
vec3 voronoi_point(vec3 cellPosition, vec3 cellOffset, float randomness)
{
  precise vec3 r = cellOffset + hash_float3_to_float3(tex_cell(cellPosition + cellOffset)) *
                                    randomness;
  return r;
}
vec4 voronoi_point(vec4 cellPosition, vec4 cellOffset, float randomness)
{
  precise vec4 r = cellOffset + hash_float4_to_float4(tex_cell(cellPosition + cellOffset)) *
                                    randomness;
  return r;
}

/* voronoi.h: voronoi_distance_1d(): 1D has one metric. */
float voronoi_distance_1d(float a, float b, int metric, float exponent)
{
  return abs(b - a);
}

/* voronoi.h: voronoi_distance_2d() */
float voronoi_distance_2d(vec2 a, vec2 b, int metric, float exponent)
{
  if (metric == 0) { /* EUCLIDEAN */
    return tex_distance(a, b);
  }
  else if (metric == 1) { /* MANHATTAN */
    return abs(a.x - b.x) + abs(a.y - b.y);
  }
  else if (metric == 2) { /* CHEBYCHEV */
    return max(abs(a.x - b.x), abs(a.y - b.y));
  }
  else if (metric == 3) { /* MINKOWSKI */
    return tex_powf_nonneg(tex_powf_nonneg(abs(a.x - b.x), exponent) +
                               tex_powf_nonneg(abs(a.y - b.y), exponent),
                           1.0 / exponent);
  }
  else {
    return 0.0;
  }
}

/* voronoi.h: voronoi_distance_3d() */
float voronoi_distance_3d(vec3 a, vec3 b, int metric, float exponent)
{
  if (metric == 0) { /* EUCLIDEAN */
    return tex_distance(a, b);
  }
  else if (metric == 1) { /* MANHATTAN */
    return abs(a.x - b.x) + abs(a.y - b.y) + abs(a.z - b.z);
  }
  else if (metric == 2) { /* CHEBYCHEV */
    return max(abs(a.x - b.x), max(abs(a.y - b.y), abs(a.z - b.z)));
  }
  else if (metric == 3) { /* MINKOWSKI */
    return tex_powf_nonneg(tex_powf_nonneg(abs(a.x - b.x), exponent) +
                               tex_powf_nonneg(abs(a.y - b.y), exponent) +
                               tex_powf_nonneg(abs(a.z - b.z), exponent),
                           1.0 / exponent);
  }
  else {
    return 0.0;
  }
}

/* voronoi.h: voronoi_distance_4d() */
float voronoi_distance_4d(vec4 a, vec4 b, int metric, float exponent)
{
  if (metric == 0) { /* EUCLIDEAN */
    return tex_distance(a, b);
  }
  else if (metric == 1) { /* MANHATTAN */
    return abs(a.x - b.x) + abs(a.y - b.y) + abs(a.z - b.z) + abs(a.w - b.w);
  }
  else if (metric == 2) { /* CHEBYCHEV */
    return max(abs(a.x - b.x), max(abs(a.y - b.y), max(abs(a.z - b.z), abs(a.w - b.w))));
  }
  else if (metric == 3) { /* MINKOWSKI */
    return tex_powf_nonneg(tex_powf_nonneg(abs(a.x - b.x), exponent) +
                               tex_powf_nonneg(abs(a.y - b.y), exponent) +
                               tex_powf_nonneg(abs(a.z - b.z), exponent) +
                               tex_powf_nonneg(abs(a.w - b.w), exponent),
                           1.0 / exponent);
  }
  else {
    return 0.0;
  }
}

/* ---- 1D Voronoi ---- */

/* voronoi.h: voronoi_f1_1d() */
void voronoi_f1_1d(float coord,
                   float exponent,
                   float randomness,
                   int metric,
                   out float outDistance,
                   out vec3 outColor,
                   out float outPosition)
{
  float cellPosition = floor(coord);
  float localPosition = coord - cellPosition;

  float minDistance = 8.0;
  float targetOffset = 0.0;
  float targetPosition = 0.0;
  for (int i = -1; i <= 1; i++) {
    float cellOffset = float(i);
    float pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
    float distanceToPoint = voronoi_distance_1d(
        pointPosition, localPosition, metric, exponent);
    if (distanceToPoint < minDistance) {
      targetOffset = cellOffset;
      minDistance = distanceToPoint;
      targetPosition = pointPosition;
    }
  }
  outDistance = minDistance;
  outColor = hash_float_to_float3(tex_cell(cellPosition + targetOffset));
  outPosition = targetPosition + cellPosition;
}

/* voronoi.h: voronoi_smooth_f1_1d() */
void voronoi_smooth_f1_1d(float coord,
                          float smoothness,
                          float exponent,
                          float randomness,
                          int metric,
                          out float outDistance,
                          out vec3 outColor,
                          out float outPosition)
{
  float cellPosition = floor(coord);
  float localPosition = coord - cellPosition;

  precise float smoothDistance = 8.0;
  precise vec3 smoothColor = vec3(0.0);
  precise float smoothPosition = 0.0;
  for (int i = -2; i <= 2; i++) {
    float cellOffset = float(i);
    float pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
    float distanceToPoint = voronoi_distance_1d(
        pointPosition, localPosition, metric, exponent);
    float h = tex_smoothstep(
        0.0, 1.0, 0.5 + 0.5 * (smoothDistance - distanceToPoint) / smoothness);
    precise float correctionFactor = smoothness * h * (1.0 - h);
    smoothDistance = tex_mix(smoothDistance, distanceToPoint, h) - correctionFactor;
    correctionFactor /= 1.0 + 3.0 * smoothness;
    vec3 cellColor = hash_float_to_float3(tex_cell(cellPosition + cellOffset));
    smoothColor = tex_mix(smoothColor, cellColor, h) - correctionFactor;
    smoothPosition = tex_mix(smoothPosition, pointPosition, h) - correctionFactor;
  }
  outDistance = smoothDistance;
  outColor = smoothColor;
  outPosition = cellPosition + smoothPosition;
}

/* voronoi.h: voronoi_f2_1d() */
void voronoi_f2_1d(float coord,
                   float exponent,
                   float randomness,
                   int metric,
                   out float outDistance,
                   out vec3 outColor,
                   out float outPosition)
{
  float cellPosition = floor(coord);
  float localPosition = coord - cellPosition;

  float distanceF1 = 8.0;
  float distanceF2 = 8.0;
  float offsetF1 = 0.0;
  float positionF1 = 0.0;
  float offsetF2 = 0.0;
  float positionF2 = 0.0;
  for (int i = -1; i <= 1; i++) {
    float cellOffset = float(i);
    float pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
    float distanceToPoint = voronoi_distance_1d(
        pointPosition, localPosition, metric, exponent);
    if (distanceToPoint < distanceF1) {
      distanceF2 = distanceF1;
      distanceF1 = distanceToPoint;
      offsetF2 = offsetF1;
      offsetF1 = cellOffset;
      positionF2 = positionF1;
      positionF1 = pointPosition;
    }
    else if (distanceToPoint < distanceF2) {
      distanceF2 = distanceToPoint;
      offsetF2 = cellOffset;
      positionF2 = pointPosition;
    }
  }
  outDistance = distanceF2;
  outColor = hash_float_to_float3(tex_cell(cellPosition + offsetF2));
  outPosition = positionF2 + cellPosition;
}

/* voronoi.h: voronoi_distance_to_edge_1d() */
void voronoi_distance_to_edge_1d(float w, float randomness, out float outDistance)
{
  float cellPosition = floor(w);
  float localPosition = w - cellPosition;

  float midPointPosition = hash_float_to_float(cellPosition) * randomness;
  precise float leftPointPosition = -1.0 +
                                    hash_float_to_float(tex_cell(cellPosition - 1.0)) * randomness;
  precise float rightPointPosition = 1.0 +
                                     hash_float_to_float(tex_cell(cellPosition + 1.0)) * randomness;
  float distanceToMidLeft = abs((midPointPosition + leftPointPosition) / 2.0 - localPosition);
  float distanceToMidRight = abs((midPointPosition + rightPointPosition) / 2.0 - localPosition);

  outDistance = min(distanceToMidLeft, distanceToMidRight);
}

/* voronoi.h: voronoi_n_sphere_radius_1d() */
void voronoi_n_sphere_radius_1d(float coord, float randomness, out float outRadius)
{
  float cellPosition = floor(coord);
  float localPosition = coord - cellPosition;

  float closestPoint = 0.0;
  float closestPointOffset = 0.0;
  float minDistance = 8.0;
  for (int i = -1; i <= 1; i++) {
    float cellOffset = float(i);
    float pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
    float distanceToPoint = tex_distance(pointPosition, localPosition);
    if (distanceToPoint < minDistance) {
      minDistance = distanceToPoint;
      closestPoint = pointPosition;
      closestPointOffset = cellOffset;
    }
  }
  minDistance = 8.0;
  float closestPointToClosestPoint = 0.0;
  for (int i = -1; i <= 1; i++) {
    if (i == 0) {
      continue;
    }
    float cellOffset = float(i) + closestPointOffset;
    float pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
    float distanceToPoint = tex_distance(closestPoint, pointPosition);
    if (distanceToPoint < minDistance) {
      minDistance = distanceToPoint;
      closestPointToClosestPoint = pointPosition;
    }
  }
  outRadius = tex_distance(closestPointToClosestPoint, closestPoint) / 2.0;
}

/* ---- 2D Voronoi ---- */

/* voronoi.h: voronoi_f1_2d() */
void voronoi_f1_2d(vec2 coord,
                   float exponent,
                   float randomness,
                   int metric,
                   out float outDistance,
                   out vec3 outColor,
                   out vec2 outPosition)
{
  vec2 cellPosition = floor(coord);
  vec2 localPosition = coord - cellPosition;

  float minDistance = 8.0;
  vec2 targetOffset = vec2(0.0);
  vec2 targetPosition = vec2(0.0);
  for (int j = -1; j <= 1; j++) {
    for (int i = -1; i <= 1; i++) {
      vec2 cellOffset = vec2(i, j);
      vec2 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
      float distanceToPoint = voronoi_distance_2d(
          pointPosition, localPosition, metric, exponent);
      if (distanceToPoint < minDistance) {
        targetOffset = cellOffset;
        minDistance = distanceToPoint;
        targetPosition = pointPosition;
      }
    }
  }
  outDistance = minDistance;
  outColor = hash_float2_to_float3(tex_cell(cellPosition + targetOffset));
  outPosition = targetPosition + cellPosition;
}

/* voronoi.h: voronoi_smooth_f1_2d() */
void voronoi_smooth_f1_2d(vec2 coord,
                          float smoothness,
                          float exponent,
                          float randomness,
                          int metric,
                          out float outDistance,
                          out vec3 outColor,
                          out vec2 outPosition)
{
  vec2 cellPosition = floor(coord);
  vec2 localPosition = coord - cellPosition;

  precise float smoothDistance = 8.0;
  precise vec3 smoothColor = vec3(0.0);
  precise vec2 smoothPosition = vec2(0.0);
  for (int j = -2; j <= 2; j++) {
    for (int i = -2; i <= 2; i++) {
      vec2 cellOffset = vec2(i, j);
      vec2 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
      float distanceToPoint = voronoi_distance_2d(
          pointPosition, localPosition, metric, exponent);
      float h = tex_smoothstep(
          0.0, 1.0, 0.5 + 0.5 * (smoothDistance - distanceToPoint) / smoothness);
      precise float correctionFactor = smoothness * h * (1.0 - h);
      smoothDistance = tex_mix(smoothDistance, distanceToPoint, h) - correctionFactor;
      correctionFactor /= 1.0 + 3.0 * smoothness;
      vec3 cellColor = hash_float2_to_float3(tex_cell(cellPosition + cellOffset));
      smoothColor = tex_mix(smoothColor, cellColor, h) - correctionFactor;
      smoothPosition = tex_mix(smoothPosition, pointPosition, h) - correctionFactor;
    }
  }
  outDistance = smoothDistance;
  outColor = smoothColor;
  outPosition = cellPosition + smoothPosition;
}

/* voronoi.h: voronoi_f2_2d() */
void voronoi_f2_2d(vec2 coord,
                   float exponent,
                   float randomness,
                   int metric,
                   out float outDistance,
                   out vec3 outColor,
                   out vec2 outPosition)
{
  vec2 cellPosition = floor(coord);
  vec2 localPosition = coord - cellPosition;

  float distanceF1 = 8.0;
  float distanceF2 = 8.0;
  vec2 offsetF1 = vec2(0.0);
  vec2 positionF1 = vec2(0.0);
  vec2 offsetF2 = vec2(0.0);
  vec2 positionF2 = vec2(0.0);
  for (int j = -1; j <= 1; j++) {
    for (int i = -1; i <= 1; i++) {
      vec2 cellOffset = vec2(i, j);
      vec2 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
      float distanceToPoint = voronoi_distance_2d(
          pointPosition, localPosition, metric, exponent);
      if (distanceToPoint < distanceF1) {
        distanceF2 = distanceF1;
        distanceF1 = distanceToPoint;
        offsetF2 = offsetF1;
        offsetF1 = cellOffset;
        positionF2 = positionF1;
        positionF1 = pointPosition;
      }
      else if (distanceToPoint < distanceF2) {
        distanceF2 = distanceToPoint;
        offsetF2 = cellOffset;
        positionF2 = pointPosition;
      }
    }
  }
  outDistance = distanceF2;
  outColor = hash_float2_to_float3(tex_cell(cellPosition + offsetF2));
  outPosition = positionF2 + cellPosition;
}

/* voronoi.h: voronoi_distance_to_edge_2d() */
void voronoi_distance_to_edge_2d(vec2 coord, float randomness, out float outDistance)
{
  vec2 cellPosition = floor(coord);
  vec2 localPosition = coord - cellPosition;

  vec2 vectorToClosest = vec2(0.0);
  float minDistance = 8.0;
  for (int j = -1; j <= 1; j++) {
    for (int i = -1; i <= 1; i++) {
      vec2 cellOffset = vec2(i, j);
      vec2 vectorToPoint = voronoi_point(cellPosition, cellOffset, randomness) - localPosition;
      float distanceToPoint = tex_dot(vectorToPoint, vectorToPoint);
      if (distanceToPoint < minDistance) {
        minDistance = distanceToPoint;
        vectorToClosest = vectorToPoint;
      }
    }
  }
  minDistance = 8.0;
  for (int j = -1; j <= 1; j++) {
    for (int i = -1; i <= 1; i++) {
      vec2 cellOffset = vec2(i, j);
      vec2 vectorToPoint = voronoi_point(cellPosition, cellOffset, randomness) - localPosition;
      vec2 perpendicularToEdge = vectorToPoint - vectorToClosest;
      if (tex_dot(perpendicularToEdge, perpendicularToEdge) > 0.0001) {
        float distanceToEdge = tex_dot(tex_div_vs(vectorToClosest + vectorToPoint, 2.0),
                                       tex_normalize(perpendicularToEdge));
        minDistance = min(minDistance, distanceToEdge);
      }
    }
  }
  outDistance = minDistance;
}

/* voronoi.h: voronoi_n_sphere_radius_2d() */
void voronoi_n_sphere_radius_2d(vec2 coord, float randomness, out float outRadius)
{
  vec2 cellPosition = floor(coord);
  vec2 localPosition = coord - cellPosition;

  vec2 closestPoint = vec2(0.0);
  vec2 closestPointOffset = vec2(0.0);
  float minDistance = 8.0;
  for (int j = -1; j <= 1; j++) {
    for (int i = -1; i <= 1; i++) {
      vec2 cellOffset = vec2(i, j);
      vec2 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
      float distanceToPoint = tex_distance(pointPosition, localPosition);
      if (distanceToPoint < minDistance) {
        minDistance = distanceToPoint;
        closestPoint = pointPosition;
        closestPointOffset = cellOffset;
      }
    }
  }
  minDistance = 8.0;
  vec2 closestPointToClosestPoint = vec2(0.0);
  for (int j = -1; j <= 1; j++) {
    for (int i = -1; i <= 1; i++) {
      if (i == 0 && j == 0) {
        continue;
      }
      vec2 cellOffset = vec2(i, j) + closestPointOffset;
      vec2 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
      float distanceToPoint = tex_distance(closestPoint, pointPosition);
      if (distanceToPoint < minDistance) {
        minDistance = distanceToPoint;
        closestPointToClosestPoint = pointPosition;
      }
    }
  }
  outRadius = tex_distance(closestPointToClosestPoint, closestPoint) / 2.0;
}

/* ---- 3D Voronoi ---- */

/* voronoi.h: voronoi_f1_3d() */
void voronoi_f1_3d(vec3 coord,
                   float exponent,
                   float randomness,
                   int metric,
                   out float outDistance,
                   out vec3 outColor,
                   out vec3 outPosition)
{
  vec3 cellPosition = floor(coord);
  vec3 localPosition = coord - cellPosition;

  float minDistance = 8.0;
  vec3 targetOffset = vec3(0.0);
  vec3 targetPosition = vec3(0.0);
  for (int k = -1; k <= 1; k++) {
    for (int j = -1; j <= 1; j++) {
      for (int i = -1; i <= 1; i++) {
        vec3 cellOffset = vec3(i, j, k);
        vec3 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
        float distanceToPoint = voronoi_distance_3d(
            pointPosition, localPosition, metric, exponent);
        if (distanceToPoint < minDistance) {
          targetOffset = cellOffset;
          minDistance = distanceToPoint;
          targetPosition = pointPosition;
        }
      }
    }
  }
  outDistance = minDistance;
  outColor = hash_float3_to_float3(tex_cell(cellPosition + targetOffset));
  outPosition = targetPosition + cellPosition;
}

/* voronoi.h: voronoi_smooth_f1_3d() */
void voronoi_smooth_f1_3d(vec3 coord,
                          float smoothness,
                          float exponent,
                          float randomness,
                          int metric,
                          out float outDistance,
                          out vec3 outColor,
                          out vec3 outPosition)
{
  vec3 cellPosition = floor(coord);
  vec3 localPosition = coord - cellPosition;

  precise float smoothDistance = 8.0;
  precise vec3 smoothColor = vec3(0.0);
  precise vec3 smoothPosition = vec3(0.0);
  for (int k = -2; k <= 2; k++) {
    for (int j = -2; j <= 2; j++) {
      for (int i = -2; i <= 2; i++) {
        vec3 cellOffset = vec3(i, j, k);
        vec3 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
        float distanceToPoint = voronoi_distance_3d(
            pointPosition, localPosition, metric, exponent);
        float h = tex_smoothstep(
            0.0, 1.0, 0.5 + 0.5 * (smoothDistance - distanceToPoint) / smoothness);
        precise float correctionFactor = smoothness * h * (1.0 - h);
        smoothDistance = tex_mix(smoothDistance, distanceToPoint, h) - correctionFactor;
        correctionFactor /= 1.0 + 3.0 * smoothness;
        vec3 cellColor = hash_float3_to_float3(tex_cell(cellPosition + cellOffset));
        smoothColor = tex_mix(smoothColor, cellColor, h) - correctionFactor;
        smoothPosition = tex_mix(smoothPosition, pointPosition, h) - correctionFactor;
      }
    }
  }
  outDistance = smoothDistance;
  outColor = smoothColor;
  outPosition = cellPosition + smoothPosition;
}

/* voronoi.h: voronoi_f2_3d() */
void voronoi_f2_3d(vec3 coord,
                   float exponent,
                   float randomness,
                   int metric,
                   out float outDistance,
                   out vec3 outColor,
                   out vec3 outPosition)
{
  vec3 cellPosition = floor(coord);
  vec3 localPosition = coord - cellPosition;

  float distanceF1 = 8.0;
  float distanceF2 = 8.0;
  vec3 offsetF1 = vec3(0.0);
  vec3 positionF1 = vec3(0.0);
  vec3 offsetF2 = vec3(0.0);
  vec3 positionF2 = vec3(0.0);
  for (int k = -1; k <= 1; k++) {
    for (int j = -1; j <= 1; j++) {
      for (int i = -1; i <= 1; i++) {
        vec3 cellOffset = vec3(i, j, k);
        vec3 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
        float distanceToPoint = voronoi_distance_3d(
            pointPosition, localPosition, metric, exponent);
        if (distanceToPoint < distanceF1) {
          distanceF2 = distanceF1;
          distanceF1 = distanceToPoint;
          offsetF2 = offsetF1;
          offsetF1 = cellOffset;
          positionF2 = positionF1;
          positionF1 = pointPosition;
        }
        else if (distanceToPoint < distanceF2) {
          distanceF2 = distanceToPoint;
          offsetF2 = cellOffset;
          positionF2 = pointPosition;
        }
      }
    }
  }
  outDistance = distanceF2;
  outColor = hash_float3_to_float3(tex_cell(cellPosition + offsetF2));
  outPosition = positionF2 + cellPosition;
}

/* voronoi.h: voronoi_distance_to_edge_3d() */
void voronoi_distance_to_edge_3d(vec3 coord, float randomness, out float outDistance)
{
  vec3 cellPosition = floor(coord);
  vec3 localPosition = coord - cellPosition;

  vec3 vectorToClosest = vec3(0.0);
  float minDistance = 8.0;
  for (int k = -1; k <= 1; k++) {
    for (int j = -1; j <= 1; j++) {
      for (int i = -1; i <= 1; i++) {
        vec3 cellOffset = vec3(i, j, k);
        vec3 vectorToPoint = voronoi_point(cellPosition, cellOffset, randomness) - localPosition;
        float distanceToPoint = tex_dot(vectorToPoint, vectorToPoint);
        if (distanceToPoint < minDistance) {
          minDistance = distanceToPoint;
          vectorToClosest = vectorToPoint;
        }
      }
    }
  }
  minDistance = 8.0;
  for (int k = -1; k <= 1; k++) {
    for (int j = -1; j <= 1; j++) {
      for (int i = -1; i <= 1; i++) {
        vec3 cellOffset = vec3(i, j, k);
        vec3 vectorToPoint = voronoi_point(cellPosition, cellOffset, randomness) - localPosition;
        vec3 perpendicularToEdge = vectorToPoint - vectorToClosest;
        if (tex_dot(perpendicularToEdge, perpendicularToEdge) > 0.0001) {
          float distanceToEdge = tex_dot(tex_div_vs(vectorToClosest + vectorToPoint, 2.0),
                                         tex_normalize(perpendicularToEdge));
          minDistance = min(minDistance, distanceToEdge);
        }
      }
    }
  }
  outDistance = minDistance;
}

/* voronoi.h: voronoi_n_sphere_radius_3d() */
void voronoi_n_sphere_radius_3d(vec3 coord, float randomness, out float outRadius)
{
  vec3 cellPosition = floor(coord);
  vec3 localPosition = coord - cellPosition;

  vec3 closestPoint = vec3(0.0);
  vec3 closestPointOffset = vec3(0.0);
  float minDistance = 8.0;
  for (int k = -1; k <= 1; k++) {
    for (int j = -1; j <= 1; j++) {
      for (int i = -1; i <= 1; i++) {
        vec3 cellOffset = vec3(i, j, k);
        vec3 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
        float distanceToPoint = tex_distance(pointPosition, localPosition);
        if (distanceToPoint < minDistance) {
          minDistance = distanceToPoint;
          closestPoint = pointPosition;
          closestPointOffset = cellOffset;
        }
      }
    }
  }
  minDistance = 8.0;
  vec3 closestPointToClosestPoint = vec3(0.0);
  for (int k = -1; k <= 1; k++) {
    for (int j = -1; j <= 1; j++) {
      for (int i = -1; i <= 1; i++) {
        if (i == 0 && j == 0 && k == 0) {
          continue;
        }
        vec3 cellOffset = vec3(i, j, k) + closestPointOffset;
        vec3 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
        float distanceToPoint = tex_distance(closestPoint, pointPosition);
        if (distanceToPoint < minDistance) {
          minDistance = distanceToPoint;
          closestPointToClosestPoint = pointPosition;
        }
      }
    }
  }
  outRadius = tex_distance(closestPointToClosestPoint, closestPoint) / 2.0;
}

/* ---- 4D Voronoi ---- */

/* voronoi.h: voronoi_f1_4d() */
void voronoi_f1_4d(vec4 coord,
                   float exponent,
                   float randomness,
                   int metric,
                   out float outDistance,
                   out vec3 outColor,
                   out vec4 outPosition)
{
  vec4 cellPosition = floor(coord);
  vec4 localPosition = coord - cellPosition;

  float minDistance = 8.0;
  vec4 targetOffset = vec4(0.0);
  vec4 targetPosition = vec4(0.0);
  for (int u = -1; u <= 1; u++) {
    for (int k = -1; k <= 1; k++) {
      for (int j = -1; j <= 1; j++) {
        for (int i = -1; i <= 1; i++) {
          vec4 cellOffset = vec4(i, j, k, u);
          vec4 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
          float distanceToPoint = voronoi_distance_4d(
              pointPosition, localPosition, metric, exponent);
          if (distanceToPoint < minDistance) {
            targetOffset = cellOffset;
            minDistance = distanceToPoint;
            targetPosition = pointPosition;
          }
        }
      }
    }
  }
  outDistance = minDistance;
  outColor = hash_float4_to_float3(tex_cell(cellPosition + targetOffset));
  outPosition = targetPosition + cellPosition;
}

/* voronoi.h: voronoi_smooth_f1_4d() */
void voronoi_smooth_f1_4d(vec4 coord,
                          float smoothness,
                          float exponent,
                          float randomness,
                          int metric,
                          out float outDistance,
                          out vec3 outColor,
                          out vec4 outPosition)
{
  vec4 cellPosition = floor(coord);
  vec4 localPosition = coord - cellPosition;

  precise float smoothDistance = 8.0;
  precise vec3 smoothColor = vec3(0.0);
  precise vec4 smoothPosition = vec4(0.0);
  for (int u = -2; u <= 2; u++) {
    for (int k = -2; k <= 2; k++) {
      for (int j = -2; j <= 2; j++) {
        for (int i = -2; i <= 2; i++) {
          vec4 cellOffset = vec4(i, j, k, u);
          vec4 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
          float distanceToPoint = voronoi_distance_4d(
              pointPosition, localPosition, metric, exponent);
          float h = tex_smoothstep(
              0.0, 1.0, 0.5 + 0.5 * (smoothDistance - distanceToPoint) / smoothness);
          precise float correctionFactor = smoothness * h * (1.0 - h);
          smoothDistance = tex_mix(smoothDistance, distanceToPoint, h) - correctionFactor;
          correctionFactor /= 1.0 + 3.0 * smoothness;
          vec3 cellColor = hash_float4_to_float3(tex_cell(cellPosition + cellOffset));
          smoothColor = tex_mix(smoothColor, cellColor, h) - correctionFactor;
          smoothPosition = tex_mix(smoothPosition, pointPosition, h) - correctionFactor;
        }
      }
    }
  }
  outDistance = smoothDistance;
  outColor = smoothColor;
  outPosition = cellPosition + smoothPosition;
}

/* voronoi.h: voronoi_f2_4d() */
void voronoi_f2_4d(vec4 coord,
                   float exponent,
                   float randomness,
                   int metric,
                   out float outDistance,
                   out vec3 outColor,
                   out vec4 outPosition)
{
  vec4 cellPosition = floor(coord);
  vec4 localPosition = coord - cellPosition;

  float distanceF1 = 8.0;
  float distanceF2 = 8.0;
  vec4 offsetF1 = vec4(0.0);
  vec4 positionF1 = vec4(0.0);
  vec4 offsetF2 = vec4(0.0);
  vec4 positionF2 = vec4(0.0);
  for (int u = -1; u <= 1; u++) {
    for (int k = -1; k <= 1; k++) {
      for (int j = -1; j <= 1; j++) {
        for (int i = -1; i <= 1; i++) {
          vec4 cellOffset = vec4(i, j, k, u);
          vec4 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
          float distanceToPoint = voronoi_distance_4d(
              pointPosition, localPosition, metric, exponent);
          if (distanceToPoint < distanceF1) {
            distanceF2 = distanceF1;
            distanceF1 = distanceToPoint;
            offsetF2 = offsetF1;
            offsetF1 = cellOffset;
            positionF2 = positionF1;
            positionF1 = pointPosition;
          }
          else if (distanceToPoint < distanceF2) {
            distanceF2 = distanceToPoint;
            offsetF2 = cellOffset;
            positionF2 = pointPosition;
          }
        }
      }
    }
  }
  outDistance = distanceF2;
  outColor = hash_float4_to_float3(tex_cell(cellPosition + offsetF2));
  outPosition = positionF2 + cellPosition;
}

/* voronoi.h: voronoi_distance_to_edge_4d() */
void voronoi_distance_to_edge_4d(vec4 coord, float randomness, out float outDistance)
{
  vec4 cellPosition = floor(coord);
  vec4 localPosition = coord - cellPosition;

  vec4 vectorToClosest = vec4(0.0);
  float minDistance = 8.0;
  for (int u = -1; u <= 1; u++) {
    for (int k = -1; k <= 1; k++) {
      for (int j = -1; j <= 1; j++) {
        for (int i = -1; i <= 1; i++) {
          vec4 cellOffset = vec4(i, j, k, u);
          vec4 vectorToPoint = voronoi_point(cellPosition, cellOffset, randomness) - localPosition;
          float distanceToPoint = tex_dot(vectorToPoint, vectorToPoint);
          if (distanceToPoint < minDistance) {
            minDistance = distanceToPoint;
            vectorToClosest = vectorToPoint;
          }
        }
      }
    }
  }
  minDistance = 8.0;
  for (int u = -1; u <= 1; u++) {
    for (int k = -1; k <= 1; k++) {
      for (int j = -1; j <= 1; j++) {
        for (int i = -1; i <= 1; i++) {
          vec4 cellOffset = vec4(i, j, k, u);
          vec4 vectorToPoint = voronoi_point(cellPosition, cellOffset, randomness) - localPosition;
          vec4 perpendicularToEdge = vectorToPoint - vectorToClosest;
          if (tex_dot(perpendicularToEdge, perpendicularToEdge) > 0.0001) {
            float distanceToEdge = tex_dot(tex_div_vs(vectorToClosest + vectorToPoint, 2.0),
                                           tex_normalize(perpendicularToEdge));
            minDistance = min(minDistance, distanceToEdge);
          }
        }
      }
    }
  }
  outDistance = minDistance;
}

/* voronoi.h: voronoi_n_sphere_radius_4d() */
void voronoi_n_sphere_radius_4d(vec4 coord, float randomness, out float outRadius)
{
  vec4 cellPosition = floor(coord);
  vec4 localPosition = coord - cellPosition;

  vec4 closestPoint = vec4(0.0);
  vec4 closestPointOffset = vec4(0.0);
  float minDistance = 8.0;
  for (int u = -1; u <= 1; u++) {
    for (int k = -1; k <= 1; k++) {
      for (int j = -1; j <= 1; j++) {
        for (int i = -1; i <= 1; i++) {
          vec4 cellOffset = vec4(i, j, k, u);
          vec4 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
          float distanceToPoint = tex_distance(pointPosition, localPosition);
          if (distanceToPoint < minDistance) {
            minDistance = distanceToPoint;
            closestPoint = pointPosition;
            closestPointOffset = cellOffset;
          }
        }
      }
    }
  }
  minDistance = 8.0;
  vec4 closestPointToClosestPoint = vec4(0.0);
  for (int u = -1; u <= 1; u++) {
    for (int k = -1; k <= 1; k++) {
      for (int j = -1; j <= 1; j++) {
        for (int i = -1; i <= 1; i++) {
          if (i == 0 && j == 0 && k == 0 && u == 0) {
            continue;
          }
          vec4 cellOffset = vec4(i, j, k, u) + closestPointOffset;
          vec4 pointPosition = voronoi_point(cellPosition, cellOffset, randomness);
          float distanceToPoint = tex_distance(closestPoint, pointPosition);
          if (distanceToPoint < minDistance) {
            minDistance = distanceToPoint;
            closestPointToClosestPoint = pointPosition;
          }
        }
      }
    }
  }
  outRadius = tex_distance(closestPointToClosestPoint, closestPoint) / 2.0;
}

/* Voronoi Texture node (ShaderNodeTexVoronoi): voronoi.h: svm_node_tex_voronoi().
 * Outputs Cycles leaves unwritten for a feature are 0 (Cycles' 4D DISTANCE_TO_EDGE and
 * N_SPHERE_RADIUS leave Position/W uninitialised; Blender hides those sockets). */
void node_tex_voronoi(int dimensions,
                      int feature,
                      int metric,
                      int map_mode,
                      int map_block,
                      vec3 vector_in,
                      float w,
                      float scale,
                      float smoothness,
                      float exponent,
                      float randomness,
                      out float distance_out,
                      out vec3 color_out,
                      out vec3 position_out,
                      out float w_out,
                      out float radius_out)
{
  vec3 coord = tex_mapping_apply(map_mode, map_block, vector_in);

  float dist = 0.0;
  float wo = 0.0;
  float radius = 0.0;
  vec3 color = vec3(0.0);
  vec3 position = vec3(0.0);

  randomness = clamp(randomness, 0.0, 1.0);
  smoothness = clamp(smoothness / 2.0, 0.0, 0.5);

  w *= scale;
  coord *= scale;

  if (dimensions == 1) {
    if (feature == 0) {
      voronoi_f1_1d(w, exponent, randomness, metric, dist, color, wo);
    }
    else if (feature == 2) {
      voronoi_smooth_f1_1d(w, smoothness, exponent, randomness, metric, dist, color, wo);
    }
    else if (feature == 1) {
      voronoi_f2_1d(w, exponent, randomness, metric, dist, color, wo);
    }
    else if (feature == 3) {
      voronoi_distance_to_edge_1d(w, randomness, dist);
    }
    else if (feature == 4) {
      voronoi_n_sphere_radius_1d(w, randomness, radius);
    }
    wo = tex_safe_divide(wo, scale);
  }
  else if (dimensions == 2) {
    vec2 coord_2d = vec2(coord.x, coord.y);
    vec2 position_2d = vec2(0.0);
    if (feature == 0) {
      voronoi_f1_2d(coord_2d, exponent, randomness, metric, dist, color, position_2d);
    }
    else if (feature == 2) {
      voronoi_smooth_f1_2d(
          coord_2d, smoothness, exponent, randomness, metric, dist, color, position_2d);
    }
    else if (feature == 1) {
      voronoi_f2_2d(coord_2d, exponent, randomness, metric, dist, color, position_2d);
    }
    else if (feature == 3) {
      voronoi_distance_to_edge_2d(coord_2d, randomness, dist);
    }
    else if (feature == 4) {
      voronoi_n_sphere_radius_2d(coord_2d, randomness, radius);
    }
    position_2d = tex_safe_divide(position_2d, scale);
    position = vec3(position_2d.x, position_2d.y, 0.0);
  }
  else if (dimensions == 3) {
    if (feature == 0) {
      voronoi_f1_3d(coord, exponent, randomness, metric, dist, color, position);
    }
    else if (feature == 2) {
      voronoi_smooth_f1_3d(coord, smoothness, exponent, randomness, metric, dist, color, position);
    }
    else if (feature == 1) {
      voronoi_f2_3d(coord, exponent, randomness, metric, dist, color, position);
    }
    else if (feature == 3) {
      voronoi_distance_to_edge_3d(coord, randomness, dist);
    }
    else if (feature == 4) {
      voronoi_n_sphere_radius_3d(coord, randomness, radius);
    }
    position = tex_safe_divide(position, scale);
  }
  else {
    vec4 coord_4d = vec4(coord.x, coord.y, coord.z, w);
    vec4 position_4d = vec4(0.0);
    if (feature == 0) {
      voronoi_f1_4d(coord_4d, exponent, randomness, metric, dist, color, position_4d);
    }
    else if (feature == 2) {
      voronoi_smooth_f1_4d(
          coord_4d, smoothness, exponent, randomness, metric, dist, color, position_4d);
    }
    else if (feature == 1) {
      voronoi_f2_4d(coord_4d, exponent, randomness, metric, dist, color, position_4d);
    }
    else if (feature == 3) {
      voronoi_distance_to_edge_4d(coord_4d, randomness, dist);
    }
    else if (feature == 4) {
      voronoi_n_sphere_radius_4d(coord_4d, randomness, radius);
    }
    position_4d = tex_safe_divide(position_4d, scale);
    position = vec3(position_4d.x, position_4d.y, position_4d.z);
    wo = position_4d.w;
  }

  distance_out = dist;
  color_out = color;
  position_out = position;
  w_out = wo;
  radius_out = radius;
}

/* ==================================================================================== */
/* Musgrave Texture: kernel/svm/musgrave.h                                              */
/* ==================================================================================== */

/* musgrave.h: noise_musgrave_fBm_1d() */
float noise_musgrave_fBm_1d(float co, float H, float lacunarity, float octaves)
{
  float p = co;
  precise float value = 0.0;
  float pwr = 1.0;
  float pwHL = tex_powf(lacunarity, -H);

  for (int i = 0; i < int(octaves); i++) {
    value += snoise_1d(p) * pwr;
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    value += rmd * snoise_1d(p) * pwr;
  }

  return value;
}

/* musgrave.h: noise_musgrave_multi_fractal_1d() */
float noise_musgrave_multi_fractal_1d(float co, float H, float lacunarity, float octaves)
{
  float p = co;
  precise float value = 1.0;
  float pwr = 1.0;
  float pwHL = tex_powf(lacunarity, -H);

  for (int i = 0; i < int(octaves); i++) {
    value *= (pwr * snoise_1d(p) + 1.0);
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    value *= (rmd * pwr * snoise_1d(p) + 1.0);
  }

  return value;
}

/* musgrave.h: noise_musgrave_hetero_terrain_1d() */
float noise_musgrave_hetero_terrain_1d(
    float co, float H, float lacunarity, float octaves, float offset)
{
  float p = co;
  float pwHL = tex_powf(lacunarity, -H);
  float pwr = pwHL;

  /* first unscaled octave of function; later octaves are scaled */
  precise float value = offset + snoise_1d(p);
  p *= lacunarity;

  for (int i = 1; i < int(octaves); i++) {
    precise float increment = (snoise_1d(p) + offset) * pwr * value;
    value += increment;
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    precise float increment = (snoise_1d(p) + offset) * pwr * value;
    value += rmd * increment;
  }

  return value;
}

/* musgrave.h: noise_musgrave_hybrid_multi_fractal_1d() */
float noise_musgrave_hybrid_multi_fractal_1d(
    float co, float H, float lacunarity, float octaves, float offset, float gain)
{
  float p = co;
  float pwHL = tex_powf(lacunarity, -H);

  float pwr = 1.0;
  precise float value = 0.0;
  precise float weight = 1.0;

  for (int i = 0; (weight > 0.001) && (i < int(octaves)); i++) {
    if (weight > 1.0) {
      weight = 1.0;
    }

    precise float signal = (snoise_1d(p) + offset) * pwr;
    pwr *= pwHL;
    value += weight * signal;
    weight *= gain * signal;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if ((rmd != 0.0) && (weight > 0.001)) {
    if (weight > 1.0) {
      weight = 1.0;
    }
    float signal = (snoise_1d(p) + offset) * pwr;
    value += rmd * weight * signal;
  }

  return value;
}

/* musgrave.h: noise_musgrave_ridged_multi_fractal_1d() */
float noise_musgrave_ridged_multi_fractal_1d(
    float co, float H, float lacunarity, float octaves, float offset, float gain)
{
  float p = co;
  float pwHL = tex_powf(lacunarity, -H);
  float pwr = pwHL;

  precise float signal = offset - abs(snoise_1d(p));
  signal *= signal;
  precise float value = signal;
  float weight = 1.0;

  for (int i = 1; i < int(octaves); i++) {
    p *= lacunarity;
    weight = clamp(signal * gain, 0.0, 1.0);
    signal = offset - abs(snoise_1d(p));
    signal *= signal;
    signal *= weight;
    value += signal * pwr;
    pwr *= pwHL;
  }

  return value;
}

/* The svm_node_tex_musgrave() switch on the type, for one dimension count. */
float noise_musgrave_1d(int type, float p, float dimension, float lacunarity, float detail,
                        float foffset, float gain)
{
  if (type == 0) { /* MULTIFRACTAL */
    return noise_musgrave_multi_fractal_1d(p, dimension, lacunarity, detail);
  }
  else if (type == 1) { /* FBM */
    return noise_musgrave_fBm_1d(p, dimension, lacunarity, detail);
  }
  else if (type == 2) { /* HYBRID_MULTIFRACTAL */
    return noise_musgrave_hybrid_multi_fractal_1d(
        p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (type == 3) { /* RIDGED_MULTIFRACTAL */
    return noise_musgrave_ridged_multi_fractal_1d(
        p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (type == 4) { /* HETERO_TERRAIN */
    return noise_musgrave_hetero_terrain_1d(p, dimension, lacunarity, detail, foffset);
  }
  return 0.0;
}

/* musgrave.h: noise_musgrave_fBm_2d() */
float noise_musgrave_fBm_2d(vec2 co, float H, float lacunarity, float octaves)
{
  vec2 p = co;
  precise float value = 0.0;
  float pwr = 1.0;
  float pwHL = tex_powf(lacunarity, -H);

  for (int i = 0; i < int(octaves); i++) {
    value += snoise_2d(p) * pwr;
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    value += rmd * snoise_2d(p) * pwr;
  }

  return value;
}

/* musgrave.h: noise_musgrave_multi_fractal_2d() */
float noise_musgrave_multi_fractal_2d(vec2 co, float H, float lacunarity, float octaves)
{
  vec2 p = co;
  precise float value = 1.0;
  float pwr = 1.0;
  float pwHL = tex_powf(lacunarity, -H);

  for (int i = 0; i < int(octaves); i++) {
    value *= (pwr * snoise_2d(p) + 1.0);
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    value *= (rmd * pwr * snoise_2d(p) + 1.0);
  }

  return value;
}

/* musgrave.h: noise_musgrave_hetero_terrain_2d() */
float noise_musgrave_hetero_terrain_2d(
    vec2 co, float H, float lacunarity, float octaves, float offset)
{
  vec2 p = co;
  float pwHL = tex_powf(lacunarity, -H);
  float pwr = pwHL;

  /* first unscaled octave of function; later octaves are scaled */
  precise float value = offset + snoise_2d(p);
  p *= lacunarity;

  for (int i = 1; i < int(octaves); i++) {
    precise float increment = (snoise_2d(p) + offset) * pwr * value;
    value += increment;
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    precise float increment = (snoise_2d(p) + offset) * pwr * value;
    value += rmd * increment;
  }

  return value;
}

/* musgrave.h: noise_musgrave_hybrid_multi_fractal_2d() */
float noise_musgrave_hybrid_multi_fractal_2d(
    vec2 co, float H, float lacunarity, float octaves, float offset, float gain)
{
  vec2 p = co;
  float pwHL = tex_powf(lacunarity, -H);

  float pwr = 1.0;
  precise float value = 0.0;
  precise float weight = 1.0;

  for (int i = 0; (weight > 0.001) && (i < int(octaves)); i++) {
    if (weight > 1.0) {
      weight = 1.0;
    }

    precise float signal = (snoise_2d(p) + offset) * pwr;
    pwr *= pwHL;
    value += weight * signal;
    weight *= gain * signal;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if ((rmd != 0.0) && (weight > 0.001)) {
    if (weight > 1.0) {
      weight = 1.0;
    }
    float signal = (snoise_2d(p) + offset) * pwr;
    value += rmd * weight * signal;
  }

  return value;
}

/* musgrave.h: noise_musgrave_ridged_multi_fractal_2d() */
float noise_musgrave_ridged_multi_fractal_2d(
    vec2 co, float H, float lacunarity, float octaves, float offset, float gain)
{
  vec2 p = co;
  float pwHL = tex_powf(lacunarity, -H);
  float pwr = pwHL;

  precise float signal = offset - abs(snoise_2d(p));
  signal *= signal;
  precise float value = signal;
  float weight = 1.0;

  for (int i = 1; i < int(octaves); i++) {
    p *= lacunarity;
    weight = clamp(signal * gain, 0.0, 1.0);
    signal = offset - abs(snoise_2d(p));
    signal *= signal;
    signal *= weight;
    value += signal * pwr;
    pwr *= pwHL;
  }

  return value;
}

/* The svm_node_tex_musgrave() switch on the type, for one dimension count. */
float noise_musgrave_2d(int type, vec2 p, float dimension, float lacunarity, float detail,
                        float foffset, float gain)
{
  if (type == 0) { /* MULTIFRACTAL */
    return noise_musgrave_multi_fractal_2d(p, dimension, lacunarity, detail);
  }
  else if (type == 1) { /* FBM */
    return noise_musgrave_fBm_2d(p, dimension, lacunarity, detail);
  }
  else if (type == 2) { /* HYBRID_MULTIFRACTAL */
    return noise_musgrave_hybrid_multi_fractal_2d(
        p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (type == 3) { /* RIDGED_MULTIFRACTAL */
    return noise_musgrave_ridged_multi_fractal_2d(
        p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (type == 4) { /* HETERO_TERRAIN */
    return noise_musgrave_hetero_terrain_2d(p, dimension, lacunarity, detail, foffset);
  }
  return 0.0;
}

/* musgrave.h: noise_musgrave_fBm_3d() */
float noise_musgrave_fBm_3d(vec3 co, float H, float lacunarity, float octaves)
{
  vec3 p = co;
  precise float value = 0.0;
  float pwr = 1.0;
  float pwHL = tex_powf(lacunarity, -H);

  for (int i = 0; i < int(octaves); i++) {
    value += snoise_3d(p) * pwr;
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    value += rmd * snoise_3d(p) * pwr;
  }

  return value;
}

/* musgrave.h: noise_musgrave_multi_fractal_3d() */
float noise_musgrave_multi_fractal_3d(vec3 co, float H, float lacunarity, float octaves)
{
  vec3 p = co;
  precise float value = 1.0;
  float pwr = 1.0;
  float pwHL = tex_powf(lacunarity, -H);

  for (int i = 0; i < int(octaves); i++) {
    value *= (pwr * snoise_3d(p) + 1.0);
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    value *= (rmd * pwr * snoise_3d(p) + 1.0);
  }

  return value;
}

/* musgrave.h: noise_musgrave_hetero_terrain_3d() */
float noise_musgrave_hetero_terrain_3d(
    vec3 co, float H, float lacunarity, float octaves, float offset)
{
  vec3 p = co;
  float pwHL = tex_powf(lacunarity, -H);
  float pwr = pwHL;

  /* first unscaled octave of function; later octaves are scaled */
  precise float value = offset + snoise_3d(p);
  p *= lacunarity;

  for (int i = 1; i < int(octaves); i++) {
    precise float increment = (snoise_3d(p) + offset) * pwr * value;
    value += increment;
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    precise float increment = (snoise_3d(p) + offset) * pwr * value;
    value += rmd * increment;
  }

  return value;
}

/* musgrave.h: noise_musgrave_hybrid_multi_fractal_3d() */
float noise_musgrave_hybrid_multi_fractal_3d(
    vec3 co, float H, float lacunarity, float octaves, float offset, float gain)
{
  vec3 p = co;
  float pwHL = tex_powf(lacunarity, -H);

  float pwr = 1.0;
  precise float value = 0.0;
  precise float weight = 1.0;

  for (int i = 0; (weight > 0.001) && (i < int(octaves)); i++) {
    if (weight > 1.0) {
      weight = 1.0;
    }

    precise float signal = (snoise_3d(p) + offset) * pwr;
    pwr *= pwHL;
    value += weight * signal;
    weight *= gain * signal;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if ((rmd != 0.0) && (weight > 0.001)) {
    if (weight > 1.0) {
      weight = 1.0;
    }
    float signal = (snoise_3d(p) + offset) * pwr;
    value += rmd * weight * signal;
  }

  return value;
}

/* musgrave.h: noise_musgrave_ridged_multi_fractal_3d() */
float noise_musgrave_ridged_multi_fractal_3d(
    vec3 co, float H, float lacunarity, float octaves, float offset, float gain)
{
  vec3 p = co;
  float pwHL = tex_powf(lacunarity, -H);
  float pwr = pwHL;

  precise float signal = offset - abs(snoise_3d(p));
  signal *= signal;
  precise float value = signal;
  float weight = 1.0;

  for (int i = 1; i < int(octaves); i++) {
    p *= lacunarity;
    weight = clamp(signal * gain, 0.0, 1.0);
    signal = offset - abs(snoise_3d(p));
    signal *= signal;
    signal *= weight;
    value += signal * pwr;
    pwr *= pwHL;
  }

  return value;
}

/* The svm_node_tex_musgrave() switch on the type, for one dimension count. */
float noise_musgrave_3d(int type, vec3 p, float dimension, float lacunarity, float detail,
                        float foffset, float gain)
{
  if (type == 0) { /* MULTIFRACTAL */
    return noise_musgrave_multi_fractal_3d(p, dimension, lacunarity, detail);
  }
  else if (type == 1) { /* FBM */
    return noise_musgrave_fBm_3d(p, dimension, lacunarity, detail);
  }
  else if (type == 2) { /* HYBRID_MULTIFRACTAL */
    return noise_musgrave_hybrid_multi_fractal_3d(
        p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (type == 3) { /* RIDGED_MULTIFRACTAL */
    return noise_musgrave_ridged_multi_fractal_3d(
        p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (type == 4) { /* HETERO_TERRAIN */
    return noise_musgrave_hetero_terrain_3d(p, dimension, lacunarity, detail, foffset);
  }
  return 0.0;
}

/* musgrave.h: noise_musgrave_fBm_4d() */
float noise_musgrave_fBm_4d(vec4 co, float H, float lacunarity, float octaves)
{
  vec4 p = co;
  precise float value = 0.0;
  float pwr = 1.0;
  float pwHL = tex_powf(lacunarity, -H);

  for (int i = 0; i < int(octaves); i++) {
    value += snoise_4d(p) * pwr;
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    value += rmd * snoise_4d(p) * pwr;
  }

  return value;
}

/* musgrave.h: noise_musgrave_multi_fractal_4d() */
float noise_musgrave_multi_fractal_4d(vec4 co, float H, float lacunarity, float octaves)
{
  vec4 p = co;
  precise float value = 1.0;
  float pwr = 1.0;
  float pwHL = tex_powf(lacunarity, -H);

  for (int i = 0; i < int(octaves); i++) {
    value *= (pwr * snoise_4d(p) + 1.0);
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    value *= (rmd * pwr * snoise_4d(p) + 1.0);
  }

  return value;
}

/* musgrave.h: noise_musgrave_hetero_terrain_4d() */
float noise_musgrave_hetero_terrain_4d(
    vec4 co, float H, float lacunarity, float octaves, float offset)
{
  vec4 p = co;
  float pwHL = tex_powf(lacunarity, -H);
  float pwr = pwHL;

  /* first unscaled octave of function; later octaves are scaled */
  precise float value = offset + snoise_4d(p);
  p *= lacunarity;

  for (int i = 1; i < int(octaves); i++) {
    precise float increment = (snoise_4d(p) + offset) * pwr * value;
    value += increment;
    pwr *= pwHL;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if (rmd != 0.0) {
    precise float increment = (snoise_4d(p) + offset) * pwr * value;
    value += rmd * increment;
  }

  return value;
}

/* musgrave.h: noise_musgrave_hybrid_multi_fractal_4d() */
float noise_musgrave_hybrid_multi_fractal_4d(
    vec4 co, float H, float lacunarity, float octaves, float offset, float gain)
{
  vec4 p = co;
  float pwHL = tex_powf(lacunarity, -H);

  float pwr = 1.0;
  precise float value = 0.0;
  precise float weight = 1.0;

  for (int i = 0; (weight > 0.001) && (i < int(octaves)); i++) {
    if (weight > 1.0) {
      weight = 1.0;
    }

    precise float signal = (snoise_4d(p) + offset) * pwr;
    pwr *= pwHL;
    value += weight * signal;
    weight *= gain * signal;
    p *= lacunarity;
  }

  float rmd = octaves - floor(octaves);
  if ((rmd != 0.0) && (weight > 0.001)) {
    if (weight > 1.0) {
      weight = 1.0;
    }
    float signal = (snoise_4d(p) + offset) * pwr;
    value += rmd * weight * signal;
  }

  return value;
}

/* musgrave.h: noise_musgrave_ridged_multi_fractal_4d() */
float noise_musgrave_ridged_multi_fractal_4d(
    vec4 co, float H, float lacunarity, float octaves, float offset, float gain)
{
  vec4 p = co;
  float pwHL = tex_powf(lacunarity, -H);
  float pwr = pwHL;

  precise float signal = offset - abs(snoise_4d(p));
  signal *= signal;
  precise float value = signal;
  float weight = 1.0;

  for (int i = 1; i < int(octaves); i++) {
    p *= lacunarity;
    weight = clamp(signal * gain, 0.0, 1.0);
    signal = offset - abs(snoise_4d(p));
    signal *= signal;
    signal *= weight;
    value += signal * pwr;
    pwr *= pwHL;
  }

  return value;
}

/* The svm_node_tex_musgrave() switch on the type, for one dimension count. */
float noise_musgrave_4d(int type, vec4 p, float dimension, float lacunarity, float detail,
                        float foffset, float gain)
{
  if (type == 0) { /* MULTIFRACTAL */
    return noise_musgrave_multi_fractal_4d(p, dimension, lacunarity, detail);
  }
  else if (type == 1) { /* FBM */
    return noise_musgrave_fBm_4d(p, dimension, lacunarity, detail);
  }
  else if (type == 2) { /* HYBRID_MULTIFRACTAL */
    return noise_musgrave_hybrid_multi_fractal_4d(
        p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (type == 3) { /* RIDGED_MULTIFRACTAL */
    return noise_musgrave_ridged_multi_fractal_4d(
        p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (type == 4) { /* HETERO_TERRAIN */
    return noise_musgrave_hetero_terrain_4d(p, dimension, lacunarity, detail, foffset);
  }
  return 0.0;
}

/* Musgrave Texture node (ShaderNodeTexMusgrave): musgrave.h: svm_node_tex_musgrave(). */
void node_tex_musgrave(int dimensions,
                       int type,
                       int map_mode,
                       int map_block,
                       vec3 vector_in,
                       float w,
                       float scale,
                       float detail,
                       float dimension,
                       float lacunarity,
                       float foffset,
                       float gain,
                       out float fac)
{
  vec3 co = tex_mapping_apply(map_mode, map_block, vector_in);

  dimension = max(dimension, 1e-5);
  detail = clamp(detail, 0.0, 15.0);
  lacunarity = max(lacunarity, 1e-5);

  if (dimensions == 1) {
    float p = w * scale;
    fac = noise_musgrave_1d(type, p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (dimensions == 2) {
    vec2 p = vec2(co.x, co.y) * scale;
    fac = noise_musgrave_2d(type, p, dimension, lacunarity, detail, foffset, gain);
  }
  else if (dimensions == 3) {
    vec3 p = co * scale;
    fac = noise_musgrave_3d(type, p, dimension, lacunarity, detail, foffset, gain);
  }
  else {
    vec4 p = vec4(co.x, co.y, co.z, w) * scale;
    fac = noise_musgrave_4d(type, p, dimension, lacunarity, detail, foffset, gain);
  }
}

/* ==================================================================================== */
/* Wave Texture: kernel/svm/wave.h                                                      */
/* ==================================================================================== */

/* wave.h: svm_wave() */
float svm_wave(int type,
               int bands_dir,
               int rings_dir,
               int profile,
               vec3 p,
               float distortion,
               float detail,
               float dscale,
               float droughness,
               float phase)
{
  /* Prevent precision issues on unit coordinates. */
  p = (p + 0.000001) * 0.999999;

  precise float n;

  if (type == 0) { /* BANDS */
    if (bands_dir == 0) {
      n = p.x * 20.0;
    }
    else if (bands_dir == 1) {
      n = p.y * 20.0;
    }
    else if (bands_dir == 2) {
      n = p.z * 20.0;
    }
    else { /* DIAGONAL */
      n = (p.x + p.y + p.z) * 10.0;
    }
  }
  else { /* RINGS */
    vec3 rp = p;
    if (rings_dir == 0) {
      rp *= vec3(0.0, 1.0, 1.0);
    }
    else if (rings_dir == 1) {
      rp *= vec3(1.0, 0.0, 1.0);
    }
    else if (rings_dir == 2) {
      rp *= vec3(1.0, 1.0, 0.0);
    }
    /* else: SPHERICAL */

    n = tex_len(rp) * 20.0;
  }

  n += phase;

  if (distortion != 0.0) {
    n += distortion * (fractal_noise_3d(p * dscale, detail, droughness) * 2.0 - 1.0);
  }

  if (profile == 0) { /* SIN */
    precise float r = 0.5 + 0.5 * tex_sinf(n - 1.5707963267948966); /* sinf(n - M_PI_2_F) */
    return r;
  }
  else if (profile == 1) { /* SAW */
    n = tex_div(n, 6.2831853071795864); /* n /= M_2PI_F */
    return n - floor(n);
  }
  else { /* TRI */
    n = tex_div(n, 6.2831853071795864); /* n /= M_2PI_F */
    return abs(n - floor(n + 0.5)) * 2.0;
  }
}

/* Wave Texture node (ShaderNodeTexWave): wave.h: svm_node_tex_wave(). */
void node_tex_wave(int wave_type,
                   int bands_direction,
                   int rings_direction,
                   int profile,
                   int map_mode,
                   int map_block,
                   vec3 vector_in,
                   float scale,
                   float distortion,
                   float detail,
                   float dscale,
                   float droughness,
                   float phase,
                   out vec3 color,
                   out float fac)
{
  vec3 co = tex_mapping_apply(map_mode, map_block, vector_in);
  float f = svm_wave(wave_type,
                     bands_direction,
                     rings_direction,
                     profile,
                     co * scale,
                     distortion,
                     detail,
                     dscale,
                     droughness,
                     phase);
  fac = f;
  color = vec3(f, f, f);
}

/* ==================================================================================== */
/* Checker Texture: kernel/svm/checker.h                                                */
/* ==================================================================================== */

/* checker.h: svm_checker() */
float svm_checker(vec3 p)
{
  /* avoid precision issues on unit coordinates */
  p.x = (p.x + 0.000001) * 0.999999;
  p.y = (p.y + 0.000001) * 0.999999;
  p.z = (p.z + 0.000001) * 0.999999;

  /* abs(float_to_int(floorf(x))): non-negative, so GLSL's % is defined. */
  int xi = abs(int(floor(p.x)));
  int yi = abs(int(floor(p.y)));
  int zi = abs(int(floor(p.z)));

  /* C: ((xi % 2 == yi % 2) == (zi % 2)), a bool compared with an int. */
  return ((((xi % 2) == (yi % 2)) ? 1 : 0) == (zi % 2)) ? 1.0 : 0.0;
}

/* Checker Texture node (ShaderNodeTexChecker): checker.h: svm_node_tex_checker(). */
void node_tex_checker(int map_mode,
                      int map_block,
                      vec3 vector_in,
                      vec3 color1,
                      vec3 color2,
                      float scale,
                      out vec3 color,
                      out float fac)
{
  vec3 co = tex_mapping_apply(map_mode, map_block, vector_in);
  float f = svm_checker(co * scale);
  color = (f == 1.0) ? color1 : color2;
  fac = f;
}

/* ==================================================================================== */
/* Brick Texture: kernel/svm/brick.h                                                    */
/* ==================================================================================== */

/* brick.h: brick_noise(): fast integer noise (not the Jenkins hash). */
float brick_noise(uint n)
{
  uint nn;
  n = (n + 1013u) & 0x7fffffffu;
  n = (n >> 13) ^ n;
  nn = (n * (n * n * 60493u + 19990303u) + 1376312589u) & 0x7fffffffu;
  return 0.5 * (float(nn) / 1073741824.0);
}

/* brick.h: svm_brick(), returns (tint, mortar). `rownum % frequency` is only tested against
 * zero, which |rownum| % frequency gives without GLSL's undefined negative remainder. */
vec2 svm_brick(vec3 p,
               float mortar_size,
               float mortar_smooth,
               float bias,
               float brick_width,
               float row_height,
               float offset_amount,
               int offset_frequency,
               float squash_amount,
               int squash_frequency)
{
  int bricknum, rownum;
  float offset = 0.0;
  float x, y;

  rownum = int(floor(p.y / row_height));

  if (offset_frequency != 0 && squash_frequency != 0) {
    brick_width *= ((abs(rownum) % squash_frequency) != 0) ? 1.0 : squash_amount; /* squash */
    offset = ((abs(rownum) % offset_frequency) != 0) ? 0.0 :
                                                       (brick_width * offset_amount); /* offset */
  }

  /* Cycles' CPU kernel is built with fast math, where `brick_width * bricknum`
   * uses floorf()'s float itself (the int round trip folded away): a row
   * squashed to width 0 (Squash 0) has x = (p.x + offset) - 0 * inf = NaN,
   * and its min() ((a < b) ? a : b: a NaN first argument gives the
   * second) then drops the vertical mortar, so
   * such a row is one brick between horizontal mortar lines (measured:
   * Cycles 3.4.1, Brick Width 0.75, Squash 0 every 3rd row, 26 % mortar;
   * with the int round trip it was all mortar, 56 %). The tint's brick
   * number is the int conversion's, x86's INT_MIN for an infinite quotient. */
  float brick = floor((p.x + offset) / brick_width);
  bricknum = abs(brick) < 2147483520.0 ? int(brick) : int(0x80000000u);

  precise float xx = (p.x + offset) - brick_width * brick;
  precise float yy = p.y - row_height * float(rownum);
  x = xx;
  y = yy;

  /* (rownum << 16) + (bricknum & 0xFFFF) in C int arithmetic, wrapped, as uint bits. */
  float tint = clamp(
      brick_noise((uint(rownum) << 16) + uint(bricknum & 0xFFFF)) + bias, 0.0, 1.0);
  /* x NaN (no width): Cycles' min(NaN, y) is y, min(NaN, row_height - y)
   * row_height - y; said explicitly rather than left to a driver's NaN
   * rules (a GPU compiler may assume finite floats). */
  const bool no_width = brick_width == 0.0 || isinf(brick) || isnan(brick);
  float min_dist = no_width ? min(y, row_height - y) :
                              min(min(x, y), min(brick_width - x, row_height - y));

  float mortar;
  if (min_dist >= mortar_size) {
    mortar = 0.0;
  }
  else if (mortar_smooth == 0.0) {
    mortar = 1.0;
  }
  else {
    min_dist = 1.0 - min_dist / mortar_size;
    mortar = (min_dist < mortar_smooth) ? tex_smoothstepf(min_dist / mortar_smooth) : 1.0;
  }

  return vec2(tint, mortar);
}

/* Brick Texture node (ShaderNodeTexBrick): brick.h: svm_node_tex_brick().
 * offset_amount / offset_frequency / squash_amount / squash_frequency are the node's
 * offset, offset_frequency, squash, squash_frequency properties (frequencies are ints
 * 1..99, passed as floats so that editing them does not recompile). */
void node_tex_brick(int map_mode,
                    int map_block,
                    vec3 vector_in,
                    vec3 color1,
                    vec3 color2,
                    vec3 mortar,
                    float scale,
                    float mortar_size,
                    float mortar_smooth,
                    float bias,
                    float brick_width,
                    float row_height,
                    float offset_amount,
                    float offset_frequency,
                    float squash_amount,
                    float squash_frequency,
                    out vec3 color,
                    out float fac)
{
  vec3 co = tex_mapping_apply(map_mode, map_block, vector_in);

  vec2 f2 = svm_brick(co * scale,
                      mortar_size,
                      mortar_smooth,
                      bias,
                      brick_width,
                      row_height,
                      offset_amount,
                      int(offset_frequency + 0.5),
                      squash_amount,
                      int(squash_frequency + 0.5));

  float tint = f2.x;
  float f = f2.y;

  if (f != 1.0) {
    float facm = 1.0 - tint;
    precise vec3 c1 = facm * color1 + tint * color2;
    color1 = c1;
  }

  precise vec3 c = color1 * (1.0 - f) + mortar * f;
  color = c;
  fac = f;
}

/* ==================================================================================== */
/* Gradient Texture: kernel/svm/gradient.h                                              */
/* ==================================================================================== */

/* gradient.h: svm_gradient() */
float svm_gradient(vec3 p, int type)
{
  float x, y, z;

  x = p.x;
  y = p.y;
  z = p.z;

  if (type == 0) { /* LINEAR */
    return x;
  }
  else if (type == 1) { /* QUADRATIC */
    float r = max(x, 0.0);
    return r * r;
  }
  else if (type == 2) { /* EASING */
    float r = min(max(x, 0.0), 1.0);
    float t = r * r;

    precise float e = (3.0 * t - 2.0 * t * r);
    return e;
  }
  else if (type == 3) { /* DIAGONAL */
    return (x + y) * 0.5;
  }
  else if (type == 4) { /* RADIAL */
    return tex_div(tex_atan2f(y, x), 6.2831853071795864) + 0.5; /* atan2f(y, x) / M_2PI_F */
  }
  else {
    /* Bias a little bit for the case where p is a unit length vector,
     * to get exactly zero instead of a small random value depending
     * on float precision. */
    precise float len_sq = x * x + y * y + z * z;
    float r = max(0.999999 - sqrt(len_sq), 0.0);

    if (type == 5) { /* QUADRATIC_SPHERE */
      return r * r;
    }
    else if (type == 6) { /* SPHERICAL */
      return r;
    }
  }

  return 0.0;
}

/* Gradient Texture node (ShaderNodeTexGradient): gradient.h: svm_node_tex_gradient(). */
void node_tex_gradient(int type, int map_mode, int map_block, vec3 vector_in, out vec3 color,
                       out float fac)
{
  vec3 co = tex_mapping_apply(map_mode, map_block, vector_in);
  float f = svm_gradient(co, type);
  f = clamp(f, 0.0, 1.0); /* saturatef */
  fac = f;
  color = vec3(f, f, f);
}

/* ==================================================================================== */
/* Magic Texture: kernel/svm/magic.h                                                    */
/* ==================================================================================== */

/* magic.h: svm_magic() */
vec3 svm_magic(vec3 p, float scale, int n, float distortion)
{
  /* Cycles wraps the input with fmodf(p, M_2PI_F) to keep sin/cos in range.
   * sinf/cosf are tex_sinf/tex_cosf (C precision; see above). */
  float px = tex_fmodf(p.x, 6.2831853071795864);
  float py = tex_fmodf(p.y, 6.2831853071795864);
  float pz = tex_fmodf(p.z, 6.2831853071795864);

  float x = tex_sinf((px + py + pz) * 5.0 * scale);
  float y = tex_cosf((-px + py - pz) * 5.0 * scale);
  float z = -tex_cosf((-px - py + pz) * 5.0 * scale);

  if (n > 0) {
    x *= distortion;
    y *= distortion;
    z *= distortion;
    y = -tex_cosf(x - y + z);
    y *= distortion;

    if (n > 1) {
      x = tex_cosf(x - y - z);
      x *= distortion;

      if (n > 2) {
        z = tex_sinf(-x - y - z);
        z *= distortion;

        if (n > 3) {
          x = -tex_cosf(-x + y - z);
          x *= distortion;

          if (n > 4) {
            y = -tex_sinf(-x + y + z);
            y *= distortion;

            if (n > 5) {
              y = -tex_cosf(-x + y + z);
              y *= distortion;

              if (n > 6) {
                x = tex_cosf(x + y + z);
                x *= distortion;

                if (n > 7) {
                  z = tex_sinf(x + y - z);
                  z *= distortion;

                  if (n > 8) {
                    x = -tex_cosf(-x - y + z);
                    x *= distortion;

                    if (n > 9) {
                      y = -tex_sinf(x - y + z);
                      y *= distortion;
                    }
                  }
                }
              }
            }
          }
        }
      }
    }
  }

  if (distortion != 0.0) {
    distortion *= 2.0;
    x /= distortion;
    y /= distortion;
    z /= distortion;
  }

  return vec3(0.5 - x, 0.5 - y, 0.5 - z);
}

/* Magic Texture node (ShaderNodeTexMagic): magic.h: svm_node_tex_magic().
 * depth: the node's turbulence_depth (0..10). */
void node_tex_magic(int depth,
                    int map_mode,
                    int map_block,
                    vec3 vector_in,
                    float scale,
                    float distortion,
                    out vec3 color,
                    out float fac)
{
  vec3 co = tex_mapping_apply(map_mode, map_block, vector_in);
  vec3 c = svm_magic(co, scale, depth, distortion);
  fac = (c.x + c.y + c.z) * (1.0 / 3.0); /* average() */
  color = c;
}

/* ==================================================================================== */
/* White Noise Texture: kernel/svm/white_noise.h                                        */
/* ==================================================================================== */

/* White Noise Texture node (ShaderNodeTexWhiteNoise): white_noise.h:
 * svm_node_tex_white_noise(). No texture mapping (Cycles' WhiteNoiseTextureNode is not a
 * TextureNode) and no implicit coordinates: an unlinked Vector is its (0, 0, 0) default. */
void node_tex_white_noise(int dimensions, vec3 vector, float w, out float value, out vec3 color)
{
  if (dimensions == 1) {
    color = hash_float_to_float3(w);
    value = hash_float_to_float(w);
  }
  else if (dimensions == 2) {
    color = hash_float2_to_float3(vec2(vector.x, vector.y));
    value = hash_float2_to_float(vec2(vector.x, vector.y));
  }
  else if (dimensions == 3) {
    color = hash_float3_to_float3(vector);
    value = hash_float3_to_float(vector);
  }
  else {
    color = hash_float4_to_float3(vec4(vector.x, vector.y, vector.z, w));
    value = hash_float4_to_float(vec4(vector.x, vector.y, vector.z, w));
  }
}

#endif /* NODE_TEXTURE_LIB */
