/* Colour nodes: Mix (3.4 ShaderNodeMix: float, vector, colour), MixRGB,
 * Invert, Hue/Saturation/Value, Gamma, Bright/Contrast, ColorRamp, RGB Curves,
 * Vector Curves, Float Curve.
 *
 * Every function reproduces Cycles 3.4 (SVM kernel, intern/cycles/kernel/svm/);
 * the Cycles function is named above each one. Enum ints are passed by the
 * node specs in addon/deferred_render/materials/nodes/color.py and must stay
 * equal to the #defines below.
 *
 * Uses math_min/math_max/math_saturate and the colour-space conversions of
 * node_converter_lib.glsl (declared here so the include order does not
 * matter). */

float math_min(float a, float b);
float math_max(float a, float b);
float math_saturate(float a);
float math_fract(float a);
float math_fmod(float a, float b);
vec3 color_rgb_to_hsv(vec3 rgb);
vec3 color_hsv_to_rgb(vec3 hsv);

/* ---- enums (color.py BLEND_TYPES: Blender's MA_RAMP_* values, which are
 * Cycles' NodeMix values) ----------------------------------------------- */
#define NODE_MIX_BLEND 0
#define NODE_MIX_ADD 1
#define NODE_MIX_MUL 2
#define NODE_MIX_SUB 3
#define NODE_MIX_SCREEN 4
#define NODE_MIX_DIV 5
#define NODE_MIX_DIFF 6
#define NODE_MIX_DARK 7
#define NODE_MIX_LIGHT 8
#define NODE_MIX_OVERLAY 9
#define NODE_MIX_DODGE 10
#define NODE_MIX_BURN 11
#define NODE_MIX_HUE 12
#define NODE_MIX_SAT 13
#define NODE_MIX_VAL 14
#define NODE_MIX_COL 15
#define NODE_MIX_SOFT 16
#define NODE_MIX_LINEAR 17

/* Baked ramp / curve tables: RAMP_TABLE_SIZE of scene/shader_nodes.h; the
 * node specs bake exactly this many entries (color.py RAMP_TABLE_SIZE). */
#define COLOR_RAMP_TABLE_SIZE 256

vec3 color_saturate(vec3 c) { return vec3(math_saturate(c.x), math_saturate(c.y), math_saturate(c.z)); }

/* util/math.h: interp(a, b, t) = a + t * (b - a) */
vec3 color_interp(vec3 a, vec3 b, float t) { return a + t * (b - a); }

/* ---- blend modes (kernel/svm/color_util.h, 3.4) ------------------------- */

/* color_util.h: svm_mix_screen */
vec3 mix_blend_screen(float t, vec3 col1, vec3 col2)
{
  float tm = 1.0 - t;
  return vec3(1.0) - (vec3(tm) + t * (vec3(1.0) - col2)) * (vec3(1.0) - col1);
}

/* color_util.h: svm_mix_overlay, one channel */
float mix_overlay_channel(float t, float c1, float c2)
{
  float tm = 1.0 - t;
  if (c1 < 0.5) {
    return c1 * (tm + 2.0 * t * c2);
  }
  return 1.0 - (tm + 2.0 * t * (1.0 - c2)) * (1.0 - c1);
}

vec3 mix_blend_overlay(float t, vec3 col1, vec3 col2)
{
  return vec3(mix_overlay_channel(t, col1.x, col2.x), mix_overlay_channel(t, col1.y, col2.y),
              mix_overlay_channel(t, col1.z, col2.z));
}

/* color_util.h: svm_mix_div, one channel (a zero divisor keeps col1) */
float mix_div_channel(float t, float c1, float c2)
{
  return (c2 != 0.0) ? (1.0 - t) * c1 + t * c1 / c2 : c1;
}

vec3 mix_blend_div(float t, vec3 col1, vec3 col2)
{
  return vec3(mix_div_channel(t, col1.x, col2.x), mix_div_channel(t, col1.y, col2.y),
              mix_div_channel(t, col1.z, col2.z));
}

/* color_util.h: svm_mix_dodge, one channel */
float mix_dodge_channel(float t, float c1, float c2)
{
  if (c1 == 0.0) {
    return c1;
  }
  float tmp = 1.0 - t * c2;
  if (tmp <= 0.0) {
    return 1.0;
  }
  tmp = c1 / tmp;
  return (tmp > 1.0) ? 1.0 : tmp;
}

vec3 mix_blend_dodge(float t, vec3 col1, vec3 col2)
{
  return vec3(mix_dodge_channel(t, col1.x, col2.x), mix_dodge_channel(t, col1.y, col2.y),
              mix_dodge_channel(t, col1.z, col2.z));
}

