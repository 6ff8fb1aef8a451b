/* Shader nodes -> Closure (the G-buffer's Principled parameter set).
 * Cycles: intern/cycles/kernel/svm/closure.h (svm_node_closure_bsdf,
 * svm_node_emission, mix/add via closure weights in scene/shader_nodes.cpp). */

float clamp01(float x) { return clamp(x, 0.0, 1.0); }

/* A closure's normal input: unit length (the shading normal where it
 * degenerates), then bent so the reflection of I stays above the surface, as
 * svm_node_closure_bsdf does for every BSDF closure (3.4). */
vec3 closure_normal(vec3 n) {
    vec3 m = safe_normalize(n);
    m = (dot(m, m) > 0.0 && !any(isnan(m))) ? m : g_sd.N;
    return ensure_valid_reflection(g_sd.Ng, g_sd.I, m);
}

/* Transmission folded into the Principled parameter set as Cycles shows a
 * closed glass object at Max Bounces 0 (the add-on's export/material.py
 * fold_transmission is the same formula, with its derivation). Cycles 3.4
 * svm_node_closure_bsdf: T' = T (1 - m); diffuse and sheen take
 * wd = (1 - m)(1 - T), the specular lobe ws = 1 - T', the glass closure T':
 * a reflection of weight fresnel_dielectric_cos(N.I, ior) and a refraction,
 * which meets the object's far side (nothing at Max Bounces 0). So
 * base' = base (wd + m ws), metallic' = m ws / (wd + m ws), sheen' =
 * sheen wd / (1 - metallic'), and one specular lobe of normal-incidence
 * reflectance D = 0.08 specular (1 - m) ws + T' F0(ior) (wholly metallic,
 * of colour base (wd + m ws) + D, where specular' would pass 12). */
void principled_fold_transmission(float transmission, float ior, inout vec3 base_color, inout float metallic,
                                  inout float specular, inout float sheen) {
    float t = clamp01(transmission);
    if (!(t > 0.0)) return;
    float m = metallic;
    float glass = t * (1.0 - m), wd = (1.0 - m) * (1.0 - t), ws = 1.0 - glass;
    float k = wd + m * ws;
    float eta = max(ior, 1e-5);
    float r = (eta - 1.0) / (eta + 1.0);
    float dielectric = 0.08 * specular * (1.0 - m) * ws + glass * r * r; /* r^2: fresnel_dielectric_cos(1, ior) */
    float folded = k > 0.0 ? m * ws / k : m;
    base_color *= k;
    if (1.0 - folded > 1e-6 && dielectric <= 12.0 * 0.08 * (1.0 - folded)) {
        metallic = folded;
        specular = dielectric / (0.08 * (1.0 - folded));
        sheen *= wd / (1.0 - folded);
    } else {
        /* specular' past the G-buffer's 12: wholly metallic, colour
         * base (wd + m ws) + D (fold_transmission). */
        metallic = 1.0;
        base_color += vec3(dielectric);
        sheen = 0.0;
    }
}

/* Principled BSDF (3.4 inputs). The ranges are those of the G-buffer and of
 * Cycles' own clamps: metallic/transmission weights saturate, GGX alpha is
 * clamped to [0, 1], base colour is not negative. Transmission is folded in
 * (principled_fold_transmission); subsurface and anisotropy are not
 * modelled (the add-on warns when they are used). */
void node_bsdf_principled(vec3 base_color, float metallic, float specular, float specular_tint,
                          float roughness, float sheen, float sheen_tint, float clearcoat,
                          float clearcoat_roughness, float transmission, float ior, vec3 emission,
                          float emission_strength, float alpha, vec3 normal, out Closure c) {
    c = closure_none();
    c.base_color = max(base_color, vec3(0.0));
    c.metallic = clamp01(metallic);
    c.specular = clamp(specular, 0.0, 12.0);
    c.specular_tint = clamp01(specular_tint);
    c.roughness = clamp01(roughness);
    c.sheen = clamp01(sheen);
    principled_fold_transmission(transmission, ior, c.base_color, c.metallic, c.specular, c.sheen);
    c.specular = clamp(c.specular, 0.0, 12.0);
    c.sheen_tint = clamp01(sheen_tint);
    c.clearcoat = clamp01(clearcoat);
    c.clearcoat_roughness = clamp01(clearcoat_roughness);
    c.emission = emission * emission_strength; /* Cycles does not clamp: negative light subtracts */
    c.alpha = clamp01(alpha);
    c.N = closure_normal(normal);
    c.reflects = 1.0;
}

