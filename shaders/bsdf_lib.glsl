/* Blender 3.4 Principled BSDF as Cycles evaluates it for light sampling
 * (intern/cycles/kernel/closure: bsdf_principled_diffuse.h,
 * bsdf_principled_sheen.h, bsdf_microfacet.h; svm_closure.h for the weights).
 * Every function returns BSDF x cos(theta_l) for unit incident radiance, the
 * quantity Cycles' bsdf_eval returns. Formulas: shared/REFERENCE.md section 2.
 * The CPU oracle (tests/oracle) implements the same in double. */

#include "gbuffer_lib.glsl"

#define M_PI_F 3.14159265358979
#define M_1_PI_F 0.318309886183791

/* Closures whose weight is below this are never allocated (CLOSURE_WEIGHT_CUTOFF). */
#define CLOSURE_WEIGHT_CUTOFF 1e-5

/* Specular tint: Cycles' luminance approximation (svm_closure.h, "luminance approx."). */
vec3 principled_tint(vec3 base) {
    float lum = 0.3 * base.r + 0.6 * base.g + 0.1 * base.b;
    return lum > 0.0 ? base / lum : vec3(1.0);
}

/* Sheen tint: linear_rgb_to_gray, the Rec.709 luminance of Blender's OCIO config. */
vec3 principled_sheen_tint(vec3 base) {
    float lum = dot(base, vec3(0.2126729, 0.7151522, 0.0721750));
    return lum > 0.0 ? base / lum : vec3(1.0);
}

float schlick_fresnel(float u) {
    float m = clamp(1.0 - u, 0.0, 1.0);
    float m2 = m * m;
    return m2 * m2 * m;
}

/* Exact dielectric Fresnel (Cycles fresnel_dielectric_cos). g is
 * (eta^2 - 1) + c^2 in that order, `precise`: a compiler free to reassociate
 * may form (eta^2 + c^2) - 1, which at eta = 1 (Specular 0: F0 = 0) rounds
 * c^2 < 6e-8 away, takes g <= 0 for total reflection and returns 1 instead of
 * 0 (NVIDIA 580 did: a metallic surface's glossy light at N.V = N.L = 1e-4 was
 * 0.008 where Cycles' is 0; BsdfExtremes.GrazingAnglesAreFiniteAndBounded). */
float fresnel_dielectric_cos(float cosi, float eta) {
    float c = abs(cosi);
    precise float g = (eta * eta - 1.0) + c * c;
    if (g > 0.0) {
        g = sqrt(g);
        float A = (g - c) / (g + c);
        float B = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
        return 0.5 * A * A * (1.0 + B * B);
    }
    return 1.0;
}

/* GGX's D = alpha^2 / (pi cos^4 (alpha^2 + tan^2)^2) (Cycles'
 * bsdf_microfacet_ggx_eval_reflect), written as alpha^2 / (pi (alpha^2 cos^2
 * + sin^2)^2): the same value, but cos^4 alone underflows below cos ~ 1e-10,
 * which a GPU that flushes denormals to zero turned into 0 and D into inf
 * (NVIDIA: BsdfExtremes.GrazingAnglesAreFiniteAndBounded at N.V = N.L = 1e-10). */
float ggx_D(float alpha2, float cos2, float sin2) {
    float t = alpha2 * cos2 + sin2;
    return alpha2 / (M_PI_F * t * t);
}

/* Smith G1 for GGX, separable form used by Cycles 3.4. sin^2 comes from a
 * cross product: 1 - cos^2 cancels catastrophically in float near cos = 1. */
float ggx_G1(float alpha2, vec3 N, vec3 D) {
    float c = dot(N, D);
    vec3 nxd = cross(N, D);
    return 2.0 / (1.0 + sqrt(1.0 + alpha2 * dot(nxd, nxd) / (c * c)));
}