/* color_util.h: svm_mix_burn, one channel */
float mix_burn_channel(float t, float c1, float c2)
{
  float tmp = (1.0 - t) + t * c2;
  if (tmp <= 0.0) {
    return 0.0;
  }
  tmp = 1.0 - (1.0 - c1) / tmp;
  if (tmp < 0.0) {
    return 0.0;
  }
  return (tmp > 1.0) ? 1.0 : tmp;
}

vec3 mix_blend_burn(float t, vec3 col1, vec3 col2)
{
  return vec3(mix_burn_channel(t, col1.x, col2.x), mix_burn_channel(t, col1.y, col2.y),
              mix_burn_channel(t, col1.z, col2.z));
}

/* color_util.h: svm_mix_hue */
vec3 mix_blend_hue(float t, vec3 col1, vec3 col2)
{
  vec3 hsv2 = color_rgb_to_hsv(col2);
  if (hsv2.y == 0.0) {
    return col1;
  }
  vec3 hsv = color_rgb_to_hsv(col1);
  hsv.x = hsv2.x;
  return color_interp(col1, color_hsv_to_rgb(hsv), t);
}

/* color_util.h: svm_mix_sat */
vec3 mix_blend_sat(float t, vec3 col1, vec3 col2)
{
  vec3 hsv = color_rgb_to_hsv(col1);
  if (hsv.y == 0.0) {
    return col1;
  }
  vec3 hsv2 = color_rgb_to_hsv(col2);
  hsv.y = (1.0 - t) * hsv.y + t * hsv2.y;
  return color_hsv_to_rgb(hsv);
}

/* color_util.h: svm_mix_val */
vec3 mix_blend_val(float t, vec3 col1, vec3 col2)
{
  vec3 hsv = color_rgb_to_hsv(col1);
  vec3 hsv2 = color_rgb_to_hsv(col2);
  hsv.z = (1.0 - t) * hsv.z + t * hsv2.z;
  return color_hsv_to_rgb(hsv);
}

/* color_util.h: svm_mix_color */
vec3 mix_blend_color(float t, vec3 col1, vec3 col2)
{
  vec3 hsv2 = color_rgb_to_hsv(col2);
  if (hsv2.y == 0.0) {
    return col1;
  }
  vec3 hsv = color_rgb_to_hsv(col1);
  hsv.x = hsv2.x;
  hsv.y = hsv2.y;
  return color_interp(col1, color_hsv_to_rgb(hsv), t);
}

/* color_util.h: svm_mix_soft */
vec3 mix_blend_soft(float t, vec3 col1, vec3 col2)
{
  vec3 one = vec3(1.0);
  vec3 scr = one - (one - col2) * (one - col1);
  return (1.0 - t) * col1 + t * ((one - col1) * col2 * col1 + col1 * scr);
}

/* color_util.h: svm_mix_linear */
vec3 mix_blend_linear(float t, vec3 col1, vec3 col2)
{
  return col1 + t * (2.0 * col2 + vec3(-1.0));
}

/* color_util.h: svm_mix (3.4: the factor is not clamped here) */
vec3 mix_blend(int blend_type, float t, vec3 c1, vec3 c2)
{
  switch (blend_type) {
    case NODE_MIX_BLEND: return color_interp(c1, c2, t);
    case NODE_MIX_ADD: return color_interp(c1, c1 + c2, t);
    case NODE_MIX_MUL: return color_interp(c1, c1 * c2, t);
    case NODE_MIX_SUB: return color_interp(c1, c1 - c2, t);
    case NODE_MIX_SCREEN: return mix_blend_screen(t, c1, c2);
    case NODE_MIX_DIV: return mix_blend_div(t, c1, c2);
    case NODE_MIX_DIFF: return color_interp(c1, abs(c1 - c2), t);
    case NODE_MIX_DARK:
      return color_interp(c1, vec3(math_min(c1.x, c2.x), math_min(c1.y, c2.y), math_min(c1.z, c2.z)), t);
    case NODE_MIX_LIGHT:
      return color_interp(c1, vec3(math_max(c1.x, c2.x), math_max(c1.y, c2.y), math_max(c1.z, c2.z)), t);
    case NODE_MIX_OVERLAY: return mix_blend_overlay(t, c1, c2);
    case NODE_MIX_DODGE: return mix_blend_dodge(t, c1, c2);
    case NODE_MIX_BURN: return mix_blend_burn(t, c1, c2);
    case NODE_MIX_HUE: return mix_blend_hue(t, c1, c2);
    case NODE_MIX_SAT: return mix_blend_sat(t, c1, c2);
    case NODE_MIX_VAL: return mix_blend_val(t, c1, c2);
    case NODE_MIX_COL: return mix_blend_color(t, c1, c2);
    case NODE_MIX_SOFT: return mix_blend_soft(t, c1, c2);
    case NODE_MIX_LINEAR: return mix_blend_linear(t, c1, c2);
  }
  return vec3(0.0);
}

