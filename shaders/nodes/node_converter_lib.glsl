/* Converter nodes: Math, Vector Math, Clamp, Map Range, Separate/Combine
 * (RGB, XYZ, HSV, Color), RGB to BW, Blackbody, Wavelength.
 *
 * Every function reproduces Cycles 3.4 (SVM kernel, intern/cycles/kernel/svm/
 * and intern/cycles/util/); the Cycles function is named above each one.
 * Enum ints are passed by the node specs in
 * addon/deferred_render/materials/nodes/converter.py and must stay equal to the
 * #defines below.
 *
 * Also defines the helpers node_color_lib.glsl uses: the C-semantics scalar
 * functions math_* (min/max/clamp/saturate/fmod/fract...) and the colour-space
 * conversions color_rgb_to_hsv, color_hsv_to_rgb, color_rgb_to_hsl and
 * color_hsl_to_rgb.
 *
 * Verified against Cycles 3.4.1 itself: every operation/mode baked (EMIT) on
 * 1024 inputs and compared with this GLSL on llvmpipe; agreement to float
 * rounding (worst cases: cancellation in CROSS_PRODUCT / SMOOTHERSTEP). */

/* ---- enums (converter.py MATH_OPS) -------------------------------------- */
#define NODE_MATH_ADD 0
#define NODE_MATH_SUBTRACT 1
#define NODE_MATH_MULTIPLY 2
#define NODE_MATH_DIVIDE 3
#define NODE_MATH_MULTIPLY_ADD 4
#define NODE_MATH_POWER 5
#define NODE_MATH_LOGARITHM 6
#define NODE_MATH_SQRT 7
#define NODE_MATH_INVERSE_SQRT 8
#define NODE_MATH_ABSOLUTE 9
#define NODE_MATH_EXPONENT 10
#define NODE_MATH_MINIMUM 11
#define NODE_MATH_MAXIMUM 12
#define NODE_MATH_LESS_THAN 13
#define NODE_MATH_GREATER_THAN 14
#define NODE_MATH_SIGN 15
#define NODE_MATH_COMPARE 16
#define NODE_MATH_SMOOTH_MIN 17
#define NODE_MATH_SMOOTH_MAX 18
#define NODE_MATH_ROUND 19
#define NODE_MATH_FLOOR 20
#define NODE_MATH_CEIL 21
#define NODE_MATH_TRUNC 22
#define NODE_MATH_FRACT 23
#define NODE_MATH_MODULO 24
#define NODE_MATH_WRAP 25
#define NODE_MATH_SNAP 26
#define NODE_MATH_PINGPONG 27
#define NODE_MATH_SINE 28
#define NODE_MATH_COSINE 29
#define NODE_MATH_TANGENT 30
#define NODE_MATH_ARCSINE 31
#define NODE_MATH_ARCCOSINE 32
#define NODE_MATH_ARCTANGENT 33
#define NODE_MATH_ARCTAN2 34
#define NODE_MATH_SINH 35
#define NODE_MATH_COSH 36
#define NODE_MATH_TANH 37
#define NODE_MATH_RADIANS 38
#define NODE_MATH_DEGREES 39

/* converter.py VECTOR_MATH_OPS */
#define NODE_VECTOR_MATH_ADD 0
#define NODE_VECTOR_MATH_SUBTRACT 1
#define NODE_VECTOR_MATH_MULTIPLY 2
#define NODE_VECTOR_MATH_DIVIDE 3
#define NODE_VECTOR_MATH_MULTIPLY_ADD 4
#define NODE_VECTOR_MATH_CROSS_PRODUCT 5
#define NODE_VECTOR_MATH_PROJECT 6
#define NODE_VECTOR_MATH_REFLECT 7
#define NODE_VECTOR_MATH_REFRACT 8
#define NODE_VECTOR_MATH_FACEFORWARD 9
#define NODE_VECTOR_MATH_DOT_PRODUCT 10
#define NODE_VECTOR_MATH_DISTANCE 11
#define NODE_VECTOR_MATH_LENGTH 12
#define NODE_VECTOR_MATH_SCALE 13
#define NODE_VECTOR_MATH_NORMALIZE 14
#define NODE_VECTOR_MATH_ABSOLUTE 15
#define NODE_VECTOR_MATH_MINIMUM 16
#define NODE_VECTOR_MATH_MAXIMUM 17
#define NODE_VECTOR_MATH_FLOOR 18
#define NODE_VECTOR_MATH_CEIL 19
#define NODE_VECTOR_MATH_FRACTION 20
#define NODE_VECTOR_MATH_MODULO 21
#define NODE_VECTOR_MATH_WRAP 22
#define NODE_VECTOR_MATH_SNAP 23
#define NODE_VECTOR_MATH_SINE 24
#define NODE_VECTOR_MATH_COSINE 25
#define NODE_VECTOR_MATH_TANGENT 26

/* converter.py CLAMP_TYPES */
#define NODE_CLAMP_MINMAX 0
#define NODE_CLAMP_RANGE 1

/* converter.py MAP_RANGE_TYPES */
#define NODE_MAP_RANGE_LINEAR 0
#define NODE_MAP_RANGE_STEPPED 1
#define NODE_MAP_RANGE_SMOOTHSTEP 2
#define NODE_MAP_RANGE_SMOOTHERSTEP 3

/* converter.py COLOR_MODES (Separate/Combine Color) */
#define NODE_COMBSEP_COLOR_RGB 0
#define NODE_COMBSEP_COLOR_HSV 1
#define NODE_COMBSEP_COLOR_HSL 2

/* ---- scalar helpers (intern/cycles/util/math.h of 3.4) ------------------ */

