/* Light evaluation with Cycles 3.4's light units (intern/cycles/kernel/light/
 * light.h and shared/REFERENCE.md section 2). S = colour x energy.
 *
 *  point/spot, R = 0 : delta light, E = S cos / (4 pi d^2) (x spot attenuation)
 *  point/spot, R > 0 : Cycles samples a disk of radius R centred on the light
 *                      and facing the shading point, radiance S / (4 pi pi R^2)
 *                      (eval_fac = 1/(4 pi) * invarea): shaded as that disk;
 *                      the spot attenuation is taken per disk point
 *                      (measured against Cycles 3.4.1: tools/cycles_probe)
 *  sun               : E = S cos, one point of its disk per film sample
 *  area              : one-sided towards -Z, radiance S / (4 A)
 *
 * Disks and area lights are shaded in two parts (Arvo 1995 vector irradiance,
 * used as a control variate):
 *  - the Lambertian projected solid angle is EXACT: the vector irradiance
 *    J = 1/2 sum theta_i normalize(v_i x v_i+1) of the light's outline
 *    clipped to the surface's horizon (polygons: Sutherland-Hodgman; disks and
 *    ellipses: the contour integral 1/2 closed-integral (r x dr)/|r|^2 by
 *    Gauss-Legendre quadrature, plus the straight chord where the horizon cuts);
 *  - the diffuse and sheen lobes are that exact term times their value in the
 *    direction of J, plus a Monte Carlo correction over K stratified points
 *    of the light; the glossy lobes are Monte Carlo over the same points,
 *    and a low-roughness specular lobe is also sampled by direction (GGX
 *    visible normals), the two combined by the power heuristic as Cycles
 *    combines light and BSDF rays; a mirror lobe (alpha^2 <= 1e-7) sees the
 *    light only along its reflected ray.
 * The points are one per cell of a G x G grid, placed in each cell at
 * frame.sample_shift (a low-discrepancy point per film sample), so
 * accumulating samples converges to the integral Cycles computes. */

#include "bsdf_lib.glsl"
#ifdef HAS_SHADOWS
#include "shadow_lib.glsl"
#endif

struct LightContribution {
    vec3 diffuse; /* radiance through the diffuse group (with albedo) */
    vec3 glossy;
};

float spot_attenuation(GpuLight light, vec3 light_to_point) {
    /* Cycles 3.4 spot_attenuation, with its leading cos factor. */
    float cs = light.direction.w, smooth_w = light.axis_x.w;
    float c = dot(light.direction.xyz, light_to_point);
    if (c <= cs) return 0.0;
    float t = c - cs;
    float att = c;
    if (t < smooth_w && smooth_w != 0.0) {
        float x = t / smooth_w;
        att *= x * x * (3.0 - 2.0 * x);
    }
    return att;
}

/* Edge term of the vector irradiance: theta * normalize(a x b). */
vec3 edge_vector_irradiance(vec3 a, vec3 b) {
    vec3 c = cross(a, b);
    float s = length(c);
    if (s <= 0.0) return vec3(0.0);
    return c * (atan(s, dot(a, b)) / s);
}

/* Twice the vector irradiance of the rectangle c +- a +- b (relative to the
 * shading point) clipped to the half space dot(N, x) >= 0. */
vec3 rect_vector_irradiance(vec3 c, vec3 a, vec3 b, vec3 N) {
    vec3 quad[4] = vec3[4](c - a - b, c + a - b, c + a + b, c - a + b);
    vec3 poly[5];
    int n = 0;
    for (int i = 0; i < 4; ++i) {
        vec3 p = quad[i], q = quad[(i + 1) & 3];
        float dp = dot(N, p), dq = dot(N, q);
        if (dp >= 0.0) poly[n++] = p;
        if ((dp >= 0.0) != (dq >= 0.0)) poly[n++] = p + (q - p) * (dp / (dp - dq));
    }
    vec3 J = vec3(0.0);
    for (int i = 0; i < n; ++i) J += edge_vector_irradiance(poly[i], poly[(i + 1) % n]);
    return J;
}

/* Gauss-Legendre, 8 nodes on [-1, 1]. */
const float GL8_X[4] = float[4](0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363);
const float GL8_W[4] = float[4](0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763);
#define ELLIPSE_PANELS 4

