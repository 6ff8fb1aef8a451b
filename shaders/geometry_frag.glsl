/* Geometry pass, fragment stage: fills the G-buffer (layout in gbuffer_lib.glsl).
 * SHADOW_PASS (node materials that drive alpha only): a shadow-map caster
 * instead, evaluating the graph for its alpha and writing what
 * shadow_frag.glsl writes.
 * AOV_PASS (node materials with AOV Output nodes, aov_module.h): one of
 * the graph's shader AOVs where the G-buffer sees the surface.
 * FORWARD_PASS (materials in Blend mode, forward_module.h): the surface is
 * lit here, by the lighting pass's own code (lighting_lib.glsl), in front
 * of the opaque depth, and blended over the forward layer with its alpha.
 * EMISSION_BAKE (node materials whose emission varies, emitter_module.h):
 * the radiance the surface emits towards a light sample, drawn into each
 * emitting triangle's tile of the bake target (geometry_vert.glsl).
 * VISIBILITY_PASS (visibility_module.h, for the surfaces whose coverage is
 * stochastic: a partly transparent constant material, a node material that
 * drives alpha): the visibility buffer's ids where the surface is kept, the
 * G-buffer's values left unwritten (gbuffer_resolve_comp.glsl makes them).
 * GBUFFER_RESOLVE (visibility_module.h): not a fragment shader at all, but
 * this file included by gbuffer_resolve_comp.glsl, which computes what the
 * varyings, the fragment's position and facing and their screen
 * derivatives would be (from the visibility buffer's triangle and the
 * pixel's ray) and stores the outputs into the G-buffer's images: the same
 * surface code, out of the raster pipeline. */
#ifdef GBUFFER_RESOLVE
/* Globals the resolve sets (gbuffer_resolve_comp.glsl), not varyings. */
#define VARYING
#define FLAT_VARYING
#define GBUF_OUT(slot)
#define FRAG_COORD g_frag_coord
#define FRONT_FACING g_front_facing
vec4 g_frag_coord;
bool g_front_facing;
#else
#define VARYING in
#define FLAT_VARYING flat in
#ifdef VISIBILITY_PASS
/* The G-buffer's values stay in globals: this pass writes ids only. */
#define GBUF_OUT(slot)
layout(location = 0) out uvec4 out_visibility;
flat in uint v_slot_key;
#else
#define GBUF_OUT(slot) layout(location = slot) out
#endif
#define FRAG_COORD gl_FragCoord
#define FRONT_FACING gl_FrontFacing
#endif
#include "frame_lib.glsl"
#include "octahedral_lib.glsl"
#include "gbuffer_lib.glsl"
#ifdef FORWARD_PASS
#include "lighting_lib.glsl"
#endif

layout(std430, binding = SSBO_MATERIALS) readonly buffer Materials { GpuMaterial materials[]; };

VARYING vec3 v_position;
VARYING vec3 v_normal;
VARYING vec2 v_uv;
FLAT_VARYING uint v_material;
FLAT_VARYING uint v_object_index;
FLAT_VARYING uint v_mirrored;
FLAT_VARYING uint v_instance;
FLAT_VARYING uint v_triangle;

#ifdef SHADOW_PASS
/* As shadow_frag.glsl's shadow_origin and shadow_axis (other locations: 3..12
 * are the node material's). */
layout(location = 20) uniform vec4 caster_origin;
layout(location = 21) uniform vec3 caster_axis;
#ifdef WORLD_MAP
layout(location = 0) out vec2 out_depths;
#else
layout(location = 0) out float out_distance;
#endif
#elif defined(AOV_PASS)
/* One shader AOV (aov_module.h): the graph's AOV slot `aov_slot` of the
 * surface this sample's G-buffer holds (depth test EQUAL), blended into the
 * AOV's accumulation with the constant 1 / samples. */
layout(location = 23) uniform int aov_slot;
layout(location = 24) uniform int aov_color; /* 1: a Color AOV (rgb, a coverage), 0: a Value AOV (a) */
layout(location = 0) out vec4 out_aov;
#elif defined(EMISSION_BAKE)
layout(location = 0) out vec4 out_bake;
#elif defined(FORWARD_PASS)
/* Premultiplied light and alpha; blended ONE, ONE_MINUS_SRC_ALPHA (alpha:
 * ZERO, ONE_MINUS_SRC_ALPHA), so the target's a is the transmittance. */
