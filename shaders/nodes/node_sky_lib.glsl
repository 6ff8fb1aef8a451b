/* Sky Texture node, Nishita sky (Blender 3.4's default sky type), as Cycles 3.4.1
 * renders it.
 *
 * Sources (Apache-2.0; Blender 3.4.1 ships the kernel files in
 * scripts/addons/cycles/source/):
 *   kernel/svm/sky.h            svm_node_tex_sky (the 10 floats it reads),
 *                               sky_radiance_nishita (sun disc with limb darkening,
 *                               sky lookup, black-ground fade below the horizon)
 *   kernel/camera/projection.h  direction_to_spherical (theta = acos(z), phi = atan2(x, y))
 *   util/math.h                 precise_angle, safe_sqrtf
 *   kernel/util/color.h         xyz_to_rgb_clamped
 *   kernel/device/cpu/image.h   interp_linear with EXTEND (intern/cycles, 3.x before 3.5):
 *                               the CPU kernel's bilinear lookup, -0.5 texel offset,
 *                               indices clamped to the edge (no horizontal wrap)
 *   scene/shader_nodes.cpp      sky_texture_precompute_nishita / SkyTextureNode::compile
 *                               (what the constants hold), scene/image_sky.cpp (the table)
 *
 * The table and the constants are computed in Python by
 * addon/deferred_render/materials/sky_nishita.py (precompute_texture, node_constants;
 * its radiance() is the numpy reference of this function, checked against Cycles by
 * tests/blender/check_sky_nishita.py):
 *   sky_texture  512 x 128 RGBA32F, texel (x, y) = pixels[y][x] (row 0 = the horizon),
 *                CIE XYZ in .rgb (the XYZ -> RGB conversion is done here, after the
 *                lookup, as Cycles does). Read with texelFetch only: no GL filtering,
 *                no mipmaps.
 *   const_block  19 floats: 0..2 sun pixel_bottom (XYZ), 3..5 pixel_top (XYZ),
 *                6 sun elevation, 7 sun rotation as Cycles stores it (2pi - wrapped
 *                rotation), 8 sun angular diameter (< 0: no sun disc), 9 sun intensity,
 *                10..18 XYZ -> scene linear RGB, rows r, g, b.
 *
 * acos is avoided (inaccurate on some GPUs, ~1e-4 rad on llvmpipe): acos(c) is
 * evaluated as atan(sqrt((1 - c)(1 + c)), c), the same angle for any c in [-1, 1]. */

#define SKY_NISHITA_PI 3.14159265358979323846
#define SKY_NISHITA_PI_2 1.57079632679489661923
#define SKY_NISHITA_2PI 6.28318530717958647692

/* kernel/device/cpu/image.h interp_linear, EXTENSION_EXTEND: frac() of x*size - 0.5
 * (floor and Cycles' truncate-minus-one differ only on negative integers, where
 * every clamped index is 0 either way), indices clamped to [0, size - 1]. */
vec3 sky_nishita_lookup(sampler2D sky_texture, float x, float y)
{
  ivec2 size = textureSize(sky_texture, 0);
  float fx = x * float(size.x) - 0.5;
  float fy = y * float(size.y) - 0.5;
  float flx = floor(fx);
  float fly = floor(fy);
  float tx = fx - flx;
  float ty = fy - fly;
  int ix = int(flx);
  int iy = int(fly);
  int nix = clamp(ix + 1, 0, size.x - 1);
  int niy = clamp(iy + 1, 0, size.y - 1);
  ix = clamp(ix, 0, size.x - 1);
  iy = clamp(iy, 0, size.y - 1);
  vec3 a = texelFetch(sky_texture, ivec2(ix, iy), 0).rgb;
  vec3 b = texelFetch(sky_texture, ivec2(nix, iy), 0).rgb;
  vec3 c = texelFetch(sky_texture, ivec2(ix, niy), 0).rgb;
  vec3 d = texelFetch(sky_texture, ivec2(nix, niy), 0).rgb;
  return (1.0 - ty) * (1.0 - tx) * a + (1.0 - ty) * tx * b + ty * (1.0 - tx) * c + ty * tx * d;
}