vec3 ellipse_point(vec3 c, vec3 a, vec3 b, float t) { return c + a * cos(t) + b * sin(t); }
vec3 ellipse_integrand(vec3 c, vec3 a, vec3 b, float t) {
    vec3 r = c + a * cos(t) + b * sin(t);
    vec3 dr = -a * sin(t) + b * cos(t);
    return cross(r, dr) / max(dot(r, r), 1e-30);
}

/* Twice the vector irradiance of the ellipse c + a cos t + b sin t, clipped
 * to dot(N, x) >= 0: closed integral of (r x dr)/|r|^2 over the visible arc
 * plus the chord the horizon cuts. */
vec3 ellipse_vector_irradiance(vec3 c, vec3 a, vec3 b, vec3 N) {
    float p = dot(N, c), na = dot(N, a), nb = dot(N, b);
    float q = sqrt(na * na + nb * nb);
    float t0 = 0.0, t1 = 2.0 * M_PI_F;
    bool clipped = false;
    if (p <= -q) return vec3(0.0);
    if (p < q) {
        float phi = atan(nb, na);
        float beta = acos(clamp(-p / q, -1.0, 1.0));
        t0 = phi - beta;
        t1 = phi + beta;
        clipped = true;
    }
    vec3 J = vec3(0.0);
    float panel = (t1 - t0) / float(ELLIPSE_PANELS);
    for (int k = 0; k < ELLIPSE_PANELS; ++k) {
        float mid = t0 + (float(k) + 0.5) * panel, half_w = 0.5 * panel;
        for (int i = 0; i < 4; ++i) {
            J += (GL8_W[i] * half_w) * (ellipse_integrand(c, a, b, mid + half_w * GL8_X[i]) +
                                       ellipse_integrand(c, a, b, mid - half_w * GL8_X[i]));
        }
    }
    if (clipped) J += edge_vector_irradiance(ellipse_point(c, a, b, t1), ellipse_point(c, a, b, t0));
    return J;
}

/* Shirley-Chiu concentric map of [0,1)^2 onto the unit disk. */
vec2 concentric_disk(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o == vec2(0.0)) return vec2(0.0);
    float r, theta;
    if (abs(o.x) > abs(o.y)) { r = o.x; theta = (M_PI_F / 4.0) * (o.y / o.x); }
    else { r = o.y; theta = (M_PI_F / 2.0) - (M_PI_F / 4.0) * (o.x / o.y); }
    return r * vec2(cos(theta), sin(theta));
}

/* Where the ray from the shading point along unit L meets the planar
 * emitter c + a x + b y (|x|,|y| <= 1, or x^2 + y^2 <= 1 for an ellipse;
 * a and b orthogonal) from its emitting side: distance t and the cosine at
 * the emitter. */
bool emitter_hit(vec3 c, vec3 a, vec3 b, bool ellipse, vec3 emit_dir, vec3 L, out float t, out float cos_l) {
    cos_l = -dot(emit_dir, L);
    t = 0.0;
    if (cos_l <= 0.0) return false;
    t = -dot(c, emit_dir) / cos_l;
    if (!(t > 0.0)) return false;
    vec3 q = L * t - c;
    float x = dot(q, a) / dot(a, a), y = dot(q, b) / dot(b, b);
    return ellipse ? x * x + y * y <= 1.0 : max(abs(x), abs(y)) <= 1.0;
}

/* Shade one planar emitter: outline c + a, b (relative to the shading point),
 * radiance `radiance` x a spot attenuation that Cycles evaluates per sampled
 * point (att_center at the centre; spot lights only, 1 otherwise), emitting
 * along `emit_dir` (unit). `sphere_disk`: the disk a sphere light presents,
 * facing the shading point. */