/* The node without Transmission and IOR, as graphs exported before they were
 * read (scene captures, bench/gpu/captures) call it. */
void node_bsdf_principled(vec3 base_color, float metallic, float specular, float specular_tint,
                          float roughness, float sheen, float sheen_tint, float clearcoat,
                          float clearcoat_roughness, vec3 emission, float emission_strength,
                          float alpha, vec3 normal, out Closure c) {
    node_bsdf_principled(base_color, metallic, specular, specular_tint, roughness, sheen, sheen_tint, clearcoat,
                         clearcoat_roughness, 0.0, 1.45, emission, emission_strength, alpha, normal, c);
}

/* Diffuse BSDF: the Principled diffuse lobe at roughness 1 stands in for
 * Lambert/Oren-Nayar, as the constant-material path does (export/material.py). */
void node_bsdf_diffuse(vec3 color, float roughness, vec3 normal, out Closure c) {
    c = closure_none();
    c.base_color = max(color, vec3(0.0));
    c.roughness = 1.0;
    /* svm_node_closure_bsdf: roughness 0 is Lambert, else Oren-Nayar with
     * sigma = roughness (saturated in bsdf_oren_nayar_setup); Lambert is
     * Oren-Nayar at sigma 0, so one model serves both. */
    c.diffuse_sigma = clamp01(roughness);
    c.N = closure_normal(normal);
    c.reflects = 1.0;
}

/* Glossy BSDF (model 1: GGX, 2: Beckmann): a microfacet lobe whose weight
 * is the node's colour, without Fresnel (bsdf_microfacet_{ggx,beckmann}_setup;
 * svm_node_closure_bsdf squares Roughness into alpha). Metallic 1 keeps the
 * diffuse lobe out. */
void node_bsdf_glossy(int model, vec3 color, float roughness, vec3 normal, out Closure c) {
    c = closure_none();
    c.base_color = max(color, vec3(0.0));
    c.glossy_model = float(model);
    c.metallic = 1.0;
    c.specular = 0.5;
    c.roughness = clamp01(roughness);
    c.N = closure_normal(normal);
    c.reflects = 1.0;
}

/* Glass BSDF as Cycles shows a closed glass object at Max Bounces 0: its
 * reflection (svm_node_glass_setup: weight colour x
 * fresnel_dielectric_cos(N.I, ior), a GGX lobe without Fresnel; Sharp a
 * mirror), its refraction meeting the object's far side (nothing). Here a
 * metallic Principled lobe of normal-incidence colour colour x F0(ior) and
 * the Fresnel curve of that ior (L.H's Fresnel where Cycles takes N.I's;
 * towards grazing it goes to white, Cycles' to the colour). */
void node_bsdf_glass(vec3 color, float roughness, float ior, vec3 normal, out Closure c) {
    c = closure_none();
    float eta = max(ior, 1e-5);
    float r = (eta - 1.0) / (eta + 1.0);
    float f0 = r * r; /* fresnel_dielectric_cos(1, ior) */
    c.base_color = max(color, vec3(0.0)) * f0;
    c.metallic = 1.0;
    c.specular = clamp(f0 / 0.08, 0.0, 12.0);
    c.roughness = clamp01(roughness);
    c.N = closure_normal(normal);
    c.reflects = 1.0;
}

/* An unlinked shader socket: no closure (black). */
void node_closure_none(out Closure c) { c = closure_none(); }

/* Holdout (Cycles' holdout closure): where it is the surface, a hole in the
 * image, black with alpha 0, no light and no data pass. Mixed with other
 * closures (node_mix_shader) it is drawn with its weight's probability, so
 * the accumulated image has Cycles' partial holdout: alpha 1 - weight and
 * the other closures at their weights. */
void node_holdout(out Closure c) {
    c = closure_none();
    c.holdout = 1.0;
}

/* Emission: radiance colour x strength (svm_node_emission_weight; the
 * closure weight is not clamped, so a negative colour or strength emits
 * negative radiance in Cycles, and here). */