layout(location = 0) out vec4 out_forward;
#else
GBUF_OUT(OUT_EMISSION) vec4 out_emission;
GBUF_OUT(OUT_BASE) vec4 out_base;
GBUF_OUT(OUT_PARAMS0) vec4 out_params0;
GBUF_OUT(OUT_NORMAL) uint out_normal; /* packUnorm2x16 (gbuffer.cpp) */
#endif
#if !defined(FORWARD_PASS) && !defined(AOV_PASS) && !defined(EMISSION_BAKE)
#ifdef GBUF_PARAMS1
GBUF_OUT(OUT_PARAMS1) vec4 out_params1;
#endif
#ifdef GBUF_INSTANCE_IDS
GBUF_OUT(OUT_IDS) uvec4 out_ids; /* + instance and material id for Cryptomatte */
#elif defined(GBUF_IDS)
GBUF_OUT(OUT_IDS) uvec2 out_ids;
#endif
#ifdef GBUF_UV
GBUF_OUT(OUT_UV) vec2 out_uv;
#endif
#endif
#if defined(GBUF_GEOMETRY) && !defined(SHADOW_PASS) && !defined(FORWARD_PASS) && !defined(AOV_PASS) && \
    !defined(EMISSION_BAKE)
#define GEOMETRY_OUT
GBUF_OUT(OUT_GEOMETRY) uvec4 out_geometry;
FLAT_VARYING vec3 v_term_a;
FLAT_VARYING vec3 v_term_b;
VARYING vec3 v_term_dir;
VARYING vec2 v_term_bary;
FLAT_VARYING float v_term_cutoff;

/* Cycles 3.4's shadow_ray_smooth_surface_offset (kernel/light/sample.h;
 * Hanika 2021, "Hacking the Shadow Terminator", Ray Tracing Gems II ch. 4):
 * the lift h of the shading point towards the smooth surface the vertex
 * normals describe, a parabola over the triangle bounded by the linear
 * envelope of the corners' tangent planes, along the interpolated normal
 * n (object_dir_transform, not normalised). Ng: the true normal facing the
 * ray, as Cycles flips it; the vertex normals are the mesh's own, so n
 * against Ng tells which side is hit. With Gij = dot(V_j - V_i, N_i):
 * dot(V_i - P, N_i) = -sum_j b_j Gij, a = G20 + G02, b = G21 + G12,
 * c = -(G10 + G01). */
vec3 terminator_offset(vec3 Ng) {
    const float G01 = v_term_a.x, G02 = v_term_a.y, G10 = v_term_a.z;
    const float G12 = v_term_b.x, G20 = v_term_b.y, G21 = v_term_b.z;
    const float u = v_term_bary.x, v = v_term_bary.y, w = 1.0 - u - v;
    const float D0 = -(v * G01 + w * G02), D1 = -(u * G10 + w * G12), D2 = -(u * G20 + v * G21);
    const float a = G20 + G02, b = G21 + G12, c = -(G10 + G01);
    float h = a * u * (u - 1.0) + (a + b + c) * u * v + b * v * (v - 1.0);
    if (dot(v_term_dir, Ng) > 0.0) {
        float h0 = max(D0 + max(max(G01, G02), 0.0), 0.0);
        float h1 = max(D1 + max(max(G10, G12), 0.0), 0.0);
        float h2 = max(D2 + max(max(G20, G21), 0.0), 0.0);
        h = max(min(min(h0, h1), h2), h * 0.5);
    } else {
        float h0 = max(-D0 + max(max(-G01, -G02), 0.0), 0.0);
        float h1 = max(-D1 + max(max(-G10, -G12), 0.0), 0.0);
        float h2 = max(-D2 + max(max(-G20, -G21), 0.0), 0.0);
        h = min(-min(min(h0, h1), h2), h * 0.5);
    }
    vec3 o = v_term_dir * h;
    return (isnan(o.x + o.y + o.z) || isinf(o.x + o.y + o.z)) ? vec3(0.0) : clamp(o, vec3(-65504.0), vec3(65504.0));
}
#endif