LightContribution shade_planar_light(vec3 c, vec3 a, vec3 b, bool ellipse, bool sphere_disk, vec3 emit_dir,
                                     vec3 radiance, GpuLight light, bool spot, float att_center,
                                     SurfaceParams s, PrincipledWeights w, vec3 N, vec3 V) {
    LightContribution r;
    r.diffuse = vec3(0.0);
    r.glossy = vec3(0.0);
    vec3 J2;
    float c2 = dot(c, c);
    float radius2 = dot(a, a);
    float NdotC = dot(N, c);
    float area = ellipse ? M_PI_F * length(a) * length(b) : 4.0 * length(a) * length(b);
    if (sphere_disk && NdotC > 0.0 && NdotC * NdotC >= radius2 * (c2 - NdotC * NdotC) / c2) {
        /* A disk facing the point and wholly above its horizon (a sphere
         * light's disk, R sin <= d cos): J is along c, and the projected solid
         * angle is pi R^2 cos / (d^2 + R^2) in closed form. */
        J2 = c * (2.0 * M_PI_F * radius2 / ((c2 + radius2) * sqrt(c2)));
    } else if (area < 1e-4 * c2) {
        /* An emitter that looks tiny (solid angle < 1e-4 sr): the outline sum
         * cancels catastrophically in float (edge terms ~ size/d, their sum
         * ~ (size/d)^2); use the small-emitter limit A cos_l cos_s / d^2,
         * whose own relative error is O(A / d^2) (tests/robustness). */
        float cos_l = max(-dot(emit_dir, c), 0.0) * inversesqrt(c2);
        J2 = NdotC > 0.0 ? c * (2.0 * area * cos_l / (c2 * sqrt(c2))) : vec3(0.0);
    } else {
        J2 = ellipse ? ellipse_vector_irradiance(c, a, b, N) : rect_vector_irradiance(c, a, b, N);
    }
    float proj = 0.5 * dot(N, J2); /* projected solid angle, sign from the outline's orientation */
    vec3 Jdir = proj < 0.0 ? -J2 : J2;
    proj = abs(proj);

    /* Control variate: diffuse BSDF value (f, not f cos) in the direction of J. */
    vec3 diffuse_at_J = vec3(0.0);
    float jlen = length(Jdir);
    if (proj > 0.0 && jlen > 0.0) {
        vec3 L = Jdir / jlen;
        float NdotL = dot(N, L);
        if (NdotL > 1e-4) diffuse_at_J = principled_eval(s, w, N, V, L).diffuse / NdotL;
    }
    r.diffuse = diffuse_at_J * (proj * att_center);

    /* Points per sample: up to the full G x G grid (frame.counts.z = G^2) for
     * lights that look large from here, fewer for small ones, where the BSDF
     * barely varies across the light (the estimate stays unbiased). */
    uint G = max(uint(sqrt(float(max(frame.counts.z, 1u))) + 0.5), 1u);
    float angular_size2 = area / max(c2, 1e-20); /* ~ solid angle */
    if (angular_size2 < 0.01) G = 1u;
    else if (angular_size2 < 0.2) G = min(G, 2u);
    float weight = area / float(G * G);
    /* The specular lobe is also sampled by direction (GGX visible normals)
     * and combined with the light points by the power heuristic (Veach 1997,
     * as Cycles' MIS of light and BSDF rays): light points alone miss the
     * small bright reflection a low-roughness surface makes of a large light.
     * Rough lobes (alpha >= 0.25) are wide enough for light points alone. */
    const bool bsdf_sampling = w.specular != 0.0 && w.alpha2 > 1e-7 && w.alpha2 < 0.0625;
    float alpha = sqrt(w.alpha2); /* GGX alpha = roughness^2 */
    vec3 mc_diffuse = vec3(0.0), mc_glossy = vec3(0.0);
    for (uint j = 0u; j < G; ++j) {
        for (uint i = 0u; i < G; ++i) {
            vec2 u = (vec2(i, j) + frame.sample_shift.xy) / float(G);
            vec2 xy = ellipse ? concentric_disk(u) : 2.0 * u - 1.0;
            vec3 pt = c + a * xy.x + b * xy.y;
            float t2 = dot(pt, pt);
            if (t2 <= 1e-20) continue;
            vec3 L = pt * inversesqrt(t2);
            float cos_l = -dot(emit_dir, L);
            if (cos_l <= 0.0) continue;
            float geom = cos_l / t2 * weight;
            float att = spot ? spot_attenuation(light, -L) : 1.0;
            float side = smooth_side(s, L);
            vec3 diff = principled_eval_diffuse(s, w, N, V, L);
            vec3 spec = principled_specular(w, N, V, L) * side;
            float cc = principled_clearcoat(w, N, V, L) * side;
            if (bsdf_sampling) {
                /* Power heuristic pl^2 / (pl^2 + pb^2), as a ratio: pl alone
                 * overflows float for tiny lights (1 / area). */
                float ratio = min(principled_specular_pdf(w, N, V, L) * cos_l * area / t2, 1e18);
                spec *= 1.0 / (1.0 + ratio * ratio);
            }
            mc_diffuse += (diff * att - diffuse_at_J * (att_center * max(dot(N, L), 0.0))) * geom;
            mc_glossy += (spec + vec3(cc)) * (att * geom);
            if (bsdf_sampling) {
                /* The BSDF's own direction for this cell (another point of
                 * the cell, so the two techniques do not share a pattern). */
                vec2 ub = (vec2(i, j) + fract(frame.sample_shift.yx + vec2(0.5, 0.25))) / float(G);
                vec3 Lb = sample_ggx_vndf(N, V, alpha, ub);
                float tb, cos_b;
                if (emitter_hit(c, a, b, ellipse, emit_dir, Lb, tb, cos_b)) {
                    float pb = principled_specular_pdf(w, N, V, Lb);
                    if (pb > 1e-30) {
                        /* f / pb (= F G1 <= 1) times the power heuristic
                         * 1 / (1 + (pl/pb)^2). */
                        float ratio = min(tb * tb / (cos_b * area * pb), 1e18);
                        float attb = spot ? spot_attenuation(light, -Lb) : 1.0;
                        mc_glossy += principled_specular(w, N, V, Lb) *
                                     (attb / pb / (1.0 + ratio * ratio) / float(G * G));
                    }
                }
            }
        }
    }
    /* Mirror lobes (alpha^2 <= 1e-7) see the light only along R. */
    vec3 mirror = principled_mirror_weight(w, N, V);
    if (mirror != vec3(0.0)) {
        vec3 R = reflect(-V, N);
        float tr, cos_r;
        if (emitter_hit(c, a, b, ellipse, emit_dir, R, tr, cos_r))
            mc_glossy += mirror * (spot ? spot_attenuation(light, -R) : 1.0);
    }
    r.diffuse = (r.diffuse + mc_diffuse) * radiance;
    r.glossy = mc_glossy * radiance;
    return r;
}