/* Closure weights of one surface (svm_closure.h, NODE_CLOSURE_BSDF principled). */
struct PrincipledWeights {
    vec3 diffuse;      /* base * (1 - metallic): the diffuse closure colour */
    vec3 sheen;        /* sheen * (1 - metallic) * mix(1, tint, sheen_tint) */
    vec3 cspec0;       /* specular colour at normal incidence */
    float specular;    /* 1 if the specular closure exists, else 0 */
    float spec_eta;    /* IOR giving F0 = 0.08 * specular */
    float spec_F0;
    float alpha2;      /* GGX alpha^2, alpha = roughness^2 */
    float clearcoat;   /* clearcoat weight (0.25 factor applied in eval) */
    int glossy_model;  /* 0: Principled specular (Fresnel); 1: Glossy BSDF GGX, 2: Beckmann (weight cspec0) */
    float cc_alpha;    /* GTR1 alpha = clearcoat_roughness^2 */
};

PrincipledWeights principled_weights(SurfaceParams s) {
    PrincipledWeights w;
    float m = clamp(s.metallic, 0.0, 1.0);
    float wd = 1.0 - m; /* no transmission here: the add-on folds it into the set (principled_fold_transmission) */
    bool diffuse = abs(s.base_color.r + s.base_color.g + s.base_color.b) / 3.0 > CLOSURE_WEIGHT_CUTOFF &&
                   wd > CLOSURE_WEIGHT_CUTOFF;
    w.diffuse = diffuse ? s.base_color * wd : vec3(0.0);
    w.sheen = wd > CLOSURE_WEIGHT_CUTOFF && s.sheen > CLOSURE_WEIGHT_CUTOFF
                  ? s.sheen * wd * mix(vec3(1.0), principled_sheen_tint(s.base_color), s.sheen_tint)
                  : vec3(0.0);
    float spec = max(s.specular, 0.0);
    w.specular = (s.specular > CLOSURE_WEIGHT_CUTOFF || s.metallic > CLOSURE_WEIGHT_CUTOFF) ? 1.0 : 0.0;
    /* bsdf_microfacet_ggx_fresnel_setup saturates cspec0. */
    w.cspec0 = clamp(spec * 0.08 * mix(vec3(1.0), principled_tint(s.base_color), s.specular_tint) * (1.0 - m) +
                         s.base_color * m, 0.0, 1.0);
    w.glossy_model = s.glossy_model;
    /* A Glossy BSDF's closure weight: its colour; a Diffuse + grey Glossy
     * mix (metallic 0, node_shader_lib.glsl merge_diffuse_glossy) keeps the
     * diffuse colour in base and the glossy weight in specular_tint. */
    if (s.glossy_model != 0) w.cspec0 = s.metallic < 0.5 ? vec3(max(s.specular_tint, 0.0)) : max(s.base_color, vec3(0.0));
    w.spec_eta = 2.0 / (1.0 - sqrt(0.08 * spec)) - 1.0;
    w.spec_F0 = fresnel_dielectric_cos(1.0, w.spec_eta);
    float alpha = clamp(s.roughness * s.roughness, 0.0, 1.0);
    w.alpha2 = alpha * alpha;
    w.clearcoat = s.clearcoat > CLOSURE_WEIGHT_CUTOFF ? s.clearcoat : 0.0;
    float cca = clamp(s.clearcoat_roughness * s.clearcoat_roughness, 0.0, 1.0);
    w.cc_alpha = cca;
    return w;
}

/* Diffuse closure colour and glossy closure weight, for DiffCol/GlossCol. */
vec3 principled_diffuse_color(PrincipledWeights w) { return w.diffuse + w.sheen; }
vec3 principled_glossy_color(PrincipledWeights w) {
    /* A Glossy BSDF's closure weight is its colour; the Principled BSDF's
     * specular closure has weight 1 (its Fresnel is in the eval). */
    vec3 spec = w.glossy_model != 0 ? w.cspec0 * w.specular : vec3(w.specular);
    return spec + vec3(w.clearcoat > 0.0 ? 1.0 : 0.0);
}

/* Burley diffuse with retro-reflection, without the colour: the factor B
 * such that f cos = base wd / pi * B * cos_l (bsdf_principled_diffuse.h). */