/* kernel/svm/sky.h sky_radiance_nishita (Cycles 3.4.1) + svm_node_tex_sky. */
void node_tex_sky_nishita(int const_block, sampler2D sky_texture, vec3 direction, out vec3 color)
{
  vec3 pixel_bottom = vec3(mat_const(const_block + 0), mat_const(const_block + 1),
                           mat_const(const_block + 2));
  vec3 pixel_top = vec3(mat_const(const_block + 3), mat_const(const_block + 4),
                        mat_const(const_block + 5));
  float sun_elevation = mat_const(const_block + 6);
  float sun_rotation = mat_const(const_block + 7);
  float angular_diameter = mat_const(const_block + 8);
  float sun_intensity = mat_const(const_block + 9);
  vec3 xyz_to_r = vec3(mat_const(const_block + 10), mat_const(const_block + 11),
                       mat_const(const_block + 12));
  vec3 xyz_to_g = vec3(mat_const(const_block + 13), mat_const(const_block + 14),
                       mat_const(const_block + 15));
  vec3 xyz_to_b = vec3(mat_const(const_block + 16), mat_const(const_block + 17),
                       mat_const(const_block + 18));
  bool sun_disc = angular_diameter >= 0.0;
#ifdef WORLD_LIGHTING
  /* The disc lights as a sun lamp (constant 19, the add-on's
   * sky_nishita.sun_lamp): the world map baked for light leaves it out. */
  if (mat_const(const_block + 19) > 0.5) {
    sun_disc = false;
  }
#endif
  vec3 dir = direction;

  /* direction_to_spherical: theta = safe_acosf(dir.z), phi = atan2f(dir.x, dir.y). */
  float cz = clamp(dir.z, -1.0, 1.0);
  float theta = atan(sqrt(max((1.0 - cz) * (1.0 + cz), 0.0)), cz);
  float phi = atan(dir.x, dir.y);

  /* Table column: longitude relative to the sun, wrapped once into [0, 1]. */
  float x = (phi + SKY_NISHITA_PI + sun_rotation) / SKY_NISHITA_2PI;
  if (x > 1.0) {
    x -= 1.0;
  }

  vec3 xyz;
  if (dir.z >= 0.0) {
    /* Above the horizon. geographical_to_direction(elevation, rotation + pi/2). */
    float sun_azimuth = sun_rotation + SKY_NISHITA_PI_2;
    vec3 sun_dir = vec3(cos(sun_elevation) * cos(sun_azimuth),
                        cos(sun_elevation) * sin(sun_azimuth),
                        sin(sun_elevation));
    /* precise_angle */
    float sun_dir_angle = 2.0 * atan(length(dir - sun_dir), length(dir + sun_dir));
    float half_angular = angular_diameter * 0.5;
    float dir_elevation = SKY_NISHITA_PI_2 - theta;

    if (sun_disc && sun_dir_angle < half_angular) {
      /* The sun: the two precomputed pixels interpolated along elevation (from the
       * horizon up when the disc is partly below it). Cycles leaves xyz
       * uninitialised when the whole disc is below the horizon (no direction above
       * the horizon can then be inside it): black here. */
      xyz = vec3(0.0);
      if (sun_elevation - half_angular > 0.0) {
        float y = ((dir_elevation - sun_elevation) / angular_diameter) + 0.5;
        xyz = (pixel_bottom + y * (pixel_top - pixel_bottom)) * sun_intensity;
      }
      else if (sun_elevation + half_angular > 0.0) {
        float y = dir_elevation / (sun_elevation + half_angular);
        xyz = (pixel_bottom + y * (pixel_top - pixel_bottom)) * sun_intensity;
      }
      /* Limb darkening, coefficient 0.6. */
      float r = sun_dir_angle / half_angular;
      float limb_darkening = 1.0 - 0.6 * (1.0 - sqrt(max(1.0 - r * r, 0.0)));
      xyz *= limb_darkening;
    }
    else {
      /* The sky: undo the table's quadratic crowding of rows toward the horizon. */
      float y = sqrt(max(dir_elevation / SKY_NISHITA_PI_2, 0.0));
      xyz = sky_nishita_lookup(sky_texture, x, y);
    }
  }
  else {
    /* Below the horizon: the horizon row, faded to black at z = -0.4. */
    if (dir.z < -0.4) {
      xyz = vec3(0.0);
    }
    else {
      float fade = 1.0 + dir.z * 2.5;
      fade = (fade * fade) * fade;
      xyz = sky_nishita_lookup(sky_texture, x, -0.5) * fade;
    }
  }

  /* xyz_to_rgb_clamped */
  color = max(vec3(dot(xyz_to_r, xyz), dot(xyz_to_g, xyz), dot(xyz_to_b, xyz)), vec3(0.0));
}