/* Any vector perpendicular to unit n, and a second completing the basis. */
void make_basis(vec3 n, out vec3 t, out vec3 bt) {
    vec3 up = abs(n.z) < 0.999 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
    t = normalize(cross(up, n));
    bt = cross(n, t);
}

LightContribution shade_light_unshadowed(GpuLight light, SurfaceParams s, PrincipledWeights w, vec3 P, vec3 N,
                                         vec3 V) {
    LightContribution r;
    r.diffuse = vec3(0.0);
    r.glossy = vec3(0.0);
    const int type = int(light.position_type.w);
    const vec3 S = light.strength.rgb;

#if defined(HAS_POINT_LIGHTS) || defined(HAS_SPOT_LIGHTS)
    if (type == LIGHT_POINT || type == LIGHT_SPOT) {
        vec3 to_light = light.position_type.xyz - P;
        float d2 = dot(to_light, to_light);
        if (d2 <= 1e-20) return r;
        vec3 L = to_light * inversesqrt(d2);
        bool spot = type == LIGHT_SPOT;
        float att = spot ? spot_attenuation(light, -L) : 1.0;
        float R = light.strength.w;
        if (R <= 0.0) {
            if (att <= 0.0) return r;
            LobeEval e = principled_eval(s, w, N, V, L);
            vec3 scale = S * (att / (4.0 * M_PI_F * d2));
            r.diffuse = e.diffuse * scale;
            r.glossy = e.glossy * (scale * smooth_side(s, L));
            return r;
        }
        vec3 a, b;
        make_basis(L, a, b);
        /* Spot attenuation per sampled disk point, as Cycles 3.4 does. */
        vec3 radiance = S / (4.0 * M_PI_F * M_PI_F * R * R);
        return shade_planar_light(to_light, a * R, b * R, true, true, -L, radiance, light, spot, att, s, w, N, V);
    }
#endif
#ifdef HAS_SUN_LIGHTS
    if (type == LIGHT_SUN) {
        /* One point of the sun's disk per sample (angular radius in
         * strength.w), uniform over the tangent disk as Cycles'
         * distant_light_sample; sample 0 looks at the centre. */
        vec3 L = -light.direction.xyz;
        float tan_r = light.axis_x.w;
        if (tan_r > 0.0) {
            vec3 t, bt;
            make_basis(L, t, bt);
            vec2 d = concentric_disk(frame.sample_shift.xy) * tan_r;
            L = normalize(L + t * d.x + bt * d.y);
        }
        LobeEval e = principled_eval(s, w, N, V, L);
        r.diffuse = e.diffuse * S;
        /* A sharp specular lobe also samples its own direction, combined with
         * the disk point by the power heuristic, as Cycles' MIS of light and
         * BSDF rays for a sun with an angle: the point alone makes fireflies
         * where the lobe is narrower than the disk. Solid-angle pdfs: the
         * disk point invarea / cos^3 (distant_light_sample), the BSDF
         * direction principled_specular_pdf; a BSDF direction inside the disk
         * sees radiance S invarea / cos^3 (distant_light_sample_from_
         * intersection: eval_fac = pdf). */
        const bool sun_mis = tan_r > 0.0 && w.specular != 0.0 && w.alpha2 > 1e-7 && w.alpha2 < 0.0625;
        if (sun_mis) {
            float invarea = 1.0 / (M_PI_F * tan_r * tan_r);
            float cos_l = dot(L, -light.direction.xyz);
            float ratio = min(principled_specular_pdf(w, N, V, L) * cos_l * cos_l * cos_l / invarea, 1e18);
            vec3 spec = principled_specular(w, N, V, L) * (smooth_side(s, L) / (1.0 + ratio * ratio));
            r.glossy = (spec + vec3(principled_clearcoat(w, N, V, L) * smooth_side(s, L))) * S;
            vec3 Lb = sample_ggx_vndf(N, V, sqrt(w.alpha2), fract(frame.sample_shift.yx + vec2(0.5, 0.25)));
            float cos_b = dot(Lb, -light.direction.xyz);
            if (cos_b >= light.axis_y.w) {
                float pb = principled_specular_pdf(w, N, V, Lb);
                if (pb > 1e-30) {
                    float rb = min(invarea / (cos_b * cos_b * cos_b * pb), 1e18);
                    r.glossy += principled_specular(w, N, V, Lb) *
                                (S * invarea / (cos_b * cos_b * cos_b) / pb / (1.0 + rb * rb));
                }
            }
        } else {
            r.glossy = e.glossy * (S * smooth_side(s, L));
        }
        /* A mirror sees the sun's disk where R falls inside it, with the
         * radiance Cycles gives a ray that hits it: S invarea / cos^3 of its
         * angle to the sun's axis, invarea = 1 / (pi tan^2 r)
         * (distant_light_sample_from_intersection). */
        vec3 mirror = principled_mirror_weight(w, N, V);
        float cos_r = dot(reflect(-V, N), -light.direction.xyz);
        if (tan_r > 0.0 && mirror != vec3(0.0) && cos_r >= light.axis_y.w)
            r.glossy += mirror * S / (M_PI_F * tan_r * tan_r * cos_r * cos_r * cos_r);
        return r;
    }
#endif
#ifdef HAS_AREA_LIGHTS
    if (type == LIGHT_AREA) {
        vec3 c = light.position_type.xyz - P;
        /* One-sided: only points in front of the emitting (-Z) face. */
        if (dot(-c, light.direction.xyz) <= 0.0) return r;
        float A = light.params.x;
        if (A <= 0.0) return r;
        vec3 radiance = S / (4.0 * A);
        return shade_planar_light(c, light.axis_x.xyz, light.axis_y.xyz, int(light.axis_y.w) == AREA_ELLIPSE, false,
                                  light.direction.xyz, radiance, light, false, 1.0, s, w, N, V);
    }
#endif
    return r;
}