float principled_diffuse_factor(float NdotL, float NdotV, float LdotV, float roughness) {
    if (NdotL <= 0.0) return 0.0;
    float FL = schlick_fresnel(NdotL), FV = schlick_fresnel(NdotV);
    float RR = roughness * (1.0 + LdotV); /* 2 roughness cos^2(theta_d) */
    float f = (1.0 - 0.5 * FL) * (1.0 - 0.5 * FV) + RR * (FL + FV + FL * FV * (RR - 1.0));
    return f * M_1_PI_F * NdotL;
}

/* Diffuse BSDF without the colour: Oren-Nayar in Fujii's form, f cos =
 * nl (A + B t), t = L.V - nl nv, divided by max(nl, nv) where positive,
 * A = 1 / (pi + (pi/2 - 2/3) sigma), B = sigma A (bsdf_oren_nayar.h,
 * Cycles 3.4). sigma = 0 is Lambert, cos / pi. */
float oren_nayar_factor(float NdotL, float NdotV, float LdotV, float sigma) {
    if (NdotL <= 0.0) return 0.0;
    float nl = NdotL, nv = max(NdotV, 0.0);
    float t = LdotV - nl * nv;
    if (t > 0.0) t /= max(nl, nv) + 1.175494e-38;
    sigma = clamp(sigma, 0.0, 1.0);
    float A = 1.0 / (M_PI_F + ((3.0 * M_PI_F - 4.0) / 6.0) * sigma);
    return nl * (A + sigma * A * t);
}

/* Its directional albedo, in closed form: A pi + B E(mu_v) with, for the
 * azimuth-integrated t (the positive half divided by max(mu, mu_v)),
 * E = 2 s_v [ (1 - s_v^3) / (3 mu_v) + pi/4 - (mu_v s_v + asin mu_v) / 2 - 1/3 ],
 * s_v = sqrt(1 - mu_v^2) (checked against quadrature in the native tests). */
float oren_nayar_albedo(float mu_v, float sigma) {
    mu_v = clamp(mu_v, 0.0, 1.0);
    sigma = clamp(sigma, 0.0, 1.0);
    float A = 1.0 / (M_PI_F + ((3.0 * M_PI_F - 4.0) / 6.0) * sigma);
    float s_v = sqrt(max(1.0 - mu_v * mu_v, 0.0));
    float near = mu_v < 1e-3 ? 0.5 * mu_v : (1.0 - s_v * s_v * s_v) / (3.0 * mu_v);
    float E = 2.0 * s_v * (near + 0.25 * M_PI_F - 0.5 * (mu_v * s_v + asin(mu_v)) - 1.0 / 3.0);
    return A * M_PI_F + sigma * A * E;
}

/* Sheen without the weight: f cos = (1 - L.H)^5 cos_l (bsdf_principled_sheen.h). */
float principled_sheen_factor(vec3 N, vec3 V, vec3 L) {
    float NdotL = dot(N, L), NdotV = dot(N, V);
    if (NdotL < 0.0 || NdotV < 0.0) return 0.0;
    vec3 H = normalize(L + V);
    return schlick_fresnel(dot(L, H)) * NdotL;
}

/* Beckmann's Smith G1 as Cycles 3.4 approximates it (bsdf_beckmann_G1):
 * 1 for a = 1 / (alpha tan) >= 1.6, else a rational fit in a. */
float beckmann_G1(float alpha, float cos_n) {
    float c2 = cos_n * cos_n;
    float inv_a = alpha * sqrt(max((1.0 - c2) / c2, 0.0));
    if (inv_a < 0.625) return 1.0;
    float a = 1.0 / inv_a;
    return ((2.181 * a + 3.535) * a) / ((2.577 * a + 2.276) * a + 1.0);
}

/* Specular lobe, f cos = F D G / (4 cos_v): GGX with Cycles' principled
 * Fresnel interpolation (bsdf_microfacet_ggx_eval_reflect,
 * interpolate_fresnel_color) for the Principled BSDF; for a Glossy BSDF F is
 * its colour, D and G GGX's or Beckmann's
 * (bsdf_microfacet_beckmann_eval_reflect: D = exp(-tan^2 / alpha^2) /
 * (pi alpha^2 cos^4), G = G1(V) G1(L) as above). */