void node_emission(vec3 color, float strength, out Closure c) {
    c = closure_none();
    c.emission = color * strength;
}

/* Transparent BSDF: Cycles passes its colour's fraction of the light behind
 * (camera and shadow rays). Coverage (alpha) is what it does not pass:
 * 1 - the colour's average; a tinted colour is rendered as that grey (the
 * add-on notes it). It reflects and emits nothing. */
void node_bsdf_transparent(vec3 color, out Closure c) {
    c = closure_none();
    c.alpha = clamp01(1.0 - (color.r + color.g + color.b) * (1.0 / 3.0));
}

/* One of two closures, b with probability pb, drawn from g_mix_u, which is
 * then rescaled to [0, 1) within the chosen side so nested mixes stay
 * uniform and stratified. */
Closure pick_closure(Closure a, Closure b, float pb) {
    if (g_mix_u < pb) {
        g_mix_u = g_mix_u / max(pb, 1e-30);
        return b;
    }
    g_mix_u = (g_mix_u - pb) / max(1.0 - pb, 1e-30);
    return a;
}

/* A Lambert Diffuse BSDF `d` and a grey Glossy BSDF `g` (one normal) mixed
 * with weights wd and wg, as one closure instead of one of them drawn per
 * sample: Cycles sums the two closures, wd Cd Lambert + wg k Glossy (k the
 * glossy colour's grey), and so does this closure, exactly and with no
 * noise from the pick (a Layer Weight or Fresnel mix of a diffuse and a
 * sharp glossy lobe, the materials library's Ceramic Polished, drew the
 * glossy side in a few samples of a pixel: speckles of its highlight).
 * Its layout (gbuffer_lib.glsl, bsdf_lib.glsl principled_weights): the
 * glossy model, metallic 0 (so the diffuse lobe is base colour = wd Cd,
 * Lambert), the glossy weight wg k in specular_tint (a Glossy BSDF's
 * weight is otherwise its base colour). Not where the diffuse lobe is
 * Oren-Nayar (the model field holds the glossy model, not sigma) or the
 * glossy colour is not grey: those are picked. */
bool merged_diffuse_glossy(Closure c) { return c.glossy_model > 0.5 && c.metallic < 0.5; }

bool merge_diffuse_glossy(Closure d, Closure g, float wd, float wg, out Closure c) {
    c = d;
    const bool diffuse = d.glossy_model < 0.5 && d.diffuse_sigma == 0.0 && d.metallic == 0.0 && d.specular == 0.0 &&
                         d.sheen == 0.0 && d.clearcoat == 0.0;
    const bool glossy = g.glossy_model > 0.5 && g.metallic == 1.0 && g.sheen == 0.0 && g.clearcoat == 0.0 &&
                        g.base_color.r == g.base_color.g && g.base_color.g == g.base_color.b;
    const float k = wg * g.base_color.r;
    if (!diffuse || !glossy || !all(equal(d.N, g.N)) || !(k >= 0.0)) return false;
    c = g;
    c.base_color = d.base_color * wd;
    c.metallic = 0.0;
    c.specular_tint = k;
    return true;
}

/* A closure is the opaque part of the surface, with coverage `alpha`: the
 * surface contributes alpha x (its lobes and emission) and lets 1 - alpha of
 * what is behind through (the geometry pass keeps it with probability alpha).
 *
 * Mix Shader: closure weights (1 - fac) and fac, so the sides cover
 * wa = (1 - fac) a.alpha and wb = fac b.alpha; the mix covers wa + wb and its
 * opaque part is (wa A + wb B) / (wa + wb). Emission is linear and mixes
 * exactly; the BSDF is one side, picked with probability wb / (wa + wb) from
 * g_mix_u, which is then rescaled so nested mixes stay uniform and
 * stratified. A side that reflects nothing (emission, a Transparent BSDF,
 * none) keeps the other side's lobes scaled by its share: exact for the
 * diffuse and metallic lobes (linear in the base colour); the dielectric
 * specular weight scales F0, which leaves the grazing-angle Fresnel rise
 * unscaled. */
/* AOV Output (Cycles' svm_node_aov_color / svm_node_aov_value): the values
 * of the view layer's AOV of this slot at this shading point. */
void node_aov_output(int slot, vec3 color, float value) {
    g_aov[slot] = vec4(color, value);
}

