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

/* The pixel being shaded: the lighting pass's (its main sets it: later
 * batches run over a list of pixels, not the image's grid), the forward
 * pass's fragment, or another compute pass's invocation. */
#if defined(LIGHTING_PASS)
uvec2 lighting_pixel;
uvec2 shading_pixel() { return lighting_pixel; }
#elif defined(FORWARD_PASS)
uvec2 shading_pixel() { return uvec2(gl_FragCoord.xy); }
#else
uvec2 shading_pixel() { return gl_GlobalInvocationID.xy; }
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
/* A per-pixel, per-salt rotation (pcg4d hash) of the light sequences
 * below, in 32-bit fixed point. */
uvec2 light_ray_rotation(uint salt) {
    uvec4 v = uvec4(shading_pixel(), salt * 0x9E3779B9u + 0x7F4A7C15u, 0x2545F491u);
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    return v.xy;
}

/* Two numbers in [0, 1) per pixel, film sample and `salt`: the R2 sequence
 * over the samples (Roberts 2018, in 32-bit fixed point), rotated per pixel
 * and salt (decorrelated pixels: noise, not bands). Every salt steps by the
 * same alphas: two salts' numbers differ by a constant shift, so they are
 * not independent of each other (fine for estimates that are summed). */
vec2 light_ray_sequence(uint salt) {
    uvec2 x = light_ray_rotation(salt) + uint(frame.sample_shift.w) * uvec2(0xC13FA9A9u, 0x91E10DA5u);
    return vec2(x >> 8u) * (1.0 / 16777216.0);
}

/* As light_ray_sequence, but independent of it and of the film's own
 * sequence (sample_point: R4, the pixel jitter and the shared light points,
 * frame.sample_shift.xy): the last two dimensions of the R3 sequence
 * (alpha_i = phi3^-i, phi3^4 = phi3 + 1; the world's world_sequence uses
 * R3 too, but no estimate multiplies the two). Fields of degree 3 (R2), 4
 * (R3) and 5 (R4) share no irrationals, so the alphas are rationally
 * independent and over the samples the numbers of the three sequences fill
 * their joint cube evenly. For an estimate that multiplies two samples (the
 * shadow probe times the control variate), whose expectation is the
 * product only when they are independent: with the probe on
 * light_ray_sequence, its point was a fixed shift of the traced point's
 * (per pixel), and each pixel of a penumbra kept its own bias. */
vec2 light_ray_independent(uint salt) {
    uvec2 x = light_ray_rotation(salt) + uint(frame.sample_shift.w) * uvec2(0xABC98388u, 0x8CB92BA7u);
    return vec2(x >> 8u) * (1.0 / 16777216.0);
}

/* The GGX directions the specular lobe samples sized lights and the sun's
 * disk with: a sequence of their own, rotated per pixel. One shared by every
 * pixel (as the light points must be, for the shadow maps) correlates the
 * pixels' errors: the 64-segment sphere's highlight under an area light
 * summed 6 % bright at 64 samples and 1.3 % at 256 against Cycles, converging
 * only slowly (measured; 0.2 % at 4096). */
#define SALT_PLANAR_BSDF 0x3C6EF372u
#define SALT_SUN_BSDF 0xA54FF53Au

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
    const vec2 bsdf_shift = bsdf_sampling ? light_ray_sequence(SALT_PLANAR_BSDF) : vec2(0.0);
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
                vec2 ub = (vec2(i, j) + bsdf_shift) / float(G);
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

/* This sample's direction towards the sun: one point of its disk
 * (angular radius atan(axis_x.w)), uniform over the tangent disk as Cycles'
 * distant_light_sample; sample 0 looks at the centre. */
vec3 sun_sample_direction(GpuLight light) {
    vec3 L = -light.direction.xyz;
    float tan_r = light.axis_x.w;
    if (tan_r > 0.0) {
        vec3 t, bt;
        make_basis(L, t, bt);
        vec2 d = concentric_disk(frame.sample_shift.xy) * tan_r;
        L = normalize(L + t * d.x + bt * d.y);
    }
    return L;
}

/* Light kinds, the groups of types that share code: LIGHT_POINT (point and
 * spot lights), LIGHT_SUN, LIGHT_AREA, LIGHT_MESH; LIGHT_ANY_KIND reads the
 * type from the light. A caller that passes a literal kind gets only that
 * kind's code once the compiler has inlined and folded the tests: llvmpipe
 * runs both sides of every branch (masked SIMD lanes, no jump over a side
 * no lane takes), so a loop body holding every type's code costs all of
 * them per light; there the lighting pass loops over each kind apart
 * (lighting_comp.glsl LIGHT_KIND_LOOPS). */
#define LIGHT_ANY_KIND (-1)
int light_kind(int type) { return type <= LIGHT_SPOT ? LIGHT_POINT : type; }
bool is_kind(int kind, int type, int want) { return kind == LIGHT_ANY_KIND ? light_kind(type) == want : kind == want; }