#ifdef MATERIAL_GRAPH
/* A node material (material_lib.glsl, nodes/, the generated graph). Depth
 * was laid down by the pre-pass: test before shading (no depth write here),
 * so hidden fragments cost nothing. A graph that drives alpha
 * (MATERIAL_ALPHA) discards, and draws the pre-pass itself: late tests. */
#if !defined(MATERIAL_ALPHA) && !defined(GBUFFER_RESOLVE)
layout(early_fragment_tests) in;
#endif
VARYING vec3 v_object_position;
VARYING vec3 v_object_normal;
FLAT_VARYING vec3 v_true_normal;
VARYING vec2 v_barycentric;
#if MATERIAL_ATTRIBUTE_COUNT > 0
VARYING vec4 v_attr[MATERIAL_ATTRIBUTE_COUNT];
#endif
#ifdef MATERIAL_FLAT_ATTRIBUTE
FLAT_VARYING vec4 v_attr_flat;
#endif
layout(std430, binding = SSBO_INSTANCES) readonly buffer Instances { GpuInstance instances[]; };
layout(location = 11) uniform vec3 texspace_location;
layout(location = 12) uniform vec3 texspace_size;
#if MATERIAL_IMAGE_COUNT > 0
layout(binding = TEX_MATERIAL_IMAGE0) uniform sampler2D material_images[MATERIAL_IMAGE_COUNT];
#endif
/* Generated: includes material_lib.glsl and nodes/node_lib.glsl, then the graph. */
#include "material_graph.glsl"
#endif

/* One-pixel screen derivatives of the varyings. The fragment stage takes
 * them from its quad (dFdxFine); the resolve computes them exactly, as the
 * change of the varyings between this pixel's ray and its right and upper
 * neighbours' rays met on the triangle's plane (gbuffer_resolve_comp.glsl),
 * which is what Cycles' ray differentials describe. */
#ifdef GBUFFER_RESOLVE
vec3 g_dposition_dx, g_dposition_dy;  /* camera-relative world */
vec3 g_dobject_dx, g_dobject_dy;      /* object-space position */
vec2 g_duv_dx, g_duv_dy;
vec4 g_dattr_dx[8], g_dattr_dy[8];
vec3 g_triangle_normal;               /* cross of the triangle's world edges */
vec3 ddx_position() { return g_dposition_dx; }
vec3 ddy_position() { return g_dposition_dy; }
/* The true normal's direction (either side): the triangle's own plane, the
 * one the two differentials span, without their rounding (a flat plane's
 * normal exactly as the raster's derivatives give it). */
vec3 screen_plane_normal() { return g_triangle_normal; }
#else
vec3 ddx_position() { return dFdxFine(v_position); }
vec3 ddy_position() { return dFdyFine(v_position); }
vec3 screen_plane_normal() { return cross(dFdx(v_position), dFdy(v_position)); }
#endif
#ifdef MATERIAL_GRAPH
#ifdef GBUFFER_RESOLVE
/* The camera ray's direction changes by the difference of the neighbours' unit directions. */
vec3 ddx_view_dir() {
    return normalize(v_position + g_dposition_dx - frame.motion.xyz) - normalize(v_position - frame.motion.xyz);
}
vec3 ddy_view_dir() {
    return normalize(v_position + g_dposition_dy - frame.motion.xyz) - normalize(v_position - frame.motion.xyz);
}
/* Generated coordinates are affine in the object position: (P - (loc - size)) / (2 size). */
vec3 ddx_generated(vec3 generated, vec3 size) { return g_dobject_dx / (2.0 * size); }
vec3 ddy_generated(vec3 generated, vec3 size) { return g_dobject_dy / (2.0 * size); }
vec3 ddx_uv() { return vec3(g_duv_dx, 0.0); }
vec3 ddy_uv() { return vec3(g_duv_dy, 0.0); }
vec4 ddx_attr(int k) { return g_dattr_dx[k]; }
vec4 ddy_attr(int k) { return g_dattr_dy[k]; }
#else
vec3 ddx_view_dir() { return dFdxFine(normalize(v_position - frame.motion.xyz)); }
vec3 ddy_view_dir() { return dFdyFine(normalize(v_position - frame.motion.xyz)); }
vec3 ddx_generated(vec3 generated, vec3 size) { return dFdxFine(generated); }
vec3 ddy_generated(vec3 generated, vec3 size) { return dFdyFine(generated); }
vec3 ddx_uv() { return dFdxFine(vec3(v_uv, 0.0)); }
vec3 ddy_uv() { return dFdyFine(vec3(v_uv, 0.0)); }
#if MATERIAL_ATTRIBUTE_COUNT > 0
vec4 ddx_attr(int k) { return dFdxFine(v_attr[k]); }
vec4 ddy_attr(int k) { return dFdyFine(v_attr[k]); }
#endif
#endif
#endif