#undef SKY_NISHITA_PI
#undef SKY_NISHITA_PI_2
#undef SKY_NISHITA_2PI

/* Sky Texture node, Preetham and Hosek/Wilkie skies, as Cycles 3.4.1 renders them.
 *
 * Sources (Apache-2.0; Blender 3.4.1 ships the kernel in scripts/addons/cycles/source/):
 *   kernel/svm/sky.h            svm_node_tex_sky (the 29 floats it reads), sky_angle_between,
 *                               sky_perez_function + sky_radiance_preetham (Preetham,
 *                               Shirley, Smits 1999: xyY with Perez distributions),
 *                               sky_radiance_internal + sky_radiance_hosek (Hosek, Wilkie
 *                               2012: XYZ, times 2pi/683); neither draws a sun disc
 *   kernel/camera/projection.h  direction_to_spherical (theta = safe_acosf(z), phi = atan2f(x, y))
 *   util/color.h                xyY_to_xyz; kernel/util/color.h xyz_to_rgb_clamped
 *   scene/shader_nodes.cpp      sky_texture_precompute_preetham / _hosek (what the constants hold)
 *
 * The constants are computed in Python by addon/deferred_render/materials/sky_hosek_preetham.py
 * (node_constants; its radiance() is the numpy reference of these functions):
 *   const_block  46 floats: 0 sun phi, 1 sun theta, 2..4 radiance x, y, z, 5..13 config x,
 *                14..22 config y, 23..31 config z (svm_node_tex_sky's order), 32/33 sinf/cosf
 *                of the sun theta, 34/35 sinf/cosf of the sun phi, 36 cosf(pi/2 - 0.001),
 *                37..45 XYZ -> scene linear RGB, rows r, g, b.
 *
 * The angles are not formed with acos/sin/cos of the GPU (acos is ~1e-4 rad off on
 * llvmpipe): with c = clamp(dir.z), sin(theta) = sqrt((1 - c)(1 + c)), cos(theta) = c,
 * and sky_angle_between's cos(sun_phi - phi) expands to cos sun_phi cos phi + sin sun_phi
 * sin phi with (sin phi, cos phi) = (x, y) / |(x, y)|. The same cosine of the angle to
 * the sun as Cycles', for any input vector; gamma = acos of it, as atan(sqrt((1 - c)(1 + c)), c)
 * (exact from (1 - c) where c is near 1, the ill-conditioned end). cos(gamma) is that
 * cosine. The zenith angle clamped to the horizon has its cosine precomputed (36). */

struct SkyAngles {
  float gamma;      /* angle to the sun (sky_angle_between) */
  float cos_gamma;  /* its cosine */
  float cos_theta;  /* cosine of the zenith angle clamped to pi/2 - 0.001 */
};

SkyAngles sky_angles(int const_block, vec3 dir)
{
  float sin_sun_theta = mat_const(const_block + 32);
  float cos_sun_theta = mat_const(const_block + 33);
  float sin_sun_phi = mat_const(const_block + 34);
  float cos_sun_phi = mat_const(const_block + 35);
  float cos_theta_clamp = mat_const(const_block + 36);

  float cz = clamp(dir.z, -1.0, 1.0);
  float sin_theta = sqrt(max((1.0 - cz) * (1.0 + cz), 0.0));
  /* atan2f(x, y): (0, 0) -> phi = 0 -> (sin, cos) = (0, 1). */
  float r = length(dir.xy);
  float sin_phi = r > 0.0 ? dir.x / r : 0.0;
  float cos_phi = r > 0.0 ? dir.y / r : 1.0;
  float cospsi = sin_theta * sin_sun_theta * (cos_sun_phi * cos_phi + sin_sun_phi * sin_phi) +
                 cz * cos_sun_theta;
  cospsi = clamp(cospsi, -1.0, 1.0);

  SkyAngles a;
  a.gamma = atan(sqrt(max((1.0 - cospsi) * (1.0 + cospsi), 0.0)), cospsi);
  a.cos_gamma = cospsi;
  /* theta = min(theta, M_PI_2_F - 0.001f): theta >= the clamp <=> cos(theta) <= its cosine. */
  a.cos_theta = max(cz, cos_theta_clamp);
  return a;
}