/* Material > Blend Mode: Alpha Clip (EEVEE's; Cycles has no such mode): the
 * surface is there where its alpha is above the threshold and absent
 * elsewhere (EEVEE: alpha <= threshold discards). The exporter appends it
 * after the surface closure (builder.apply_alpha_clip), so the geometry
 * pass, shadow casters and data passes all see the same cut. */
void node_alpha_clip(Closure a, float threshold, out Closure c) {
    c = a;
    c.alpha = a.alpha > threshold ? 1.0 : 0.0;
}

void node_mix_shader(float fac, Closure a, Closure b, out Closure c) {
    fac = clamp01(fac);
    float wa = (1.0 - fac) * a.alpha, wb = fac * b.alpha;
    float coverage = wa + wb;
    float inv = coverage > 0.0 ? 1.0 / coverage : 0.0;
    if (a.holdout != b.holdout) {
        /* One side a holdout: a side is drawn whole (its own lobes and
         * emission) with probability its share, so the image converges to
         * Cycles' holdout weight wb (or wa) and the other side's closures
         * at their weight. */
        c = pick_closure(a, b, wb * inv);
        c.alpha = coverage;
        return;
    }
    vec3 emission = (wa * a.emission + wb * b.emission) * inv;
    if (a.reflects == 0.0 || b.reflects == 0.0) {
        float w = (a.reflects != 0.0 ? wa : wb) * inv;
        c = a.reflects != 0.0 ? a : b;
        c.base_color *= w;
        c.specular *= w;
        c.sheen *= w;
        c.clearcoat *= w;
        if (merged_diffuse_glossy(c)) c.specular_tint *= w;
        c.reflects = (a.reflects != 0.0 || b.reflects != 0.0) ? 1.0 : 0.0;
    } else if (!merge_diffuse_glossy(a, b, wa * inv, wb * inv, c) && !merge_diffuse_glossy(b, a, wb * inv, wa * inv, c)) {
        c = pick_closure(a, b, wb * inv);
    }
    c.emission = emission;
    c.alpha = coverage;
}

/* Add Shader: the closures sum. In coverage terms (see Mix Shader) the sides
 * weigh wa = a.alpha and wb = b.alpha, their transparencies add, so the sum
 * covers wa + wb - 1 (clamped to [0, 1]; a surface passing more than all the
 * light behind it is not representable) and its opaque part is
 * (wa A + wb B) / coverage. When both sides reflect, one is drawn with
 * probability w / (wa + wb) at (wa + wb) / coverage times its colour weight
 * (for two opaque sides: 1/2 and twice), exact for the diffuse and metallic
 * parts, which are linear in the base colour (the add-on warns). */
void node_add_shader(Closure a, Closure b, out Closure c) {
    if (a.holdout != 0.0 || b.holdout != 0.0) {
        /* A holdout added at full weight: Cycles ends the path at a holdout
         * weight of 1 (integrate_surface_holdout), whatever else is there. */
        c = a.holdout != 0.0 ? a : b;
        return;
    }
    float wa = a.alpha, wb = b.alpha;
    float coverage = clamp01(wa + wb - 1.0);
    float inv = coverage > 0.0 ? 1.0 / coverage : 0.0;
    vec3 emission = (wa * a.emission + wb * b.emission) * inv;
    if (a.reflects == 0.0 || b.reflects == 0.0) {
        float w = (a.reflects != 0.0 ? wa : wb) * inv;
        c = a.reflects != 0.0 ? a : b;
        c.base_color *= w;
        c.specular = min(c.specular * w, 12.0);
        c.sheen *= w;
        c.clearcoat *= w;
        if (merged_diffuse_glossy(c)) c.specular_tint *= w;
    } else if (!merge_diffuse_glossy(a, b, wa * inv, wb * inv, c) && !merge_diffuse_glossy(b, a, wb * inv, wa * inv, c)) {
        c = pick_closure(a, b, wb / max(wa + wb, 1e-30));
        float scale = (wa + wb) * inv;
        c.base_color *= scale;
        c.specular = min(c.specular * scale, 12.0);
        if (merged_diffuse_glossy(c)) c.specular_tint *= scale;
    }
    c.emission = emission;
    c.alpha = coverage;
}