/* A per-pixel value in [0, 1) (integer hash, Jarzynski & Olano 2020, pcg). */
#ifdef SCENE_ALPHA
#include "material_alpha_lib.glsl"
#endif
#if (defined(SCENE_ALPHA) || defined(MATERIAL_ALPHA)) && !defined(SHADOW_PASS)
/* x = 0: stochastic transparency (the lit G-buffer); x = 1: the data passes'
 * G-buffer, where a surface stays when its alpha reaches y, the view layer's
 * Alpha Threshold (Cycles' film_write_data_passes). */
layout(location = 22) uniform vec2 alpha_mode;
bool transparent_here(float alpha) {
    if (alpha_mode.x > 0.5) return alpha < alpha_mode.y;
    return transparency_random(uvec2(FRAG_COORD.xy), v_instance, v_triangle) >= alpha;
}
#else
bool transparent_here(float alpha) {
    return transparency_random(uvec2(FRAG_COORD.xy), v_instance, v_triangle) >= alpha;
}
#endif

float pixel_hash(uvec2 p) {
    uint v = p.x * 1973u + p.y * 9277u;
    v = v * 747796405u + 2891336453u;
    uint w = ((v >> ((v >> 28u) + 4u)) ^ v) * 277803737u;
    return float((w >> 22u) ^ w) * (1.0 / 4294967296.0);
}

/* A Mix Shader chain: take the alternative with its probability, using one
 * uniform number per pixel and sample (the golden-ratio sequence rotated per
 * pixel, so each pixel's choices are stratified over the samples). */
GpuMaterial pick_material(uint id) {
    GpuMaterial m = materials[id];
    float u = fract(pixel_hash(uvec2(FRAG_COORD.xy)) + frame.sample_shift.z);
    for (int k = 0; k < 16 && m.mix.x >= 0.0; ++k) {
        float p = m.mix.y;
        if (u >= p) break;
        u = u / max(p, 1e-30);
        m = materials[uint(m.mix.x)];
    }
    return m;
}