LightContribution shade_light_unshadowed(int kind, GpuLight light, SurfaceParams s, PrincipledWeights w, vec3 P,
                                         vec3 N, vec3 V) {
    LightContribution r;
    r.diffuse = vec3(0.0);
    r.glossy = vec3(0.0);
    const int type = int(light.position_type.w);
    const vec3 S = light.strength.rgb;

#if defined(HAS_POINT_LIGHTS) || defined(HAS_SPOT_LIGHTS)
    if (is_kind(kind, type, LIGHT_POINT)) {
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
    if (is_kind(kind, type, LIGHT_SUN)) {
        /* One point of the sun's disk per sample (angular radius in
         * strength.w), uniform over the tangent disk as Cycles'
         * distant_light_sample; sample 0 looks at the centre. */
        float tan_r = light.axis_x.w;
        vec3 L = sun_sample_direction(light);
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
            vec3 Lb = sample_ggx_vndf(N, V, sqrt(w.alpha2), light_ray_sequence(SALT_SUN_BSDF));
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
    if (is_kind(kind, type, LIGHT_AREA)) {
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
 * the nearest of the tile's (EmitterModule::radiance_at does the same).
 * Every sampled or intersected point of a mesh light takes its radiance
 * from here. */
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

/* ---- Sampling a triangle by the solid angle it subtends ----
 * Area sampling weighs a point by d^2 / cos_l: near the emitter (d small
 * against the triangle) that ratio spans orders of magnitude over the
 * triangle and the estimate is very noisy. A triangle that is large against
 * its distance is instead sampled uniformly in the solid angle it subtends
 * (Arvo 1995, "Stratified Sampling of Spherical Triangles"), as Cycles 3.4's
 * triangle_light_sample does (kernel/light/triangle.h), with its choice:
 * the spherical method where the longest edge exceeds the distance to the
 * triangle's plane (Cycles compares with that distance divided by 2 x the
 * area; here the distance itself), area sampling otherwise and where the
 * spherical triangle is too small or thin for float (its formulas divide by
 * sin b sin c and difference cosines near 1). The choice depends only on
 * the shading point and the triangle, so each triangle is integrated by one
 * unbiased technique; densities in solid-angle measure are
 * P(triangle) / solid angle, or P(triangle) d^2 / (A cos_l) for area
 * sampling. */
struct SphericalTriangle {
    vec3 A, B, C;              /* unit directions to v0, v1, v2 */
    float cos_a, cos_b, cos_c; /* cosines of the sides: B.C, A.C, A.B */
    float mixed;               /* |A . (B x C)| = sin(alpha) sin b sin c */
    float solid_angle;
};

/* The spherical triangle of the triangle v0 = P + p0, edges e1 and e2 seen
 * from P, if it is to be sampled by solid angle (else false). */
bool emitter_spherical_triangle(vec3 p0, vec3 e1, vec3 e2, out SphericalTriangle st) {
    st.solid_angle = 0.0;
    vec3 n = cross(e1, e2);
    float dist_n = dot(n, p0); /* distance to the plane x |n| */
    float longest2 = max(max(dot(e1, e1), dot(e2, e2)), dot(e2 - e1, e2 - e1));
    vec3 p1 = p0 + e1, p2 = p0 + e2;
    float m2 = min(min(dot(p0, p0), dot(p1, p1)), dot(p2, p2));
    if (!(longest2 * dot(n, n) > dist_n * dist_n) || !(m2 > 1e-24)) return false;
    st.A = normalize(p0);
    st.B = normalize(p1);
    st.C = normalize(p2);
    st.cos_a = dot(st.B, st.C);
    st.cos_b = dot(st.A, st.C);
    st.cos_c = dot(st.A, st.B);
    st.mixed = abs(dot(st.A, cross(st.B, st.C)));
    /* Van Oosterom and Strackee 1983: tan(omega / 2) = |A.(B x C)| / (1 + A.B + B.C + C.A). */
    float omega = 2.0 * atan(st.mixed, 1.0 + st.cos_a + st.cos_b + st.cos_c);
    /* Sides b and c at least ~0.01 rad, and at least 1e-3 sr: else area sampling. */
    if (!(omega > 1e-3) || min(1.0 - st.cos_b * st.cos_b, 1.0 - st.cos_c * st.cos_c) < 1e-4) return false;
    st.solid_angle = omega;
    return true;
}

/* The direction for u in [0,1)^2, uniform in the spherical triangle. Arvo's
 * construction: u.x picks the sub-triangle A B C' of area u.x x omega, C' on
 * the arc AC, from the angle alpha at A (cos q = A.C' from
 * cos(A') and the sides); u.y picks the point on the arc B C' by the cosine
 * of its angle to B, uniform in [C'.B, 1]. Written as Cycles writes it, with
 * cos(alpha) and sin(alpha) times sin b sin c (no inverse trigonometry):
 *   k = sin b sin c cos(A' - alpha), t = (cos c - 1) k cos(alpha) / (sin b sin c)
 *   cos q = (cos A' - cos c + t) / (1 - cos A' cos c + t). */
vec3 sample_spherical_triangle(SphericalTriangle st, vec2 u) {
    float sub_area = u.x * st.solid_angle;
    float s = sin(sub_area), c = cos(sub_area);
    float cos_alpha = st.cos_a - st.cos_b * st.cos_c; /* x sin b sin c */
    float k = c * cos_alpha + s * st.mixed;
    float t = (st.cos_c - 1.0) * k * cos_alpha / ((1.0 - st.cos_b * st.cos_b) * (1.0 - st.cos_c * st.cos_c));
    float q = clamp((c - st.cos_c + t) / (1.0 - c * st.cos_c + t), -1.0, 1.0);
    vec3 U = normalize(st.C - st.cos_b * st.A);
    vec3 C2 = q * st.A + sqrt(max(1.0 - q * q, 0.0)) * U;
    float cb = dot(C2, st.B);
    float z = 1.0 - u.y * (1.0 - cb);
    vec3 W = C2 - cb * st.B;
    float w2 = dot(W, W);
    return w2 > 0.0 ? z * st.B + sqrt(max(1.0 - z * z, 0.0)) * inversesqrt(w2) * W : st.B;
}

/* Where the ray from the shading point along D meets the triangle
 * p0, e1, e2 (relative to it), Moller-Trumbore: distance in hit.x,
 * barycentric weights of v1 and v2 in hit.yz. `clamp_inside`: a direction
 * sampled inside the triangle, snapped into it where float puts it just
 * outside (returns true); otherwise false when the ray misses. */
bool emitter_triangle_hit(vec3 p0, vec3 e1, vec3 e2, vec3 D, bool clamp_inside, out vec3 hit) {
    hit = vec3(0.0);
    vec3 pv = cross(D, e2);
    float det = dot(e1, pv);
    if (det == 0.0) return clamp_inside;
    float inv = 1.0 / det;
    vec3 tv = -p0;
    vec3 qv = cross(tv, e1);
    vec2 b = vec2(dot(tv, pv), dot(D, qv)) * inv;
    hit.x = dot(e2, qv) * inv;
    if (clamp_inside) {
        b = max(b, vec2(0.0));
        float sum = b.x + b.y;
        if (sum > 1.0) b /= sum;
        hit.yz = b;
        return true;
    }
    hit.yz = b;
    return hit.x > 0.0 && b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0;
}

/* What a direction L of the mesh light gives, with weight Le / (its density
 * in solid angle x the number of such samples); the specular lobe's share
 * `spec_mis` (its MIS weight: the BSDF's own directions give the rest). */
LightContribution mesh_light_value(SurfaceParams s, PrincipledWeights w, vec3 N, vec3 V, vec3 L, vec3 weight,
                                   float spec_mis) {
    LightContribution c;
    c.diffuse = c.glossy = vec3(0.0);
    /* A density near 0 (an area-sampled point almost on the receiver): no finite estimate. */
    if (any(isinf(weight)) || any(isnan(weight))) return c;
    c.diffuse = principled_eval_diffuse(s, w, N, V, L) * weight;
    c.glossy = (principled_specular(w, N, V, L) * spec_mis + vec3(principled_clearcoat(w, N, V, L))) *
               (weight * smooth_side(s, L));
    return c;
}

/* ---- Shadow rays to mesh lights: one picked candidate's ray ----
 * (One per pixel and sample for all the mesh lights with
 * MESH_LIGHT_RAY_POOL, the default; one per light without it.)
 * The light's points and the lobe's hits give candidates c_k, each with its
 * own direction; traced one by one (MESH_LIGHT_RAY_EVERY_POINT) the
 * shadowed estimate is sum_k c_k V_k, up to MESH_LIGHT_SAMPLES_NEAR +
 * 2 MESH_LIGHT_BSDF_SAMPLES rays. Instead one candidate j is picked with
 * probability w_j / W (w = the candidate's summed RGB, W = sum_k w_k) and
 * only its ray is traced: c_j (W / w_j) V_j has, over the pick, the
 * expectation sum_k c_k V_k exactly (an unbiased estimator of the traced
 * sum, as resampled importance sampling's selection by the unshadowed
 * contribution: Talbot et al. 2005, Bitterli et al. 2020 "ReSTIR", its
 * one-sample form). Where the light is wholly visible or wholly blocked
 * from P it equals the traced sum; only in penumbrae does it add noise.
 * The pick streams over the candidates (weighted reservoir sampling,
 * Chao 1982) with one number per pixel, light and film sample, rescaled at
 * every step so it stays uniform; that number is the rotated 1D sequence of
 * the R3 generator's first alpha (independent of the points' R2 numbers). */
struct MeshLightReservoir {
    LightContribution picked;
    vec3 L;
    float dist, w_picked, w_sum, u;
    uint owner; /* the picked candidate's light (light groups) */
};

void reservoir_start(out MeshLightReservoir res, uint bits) {
    res.picked.diffuse = res.picked.glossy = res.L = vec3(0.0);
    res.dist = res.w_picked = res.w_sum = 0.0;
    res.u = float((bits + uint(frame.sample_shift.w) * 0xD1B54A32u) >> 8u) * (1.0 / 16777216.0);
    res.owner = 0u;
}

void reservoir_add(inout MeshLightReservoir res, LightContribution c, vec3 L, float dist, uint owner) {
    float w = dot(abs(c.diffuse) + abs(c.glossy), vec3(1.0));
    if (!(w > 0.0) || isinf(w)) return;
    res.w_sum += w;
    float p = w / res.w_sum;
    if (res.u < p) {
        res.u = res.u / p;
        res.picked = c;
        res.L = L;
        res.dist = dist;
        res.w_picked = w;
        res.owner = owner;
    } else {
        res.u = (res.u - p) / (1.0 - p);
    }
    res.u = min(res.u, 0.99999994);
}

#ifdef SHADOW_RAYS
/* The picked candidate's light, c_j (W / w_j) V_j. */
LightContribution reservoir_trace(MeshLightReservoir res, SurfaceParams s, vec3 P) {
    LightContribution r;
    r.diffuse = r.glossy = vec3(0.0);
    if (res.w_picked > 0.0) {
        float scale = shadow_ray(s, P, res.L, res.dist) * (res.w_sum / res.w_picked);
        r.diffuse = res.picked.diffuse * scale;
        r.glossy = res.picked.glossy * scale;
    }
    return r;
}
#endif

#if defined(SHADOW_RAYS) && defined(MESH_LIGHT_RAY_POOL) && !defined(MESH_LIGHT_RAY_EVERY_POINT)
/* MESH_LIGHT_RAY_POOL: one ray per pixel and sample for all the mesh lights
 * together: each light's candidates, times its selection weight, go into
 * this pixel-wide reservoir (the caller sets mesh_ray_pool_light and
 * mesh_ray_pool_weight before each light, starts it with
 * mesh_ray_pool_start and traces it with reservoir_trace after the last).
 * The same estimator over the union of the lights' candidates. */
#define MESH_RAY_POOL
MeshLightReservoir mesh_ray_pool;
uint mesh_ray_pool_light = 0u;
float mesh_ray_pool_weight = 1.0;
void mesh_ray_pool_start() {
    uvec4 v = uvec4(shading_pixel(), 0x4D455348u, 0x2545F491u);
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    reservoir_start(mesh_ray_pool, v.x);
}
#endif

/* Power heuristic weight (Veach 1997) of a technique with n_a samples of
 * density p_a against one with n_b samples of density p_b, from their ratio
 * (either density alone may overflow float). */
float power_heuristic(float n_a, float p_a, float n_b, float p_b) {
    float ratio = min((n_b * p_b) / (n_a * p_a), 1e18);
    return 1.0 / (1.0 + ratio * ratio);
}

/* The solid-angle density with which the light's own points reach the
 * triangle p0, e1, e2 (relative to P; probability p) along D, hit at
 * distance t: p / solid angle for a triangle sampled by it, else
 * p t^2 / (A cos_l). */
float emitter_direction_pdf(vec3 p0, vec3 e1, vec3 e2, float p, float area, vec3 D, float t) {
    SphericalTriangle st;
    if (emitter_spherical_triangle(p0, e1, e2, st)) return p / st.solid_angle;
    vec3 n = cross(e1, e2);
    float cos_l = abs(dot(n, D)) * inversesqrt(dot(n, n));
    return p * t * t / (area * cos_l);
}

/* An emissive mesh's unoccluded light, per pixel and film sample:
 *  - MESH_LIGHT_SAMPLES points of its own (MESH_LIGHT_SAMPLES_NEAR within
 *    twice its bounding radius): a triangle by power from the light's CDF,
 *    then a direction uniform in the solid angle it subtends where it is
 *    large against its distance, or a point uniform on it (Turk 1990);
 *  - for a sharp specular lobe and a light of at most
 *    MESH_LIGHT_TRACED_TRIANGLES triangles, MESH_LIGHT_BSDF_SAMPLES
 *    directions of the lobe (GGX visible normals) traced against every
 *    triangle of the light (a large light's chunk by chunk, those whose
 *    bounding sphere the direction meets); the specular lobe of both kinds
 *    of samples is weighted by the power heuristic, per triangle and
 *    direction (the unoccluded integral is the sum over the triangles of
 *    their own integrals: a direction through two of them counts both, as
 *    the light's points do);
 *  - for a mirror lobe, its reflected ray (the nearest triangle it meets).
 * The numbers are stratified over the film's samples by the R2 sequence
 * (Roberts 2018), rotated per pixel and light (pcg4d). */
/* Whether the ray from P along unit D can meet the sphere (xyz centre,
 * camera-relative, w radius) nearer than `nearest`. */
bool ray_meets_sphere(vec3 P, vec3 D, vec4 sphere, float nearest) {
    vec3 to_c = sphere.xyz - P;
    float along = dot(to_c, D), c2 = dot(to_c, to_c), r2 = sphere.w * sphere.w;
    float off2 = c2 - along * along;
    if (off2 > r2 || (along < 0.0 && c2 > r2)) return false;
    return along - sqrt(max(r2 - off2, 0.0)) < nearest;
}

/* The triangles of a mesh light a ray can meet, chunk by chunk: a light of
 * at most MESH_LIGHT_CHUNK triangles is one chunk; a larger one's chunk k
 * (triangles first + k MESH_LIGHT_CHUNK on) has its bounding sphere at
 * emitters[first + count + k] (EmitterModule::finish). */
uint emitter_chunks(uint count) { return count <= uint(MESH_LIGHT_CHUNK) ? 1u : (count + uint(MESH_LIGHT_CHUNK) - 1u) / uint(MESH_LIGHT_CHUNK); }
vec4 emitter_chunk_sphere(uint first, uint count, uint k) { return emitters[first + count + k].v0; }

/* The mirror image of the light mesh_light_unoccluded last added (its part
 * of the glossy light; 0 with shadow rays, which trace it): the maps'
 * occlusion takes it as it takes a planar light's mirror image, by the
 * visibility of the sample's shared point (shade_light_kind). */
vec3 mesh_light_mirror;

LightContribution mesh_light_unoccluded(GpuLight light, SurfaceParams s, PrincipledWeights w, vec3 P, vec3 N,
                                        vec3 V) {
    LightContribution r;
    r.diffuse = vec3(0.0);
    r.glossy = vec3(0.0);
    mesh_light_mirror = vec3(0.0);
    uint first = uint(light.direction.x), count = uint(light.direction.y);
    if (count == 0u) return r;
    uvec4 h = uvec4(shading_pixel(), first * 0x9E3779B9u + 0x632BE5ABu, 0x85EBCA6Bu);
    h = h * 1664525u + 1013904223u;
    h.x += h.y * h.w; h.y += h.z * h.x; h.z += h.x * h.y; h.w += h.y * h.z;
    h ^= h >> 16u;
    h.x += h.y * h.w; h.y += h.z * h.x; h.z += h.x * h.y; h.w += h.y * h.z;
    /* Near the emitter (within its size) its light varies fast over it:
     * more points there. */
    vec3 to_center = light.position_type.xyz - P;
    float radius = light.direction.w;
    int points = dot(to_center, to_center) < 4.0 * radius * radius ? MESH_LIGHT_SAMPLES_NEAR : MESH_LIGHT_SAMPLES;
#ifdef SHADOW_RAYS
    /* Shadow rays: the sample's own visibility (a shadowed mesh light has a
     * shadow entry, params.w >= 0), so the result is the occluded light. */
    const bool traced = int(light.params.w) >= 0;
#ifdef MESH_RAY_POOL
#define MESH_RES mesh_ray_pool
    const float pool_weight = mesh_ray_pool_weight;
    const uint owner = mesh_ray_pool_light;
#else
#define MESH_RES res
    const float pool_weight = 1.0;
    const uint owner = 0u;
    MeshLightReservoir res;
    reservoir_start(res, h.x ^ h.w);
#endif
#endif
    float side = light.axis_y.w;
    /* As for the planar lights: rough lobes (alpha >= 0.25) are wide enough
     * for the light's points alone; mirrors (alpha^2 <= 1e-7) see it along
     * their reflected ray alone (below). */
    const bool mis = count <= uint(MESH_LIGHT_TRACED_TRIANGLES) && w.specular != 0.0 && w.alpha2 > 1e-7 &&
                     w.alpha2 < 0.0625;
    const float n_light = float(points), n_bsdf = float(MESH_LIGHT_BSDF_SAMPLES);
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
        vec3 p0 = t.v0.xyz - P, e1 = t.e1.xyz, e2 = t.e2.xyz;
        vec3 n = cross(e1, e2);
        /* A closed mesh's triangle seen from its inner side: no light. */
        if (side != 0.0 && side * dot(n, p0) >= 0.0) continue;
        SphericalTriangle st;
        vec3 L;
        vec2 b;
        float dist; /* to the sampled point */
        float pdf; /* solid-angle density of this triangle and direction */
        if (emitter_spherical_triangle(p0, e1, e2, st)) {
            L = sample_spherical_triangle(st, vec2(a, u.y));
            vec3 hit;
            emitter_triangle_hit(p0, e1, e2, L, true, hit);
            b = hit.yz;
            dist = hit.x;
            pdf = p / st.solid_angle;
        } else {
            float sa = sqrt(a);
            b = vec2(sa * (1.0 - u.y), sa * u.y);
            vec3 X = p0 + e1 * b.x + e2 * b.y;
            float d2 = dot(X, X);
            if (!(d2 > 1e-20)) continue;
            L = X * inversesqrt(d2);
            dist = sqrt(d2);
            float cos_l = abs(dot(n, L)) * inversesqrt(dot(n, n));
            pdf = p * d2 / (t.e1.w * cos_l);
        }
        if (!(pdf > 0.0)) continue;
        float spec_mis = mis ? power_heuristic(n_light, pdf, n_bsdf, principled_specular_pdf(w, N, V, L)) : 1.0;
        LightContribution c = mesh_light_value(s, w, N, V, L, emitter_radiance(light, t, b) / (pdf * n_light), spec_mis);
#ifdef SHADOW_RAYS
        if (traced) {
#ifdef MESH_LIGHT_RAY_EVERY_POINT
            float visible = shadow_ray(s, P, L, dist);
            r.diffuse += c.diffuse * visible;
            r.glossy += c.glossy * visible;
#else
            c.diffuse *= pool_weight;
            c.glossy *= pool_weight;
            reservoir_add(MESH_RES, c, L, dist, owner);
#endif
            continue;
        }
#endif
        r.diffuse += c.diffuse;
        r.glossy += c.glossy;
    }
    if (mis) {
        /* The lobe's directions that can reach the light's bounding sphere,
         * then every triangle against all of them at once. */
        float alpha = sqrt(w.alpha2);
        vec3 Lb[MESH_LIGHT_BSDF_SAMPLES], spec[MESH_LIGHT_BSDF_SAMPLES], Le[MESH_LIGHT_BSDF_SAMPLES];
        float pb[MESH_LIGHT_BSDF_SAMPLES];
        bool any_ray = false;
        for (int j = 0; j < MESH_LIGHT_BSDF_SAMPLES; ++j) {
            uint index = uint(frame.sample_shift.w) * uint(MESH_LIGHT_BSDF_SAMPLES) + uint(j);
            uvec2 bits = h.zw + index * uvec2(0xC13FA9A9u, 0x91E10DA5u);
            Lb[j] = sample_ggx_vndf(N, V, alpha, vec2(bits >> 8u) * (1.0 / 16777216.0));
            pb[j] = principled_specular_pdf(w, N, V, Lb[j]);
            spec[j] = pb[j] > 1e-30 ? principled_specular(w, N, V, Lb[j]) * smooth_side(s, Lb[j]) : vec3(0.0);
            if (!ray_meets_sphere(P, Lb[j], vec4(light.position_type.xyz, radius), 3.0e38)) spec[j] = vec3(0.0);
            Le[j] = vec3(0.0);
            any_ray = any_ray || spec[j] != vec3(0.0);
        }
        const uint chunks = any_ray ? emitter_chunks(count) : 0u;
        for (uint k = 0u; k < chunks; ++k) {
            bool meets[MESH_LIGHT_BSDF_SAMPLES];
            bool any_meets = false;
            for (int j = 0; j < MESH_LIGHT_BSDF_SAMPLES; ++j) {
                meets[j] = spec[j] != vec3(0.0) &&
                           (chunks == 1u || ray_meets_sphere(P, Lb[j], emitter_chunk_sphere(first, count, k), 3.0e38));
                any_meets = any_meets || meets[j];
            }
            const uint lo = first + k * uint(MESH_LIGHT_CHUNK), hi = min(lo + uint(MESH_LIGHT_CHUNK), first + count);
            for (uint i = lo; any_meets && i < hi; ++i) {
                GpuEmitterTriangle t = emitters[i];
                vec3 p0 = t.v0.xyz - P, e1 = t.e1.xyz, e2 = t.e2.xyz;
                if (side != 0.0 && side * dot(cross(e1, e2), p0) >= 0.0) continue;
                for (int j = 0; j < MESH_LIGHT_BSDF_SAMPLES; ++j) {
                    vec3 hit;
                    if (!meets[j] || !emitter_triangle_hit(p0, e1, e2, Lb[j], false, hit)) continue;
                    float pl = emitter_direction_pdf(p0, e1, e2, t.e2.w, t.e1.w, Lb[j], hit.x);
                    vec3 Le_hit = emitter_radiance(light, t, hit.yz) * power_heuristic(n_bsdf, pb[j], n_light, pl);
#ifdef SHADOW_RAYS
                    if (traced) {
#ifdef MESH_LIGHT_RAY_EVERY_POINT
                        Le[j] += Le_hit * shadow_ray(s, P, Lb[j], hit.x);
#else
                        LightContribution c;
                        c.diffuse = vec3(0.0);
                        c.glossy = spec[j] * Le_hit * (pool_weight / (pb[j] * n_bsdf));
                        reservoir_add(MESH_RES, c, Lb[j], hit.x, owner);
#endif
                        continue;
                    }
#endif
                    Le[j] += Le_hit;
                }
            }
        }
        for (int j = 0; j < MESH_LIGHT_BSDF_SAMPLES; ++j)
            if (spec[j] != vec3(0.0)) r.glossy += spec[j] * Le[j] / (pb[j] * n_bsdf);
    }
    /* A mirror lobe (alpha^2 <= 1e-7) reflects only along R: its light is
     * the lobe's weight times the radiance where R first meets the light's
     * triangles from their emitting side, as Cycles' BSDF ray of a delta
     * lobe adds the emission of the mesh it meets (PATH_RAY_TERMINATE_ON_
     * NEXT_SURFACE at max_bounces 0; no light sample can reach a delta lobe,
     * so no MIS). As for the glossy lobe's directions, only lights of at
     * most MESH_LIGHT_TRACED_TRIANGLES triangles are met (bounded loops;
     * larger ones are not reflected, warned: Renderer). */
    vec3 mirror = principled_mirror_weight(w, N, V);
    if (mirror != vec3(0.0) && count <= uint(MESH_LIGHT_TRACED_TRIANGLES)) {
        vec3 R = reflect(-V, N);
        if (ray_meets_sphere(P, R, vec4(light.position_type.xyz, radius), 3.0e38)) {
            float nearest = 3.0e38;
            vec3 Le_hit = vec3(0.0);
            const uint chunks = emitter_chunks(count);
            for (uint k = 0u; k < chunks; ++k) {
                if (chunks > 1u && !ray_meets_sphere(P, R, emitter_chunk_sphere(first, count, k), nearest)) continue;
                const uint lo = first + k * uint(MESH_LIGHT_CHUNK), hi = min(lo + uint(MESH_LIGHT_CHUNK), first + count);
                for (uint i = lo; i < hi; ++i) {
                    GpuEmitterTriangle t = emitters[i];
                    vec3 p0 = t.v0.xyz - P, e1 = t.e1.xyz, e2 = t.e2.xyz;
                    if (side != 0.0 && side * dot(cross(e1, e2), p0) >= 0.0) continue;
                    vec3 hit;
                    if (!emitter_triangle_hit(p0, e1, e2, R, false, hit) || hit.x >= nearest) continue;
                    nearest = hit.x;
                    Le_hit = emitter_radiance(light, t, hit.yz);
                }
            }
            vec3 value = mirror * Le_hit;
            if (nearest < 3.0e38 && value != vec3(0.0)) {
#ifdef SHADOW_RAYS
                if (traced) {
#ifdef MESH_LIGHT_RAY_EVERY_POINT
                    r.glossy += value * shadow_ray(s, P, R, nearest);
#else
                    LightContribution c;
                    c.diffuse = vec3(0.0);
                    c.glossy = value * pool_weight;
                    reservoir_add(MESH_RES, c, R, nearest, owner);
#endif
                } else
#endif
                {
                    r.glossy += value;
                    mesh_light_mirror = value;
                }
            }
        }
    }
#if defined(SHADOW_RAYS) && !defined(MESH_LIGHT_RAY_EVERY_POINT) && !defined(MESH_RAY_POOL)
    if (traced) {
        LightContribution t = reservoir_trace(res, s, P);
        r.diffuse += t.diffuse;
        r.glossy += t.glossy;
    }
#endif
#undef MESH_RES
    return r;
}
#endif

#ifdef SHADOW_RAYS
/* This sample's visibility of a light seen as one point per sample: the
 * sun's disk point the unshadowed term used (frame.sample_shift), a delta
 * point or spot light. The product with the unshadowed term is exactly that
 * point's shadowed light. */
float light_ray_visibility(GpuLight light, vec3 P, SurfaceParams s) {
    if (int(light.position_type.w) == LIGHT_SUN) {
        return shadow_ray(s, P, sun_sample_direction(light), -1.0);
    }
    vec3 v = light.position_type.xyz - P;
    float dist = length(v);
    return dist > 0.0 ? shadow_ray(s, P, v / dist, dist) : 1.0;
}


/* One more sample of each strategy of a disk or area light's unshadowed
 * term (shade_planar_light's arguments: c, a, b the centre and half axes
 * relative to P), unoccluded (F) and traced (D: times each ray's
 * transmittance):
 *  - a point uniform on the light (density 1 / area): f cos Le cos_l A / t^2,
 *    the specular lobe weighted by the power heuristic where that lobe is
 *    also sampled by direction;
 *  - that lobe's own GGX direction, where it meets the light, with its weight;
 *  - a mirror lobe's reflected ray.
 * Each has the expectation of its strategy's part of the unshadowed term. */
struct PlanarSamples {
    LightContribution unoccluded, direct;
};

PlanarSamples planar_light_samples(vec3 c, vec3 a, vec3 b, bool ellipse, vec3 emit_dir, vec3 radiance,
                                   GpuLight light, bool spot, uint salt, SurfaceParams s, PrincipledWeights w,
                                   vec3 P, vec3 N, vec3 V) {
    PlanarSamples r;
    r.unoccluded.diffuse = r.unoccluded.glossy = r.direct.diffuse = r.direct.glossy = vec3(0.0);
    float area = ellipse ? M_PI_F * length(a) * length(b) : 4.0 * length(a) * length(b);
    const bool bsdf_sampling = w.specular != 0.0 && w.alpha2 > 1e-7 && w.alpha2 < 0.0625;
    vec2 u = light_ray_sequence(salt);
    vec2 xy = ellipse ? concentric_disk(u) : 2.0 * u - 1.0;
    vec3 pt = c + a * xy.x + b * xy.y;
    float t2 = dot(pt, pt);
    if (t2 > 1e-20) {
        float t = sqrt(t2);
        vec3 L = pt / t;
        float cos_l = -dot(emit_dir, L);
        if (cos_l > 0.0) {
            float geom = cos_l / t2 * area;
            float att = spot ? spot_attenuation(light, -L) : 1.0;
            float side = smooth_side(s, L);
            vec3 diff = principled_eval_diffuse(s, w, N, V, L) * (att * geom);
            vec3 spec = principled_specular(w, N, V, L) * side;
            float cc = principled_clearcoat(w, N, V, L) * side;
            if (bsdf_sampling) {
                float ratio = min(principled_specular_pdf(w, N, V, L) * cos_l * area / t2, 1e18);
                spec *= 1.0 / (1.0 + ratio * ratio);
            }
            vec3 gl = (spec + vec3(cc)) * (att * geom);
            if (any(greaterThan(diff + gl, vec3(0.0)))) {
                float T = shadow_ray(s, P, L, t);
                r.unoccluded.diffuse += diff;
                r.unoccluded.glossy += gl;
                r.direct.diffuse += diff * T;
                r.direct.glossy += gl * T;
            }
        }
    }
    if (bsdf_sampling) {
        vec3 Lb = sample_ggx_vndf(N, V, sqrt(w.alpha2), light_ray_sequence(salt + 1u));
        float tb, cos_b;
        if (emitter_hit(c, a, b, ellipse, emit_dir, Lb, tb, cos_b)) {
            float pb = principled_specular_pdf(w, N, V, Lb);
            if (pb > 1e-30) {
                float ratio = min(tb * tb / (cos_b * area * pb), 1e18);
                float attb = spot ? spot_attenuation(light, -Lb) : 1.0;
                vec3 value = principled_specular(w, N, V, Lb) * (attb / pb / (1.0 + ratio * ratio));
                if (any(greaterThan(value, vec3(0.0)))) {
                    r.unoccluded.glossy += value;
                    r.direct.glossy += value * shadow_ray(s, P, Lb, tb);
                }
            }
        }
    }
    vec3 mirror = principled_mirror_weight(w, N, V);
    if (mirror != vec3(0.0)) {
        vec3 R = reflect(-V, N);
        float tr, cos_r;
        if (emitter_hit(c, a, b, ellipse, emit_dir, R, tr, cos_r)) {
            vec3 value = mirror * (spot ? spot_attenuation(light, -R) : 1.0);
            r.unoccluded.glossy += value;
            r.direct.glossy += value * shadow_ray(s, P, R, tr);
        }
    }
    r.unoccluded.diffuse *= radiance;
    r.unoccluded.glossy *= radiance;
    r.direct.diffuse *= radiance;
    r.direct.glossy *= radiance;
    return r;
}

/* The transmittance towards one more point of the light, uniform over its
 * part above the receiver's horizon (rejection: the first of up to 4
 * candidates above it; none: 1, the light is about below the horizon). */
float planar_light_probe(vec3 c, vec3 a, vec3 b, bool ellipse, uint salt, SurfaceParams s, vec3 P) {
    for (uint k = 0u; k < 4u; ++k) {
        vec2 u = light_ray_independent(salt + 2u + k);
        vec2 xy = ellipse ? concentric_disk(u) : 2.0 * u - 1.0;
        vec3 v = c + a * xy.x + b * xy.y;
        float t = length(v);
        if (!(t > 0.0) || dot(s.N, v) <= 0.0) continue;
        return shadow_ray(s, P, v / t, t);
    }
    return 1.0;
}

/* A sized light's shadowed light this sample (a sphere light's disk facing
 * P, an area light), given its unshadowed term U: with F and D the
 * unoccluded and traced samples (planar_light_samples) and p the
 * transmittance towards an independent point of the light
 * (planar_light_probe),
 *     D + p (U - F).
 * U - F has expectation 0 and p is independent of it, so this is unbiased
 * for any p; p picks, per pixel and sample, between the direct estimate D
 * (exactly 0 where the light is wholly blocked: no light leaks into a
 * closed room) and the control variate U - (F - D) (exactly U where nothing
 * blocks it: the noise-free unshadowed term), mixing them in penumbrae.
 * The maps' product of U and one point's visibility instead weighs the
 * light's near and far parts alike (a bias under large lights). False for
 * a light seen as one point (sun, delta lights). */
bool sized_light_shadowed(GpuLight light, uint salt, SurfaceParams s, PrincipledWeights w, vec3 P, vec3 N,
                          vec3 V, inout LightContribution r) {
    const int type = int(light.position_type.w);
    vec3 c, a, b, emit_dir, radiance;
    bool ellipse = true, spot = false;
    if (type == LIGHT_AREA) {
        c = light.position_type.xyz - P;
        a = light.axis_x.xyz;
        b = light.axis_y.xyz;
        ellipse = int(light.axis_y.w) == AREA_ELLIPSE;
        emit_dir = light.direction.xyz;
        radiance = light.strength.rgb / (4.0 * light.params.x);
    } else if ((type == LIGHT_POINT || type == LIGHT_SPOT) && light.strength.w > 0.0) {
        c = light.position_type.xyz - P;
        float R = light.strength.w;
        vec3 L = c * inversesqrt(dot(c, c));
        make_basis(L, a, b);
        a *= R;
        b *= R;
        emit_dir = -L;
        radiance = light.strength.rgb / (4.0 * M_PI_F * M_PI_F * R * R);
        spot = type == LIGHT_SPOT;
    } else {
        return false;
    }
    PlanarSamples x = planar_light_samples(c, a, b, ellipse, emit_dir, radiance, light, spot, salt, s, w, P, N, V);
    float p = planar_light_probe(c, a, b, ellipse, salt, s, P);
    r.diffuse = x.direct.diffuse + (r.diffuse - x.unoccluded.diffuse) * p;
    r.glossy = x.direct.glossy + (r.glossy - x.unoccluded.glossy) * p;
    return true;
}
#endif

/* The light's unshadowed contribution, and in `visible` this sample's
 * visibility of its light point (1 without a shadow map): the sample's
 * shadowed light is their product. An emissive mesh returns its shadowed
 * light with visible = 1: its own points' light minus what is blocked at
 * the sample's shared point, where its cube map looks from (a control
 * variate, as the world's occlusion: L(x_s) f G (1 - V(x_s)) / p(x_s) has
 * the expectation of the blocked light). */
/* The unshadowed light of the last shade_light call (a light's own light
 * before its shadow; an emissive mesh's as returned): the Shadow pass's
 * denominator, where shade_light returns light already shadowed (shadow
 * rays on a sized light). */
LightContribution last_unshadowed;

/* A light of kind `kind` (a literal: only its code; LIGHT_ANY_KIND: the
 * light's own). */
LightContribution shade_light_kind(int kind, GpuLight light, SurfaceParams s, PrincipledWeights w, vec3 P, vec3 N,
                                   vec3 V, out float visible) {
#ifdef HAS_MESH_LIGHTS
    if (is_kind(kind, int(light.position_type.w), LIGHT_MESH)) {
        LightContribution r = mesh_light_unoccluded(light, s, w, P, N, V);
        visible = 1.0;
#if defined(HAS_SHADOWS) && !defined(SHADOW_RAYS)
        int shadow = int(light.params.w);
        if (shadow >= 0) {
            float blocked = 1.0 - shadow_visibility_kind(kind, shadow, P, s);
            if (blocked > 0.0) {
                LightContribution c = mesh_light_point(s, w, P, N, V, light.axis_x.xyz, light.axis_y.xyz,
                                                       light.strength.rgb, light.axis_x.w, light.axis_y.w);
                r.diffuse -= c.diffuse * blocked;
                r.glossy -= (c.glossy + mesh_light_mirror) * blocked;
            }
        }
#endif
        last_unshadowed = r;
        return r;
    }
#endif
    LightContribution r = shade_light_unshadowed(kind, light, s, w, P, N, V);
    last_unshadowed = r;
    visible = 1.0;
#ifdef HAS_SHADOWS
    int shadow = int(light.params.w);
#ifdef SHADOW_RAYS
    if (shadow >= 0 && (r.diffuse != vec3(0.0) || r.glossy != vec3(0.0))) {
        if (!sized_light_shadowed(light, uint(shadow) * 8u, s, w, P, N, V, r))
            visible = light_ray_visibility(light, P, s);
    }
#else
    if (shadow >= 0 && (r.diffuse != vec3(0.0) || r.glossy != vec3(0.0)))
        visible = shadow_visibility_kind(kind, shadow, P, s);
#endif
#endif
    return r;
}

LightContribution shade_light(GpuLight light, SurfaceParams s, PrincipledWeights w, vec3 P, vec3 N, vec3 V,
                              out float visible) {
    return shade_light_kind(LIGHT_ANY_KIND, light, s, w, P, N, V, visible);
}