vec3 principled_specular(PrincipledWeights w, vec3 N, vec3 V, vec3 L) {
    float NdotV = dot(N, V), NdotL = dot(N, L);
    /* Cycles returns nothing from light sampling for a near-delta lobe. */
    if (w.specular == 0.0 || w.alpha2 <= 1e-7 || NdotL <= 0.0 || NdotV <= 0.0) return vec3(0.0);
    vec3 H = normalize(L + V);
    float cosH = dot(N, H);
    if (cosH <= 0.0) return vec3(0.0);
    float cosH2 = cosH * cosH;
    vec3 nxh = cross(N, H);
#ifndef CLOSURES_NO_BECKMANN /* no Glossy BSDF with Beckmann's distribution in the scene */
    if (w.glossy_model == 2) {
        float alpha = sqrt(w.alpha2);
        float tanH2 = dot(nxh, nxh) / cosH2;
        /* exp() is 0 long before cos^4 could underflow; evaluating cos^4
         * first would give 0 / 0 where a GPU flushes denormals to zero. */
        float e = exp(-tanH2 / w.alpha2);
        float D = e > 0.0 ? e / (M_PI_F * w.alpha2 * cosH2 * cosH2) : 0.0;
        float G = beckmann_G1(alpha, NdotV) * beckmann_G1(alpha, NdotL);
        return w.cspec0 * (D * G * 0.25 / NdotV);
    }
#endif
    float D = ggx_D(w.alpha2, cosH2, dot(nxh, nxh));
    float G = ggx_G1(w.alpha2, N, V) * ggx_G1(w.alpha2, N, L);
    if (w.glossy_model != 0) return w.cspec0 * (D * G * 0.25 / NdotV);
    float FH = (fresnel_dielectric_cos(dot(L, H), w.spec_eta) - w.spec_F0) / (1.0 - w.spec_F0);
    vec3 F = w.cspec0 * (1.0 - FH) + vec3(FH);
    return F * (D * G * 0.25 / NdotV);
}

/* Clearcoat: GTR1 distribution, Smith G with fixed alpha 0.25, dielectric
 * Fresnel at IOR 1.5 times 0.25 clearcoat (bsdf_microfacet.h, 3.4). */
float principled_clearcoat(PrincipledWeights w, vec3 N, vec3 V, vec3 L) {
    float NdotV = dot(N, V), NdotL = dot(N, L);
    if (w.clearcoat <= 0.0 || w.cc_alpha * w.cc_alpha <= 1e-7 || NdotL <= 0.0 || NdotV <= 0.0) return 0.0;
    vec3 H = normalize(L + V);
    float cosH = dot(N, H);
    if (cosH <= 0.0) return 0.0;
    float a = w.cc_alpha;
    float D;
    if (a >= 1.0) {
        D = M_1_PI_F;
    } else {
        float a2 = a * a;
        D = (a2 - 1.0) / (M_PI_F * log(a2) * (1.0 + (a2 - 1.0) * cosH * cosH));
    }
    float G = ggx_G1(0.0625, N, V) * ggx_G1(0.0625, N, L);
    float F = fresnel_dielectric_cos(dot(L, H), 1.5) * 0.25 * w.clearcoat;
    return F * D * G * 0.25 / NdotV;
}

/* Both light-transport groups of one incoming direction: diffuse (Burley +
 * sheen) and glossy (specular + clearcoat), f cos for unit radiance. */
struct LobeEval {
    vec3 diffuse;
    vec3 glossy;
};

/* Directional albedo of the Burley lobe without its colour, in closed form:
 * (1/pi) integral over the hemisphere of principled_diffuse_factor, using
 * the azimuthal averages <L.V> = mu mu_v, <(L.V)^2> = mu^2 mu_v^2 +
 * (1 - mu^2)(1 - mu_v^2)/2 and integral mu^n (1 - mu)^5 = n! 5! / (n + 6)!
 * (checked against quadrature to 1e-5). mu_v = N.V. */