#ifdef MATERIAL_GRAPH
/* Fill the shading point the node library reads (Cycles' ShaderData). */
void shading_point_init(vec3 N, vec3 Ng, vec3 V, bool back) {
    GpuInstance inst = instances[v_instance];
    g_sd.P = v_position + frame.camera_position.xyz;
    g_sd.N = N;
    g_sd.Ng = Ng;
    g_sd.I = V;
    g_sd.P_object = v_object_position;
    /* Generated: the texture space, (P - (location - size)) / (2 size). */
    vec3 size = texspace_size;
    size = vec3(size.x != 0.0 ? size.x : 1e-8, size.y != 0.0 ? size.y : 1e-8, size.z != 0.0 ? size.z : 1e-8);
    g_sd.generated = (v_object_position - (texspace_location - size)) / (2.0 * size);
    g_sd.uv = vec3(v_uv, 0.0);
    g_sd.barycentric = v_barycentric;
    g_sd.object_to_world = mat3(inst.model);
    g_sd.normal_to_world = mat3(inst.normal_matrix);
    /* object_inverse_normal_transform: normalize(M^T N). */
    g_sd.N_object = safe_normalize(transpose(g_sd.object_to_world) * N);
    g_sd.N_object_smooth = dot(v_object_normal, v_object_normal) > 0.0 ? v_object_normal
                                                                       : transpose(g_sd.object_to_world) * (back ? -Ng : Ng);
    g_sd.object_location = inst.model[3].xyz + frame.camera_position.xyz;
    g_sd.object_color = inst.color;
    g_sd.object_index = float(inst.ids.x);
    g_sd.material_index = materials[v_material].emission.w;
    g_sd.object_random = inst.info.x;
    g_sd.backfacing = back ? 1.0 : 0.0;
    vec3 view = (frame.view * vec4(v_position, 1.0)).xyz;
    g_sd.P_view = vec3(view.xy, -view.z);
    g_sd.view_depth = -view.z;
    /* The camera ray's length: from the camera, or for an orthographic one from
     * its origin on the near plane (Cycles' camera_sample_orthographic). */
    g_sd.view_distance = frame.camera_position.w > 0.5 ? -view.z - frame.jitter.z : frame_eye_distance(v_position);
#ifdef EMISSION_BAKE
    /* A light sample's Window: Cycles' camera_world_to_ndc of P (the bake's
     * frame block holds the unjittered camera; its pixels are the tiles'). */
    vec4 clip = frame.projection * (frame.view * vec4(v_position, 1.0));
    g_sd.window = clip.w != 0.0 ? clip.xy / clip.w * 0.5 + 0.5 : vec2(0.0);
#else
    vec2 ndc = FRAG_COORD.xy * frame.viewport.zw * 2.0 - 1.0 - frame.jitter.xy;
    g_sd.window = ndc * 0.5 + 0.5;
#endif
    g_sd.dPdx = ddx_position();
    g_sd.dPdy = ddy_position();
    for (int k = 0; k < 8; ++k) g_sd.attr[k] = vec4(0.0);
#if MATERIAL_ATTRIBUTE_COUNT > 0
    for (int k = 0; k < MATERIAL_ATTRIBUTE_COUNT; ++k) g_sd.attr[k] = v_attr[k];
#endif
#ifdef MATERIAL_FLAT_ATTRIBUTE
    g_sd.attr[MATERIAL_FLAT_ATTRIBUTE] = v_attr_flat;
#endif
#ifdef MATERIAL_BUMP
    /* Cycles' sd->dP: orthographic, the pixel's size on the camera plane;
     * perspective, the ray length times the per-pixel change of the ray's
     * direction (camera_sample_perspective, differential_transfer_compact). */
    if (frame.camera_position.w > 0.5) {
        g_sd.bump_dP = 0.5 * (2.0 / (abs(frame.projection[0][0]) * frame.viewport.x) +
                              2.0 / (abs(frame.projection[1][1]) * frame.viewport.y));
    } else {
        g_sd.bump_dP = frame_eye_distance(v_position) * 0.5 * (length(ddx_view_dir()) + length(ddy_view_dir()));
    }
    g_sd.dgenerated_dx = ddx_generated(g_sd.generated, size);
    g_sd.dgenerated_dy = ddy_generated(g_sd.generated, size);
    g_sd.duv_dx = ddx_uv();
    g_sd.duv_dy = ddy_uv();
    for (int k = 0; k < 8; ++k) {
        g_sd.dattr_dx[k] = vec4(0.0);
        g_sd.dattr_dy[k] = vec4(0.0);
    }
#if MATERIAL_ATTRIBUTE_COUNT > 0
    for (int k = 0; k < MATERIAL_ATTRIBUTE_COUNT; ++k) {
        g_sd.dattr_dx[k] = ddx_attr(k);
        g_sd.dattr_dy[k] = ddy_attr(k);
    }
#endif
#ifdef MATERIAL_FLAT_ATTRIBUTE
    g_sd.dattr_dx[MATERIAL_FLAT_ATTRIBUTE] = vec4(0.0);
    g_sd.dattr_dy[MATERIAL_FLAT_ATTRIBUTE] = vec4(0.0);
#endif
#else
    g_sd.bump_dP = 0.0;
#endif
}

float finite_or(float x, float fallback) { return (isnan(x) || isinf(x)) ? fallback : x; }
vec3 finite_or(vec3 v, vec3 fallback) {
    return vec3(finite_or(v.x, fallback.x), finite_or(v.y, fallback.y), finite_or(v.z, fallback.z));
}
#endif