/* xyz_to_rgb_clamped with the block's matrix. */
vec3 sky_xyz_to_rgb(int const_block, vec3 xyz)
{
  vec3 to_r = vec3(mat_const(const_block + 37), mat_const(const_block + 38), mat_const(const_block + 39));
  vec3 to_g = vec3(mat_const(const_block + 40), mat_const(const_block + 41), mat_const(const_block + 42));
  vec3 to_b = vec3(mat_const(const_block + 43), mat_const(const_block + 44), mat_const(const_block + 45));
  return max(vec3(dot(to_r, xyz), dot(to_g, xyz), dot(to_b, xyz)), vec3(0.0));
}

/* kernel/svm/sky.h sky_perez_function; lam = the block's config at offset `config`. */
float sky_perez(int config, SkyAngles a)
{
  return (1.0 + mat_const(config + 0) * exp(mat_const(config + 1) / a.cos_theta)) *
         (1.0 + mat_const(config + 2) * exp(mat_const(config + 3) * a.gamma) +
          mat_const(config + 4) * a.cos_gamma * a.cos_gamma);
}

/* kernel/svm/sky.h sky_radiance_preetham + svm_node_tex_sky (sky model 0). */
void node_tex_sky_preetham(int const_block, vec3 direction, out vec3 color)
{
  SkyAngles a = sky_angles(const_block, direction);
  /* radiance_x/y/z are the zenith Y, x, y; config_x/y/z their Perez coefficients. */
  float x = mat_const(const_block + 3) * sky_perez(const_block + 14, a);
  float y = mat_const(const_block + 4) * sky_perez(const_block + 23, a);
  float Y = mat_const(const_block + 2) * sky_perez(const_block + 5, a);
  /* util/color.h xyY_to_xyz */
  float X = (y != 0.0) ? (x / y) * Y : 0.0;
  float Z = (y != 0.0 && Y != 0.0) ? (1.0 - x - y) / y * Y : 0.0;
  color = sky_xyz_to_rgb(const_block, vec3(X, Y, Z));
}

/* kernel/svm/sky.h sky_radiance_internal; c = the block's config at offset `config`.
 * powf(b, 1.5f) as b * sqrt(b). */
float sky_hosek_internal(int config, SkyAngles a)
{
  float c8 = mat_const(config + 8);
  float expM = exp(mat_const(config + 4) * a.gamma);
  float rayM = a.cos_gamma * a.cos_gamma;
  float base = 1.0 + c8 * c8 - 2.0 * c8 * a.cos_gamma;
  float mieM = (1.0 + rayM) / (base * sqrt(base));
  float zenith = sqrt(a.cos_theta);
  return (1.0 + mat_const(config + 0) * exp(mat_const(config + 1) / (a.cos_theta + 0.01))) *
         (mat_const(config + 2) + mat_const(config + 3) * expM + mat_const(config + 5) * rayM +
          mat_const(config + 6) * mieM + mat_const(config + 7) * zenith);
}

/* kernel/svm/sky.h sky_radiance_hosek + svm_node_tex_sky (sky model 1). */
void node_tex_sky_hosek(int const_block, vec3 direction, out vec3 color)
{
  SkyAngles a = sky_angles(const_block, direction);
  vec3 xyz = vec3(sky_hosek_internal(const_block + 5, a) * mat_const(const_block + 2),
                  sky_hosek_internal(const_block + 14, a) * mat_const(const_block + 3),
                  sky_hosek_internal(const_block + 23, a) * mat_const(const_block + 4));
  /* M_2PI_F / 683, folded in float */
  color = sky_xyz_to_rgb(const_block, xyz) * 0.009199393;
}