float principled_diffuse_albedo(float mu_v, float roughness) {
    mu_v = clamp(mu_v, 0.0, 1.0);
    float FV = schlick_fresnel(mu_v);
    const float I15 = 1.0 / 42.0, I25 = 1.0 / 168.0, I35 = 1.0 / 504.0;
    float t1 = (1.0 - 0.5 * FV) * (1.0 - I15);
    float t2 = 2.0 * roughness * ((1.0 - FV) * (I15 + mu_v * I25) + FV * (0.5 + mu_v / 3.0));
    float t3 = 2.0 * roughness * roughness * FV *
               (I15 + 2.0 * mu_v * I25 + mu_v * mu_v * I35 + 0.5 * (1.0 - mu_v * mu_v) * (I15 - I35));
    return t1 + t2 + t3;
}

/* Directional albedo of the surface's diffuse lobe (Burley or Oren-Nayar). */
float diffuse_lobe_albedo(SurfaceParams s, float mu_v) {
    return s.diffuse_sigma >= 0.0 ? oren_nayar_albedo(mu_v, s.diffuse_sigma) : principled_diffuse_albedo(mu_v, s.roughness);
}

/* Cycles 3.4 evaluates a light sample as a transmission when it lies below
 * the smooth normal sd->N (shader_bsdf_is_transmission), where reflection
 * closures give nothing, whatever normal Bump or a Normal Map gave them.
 * BSDF-sampled glossy directions are not tested against sd->N (only against
 * Ng), so this applies to the glossy lobes' light samples: 1 above the
 * smooth normal's horizon, else 0. (Diffuse lobes get bump_shadowing_term,
 * which includes it, for both techniques.) */
float smooth_side(SurfaceParams s, vec3 L) { return dot(s.Ns, L) < 0.0 ? 0.0 : 1.0; }

/* Diffuse closures whose normal N is not the smooth one Ns (Bump, Normal
 * Map) are darkened towards the smooth normal's terminator: Chiang, Li and
 * Burley 2019, "Taming the Shadow Terminator", as Cycles 3.4's bsdf_eval and
 * bsdf_sample apply it (bump_shadowing_term(sd->N, sc->N, L)). */
float bump_shadowing_term(vec3 Ns, vec3 N, vec3 L) {
    if (Ns == N) return 1.0;
    float denom = dot(N, L) * dot(Ns, N);
    float g = denom != 0.0 ? dot(Ns, L) / denom : 0.0;
    if (g >= 1.0) return 1.0;
    if (g < 0.0) return 0.0;
    float g2 = g * g;
    return -g2 * g + g2 + g;
}

/* The diffuse group alone (Burley or Oren-Nayar, + sheen), f cos for unit
 * radiance, without the bump shadowing term. */
vec3 principled_eval_diffuse_unbumped(SurfaceParams s, PrincipledWeights w, vec3 N, vec3 V, vec3 L) {
    float NdotL = dot(N, L), NdotV = dot(N, V), LdotV = dot(L, V);
    vec3 d = w.diffuse * (s.diffuse_sigma >= 0.0 ? oren_nayar_factor(NdotL, NdotV, LdotV, s.diffuse_sigma)
                                                 : principled_diffuse_factor(NdotL, NdotV, LdotV, s.roughness));
    if (w.sheen != vec3(0.0)) d += w.sheen * principled_sheen_factor(N, V, L);
    return d;
}

/* ... and with it: what a light (or world) direction gives the diffuse group. */
vec3 principled_eval_diffuse(SurfaceParams s, PrincipledWeights w, vec3 N, vec3 V, vec3 L) {
    return principled_eval_diffuse_unbumped(s, w, N, V, L) * bump_shadowing_term(s.Ns, N, L);
}

LobeEval principled_eval(SurfaceParams s, PrincipledWeights w, vec3 N, vec3 V, vec3 L) {
    LobeEval e;
    e.diffuse = principled_eval_diffuse(s, w, N, V, L);
    e.glossy = principled_specular(w, N, V, L) + vec3(principled_clearcoat(w, N, V, L));
    return e;
}