#ifdef HAS_MESH_LIGHTS
layout(std430, binding = SSBO_EMITTERS) readonly buffer Emitters { GpuEmitterTriangle emitters[]; };
#ifdef HAS_EMISSION_TEXELS
/* Textured emitters (emitter_module.h): each such triangle's radiance baked
 * at T(T + 1)/2 texels, texel (i, j) (i + j <= T - 1) at barycentric weights
 * ((i + 1/2), (j + 1/2)) / (T + 1/2) of vertices 1 and 2, rows j after one
 * another; rgb per texel. */
layout(std430, binding = SSBO_EMISSION_TEXELS) readonly buffer EmissionTexels {
    uint emission_tile_size;
    uint emission_texels_pad[3];
    float emission_texels[];
};
#endif

/* The radiance of triangle t at the point with barycentric weights b of its
 * vertices 1 and 2 (X = v0 + b.x e1 + b.y e2): its constant radiance, or for
 * a textured one (radiance.w = its tile + 1) the texel holding that point,
 * the nearest of the tile's (EmitterModule::radiance_at does the same). */
vec3 emitter_radiance(GpuLight light, GpuEmitterTriangle t, vec2 b) {
#ifdef HAS_EMISSION_TEXELS
    if (t.radiance.w > 0.0) {
        const int T = int(emission_tile_size);
        int i = clamp(int(floor(b.x * (float(T) + 0.5))), 0, T - 1);
        int j = clamp(int(floor(b.y * (float(T) + 0.5))), 0, T - 1);
        if (i + j > T - 1) {
            if (b.x >= b.y) i = T - 1 - j; else j = T - 1 - i;
        }
        const uint texel = uint(t.radiance.w - 1.0) * uint(T * (T + 1) / 2) + uint(j * T - j * (j - 1) / 2 + i);
        return vec3(emission_texels[3u * texel], emission_texels[3u * texel + 1u], emission_texels[3u * texel + 2u]);
    }
#endif
    return t.radiance.rgb;
}