/* ---- Mix (ShaderNodeMix, 3.4) ------------------------------------------- */

/* kernel/svm/mix.h: svm_node_mix_float */
void node_mix_float(int clamp_factor, float fac, float a, float b, out float result)
{
  float t = (clamp_factor != 0) ? math_saturate(fac) : fac;
  result = a * (1.0 - t) + b * t;
}

/* kernel/svm/mix.h: svm_node_mix_vector */
void node_mix_vector(int clamp_factor, float fac, vec3 a, vec3 b, out vec3 result)
{
  float t = (clamp_factor != 0) ? math_saturate(fac) : fac;
  result = a * (vec3(1.0) - t) + b * t;
}

/* kernel/svm/mix.h: svm_node_mix_vector_non_uniform */
void node_mix_vector_non_uniform(int clamp_factor, vec3 fac, vec3 a, vec3 b, out vec3 result)
{
  vec3 t = (clamp_factor != 0) ? color_saturate(fac) : fac;
  result = a * (vec3(1.0) - t) + b * t;
}

/* kernel/svm/mix.h: svm_node_mix_color */
void node_mix_color(int blend_type, int clamp_factor, int clamp_result, float fac, vec3 a, vec3 b,
                    out vec3 result)
{
  float t = (clamp_factor != 0) ? math_saturate(fac) : fac;
  result = mix_blend(blend_type, t, a, b);
  if (clamp_result != 0) {
    result = color_saturate(result);
  }
}

/* ---- MixRGB (legacy ShaderNodeMixRGB) ----------------------------------- */

/* kernel/svm/mix.h: svm_node_mix = svm_mix_clamped_factor (the factor is
 * always clamped); use_clamp is MixNode::compile's NODE_MIX_CLAMP pass. */
void node_mix_rgb(int blend_type, int use_clamp, float fac, vec3 color1, vec3 color2,
                  out vec3 color)
{
  color = mix_blend(blend_type, math_saturate(fac), color1, color2);
  if (use_clamp != 0) {
    color = color_saturate(color);
  }
}

/* ---- simple colour adjustments ------------------------------------------ */

/* kernel/svm/invert.h: invert, per channel */
float color_invert_channel(float color, float factor)
{
  return factor * (1.0 - color) + (1.0 - factor) * color;
}

/* kernel/svm/invert.h: svm_node_invert */
void node_invert(float fac, vec3 color, out vec3 result)
{
  result = vec3(color_invert_channel(color.x, fac), color_invert_channel(color.y, fac),
                color_invert_channel(color.z, fac));
}

/* kernel/svm/hsv.h: svm_node_hsv. Cycles 3.4 wraps the hue with fmodf, not
 * fractf: a negative sum stays negative, and hsv_to_rgb then takes its
 * last branch (measured in Cycles 3.4.1; later versions use fractf). */
void node_hue_saturation(float hue, float saturation, float value, float fac, vec3 color,
                         out vec3 result)
{
  vec3 hsv = color_rgb_to_hsv(color);
  hsv.x = math_fmod(hsv.x + hue + 0.5, 1.0);
  hsv.y = math_saturate(hsv.y * saturation);
  hsv.z *= value;
  vec3 rgb = color_hsv_to_rgb(hsv);
  rgb = fac * rgb + (1.0 - fac) * color;
  /* Clamp color to prevent negative values caused by over saturation. */
  result = vec3(math_max(rgb.x, 0.0), math_max(rgb.y, 0.0), math_max(rgb.z, 0.0));
}

/* kernel/svm/math_util.h: svm_math_gamma_color (svm_node_gamma) */
void node_gamma(vec3 color, float gamma, out vec3 result)
{
  if (gamma == 0.0) {
    result = vec3(1.0);
    return;
  }
  result = color;
  if (color.x > 0.0) {
    result.x = pow(color.x, gamma);
  }
  if (color.y > 0.0) {
    result.y = pow(color.y, gamma);
  }
  if (color.z > 0.0) {
    result.z = pow(color.z, gamma);
  }
}