#ifdef FORWARD_PASS
/* The lights this draw shades, [x, y): a batch of the scene's (as the
 * lighting pass's dispatches; forward_module.h). The first batch adds the
 * world's light and the surface's emission too. */
layout(location = 25) uniform uvec2 forward_lights;
/* 0: every fragment; a convex exact layer is drawn twice (forward_module.cpp,
 * layer_order.h): 1 only the fragments seen from the front of their
 * winding, 2 only those seen from behind. */
layout(location = 26) uniform int forward_side;

/* The surface lit as the lighting pass lights a G-buffer pixel: the draw's
 * lights, the world, its emission. */
vec3 forward_light(vec4 emission, vec4 base, vec4 params0, vec4 params1, vec3 N, vec3 Ns, vec3 Ng) {
    /* The values at the G-buffer's precision, as the lighting pass reads them. */
    SurfaceParams s = gbuffer_unpack(gbuffer_half(base), gbuffer_half(params0), gbuffer_half(params1),
                                     gbuffer_unorm16(octahedral_encode(N)));
    s.Ns = octahedral_decode(gbuffer_unorm16(octahedral_encode(Ns)));
    /* Shadow maps compare against the triangle's plane (no terminator offset here). */
    s.Ng = Ng;
    N = s.N;
    PrincipledWeights w = principled_weights(s);
    vec3 P = v_position;
    vec3 V = frame_view_vector(P);
    ivec2 pixel = ivec2(FRAG_COORD.xy);
    float ao;
    const bool first = forward_lights.x == 0u;
    LightContribution total;
    if (first) {
        total = world_light(w, s, P, N, V, pixel, ao);
    } else {
        total.diffuse = vec3(0.0);
        total.glossy = vec3(0.0);
    }
#ifdef MESH_RAY_POOL
    mesh_ray_pool_start();
#endif
    for (uint i = forward_lights.x; i < min(frame.counts.x, forward_lights.y); ++i) {
        float visible;
        LightContribution c = shade_light(lights[i], s, w, P, N, V, visible);
        total.diffuse += c.diffuse * visible;
        total.glossy += c.glossy * visible;
    }
#ifdef MESH_RAY_POOL
    LightContribution m = reservoir_trace(mesh_ray_pool, s, P);
    total.diffuse += m.diffuse;
    total.glossy += m.glossy;
#endif
    return (first ? emission.rgb : vec3(0.0)) + total.diffuse + total.glossy;
}
#endif

