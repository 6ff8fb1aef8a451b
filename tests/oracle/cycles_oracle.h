// CPU "oracle" for the deferred renderer: what Blender 3.4 Cycles converges to
// for direct lighting from one light on one Principled BSDF (GGX, no
// transmission, no subsurface, no anisotropy), with no occlusion.
//
// Everything is double precision. Formulas follow the Cycles 3.4.1 kernel
// sources (scripts/addons/cycles/source/kernel/ of the Blender 3.4.1 package):
//   svm/closure.h                      (Principled BSDF closure set-up)
//   closure/bsdf_principled_diffuse.h  (Burley diffuse + retro-reflection)
//   closure/bsdf_principled_sheen.h    (sheen)
//   closure/bsdf_microfacet.h          (GGX, GTR1 clearcoat, Fresnel blend)
//   closure/bsdf_util.h                (fresnel_dielectric_cos,
//                                       interpolate_fresnel_color, schlick_fresnel)
//   light/light.h, light/common.h      (light_sample, spot_light_attenuation,
//                                       lamp_light_pdf)
// and scene/light.cpp + blender/light.cpp of Cycles 3.4 (invarea, extents).
// See /work/shared/REFERENCE.md section 2.
#pragma once

#include <deferred/scene.h>

#include <functional>
#include <glm/glm.hpp>