/* kernel/svm/color_util.h: svm_brightness_contrast (svm_node_brightness) */
void node_bright_contrast(vec3 color, float bright, float contrast, out vec3 result)
{
  float a = 1.0 + contrast;
  float b = bright - contrast * 0.5;
  result = vec3(math_max(a * color.x + b, 0.0), math_max(a * color.y + b, 0.0),
                math_max(a * color.z + b, 0.0));
}

/* ---- baked tables: ColorRamp and curves --------------------------------- */

/* One channel of a table entry: entry i of a block of `stride` floats per
 * entry starting at `table`. */
float ramp_table_value(int table, int stride, int channel, int i)
{
  return mat_const(table + i * stride + channel);
}

/* kernel/svm/ramp.h: rgb_ramp_lookup / float_ramp_lookup, one channel
 * (the kernel does the same arithmetic on all four channels at once). */
float ramp_table_lookup(int table, int stride, int channel, float f, bool interpolate,
                        bool extrapolate)
{
  const int n = COLOR_RAMP_TABLE_SIZE;
  if ((f < 0.0 || f > 1.0) && extrapolate) {
    float t0;
    float dy;
    if (f < 0.0) {
      t0 = ramp_table_value(table, stride, channel, 0);
      dy = t0 - ramp_table_value(table, stride, channel, 1);
      f = -f;
    }
    else {
      t0 = ramp_table_value(table, stride, channel, n - 1);
      dy = t0 - ramp_table_value(table, stride, channel, n - 2);
      f = f - 1.0;
    }
    return t0 + dy * f * float(n - 1);
  }
  f = math_saturate(f) * float(n - 1);
  /* clamp int as well in case of NaN */
  int i = clamp(int(f), 0, n - 1);
  float t = f - float(i);
  float a = ramp_table_value(table, stride, channel, i);
  if (interpolate && t > 0.0) {
    a = (1.0 - t) * a + t * ramp_table_value(table, stride, channel, i + 1);
  }
  return a;
}

/* kernel/svm/ramp.h: svm_node_rgb_ramp. `table` is COLOR_RAMP_TABLE_SIZE
 * entries of (r, g, b, a): ColorRamp.evaluate(i / 255), as Cycles'
 * colorramp_to_array bakes it; interpolate is 0 for CONSTANT. */
void node_color_ramp(int interpolate, int table, float fac, out vec3 color, out float alpha)
{
  bool interp = interpolate != 0;
  color = vec3(ramp_table_lookup(table, 4, 0, fac, interp, false),
               ramp_table_lookup(table, 4, 1, fac, interp, false),
               ramp_table_lookup(table, 4, 2, fac, interp, false));
  alpha = ramp_table_lookup(table, 4, 3, fac, interp, false);
}

/* kernel/svm/ramp.h: svm_node_curves. `table` is COLOR_RAMP_TABLE_SIZE
 * entries of (r, g, b) sampled on [min_x, max_x] (Cycles'
 * curvemapping_color_to_array). */
vec3 curves_apply(int extrapolate, int table, float min_x, float max_x, float fac, vec3 color)
{
  float range_x = max_x - min_x;
  vec3 relpos = (color - vec3(min_x)) / range_x;
  bool extrap = extrapolate != 0;
  vec3 mapped = vec3(ramp_table_lookup(table, 3, 0, relpos.x, true, extrap),
                     ramp_table_lookup(table, 3, 1, relpos.y, true, extrap),
                     ramp_table_lookup(table, 3, 2, relpos.z, true, extrap));
  return (1.0 - fac) * color + fac * mapped;
}

/* RGBCurvesNode: svm_node_curves on a colour */
void node_rgb_curves(int extrapolate, int table, float min_x, float max_x, float fac, vec3 color,
                     out vec3 result)
{
  result = curves_apply(extrapolate, table, min_x, max_x, fac, color);
}

/* VectorCurvesNode: svm_node_curves on a vector */
void node_vector_curves(int extrapolate, int table, float min_x, float max_x, float fac,
                        vec3 vector, out vec3 result)
{
  result = curves_apply(extrapolate, table, min_x, max_x, fac, vector);
}

/* kernel/svm/ramp.h: svm_node_curve (Float Curve), a table of
 * COLOR_RAMP_TABLE_SIZE floats sampled on [min_x, max_x]. */
void node_float_curve(int extrapolate, int table, float min_x, float max_x, float fac,
                      float value, out float result)
{
  float range = max_x - min_x;
  float relpos = (value - min_x) / range;
  float v = ramp_table_lookup(table, 1, 0, relpos, true, extrapolate != 0);
  result = (1.0 - fac) * value + fac * v;
}