/* C++ min/max as Cycles writes them ((a < b) ? a : b): a NaN first argument
 * gives the second one, as in Cycles, where GLSL min/max are undefined. */
float math_min(float a, float b) { return (a < b) ? a : b; }
float math_max(float a, float b) { return (a > b) ? a : b; }

/* util: clamp(a, mn, mx) = min(max(a, mn), mx); defined for mn > mx too
 * (gives mx), unlike GLSL clamp. */
float math_clamp(float a, float mn, float mx) { return math_min(math_max(a, mn), mx); }

/* util: saturatef */
float math_saturate(float a) { return math_clamp(a, 0.0, 1.0); }

/* util: safe_divide */
float math_safe_divide(float a, float b) { return (b != 0.0) ? a / b : 0.0; }

vec3 math_safe_divide(vec3 a, vec3 b)
{
  return vec3(math_safe_divide(a.x, b.x), math_safe_divide(a.y, b.y), math_safe_divide(a.z, b.z));
}

/* C fmodf: a - n * b with n = trunc(a / b), sign of a, |result| < |b|. The
 * quotient is rounded in float, so fix the two cases where that moves the
 * result out of (-|b|, |b|) or to the wrong sign. */
float math_fmod(float a, float b)
{
  if (isinf(b) && !isinf(a)) {
    return a;
  }
  float r = a - b * trunc(a / b);
  float ab = abs(b);
  if (abs(r) >= ab) {
    r -= sign(r) * ab;
  }
  if (r != 0.0 && sign(r) != sign(a)) {
    r += sign(a) * ab;
  }
  return r;
}

/* util: safe_modulo (fmodf, truncated: the sign follows a) */
float math_safe_modulo(float a, float b) { return (b != 0.0) ? math_fmod(a, b) : 0.0; }

/* util: fractf */
float math_fract(float a) { return a - floor(a); }

/* util: compatible_powf as Cycles' CPU kernels compute it (powf), the
 * reference render. GLSL pow is undefined for x <= 0, so C powf's rules are
 * spelled out, as the __KERNEL_GPU__ branch of compatible_powf does (that
 * branch gives 0 where powf gives inf: 0 to a negative power). */
float math_compatible_pow(float x, float y)
{
  if (y == 0.0) {
    return 1.0; /* x^0 -> 1, including 0^0 */
  }
  if (x == 0.0) {
    return (y < 0.0) ? uintBitsToFloat(0x7f800000u) : 0.0; /* powf(0, y < 0) = inf */
  }
  if (x < 0.0) {
    /* safe_powf only gets here with an integer y: odd powers keep the sign. */
    if (math_fmod(-y, 2.0) == 0.0) {
      return pow(-x, y);
    }
    return -pow(-x, y);
  }
  return pow(x, y);
}

/* util: safe_powf (float_to_int truncates) */
float math_safe_pow(float a, float b)
{
  if (a < 0.0 && b != trunc(b)) {
    return 0.0;
  }
  return math_compatible_pow(a, b);
}

/* util: safe_logf */
float math_safe_log(float a, float b)
{
  if (a <= 0.0 || b <= 0.0) {
    return 0.0;
  }
  return math_safe_divide(log(a), log(b));
}

/* util: safe_sqrtf */
float math_safe_sqrt(float a) { return sqrt(math_max(a, 0.0)); }

/* util: inversesqrtf */
float math_inverse_sqrt(float a) { return (a > 0.0) ? 1.0 / sqrt(a) : 0.0; }

/* Inverse trigonometric and hyperbolic functions to float precision, with
 * the Cephes single-precision algorithms C libraries use for asinf, atanf,
 * tanhf...: GLSL leaves their precision to the driver (Mesa's asin and acos
 * are off by up to 4e-4) and atan(y, x) undefined at the origin. */

/* asinf */
float math_asin(float x)
{
  const float PIO2F = 1.5707963267948966;
  float a = abs(x);
  if (a < 1.0e-4) {
    return x;
  }
  bool upper = a > 0.5;
  float z = upper ? 0.5 * (1.0 - a) : a * a;
  float r = upper ? sqrt(z) : a;
  z = ((((4.2163199048e-2 * z + 2.4181311049e-2) * z + 4.5470025998e-2) * z +
        7.4953002686e-2) * z + 1.6666752422e-1) * z * r + r;
  if (upper) {
    z = PIO2F - (z + z);
  }
  return (x < 0.0) ? -z : z;
}

/* acosf */
float math_acos(float x)
{
  const float PIF = 3.1415926535897932;
  const float PIO2F = 1.5707963267948966;
  if (x < -0.5) {
    return PIF - 2.0 * math_asin(sqrt(0.5 * (1.0 + x)));
  }
  if (x > 0.5) {
    return 2.0 * math_asin(sqrt(0.5 * (1.0 - x)));
  }
  return PIO2F - math_asin(x);
}