/* Light from point X (unit winding normal n, radiance Le, density pdf in
 * area measure) of an emitter: f cos Le cos_l / (d^2 pdf), cos_l = |N.I| for
 * an open mesh (Cycles' emissive_simple_eval: both sides emit), the side's
 * own cosine for a closed one (side = +-1: its other side faces its inside). */
LightContribution mesh_light_point(SurfaceParams s, PrincipledWeights w, vec3 P, vec3 N, vec3 V, vec3 X, vec3 n,
                                   vec3 Le, float pdf, float side) {
    LightContribution r;
    r.diffuse = vec3(0.0);
    r.glossy = vec3(0.0);
    vec3 to_light = X - P;
    float d2 = dot(to_light, to_light);
    if (!(d2 > 1e-20) || !(pdf > 0.0)) return r;
    vec3 L = to_light * inversesqrt(d2);
    float cos_l = side == 0.0 ? abs(dot(n, L)) : max(-side * dot(n, L), 0.0);
    vec3 scale = Le * (cos_l / (d2 * pdf));
    /* A point almost on the receiver with a tiny density: no finite estimate. */
    if (any(isinf(scale)) || any(isnan(scale))) return r;
    LobeEval e = principled_eval(s, w, N, V, L);
    r.diffuse = e.diffuse * scale;
    r.glossy = e.glossy * (scale * smooth_side(s, L));
    return r;
}

/* An emissive mesh's unoccluded light: MESH_LIGHT_SAMPLES points of its
 * own (MESH_LIGHT_SAMPLES_NEAR within twice its bounding radius) per pixel
 * and film sample (a triangle by power from the light's CDF,
 * uniform on it, Turk 1990), stratified over the film's samples by the R2
 * sequence (Roberts 2018) rotated per pixel and light (pcg4d). */