#ifdef GBUFFER_RESOLVE
void geometry_surface() {
#else
void main() {
#endif
#ifdef FORWARD_PASS
    /* In front of this sample's opaque surfaces only (reversed Z; the same
     * jittered projection drew them). The depth test is done here, by hand:
     * the opaque depth is read as a texture, so it cannot also be this
     * pass's depth attachment. */
    if (FRAG_COORD.z <= texelFetch(gbuf_depth, ivec2(FRAG_COORD.xy), 0).r) discard;
#endif
#ifndef MATERIAL_GRAPH
    GpuMaterial m = pick_material(v_material);
#if defined(SCENE_ALPHA) && !defined(FORWARD_PASS)
    /* Partly transparent (mix.w: alpha): kept with probability alpha. */
    /* The Alpha Threshold judges the material's whole alpha (a mix chain
     * averaged), the stochastic pass the picked component's. */
    if (transparent_here(alpha_mode.x > 0.5 ? material_chain_alpha(v_material) : m.mix.w)) discard;
#endif
#ifdef VISIBILITY_PASS
    out_visibility = uvec4(v_instance, v_triangle, v_slot_key + 1u, 0u);  /* as visibility_frag.glsl */
    return;
#endif
#endif

    /* Geometric normal from the triangle's winding, in world space. Cycles
     * flips the normals of a surface hit from behind; a mirrored instance
     * (negative determinant) reverses the screen winding, hence the xor. */
#ifdef EMISSION_BAKE
    /* Seen from the front of its winding (emission is two-sided), by a ray
     * along the true normal: the bake's winding is the tile's, not a view's. */
    const bool back = false;
#else
    const bool back = FRONT_FACING == ((v_mirrored & 1u) != 0u);
#endif
#ifdef FORWARD_PASS
    if (forward_side != 0 && back != (forward_side == 2)) discard;
#endif
    vec3 Ng = normalize(screen_plane_normal());
#ifdef MATERIAL_GRAPH
    /* Node materials read Ng (True Normal, flat Normal Map): exact from the
     * triangle's vertices rather than from screen derivatives. */
    if (dot(v_true_normal, v_true_normal) > 0.0) Ng = normalize(v_true_normal);
#endif
#ifdef EMISSION_BAKE
    vec3 V = Ng;
#else
    vec3 V = frame_view_vector(v_position);
#endif
    if (dot(Ng, V) < 0.0) Ng = -Ng;
    vec3 N = Ng;
    float len2 = dot(v_normal, v_normal);
    if (len2 > 1e-20 && !isnan(len2) && !isinf(len2)) {
        N = v_normal * inversesqrt(len2);
        if (back) N = -N;
    }

#ifdef MATERIAL_GRAPH
    /* Evaluate the graph; a NaN or infinity a node produces becomes the
     * neutral value, never a G-buffer NaN. */
    shading_point_init(N, Ng, V, back);
    g_const_base = int(materials[v_material].mix.z);
    g_mix_u = fract(pixel_hash(uvec2(FRAG_COORD.xy)) + frame.sample_shift.z);
    Closure c;
    material_graph_eval(c);
    /* A Displacement bumped in (node_displacement_bump) is Cycles' sd->N
     * from here on: the smooth normal of the lighting's horizon and bump
     * shadowing terms and of the shadow terminator offset. */
    if (dot(finite_or(g_sd.N, vec3(0.0)), g_sd.N) > 0.0) N = g_sd.N;
#if defined(MATERIAL_ALPHA) && !defined(FORWARD_PASS) && !defined(EMISSION_BAKE) && !defined(GBUFFER_RESOLVE)
    /* (The resolve's pixels were kept by the visibility pass's same test.) */
    if (transparent_here(clamp(finite_or(c.alpha, 1.0), 0.0, 1.0))) discard;
#endif
#ifdef VISIBILITY_PASS
    out_visibility = uvec4(v_instance, v_triangle, v_slot_key + 1u, 0u);
    return;
#endif
#ifdef EMISSION_BAKE
    /* What a light sample receives: the closure's emission weighted by its
     * coverage (a Principled BSDF's Alpha, a Mix with Transparent), as
     * Cycles' closure weights scale it; negative light is not sampled. */
    out_bake = vec4(max(finite_or(c.emission, vec3(0.0)), vec3(0.0)) * clamp(finite_or(c.alpha, 1.0), 0.0, 1.0), 1.0);
#elif defined(AOV_PASS)
    vec4 aov = g_aov[clamp(aov_slot, 0, MAX_GRAPH_AOVS - 1)];
    out_aov = aov_color != 0 ? vec4(finite_or(aov.rgb, vec3(0.0)), 1.0) : vec4(0.0, 0.0, 0.0, finite_or(aov.a, 0.0));
#elif defined(SHADOW_PASS)
    float d = caster_depth(v_position, caster_origin, caster_axis);
#ifdef WORLD_MAP
    out_depths = vec2(-d, d);
#else
    out_distance = d;
#endif
#else
    vec3 shading_normal = finite_or(c.N, N);
    shading_normal = dot(shading_normal, shading_normal) > 0.0 ? normalize(shading_normal) : N;
    vec4 surf_emission = vec4(clamp(finite_or(c.emission, vec3(0.0)), vec3(-65504.0), vec3(65504.0)), 1.0);
    vec4 surf_base = vec4(clamp(finite_or(c.base_color, vec3(0.0)), vec3(0.0), vec3(65504.0)),
                          /* the closure model, as gbuffer_lib.glsl lays it out */
                          c.glossy_model > 0.5 ? 1.0 + c.glossy_model
                                               : clamp(finite_or(c.diffuse_sigma, -1.0), -1.0, 1.0));
    vec4 surf_params0 = vec4(clamp(finite_or(c.metallic, 0.0), 0.0, 1.0), clamp(finite_or(c.roughness, 0.5), 0.0, 1.0),
                             clamp(finite_or(c.specular, 0.0), 0.0, 12.0),
                             /* a tint fraction, or a summed Diffuse + Glossy's glossy weight (node_shader_lib.glsl) */
                             clamp(finite_or(c.specular_tint, 0.0), 0.0,
                                   c.glossy_model > 0.5 && c.metallic < 0.5 ? 65504.0 : 1.0));
    vec4 surf_params1 = clamp(vec4(finite_or(c.sheen, 0.0), finite_or(c.sheen_tint, 0.0), finite_or(c.clearcoat, 0.0),
                                   finite_or(c.clearcoat_roughness, 0.0)), vec4(0.0), vec4(1.0));
    uint surf_material_index = uint(materials[v_material].emission.w);
    float surf_alpha = clamp(finite_or(c.alpha, 1.0), 0.0, 1.0);
#endif  /* EMISSION_BAKE, AOV_PASS, SHADOW_PASS */
#else
    vec3 shading_normal = N;
    vec4 surf_emission = vec4(min(m.emission.rgb, vec3(65504.0)), 1.0);
    vec4 surf_base = m.base_diffuse;
    vec4 surf_params0 = m.params0;
    vec4 surf_params1 = m.params1;
    uint surf_material_index = uint(m.emission.w);
    float surf_alpha = clamp(isnan(m.mix.w) ? 1.0 : m.mix.w, 0.0, 1.0);
#endif
#if !defined(SHADOW_PASS) && !defined(AOV_PASS) && !defined(EMISSION_BAKE)
#ifndef MATERIAL_GRAPH
    const bool holdout_material = m.base_diffuse.a > 3.5; /* kClosureHoldout */
#else
    const bool holdout_material = c.holdout != 0.0;  /* node_holdout, whole or drawn from a mix */
#endif
    /* A shadow catcher object (instance flag 4): emission.a 2 tells the
     * lighting pass (SHADOW_CATCHER) to keep its light apart. */
    if ((v_mirrored & 4u) != 0u) surf_emission.a = 2.0;
    if ((v_mirrored & 2u) != 0u || holdout_material) {
        /* A holdout (Cycles' holdout closure or the object's Holdout flag): a
         * hole, black with alpha 0; the lighting pass adds nothing where
         * emission.a is 0, and the colour passes read zeros. */
        surf_emission = vec4(0.0);
        surf_base = vec4(0.0, 0.0, 0.0, -1.0);
        surf_params0 = vec4(0.0);
        surf_params1 = vec4(0.0);
    }
#ifdef FORWARD_PASS
    if (surf_alpha <= 0.0) discard;
    out_forward = vec4(forward_light(surf_emission, surf_base, surf_params0, surf_params1, shading_normal, N, Ng) *
                       surf_alpha, surf_alpha);
#else
    out_emission = surf_emission;
    out_base = surf_base;
    out_params0 = surf_params0;
    out_normal = packUnorm2x16(octahedral_encode(shading_normal));
#ifdef GBUF_PARAMS1
    out_params1 = surf_params1;
#endif
#ifdef GBUF_INSTANCE_IDS
    out_ids = uvec4(v_object_index, surf_material_index, v_instance, v_material);
#elif defined(GBUF_IDS)
    out_ids = uvec2(v_object_index, surf_material_index);
#endif
#endif
#endif
#ifdef GEOMETRY_OUT
    out_geometry = gbuffer_pack_geometry(N, Ng, terminator_offset(Ng), v_term_cutoff);
#endif
#if defined(GBUF_UV) && !defined(FORWARD_PASS) && !defined(AOV_PASS) && !defined(EMISSION_BAKE)
    /* The rasteriser interpolates through plane equations: UVs near the
     * float range on a sliver triangle overflow there (inf - inf = NaN, a
     * fuzzed scene on llvmpipe). The UV pass then reads 0, not a NaN. */
    out_uv = (any(isnan(v_uv)) || any(isinf(v_uv))) ? vec2(0.0) : v_uv;
#endif
}