/* atanf */
float math_atan(float x)
{
  const float PIO2F = 1.5707963267948966;
  const float PIO4F = 0.7853981633974483;
  float a = abs(x);
  float y = 0.0;
  if (a > 2.414213562373095) {
    y = PIO2F;
    a = -(1.0 / a);
  }
  else if (a > 0.4142135623730950) {
    y = PIO4F;
    a = (a - 1.0) / (a + 1.0);
  }
  float z = a * a;
  y += (((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z -
        3.33329491539e-1) * z * a + a;
  return (x < 0.0) ? -y : y;
}

/* atan2f (0 at the origin, as C gives for +0, +0) */
float math_atan2(float y, float x)
{
  const float PIF = 3.1415926535897932;
  const float PIO2F = 1.5707963267948966;
  if (x == 0.0) {
    return (y < 0.0) ? -PIO2F : ((y == 0.0) ? 0.0 : PIO2F);
  }
  if (y == 0.0) {
    return (x < 0.0) ? PIF : 0.0;
  }
  float w = (x < 0.0) ? ((y < 0.0) ? -PIF : PIF) : 0.0;
  return w + math_atan(y / x);
}

/* util: safe_asinf / safe_acosf */
float math_safe_asin(float a) { return math_asin(math_clamp(a, -1.0, 1.0)); }
float math_safe_acos(float a) { return math_acos(math_clamp(a, -1.0, 1.0)); }

/* sinhf: a polynomial near 0, where (e^a - e^-a) / 2 cancels */
float math_sinh(float a)
{
  float x = abs(a);
  if (x <= 1.0) {
    float z = a * a;
    return ((2.03721912945e-4 * z + 8.33028376239e-3) * z + 1.66667160211e-1) * z * a + a;
  }
  float z;
  if (x > 88.0) {
    float w = exp(0.5 * x); /* e^x overflows before sinh does */
    z = (0.5 * w) * w;
  }
  else {
    z = exp(x);
    z = 0.5 * z - (0.5 / z);
  }
  return (a < 0.0) ? -z : z;
}

/* coshf */
float math_cosh(float a)
{
  float x = abs(a);
  if (x > 88.0) {
    float w = exp(0.5 * x);
    return (0.5 * w) * w;
  }
  float z = exp(x);
  return 0.5 * z + (0.5 / z);
}

/* tanhf: a polynomial near 0, 1 - 2 / (e^2a + 1) elsewhere */
float math_tanh(float a)
{
  float x = abs(a);
  if (x > 44.0) {
    return (a < 0.0) ? -1.0 : 1.0;
  }
  if (x >= 0.625) {
    float z = 1.0 - 2.0 / (exp(2.0 * x) + 1.0);
    return (a < 0.0) ? -z : z;
  }
  float s = a * a;
  return ((((-5.70498872745e-3 * s + 2.06390887954e-2) * s - 5.37397155531e-2) * s +
           1.33314422036e-1) * s - 3.33332819422e-1) * s * a + a;
}

/* util: wrapf(value, max, min) */
float math_wrap(float value, float vmax, float vmin)
{
  float range = vmax - vmin;
  return (range != 0.0) ? value - (range * floor((value - vmin) / range)) : vmin;
}

/* util: pingpongf */
float math_pingpong(float a, float b)
{
  return (b != 0.0) ? abs(math_fract((a - b) / (b * 2.0)) * b * 2.0 - b) : 0.0;
}

/* util: smoothminf */
float math_smoothmin(float a, float b, float k)
{
  if (k != 0.0) {
    float h = math_max(k - abs(a - b), 0.0) / k;
    return math_min(a, b) - h * h * h * k * (1.0 / 6.0);
  }
  return math_min(a, b);
}

/* util: compatible_signf (0 for 0, else +-1) */
float math_compatible_sign(float a)
{
  if (a == 0.0) {
    return 0.0;
  }
  return (a < 0.0) ? -1.0 : 1.0;
}

/* ---- Math node ---------------------------------------------------------- */

/* kernel/svm/math_util.h: svm_math (3.4, no floored modulo yet) */
float node_math_eval(int op, float a, float b, float c)
{
  const float MATH_PI = 3.1415926535897932; /* not M_PI_F: bsdf_lib.glsl defines that macro (forward pass) */
  const float FLT_EPSILON = 1.192092896e-07;
  switch (op) {
    case NODE_MATH_ADD: return a + b;
    case NODE_MATH_SUBTRACT: return a - b;
    case NODE_MATH_MULTIPLY: return a * b;
    case NODE_MATH_DIVIDE: return math_safe_divide(a, b);
    case NODE_MATH_POWER: return math_safe_pow(a, b);
    case NODE_MATH_LOGARITHM: return math_safe_log(a, b);
    case NODE_MATH_SQRT: return math_safe_sqrt(a);
    case NODE_MATH_INVERSE_SQRT: return math_inverse_sqrt(a);
    case NODE_MATH_ABSOLUTE: return abs(a);
    case NODE_MATH_RADIANS: return a * (MATH_PI / 180.0);
    case NODE_MATH_DEGREES: return a * (180.0 / MATH_PI);
    case NODE_MATH_MINIMUM: return math_min(a, b);
    case NODE_MATH_MAXIMUM: return math_max(a, b);
    case NODE_MATH_LESS_THAN: return (a < b) ? 1.0 : 0.0;
    case NODE_MATH_GREATER_THAN: return (a > b) ? 1.0 : 0.0;
    case NODE_MATH_ROUND: return floor(a + 0.5);
    case NODE_MATH_FLOOR: return floor(a);
    case NODE_MATH_CEIL: return ceil(a);
    case NODE_MATH_FRACT: return math_fract(a);
    case NODE_MATH_MODULO: return math_safe_modulo(a, b);
    case NODE_MATH_TRUNC: return (a >= 0.0) ? floor(a) : ceil(a);
    case NODE_MATH_SNAP: return floor(math_safe_divide(a, b)) * b;
    case NODE_MATH_WRAP: return math_wrap(a, b, c);
    case NODE_MATH_PINGPONG: return math_pingpong(a, b);
    case NODE_MATH_SINE: return sin(a);
    case NODE_MATH_COSINE: return cos(a);
    case NODE_MATH_TANGENT: return tan(a);
    case NODE_MATH_SINH: return math_sinh(a);
    case NODE_MATH_COSH: return math_cosh(a);
    case NODE_MATH_TANH: return math_tanh(a);
    case NODE_MATH_ARCSINE: return math_safe_asin(a);
    case NODE_MATH_ARCCOSINE: return math_safe_acos(a);
    case NODE_MATH_ARCTANGENT: return math_atan(a);
    case NODE_MATH_ARCTAN2: return math_atan2(a, b);
    case NODE_MATH_SIGN: return math_compatible_sign(a);
    case NODE_MATH_EXPONENT: return exp(a);
    case NODE_MATH_COMPARE:
      return ((a == b) || (abs(a - b) <= math_max(c, FLT_EPSILON))) ? 1.0 : 0.0;
    case NODE_MATH_MULTIPLY_ADD: return a * b + c;
    case NODE_MATH_SMOOTH_MIN: return math_smoothmin(a, b, c);
    case NODE_MATH_SMOOTH_MAX: return -math_smoothmin(-a, -b, c);
  }
  return 0.0;
}

/* kernel/svm/math.h: svm_node_math; use_clamp is MathNode::expand
 * (scene/shader_nodes.cpp), which appends a Clamp node MINMAX 0..1. */
void node_math(int op, int use_clamp, float a, float b, float c, out float result)
{
  result = node_math_eval(op, a, b, c);
  if (use_clamp != 0) {
    result = math_clamp(result, 0.0, 1.0);
  }
}

/* ---- Vector Math node --------------------------------------------------- */

/* util/math_float3.h: safe_normalize (3.4) */
vec3 math_safe_normalize(vec3 a)
{
  float t = length(a);
  return (t != 0.0) ? a * (1.0 / t) : a;
}

/* util/math_float3.h: project */
vec3 math_project(vec3 v, vec3 v_proj)
{
  float len_squared = dot(v_proj, v_proj);
  return (len_squared != 0.0) ? (dot(v, v_proj) / len_squared) * v_proj : vec3(0.0);
}

/* util/math_float3.h: reflect (3.4 normalizes the normal itself) */
vec3 math_reflect(vec3 incident, vec3 normal)
{
  vec3 unit_normal = normalize(normal);
  return incident - 2.0 * unit_normal * dot(incident, unit_normal);
}

/* util/math_float3.h: refract (the node passes normalize(b)) */
vec3 math_refract(vec3 incident, vec3 normal, float eta)
{
  float k = 1.0 - eta * eta * (1.0 - dot(normal, incident) * dot(normal, incident));
  if (k < 0.0) {
    return vec3(0.0);
  }
  return eta * incident - (eta * dot(normal, incident) + sqrt(k)) * normal;
}

/* util/math_float3.h: faceforward(vector, incident, reference) */
vec3 math_faceforward(vec3 v, vec3 incident, vec3 reference)
{
  return (dot(reference, incident) < 0.0) ? v : -v;
}

vec3 math_min(vec3 a, vec3 b) { return vec3(math_min(a.x, b.x), math_min(a.y, b.y), math_min(a.z, b.z)); }
vec3 math_max(vec3 a, vec3 b) { return vec3(math_max(a.x, b.x), math_max(a.y, b.y), math_max(a.z, b.z)); }

/* kernel/svm/math_util.h: svm_vector_math. Both outputs are always written:
 * the one an operation does not compute is 0, as in Cycles' constant folding
 * (VectorMathNode::constant_fold starts from zero). */
void node_vector_math(int op, vec3 a, vec3 b, vec3 c, float scale,
                      out vec3 vector, out float value)
{
  vector = vec3(0.0);
  value = 0.0;
  switch (op) {
    case NODE_VECTOR_MATH_ADD: vector = a + b; break;
    case NODE_VECTOR_MATH_SUBTRACT: vector = a - b; break;
    case NODE_VECTOR_MATH_MULTIPLY: vector = a * b; break;
    case NODE_VECTOR_MATH_DIVIDE: vector = math_safe_divide(a, b); break;
    case NODE_VECTOR_MATH_CROSS_PRODUCT: vector = cross(a, b); break;
    case NODE_VECTOR_MATH_PROJECT: vector = math_project(a, b); break;
    case NODE_VECTOR_MATH_REFLECT: vector = math_reflect(a, b); break;
    case NODE_VECTOR_MATH_REFRACT: vector = math_refract(a, normalize(b), scale); break;
    case NODE_VECTOR_MATH_FACEFORWARD: vector = math_faceforward(a, b, c); break;
    case NODE_VECTOR_MATH_MULTIPLY_ADD: vector = a * b + c; break;
    case NODE_VECTOR_MATH_DOT_PRODUCT: value = dot(a, b); break;
    case NODE_VECTOR_MATH_DISTANCE: value = length(a - b); break;
    case NODE_VECTOR_MATH_LENGTH: value = length(a); break;
    case NODE_VECTOR_MATH_SCALE: vector = a * scale; break;
    case NODE_VECTOR_MATH_NORMALIZE: vector = math_safe_normalize(a); break;
    case NODE_VECTOR_MATH_SNAP: vector = floor(math_safe_divide(a, b)) * b; break;
    case NODE_VECTOR_MATH_FLOOR: vector = floor(a); break;
    case NODE_VECTOR_MATH_CEIL: vector = ceil(a); break;
    case NODE_VECTOR_MATH_MODULO:
      vector = vec3(math_safe_modulo(a.x, b.x), math_safe_modulo(a.y, b.y), math_safe_modulo(a.z, b.z));
      break;
    case NODE_VECTOR_MATH_WRAP:
      vector = vec3(math_wrap(a.x, b.x, c.x), math_wrap(a.y, b.y, c.y), math_wrap(a.z, b.z, c.z));
      break;
    case NODE_VECTOR_MATH_FRACTION: vector = a - floor(a); break;
    case NODE_VECTOR_MATH_ABSOLUTE: vector = abs(a); break;
    case NODE_VECTOR_MATH_MINIMUM: vector = math_min(a, b); break;
    case NODE_VECTOR_MATH_MAXIMUM: vector = math_max(a, b); break;
    case NODE_VECTOR_MATH_SINE: vector = sin(a); break;
    case NODE_VECTOR_MATH_COSINE: vector = cos(a); break;
    case NODE_VECTOR_MATH_TANGENT: vector = tan(a); break;
  }
}

/* ---- Clamp and Map Range ------------------------------------------------ */

/* kernel/svm/clamp.h: svm_node_clamp */
void node_clamp(int clamp_type, float value, float vmin, float vmax, out float result)
{
  if (clamp_type == NODE_CLAMP_RANGE && vmin > vmax) {
    result = math_clamp(value, vmax, vmin);
  }
  else {
    result = math_clamp(value, vmin, vmax);
  }
}

/* util/math.h: smoothstep(edge0, edge1, x) (defined piecewise, not GLSL's) */
float map_range_smoothstep(float edge0, float edge1, float x)
{
  if (x < edge0) {
    return 0.0;
  }
  if (x >= edge1) {
    return 1.0;
  }
  float t = (x - edge0) / (edge1 - edge0);
  return (3.0 - 2.0 * t) * (t * t);
}

/* kernel/svm/map_range.h: smootherstep */
float map_range_smootherstep(float edge0, float edge1, float x)
{
  x = math_clamp(math_safe_divide(x - edge0, edge1 - edge0), 0.0, 1.0);
  return x * x * x * (x * (x * 6.0 - 15.0) + 10.0);
}

/* kernel/svm/map_range.h: svm_node_map_range; use_clamp is
 * MapRangeNode::expand, a Clamp node RANGE between To Min and To Max. */
void node_map_range(int range_type, int use_clamp, float value, float from_min, float from_max,
                    float to_min, float to_max, float steps, out float result)
{
  if (from_max != from_min) {
    float factor = value;
    switch (range_type) {
      default:
      case NODE_MAP_RANGE_LINEAR:
        factor = (value - from_min) / (from_max - from_min);
        break;
      case NODE_MAP_RANGE_STEPPED:
        factor = (value - from_min) / (from_max - from_min);
        factor = (steps > 0.0) ? floor(factor * (steps + 1.0)) / steps : 0.0;
        break;
      case NODE_MAP_RANGE_SMOOTHSTEP:
        factor = (from_min > from_max) ? 1.0 - map_range_smoothstep(from_max, from_min, factor) :
                                         map_range_smoothstep(from_min, from_max, factor);
        break;
      case NODE_MAP_RANGE_SMOOTHERSTEP:
        factor = (from_min > from_max) ? 1.0 - map_range_smootherstep(from_max, from_min, factor) :
                                         map_range_smootherstep(from_min, from_max, factor);
        break;
    }
    result = to_min + factor * (to_max - to_min);
  }
  else {
    result = 0.0;
  }
  if (use_clamp != 0) {
    node_clamp(NODE_CLAMP_RANGE, result, to_min, to_max, result);
  }
}

/* kernel/svm/map_range.h: one component of the STEPPED factor */
float map_range_step(float factor, float steps)
{
  return (steps > 0.0) ? floor(factor * (steps + 1.0)) / steps : 0.0;
}

/* kernel/svm/map_range.h: one component of the result clamp */
float map_range_clamp_to(float r, float to_min, float to_max)
{
  return (to_min > to_max) ? math_clamp(r, to_max, to_min) : math_clamp(r, to_min, to_max);
}

/* kernel/svm/map_range.h: svm_node_vector_map_range (no clamp for the smooth
 * types, as the kernel decides) */
void node_vector_map_range(int range_type, int use_clamp, vec3 value, vec3 from_min,
                           vec3 from_max, vec3 to_min, vec3 to_max, vec3 steps,
                           out vec3 result)
{
  vec3 factor = math_safe_divide(value - from_min, from_max - from_min);
  switch (range_type) {
    default:
    case NODE_MAP_RANGE_LINEAR:
      break;
    case NODE_MAP_RANGE_STEPPED:
      factor = vec3(map_range_step(factor.x, steps.x), map_range_step(factor.y, steps.y),
                    map_range_step(factor.z, steps.z));
      break;
    case NODE_MAP_RANGE_SMOOTHSTEP:
      factor = vec3(math_saturate(factor.x), math_saturate(factor.y), math_saturate(factor.z));
      factor = (vec3(3.0) - 2.0 * factor) * (factor * factor);
      break;
    case NODE_MAP_RANGE_SMOOTHERSTEP:
      factor = vec3(math_saturate(factor.x), math_saturate(factor.y), math_saturate(factor.z));
      factor = factor * factor * factor * (factor * (factor * 6.0 - 15.0) + 10.0);
      break;
  }
  result = to_min + factor * (to_max - to_min);
  bool smooth_type = (range_type == NODE_MAP_RANGE_SMOOTHSTEP ||
                 range_type == NODE_MAP_RANGE_SMOOTHERSTEP);
  if (use_clamp != 0 && !smooth_type) {
    result = vec3(map_range_clamp_to(result.x, to_min.x, to_max.x),
                  map_range_clamp_to(result.y, to_min.y, to_max.y),
                  map_range_clamp_to(result.z, to_min.z, to_max.z));
  }
}

/* ---- colour spaces (intern/cycles/util/color.h of 3.4) ------------------ */

/* util/color.h: rgb_to_hsv */
vec3 color_rgb_to_hsv(vec3 rgb)
{
  float cmax = math_max(rgb.x, math_max(rgb.y, rgb.z));
  float cmin = math_min(rgb.x, math_min(rgb.y, rgb.z));
  float cdelta = cmax - cmin;
  float v = cmax;
  float s = (cmax != 0.0) ? cdelta / cmax : 0.0;
  float h = 0.0;
  if (s != 0.0) {
    vec3 c = (vec3(cmax) - rgb) / cdelta;
    if (rgb.x == cmax) {
      h = c.z - c.y;
    }
    else if (rgb.y == cmax) {
      h = 2.0 + c.x - c.z;
    }
    else {
      h = 4.0 + c.y - c.x;
    }
    h /= 6.0;
    if (h < 0.0) {
      h += 1.0;
    }
  }
  return vec3(h, s, v);
}

/* util/color.h: hsv_to_rgb */
vec3 color_hsv_to_rgb(vec3 hsv)
{
  float h = hsv.x;
  float s = hsv.y;
  float v = hsv.z;
  if (s == 0.0) {
    return vec3(v);
  }
  if (h == 1.0) {
    h = 0.0;
  }
  h *= 6.0;
  float i = floor(h);
  float f = h - i;
  float p = v * (1.0 - s);
  float q = v * (1.0 - (s * f));
  float t = v * (1.0 - (s * (1.0 - f)));
  if (i == 0.0) {
    return vec3(v, t, p);
  }
  if (i == 1.0) {
    return vec3(q, v, p);
  }
  if (i == 2.0) {
    return vec3(p, v, t);
  }
  if (i == 3.0) {
    return vec3(p, q, v);
  }
  if (i == 4.0) {
    return vec3(t, p, v);
  }
  return vec3(v, p, q);
}

/* util/color.h: rgb_to_hsl */
vec3 color_rgb_to_hsl(vec3 rgb)
{
  float cmax = math_max(rgb.x, math_max(rgb.y, rgb.z));
  float cmin = math_min(rgb.x, math_min(rgb.y, rgb.z));
  float l = math_min(1.0, (cmax + cmin) / 2.0);
  float h = 0.0;
  float s = 0.0;
  if (cmax != cmin) {
    float cdelta = cmax - cmin;
    s = (l > 0.5) ? cdelta / (2.0 - cmax - cmin) : cdelta / (cmax + cmin);
    if (cmax == rgb.x) {
      h = (rgb.y - rgb.z) / cdelta + ((rgb.y < rgb.z) ? 6.0 : 0.0);
    }
    else if (cmax == rgb.y) {
      h = (rgb.z - rgb.x) / cdelta + 2.0;
    }
    else {
      h = (rgb.x - rgb.y) / cdelta + 4.0;
    }
  }
  h /= 6.0;
  return vec3(h, s, l);
}

/* util/color.h: hsl_to_rgb */
vec3 color_hsl_to_rgb(vec3 hsl)
{
  float h = hsl.x;
  float s = hsl.y;
  float l = hsl.z;
  float nr = math_clamp(abs(h * 6.0 - 3.0) - 1.0, 0.0, 1.0);
  float ng = math_clamp(2.0 - abs(h * 6.0 - 2.0), 0.0, 1.0);
  float nb = math_clamp(2.0 - abs(h * 6.0 - 4.0), 0.0, 1.0);
  float chroma = (1.0 - abs(2.0 * l - 1.0)) * s;
  return vec3((nr - 0.5) * chroma + l, (ng - 0.5) * chroma + l, (nb - 0.5) * chroma + l);
}

/* ---- Separate / Combine ------------------------------------------------- */

/* kernel/svm/svm.h NODE_SEPARATE_VECTOR (sepcomb_vector.h) for RGB */
void node_separate_rgb(vec3 color, out float r, out float g, out float b)
{
  r = color.x;
  g = color.y;
  b = color.z;
}

/* sepcomb_vector.h: svm_node_combine_vector, for RGB */
void node_combine_rgb(float r, float g, float b, out vec3 color) { color = vec3(r, g, b); }

/* sepcomb_vector.h: svm_node_separate_vector */
void node_separate_xyz(vec3 v, out float x, out float y, out float z)
{
  x = v.x;
  y = v.y;
  z = v.z;
}

/* sepcomb_vector.h: svm_node_combine_vector */
void node_combine_xyz(float x, float y, float z, out vec3 v) { v = vec3(x, y, z); }

/* kernel/svm/sepcomb_hsv.h: svm_node_separate_hsv */
void node_separate_hsv(vec3 color, out float h, out float s, out float v)
{
  vec3 hsv = color_rgb_to_hsv(color);
  h = hsv.x;
  s = hsv.y;
  v = hsv.z;
}

/* kernel/svm/sepcomb_hsv.h: svm_node_combine_hsv */
void node_combine_hsv(float h, float s, float v, out vec3 color)
{
  color = color_hsv_to_rgb(vec3(h, s, v));
}

/* kernel/svm/color_util.h: svm_separate_color (sepcomb_color.h) */
void node_separate_color(int mode, vec3 color, out float red, out float green, out float blue)
{
  vec3 c = color;
  if (mode == NODE_COMBSEP_COLOR_HSV) {
    c = color_rgb_to_hsv(color);
  }
  else if (mode == NODE_COMBSEP_COLOR_HSL) {
    c = color_rgb_to_hsl(color);
  }
  red = c.x;
  green = c.y;
  blue = c.z;
}

/* kernel/svm/color_util.h: svm_combine_color (sepcomb_color.h) */
void node_combine_color(int mode, float red, float green, float blue, out vec3 color)
{
  vec3 c = vec3(red, green, blue);
  if (mode == NODE_COMBSEP_COLOR_HSV) {
    c = color_hsv_to_rgb(c);
  }
  else if (mode == NODE_COMBSEP_COLOR_HSL) {
    c = color_hsl_to_rgb(c);
  }
  color = c;
}

/* ---- RGB to BW ---------------------------------------------------------- */

/* kernel/svm/convert.h NODE_CONVERT_CF: linear_rgb_to_gray = dot(c, rgb_to_y).
 * rgb_to_y is the Y row of inverse(xyz_to_rgb), ShaderManager::
 * init_xyz_transforms (scene/shader.cpp). With Blender 3.4's OCIO config,
 * xyz_to_rgb = (scene_linear -> aces_interchange)^-1 * (Cycles' 6-digit
 * ACES-AP0 -> XYZ-D65 matrix)^-1, giving these weights, as measured in Cycles
 * 3.4.1 (to 3e-8): not quite Rec.709's 0.2126, 0.7152, 0.0722. */
float color_luminance(vec3 c)
{
  return dot(c, vec3(0.2126729950, 0.7151526453, 0.0721754596));
}

void node_rgb_to_bw(vec3 color, out float val) { val = color_luminance(color); }

/* ---- Blackbody ---------------------------------------------------------- */

/* kernel/svm/math_util.h: svm_math_blackbody_color_rec709 with the tables
 * blackbody_table_r/g/b of kernel/tables.h: a piecewise fit, a/t + b*t + c
 * for R and G, a cubic in t for B, on 800..12000 K. */
vec3 blackbody_rec709(float t)
{
  if (t >= 12000.0) {
    return vec3(0.8262954810464208, 0.9945080501520986, 1.566307710274283);
  }
  if (t < 800.0) {
    return vec3(5.413294490189271, -0.20319390035873933, -0.0822535242887164);
  }
  const vec3 table_r[7] = vec3[7](vec3(1.61919106e+03, -2.05010916e-03, 5.02995757e+00),
                                  vec3(2.48845471e+03, -1.11330907e-03, 3.22621544e+00),
                                  vec3(3.34143193e+03, -4.86551192e-04, 1.76486769e+00),
                                  vec3(4.09461742e+03, -1.27446582e-04, 7.25731635e-01),
                                  vec3(4.67028036e+03, 2.91258199e-05, 1.26703442e-01),
                                  vec3(4.59509185e+03, 2.87495649e-05, 1.50345020e-01),
                                  vec3(3.78717450e+03, 9.35907826e-06, 3.99075871e-01));
  const vec3 table_g[7] = vec3[7](vec3(-4.88999748e+02, 6.04330754e-04, -7.55807526e-02),
                                  vec3(-7.55994277e+02, 3.16730098e-04, 4.78306139e-01),
                                  vec3(-1.02363977e+03, 1.20223470e-04, 9.36662319e-01),
                                  vec3(-1.26571316e+03, 4.87340896e-06, 1.27054498e+00),
                                  vec3(-1.42529332e+03, -4.01150431e-05, 1.43972784e+00),
                                  vec3(-1.17554822e+03, -2.16378048e-05, 1.30408023e+00),
                                  vec3(-5.00799571e+02, -4.59832026e-06, 1.09098763e+00));
  const vec4 table_b[7] = vec4[7](
      vec4(5.96945309e-11, -4.85742887e-08, -9.70622247e-05, -4.07936148e-03),
      vec4(2.40430366e-11, 5.55021075e-08, -1.98503712e-04, 2.89312858e-02),
      vec4(-1.40949732e-11, 1.89878968e-07, -3.56632824e-04, 9.10767778e-02),
      vec4(-3.61460868e-11, 2.84822009e-07, -4.93211319e-04, 1.56723440e-01),
      vec4(-1.97075738e-11, 1.75359352e-07, -2.50542825e-04, -2.22783266e-02),
      vec4(-1.61997957e-13, -1.64216008e-08, 3.86216271e-04, -7.38077418e-01),
      vec4(6.72650283e-13, -2.73078809e-08, 4.24098264e-04, -7.52335691e-01));
  int i = (t >= 6365.0) ? 6 :
          (t >= 3315.0) ? 5 :
          (t >= 1902.0) ? 4 :
          (t >= 1449.0) ? 3 :
          (t >= 1167.0) ? 2 :
          (t >= 965.0)  ? 1 :
                          0;
  vec3 r = table_r[i];
  vec3 g = table_g[i];
  vec4 b = table_b[i];
  float t_inv = 1.0 / t;
  return vec3(r.x * t_inv + r.y * t + r.z,
              g.x * t_inv + g.y * t + g.z,
              ((b.x * t + b.y) * t + b.z) * t + b.w);
}

/* kernel/svm/blackbody.h: svm_node_blackbody. rec709_to_rgb is the identity
 * for Blender 3.4's scene linear space (Linear Rec.709); negative components
 * (outside Rec.709) are clamped to 0. */
void node_blackbody(float temperature, out vec3 color)
{
  color = max(blackbody_rec709(temperature), vec3(0.0));
}

/* ---- Wavelength --------------------------------------------------------- */

/* kernel/tables.h: cie_color_match, CIE 1931 XYZ at 380, 385, ... 780 nm */
vec3 wavelength_cie_xyz(int i)
{
  const vec3 cie[81] = vec3[81](
      vec3(0.0014, 0.0000, 0.0065), vec3(0.0022, 0.0001, 0.0105), vec3(0.0042, 0.0001, 0.0201),
      vec3(0.0076, 0.0002, 0.0362), vec3(0.0143, 0.0004, 0.0679), vec3(0.0232, 0.0006, 0.1102),
      vec3(0.0435, 0.0012, 0.2074), vec3(0.0776, 0.0022, 0.3713), vec3(0.1344, 0.0040, 0.6456),
      vec3(0.2148, 0.0073, 1.0391), vec3(0.2839, 0.0116, 1.3856), vec3(0.3285, 0.0168, 1.6230),
      vec3(0.3483, 0.0230, 1.7471), vec3(0.3481, 0.0298, 1.7826), vec3(0.3362, 0.0380, 1.7721),
      vec3(0.3187, 0.0480, 1.7441), vec3(0.2908, 0.0600, 1.6692), vec3(0.2511, 0.0739, 1.5281),
      vec3(0.1954, 0.0910, 1.2876), vec3(0.1421, 0.1126, 1.0419), vec3(0.0956, 0.1390, 0.8130),
      vec3(0.0580, 0.1693, 0.6162), vec3(0.0320, 0.2080, 0.4652), vec3(0.0147, 0.2586, 0.3533),
      vec3(0.0049, 0.3230, 0.2720), vec3(0.0024, 0.4073, 0.2123), vec3(0.0093, 0.5030, 0.1582),
      vec3(0.0291, 0.6082, 0.1117), vec3(0.0633, 0.7100, 0.0782), vec3(0.1096, 0.7932, 0.0573),
      vec3(0.1655, 0.8620, 0.0422), vec3(0.2257, 0.9149, 0.0298), vec3(0.2904, 0.9540, 0.0203),
      vec3(0.3597, 0.9803, 0.0134), vec3(0.4334, 0.9950, 0.0087), vec3(0.5121, 1.0000, 0.0057),
      vec3(0.5945, 0.9950, 0.0039), vec3(0.6784, 0.9786, 0.0027), vec3(0.7621, 0.9520, 0.0021),
      vec3(0.8425, 0.9154, 0.0018), vec3(0.9163, 0.8700, 0.0017), vec3(0.9786, 0.8163, 0.0014),
      vec3(1.0263, 0.7570, 0.0011), vec3(1.0567, 0.6949, 0.0010), vec3(1.0622, 0.6310, 0.0008),
      vec3(1.0456, 0.5668, 0.0006), vec3(1.0026, 0.5030, 0.0003), vec3(0.9384, 0.4412, 0.0002),
      vec3(0.8544, 0.3810, 0.0002), vec3(0.7514, 0.3210, 0.0001), vec3(0.6424, 0.2650, 0.0000),
      vec3(0.5419, 0.2170, 0.0000), vec3(0.4479, 0.1750, 0.0000), vec3(0.3608, 0.1382, 0.0000),
      vec3(0.2835, 0.1070, 0.0000), vec3(0.2187, 0.0816, 0.0000), vec3(0.1649, 0.0610, 0.0000),
      vec3(0.1212, 0.0446, 0.0000), vec3(0.0874, 0.0320, 0.0000), vec3(0.0636, 0.0232, 0.0000),
      vec3(0.0468, 0.0170, 0.0000), vec3(0.0329, 0.0119, 0.0000), vec3(0.0227, 0.0082, 0.0000),
      vec3(0.0158, 0.0057, 0.0000), vec3(0.0114, 0.0041, 0.0000), vec3(0.0081, 0.0029, 0.0000),
      vec3(0.0058, 0.0021, 0.0000), vec3(0.0041, 0.0015, 0.0000), vec3(0.0029, 0.0010, 0.0000),
      vec3(0.0020, 0.0007, 0.0000), vec3(0.0014, 0.0005, 0.0000), vec3(0.0010, 0.0004, 0.0000),
      vec3(0.0007, 0.0002, 0.0000), vec3(0.0005, 0.0002, 0.0000), vec3(0.0003, 0.0001, 0.0000),
      vec3(0.0002, 0.0001, 0.0000), vec3(0.0002, 0.0001, 0.0000), vec3(0.0001, 0.0000, 0.0000),
      vec3(0.0001, 0.0000, 0.0000), vec3(0.0001, 0.0000, 0.0000), vec3(0.0000, 0.0000, 0.0000));
  return cie[i];
}

/* kernel/util/colorspace.h xyz_to_rgb: kernel_data.film.xyz_to_r/g/b from
 * ShaderManager::init_xyz_transforms (see color_luminance), XYZ D65 -> Blender
 * 3.4's scene linear (Rec.709); within 2e-6 of the inverse of its OCIO
 * srgb_to_xyz.spimtx. */
vec3 color_xyz_to_scene_linear(vec3 xyz)
{
  return vec3(dot(vec3(3.2404549780, -1.5371401203, -0.4985321715), xyz),
              dot(vec3(-0.9692662720, 1.8760104222, 0.0415556675), xyz),
              dot(vec3(0.0556431964, -0.2040253449, 1.0572247801), xyz));
}

/* kernel/svm/wavelength.h: svm_node_wavelength. float_to_int truncates, so
 * 375 < lambda < 380 extrapolates the first segment, as in Cycles. */
void node_wavelength(float wavelength, out vec3 color)
{
  float ii = (wavelength - 380.0) * (1.0 / 5.0); /* scaled 0..80 */
  int i = int(ii);
  vec3 xyz = vec3(0.0);
  if (i >= 0 && i < 80) {
    ii -= float(i);
    vec3 c0 = wavelength_cie_xyz(i);
    vec3 c1 = wavelength_cie_xyz(i + 1);
    xyz = c0 + ii * (c1 - c0);
  }
  color = color_xyz_to_scene_linear(xyz);
  color *= 1.0 / 2.52; /* Cycles: empirical scale to make all components <= 1 */
  color = max(color, vec3(0.0));
}