/* ---- Sampling the specular lobe (for multiple importance sampling of
 * lights a glossy surface reflects, as Cycles does with BSDF rays). ---- */

/* GGX visible-normal sampling (Heitz 2018, "Sampling the GGX Distribution of
 * Visible Normals", JCGT 7(4)): the incident direction for uniform u, with
 * pdf principled_specular_pdf(). alpha = roughness^2. */
vec3 sample_ggx_vndf(vec3 N, vec3 V, float alpha, vec2 u) {
    vec3 T, B;
    vec3 up = abs(N.z) < 0.999 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
    T = normalize(cross(up, N));
    B = cross(N, T);
    vec3 Ve = vec3(dot(V, T), dot(V, B), dot(V, N));
    vec3 Vh = normalize(vec3(alpha * Ve.x, alpha * Ve.y, Ve.z));
    float lensq = Vh.x * Vh.x + Vh.y * Vh.y;
    vec3 T1 = lensq > 0.0 ? vec3(-Vh.y, Vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 T2 = cross(Vh, T1);
    float r = sqrt(u.x), phi = 2.0 * M_PI_F * u.y;
    float t1 = r * cos(phi), t2 = r * sin(phi);
    float sh = 0.5 * (1.0 + Vh.z);
    t2 = (1.0 - sh) * sqrt(max(1.0 - t1 * t1, 0.0)) + sh * t2;
    vec3 Nh = t1 * T1 + t2 * T2 + sqrt(max(1.0 - t1 * t1 - t2 * t2, 0.0)) * Vh;
    vec3 He = normalize(vec3(alpha * Nh.x, alpha * Nh.y, max(Nh.z, 0.0)));
    vec3 H = He.x * T + He.y * B + He.z * N;
    return reflect(-V, H);
}

/* Solid-angle pdf of sample_ggx_vndf: G1(V) D(H) / (4 N.V). */
float principled_specular_pdf(PrincipledWeights w, vec3 N, vec3 V, vec3 L) {
    float NdotV = dot(N, V);
    if (NdotV <= 0.0 || dot(N, L) <= 0.0) return 0.0;
    vec3 H = normalize(L + V);
    float cosH = dot(N, H);
    if (cosH <= 0.0) return 0.0;
    float cosH2 = cosH * cosH;
    vec3 nxh = cross(N, H);
    float D = ggx_D(w.alpha2, cosH2, dot(nxh, nxh));
    return ggx_G1(w.alpha2, N, V) * D * 0.25 / NdotV;
}

/* A lobe below Cycles' 1e-7 alpha^2 cut-off is a perfect mirror: it reflects
 * only along R = 2 (N.V) N - V, with weight reflection_color (the principled
 * Fresnel at H = N; bsdf_microfacet_ggx_sample's "specular case", eval/pdf).
 * Returns the weight of that direction for the specular plus clearcoat
 * mirrors (zero where neither is a mirror). */
vec3 principled_mirror_weight(PrincipledWeights w, vec3 N, vec3 V) {
    float NdotV = dot(N, V);
    vec3 r = vec3(0.0);
    if (NdotV <= 0.0) return r;
    if (w.specular != 0.0 && w.alpha2 <= 1e-7 && w.glossy_model != 0) {
        r += w.cspec0;  /* a Glossy BSDF mirror: its colour, no Fresnel */
    } else if (w.specular != 0.0 && w.alpha2 <= 1e-7) {
        float FH = (fresnel_dielectric_cos(NdotV, w.spec_eta) - w.spec_F0) / (1.0 - w.spec_F0);
        r += w.cspec0 * (1.0 - FH) + vec3(FH);
    }
    if (w.clearcoat > 0.0 && w.cc_alpha * w.cc_alpha <= 1e-7)
        r += vec3(fresnel_dielectric_cos(NdotV, 1.5) * 0.25 * w.clearcoat);
    return r;
}