LightContribution mesh_light_unoccluded(GpuLight light, SurfaceParams s, PrincipledWeights w, vec3 P, vec3 N,
                                        vec3 V) {
    LightContribution r;
    r.diffuse = vec3(0.0);
    r.glossy = vec3(0.0);
    uint first = uint(light.direction.x), count = uint(light.direction.y);
    if (count == 0u) return r;
    uvec4 h = uvec4(gl_GlobalInvocationID.xy, first * 0x9E3779B9u + 0x632BE5ABu, 0x85EBCA6Bu);
    h = h * 1664525u + 1013904223u;
    h.x += h.y * h.w; h.y += h.z * h.x; h.z += h.x * h.y; h.w += h.y * h.z;
    h ^= h >> 16u;
    h.x += h.y * h.w; h.y += h.z * h.x; h.z += h.x * h.y; h.w += h.y * h.z;
    /* Near the emitter (within its size) the 1/d^2 of area sampling makes
     * its own points' estimate noisy: more of them there. */
    vec3 to_center = light.position_type.xyz - P;
    float radius = light.direction.w;
    int points = dot(to_center, to_center) < 4.0 * radius * radius ? MESH_LIGHT_SAMPLES_NEAR : MESH_LIGHT_SAMPLES;
    for (int k = 0; k < points; ++k) {
        uint index = uint(frame.sample_shift.w) * uint(MESH_LIGHT_SAMPLES_NEAR) + uint(k);
        uvec2 bits = h.xy + index * uvec2(0xC13FA9A9u, 0x91E10DA5u);
        vec2 u = vec2(bits >> 8u) * (1.0 / 16777216.0);
        /* The first triangle whose running CDF exceeds u.x. */
        uint lo = first, hi = first + count - 1u;
        while (lo < hi) {
            uint mid = (lo + hi) >> 1u;
            if (emitters[mid].v0.w > u.x) hi = mid; else lo = mid + 1u;
        }
        GpuEmitterTriangle t = emitters[lo];
        float p = t.e2.w;
        float a = p > 0.0 ? clamp((u.x - (t.v0.w - p)) / p, 0.0, 1.0) : 0.5;
        float sa = sqrt(a);
        vec3 X = t.v0.xyz + t.e1.xyz * (sa * (1.0 - u.y)) + t.e2.xyz * (sa * u.y);
        vec3 n = normalize(cross(t.e1.xyz, t.e2.xyz));
        vec3 Le = emitter_radiance(light, t, vec2(sa * (1.0 - u.y), sa * u.y));
        LightContribution c = mesh_light_point(s, w, P, N, V, X, n, Le, p / t.e1.w, light.axis_y.w);
        r.diffuse += c.diffuse * (1.0 / float(points));
        r.glossy += c.glossy * (1.0 / float(points));
    }
    return r;
}
#endif

/* The light's unshadowed contribution, and in `visible` this sample's
 * visibility of its light point (1 without a shadow map): the sample's
 * shadowed light is their product. An emissive mesh returns its shadowed
 * light with visible = 1: its own points' light minus what is blocked at
 * the sample's shared point, where its cube map looks from (a control
 * variate, as the world's occlusion: L(x_s) f G (1 - V(x_s)) / p(x_s) has
 * the expectation of the blocked light). */
LightContribution shade_light(GpuLight light, SurfaceParams s, PrincipledWeights w, vec3 P, vec3 N, vec3 V,
                              out float visible) {
#ifdef HAS_MESH_LIGHTS
    if (int(light.position_type.w) == LIGHT_MESH) {
        LightContribution r = mesh_light_unoccluded(light, s, w, P, N, V);
        visible = 1.0;
#ifdef HAS_SHADOWS
        int shadow = int(light.params.w);
        if (shadow >= 0) {
            float blocked = 1.0 - shadow_visibility(shadow, P, N);
            if (blocked > 0.0) {
                LightContribution c = mesh_light_point(s, w, P, N, V, light.axis_x.xyz, light.axis_y.xyz,
                                                       light.strength.rgb, light.axis_x.w, light.axis_y.w);
                r.diffuse -= c.diffuse * blocked;
                r.glossy -= c.glossy * blocked;
            }
        }
#endif
        return r;
    }
#endif
    LightContribution r = shade_light_unshadowed(light, s, w, P, N, V);
    visible = 1.0;
#ifdef HAS_SHADOWS
    int shadow = int(light.params.w);
    if (shadow >= 0 && (r.diffuse != vec3(0.0) || r.glossy != vec3(0.0))) visible = shadow_visibility(shadow, P, N);
#endif
    return r;
}