namespace oracle {

// ---------------------------------------------------------------------------
// Principled BSDF (Blender 3.4, distribution GGX)
// ---------------------------------------------------------------------------

// BSDF x cos(theta_l) of each lobe, including its closure weight:
//   diffuse   = base*(1-metallic) * Burley(...)            (bsdf_principled_diffuse.h)
//   sheen     = sheen*(1-metallic)*mix(1, base/lum709, sheen_tint) * (1-L.H)^5 cos_l
//   specular  = F(cspec0, eta) * D_GGX * G / (4 cos_v)      (bsdf_microfacet.h)
//   clearcoat = Fdielectric(L.H,1.5)*0.25*clearcoat * D_GTR1 * G(alpha=0.25) / (4 cos_v)
// N, V (towards the viewer) and L (towards the light) are normalised inside.
// The geometric normal is taken equal to N.
struct Lobes {
    glm::dvec3 diffuse{0.0}, sheen{0.0}, specular{0.0}, clearcoat{0.0};
};

// The G-buffer's closure model for `m` (base target alpha, gbuffer_lib.glsl),
// for the GPU unit tests that fill G-buffer parameters directly.
inline float gbuffer_closure_model(const deferred::Material& m) {
    if (m.glossy_model > 0) return 1.0f + float(m.glossy_model);
    return m.diffuse_roughness < 0.0f ? -1.0f : m.diffuse_roughness;
}

Lobes eval_principled(const deferred::Material& m, glm::dvec3 N, glm::dvec3 V, glm::dvec3 L);

// Directional albedo of each lobe: the integral of eval_principled over the
// hemisphere of N (what a constant white world gives an unoccluded point),
// by the midpoint rule in (cos theta, phi) with n x 4n cells; good for the
// smooth lobes (diffuse, sheen, rough specular), not for sharp highlights.
Lobes hemisphere_albedo(const deferred::Material& m, glm::dvec3 N, glm::dvec3 V, int n = 256);

// Pass colours (Cycles' shader_bsdf_diffuse / shader_bsdf_glossy: the sum of
// the closure weights). DiffCol = base*(1-m) [+ sheen weight]; GlossCol = 1
// for the specular closure [+ 1 for clearcoat]. A closure Cycles does not
// allocate (svm/closure.h cut-offs, CLOSURE_WEIGHT_CUTOFF = 1e-5) adds nothing:
// notably there is no specular closure when specular <= 1e-5 and
// metallic <= 1e-5, so GlossCol is 0 then.
glm::dvec3 diffuse_color(const deferred::Material& m);
glm::dvec3 glossy_color(const deferred::Material& m);

// Building blocks, exposed for tests.
double schlick_fresnel(double u);                   // bsdf_util.h: clamp(1-u,0,1)^5
double fresnel_dielectric_cos(double cosi, double eta);  // bsdf_util.h
double specular_ior(const deferred::Material& m);   // 2/(1-sqrt(0.08 specular)) - 1
glm::dvec3 specular_cspec0(const deferred::Material& m);  // saturated, as in ggx_fresnel_setup
double ggx_D(double cos_h, double alpha);           // GTR2, alpha = roughness^2
double gtr1_D(double cos_h, double alpha);          // bsdf_microfacet.h D_GTR1
double smith_G1(double cos_theta, double alpha2);   // 2/(1+sqrt(1+alpha2 tan^2))

// ---------------------------------------------------------------------------
// Lights
// ---------------------------------------------------------------------------

// World-space light frame derived from `Light::matrix` (Cycles 3.4
// blender/light.cpp: co = column 3, dir = -column 2; area axes = columns 0/1
// times size/size_y).
struct LightFrame {
    glm::dvec3 position{0.0};   // translation column
    glm::dvec3 direction{0.0};  // normalised -Z column: spot axis / sun travel / area emission
    glm::dvec3 half_u{0.0};     // area: 0.5*size*column0
    glm::dvec3 half_v{0.0};     // area: 0.5*(size_y or size)*column1
    double area = 0.0;          // area lights: 4|a||b| (rect) or pi|a||b| (round), as Cycles' invarea
    bool round = false;         // area DISK/ELLIPSE
};
LightFrame light_frame(const deferred::Light& light);

// Cycles 3.4 spot_light_attenuation (light/common.h) for the unit direction
// from the emitting point towards the shaded point. Includes the leading
// cos factor that 3.4 has (removed in 3.5). Returns 1 for non-spot lights.
double spot_attenuation(const deferred::Light& light, glm::dvec3 dir_light_to_point);

// Calls fn(omega, weight) for quadrature nodes over the light such that
//   sum weight * g(omega)  ->  (1/colour) * integral L_e(omega) g(omega) d omega
// i.e. weight already carries energy, the spot attenuation, cos_light/t^2 and
// the quadrature weight, but not the light colour. omega is the unit
// direction from P towards the node. Delta lights (point/spot of radius 0,
// sun) give exactly one node; a sun is treated as a delta direction (its
// `angle` is ignored). Area lights: composite 4-point Gauss-Legendre,
// `resolution` nodes per axis (rectangles), or a polar grid with Gauss-Legendre
// in r and `resolution` uniform angles (ellipses, and the disk that Cycles 3.4
// samples for a point/spot light with radius > 0: it faces P, radiance
// energy/(4 pi * pi R^2), spot attenuation evaluated per node for the
// direction node -> P exactly as light_sample() does).
void for_each_light_sample(const deferred::Light& light, glm::dvec3 P, int resolution,
                           const std::function<void(const glm::dvec3& omega, double weight)>& fn);

// Converged direct lighting at P: diffuse = diffuse+sheen lobes, glossy =
// specular+clearcoat lobes (radiance, W/(m^2 sr), not divided by the pass
// colour), colour included.
struct Shade {
    glm::dvec3 diffuse{0.0}, glossy{0.0};
};
Shade shade(const deferred::Light& light, const deferred::Material& m, glm::dvec3 P, glm::dvec3 N,
            glm::dvec3 V, int resolution = 512);

// Irradiance E = integral L_e(omega) max(N.omega, 0) d omega (not divided by
// pi) for a white light (multiply by the colour for RGB). Closed form where one
// exists: delta lights exactly; rectangles by the polygon form factor after
// Sutherland-Hodgman clipping to N.x >= 0; disks/ellipses (also the disk of a
// point light with radius > 0) by the contour integral 1/2 closed-int r x dr/|r|^2
// (adaptive Gauss-Kronrod on the arc above the horizon + the chord in the
// tangent plane). A spot light with radius > 0 has no closed form in 3.4
// (attenuation varies over the disk): it falls back to
// irradiance_numeric(..., 1024).
double irradiance(const deferred::Light& light, glm::dvec3 P, glm::dvec3 N);

// The same integral by the quadrature of for_each_light_sample (the path
// shade() uses).
double irradiance_numeric(const deferred::Light& light, glm::dvec3 P, glm::dvec3 N,
                          int resolution = 512);

}  // namespace oracle
