/* Node materials in the geometry pass: the closure a graph produces, the
 * shading point the node library reads, the material's constants.
 * The generated graph (material_codegen.cpp) is a list of calls into
 * shaders/nodes/; this file is what those calls see. */
#ifndef MATERIAL_LIB
#define MATERIAL_LIB

/* What one pixel and film sample shades with: one Principled parameter set
 * (the G-buffer's), the emitted radiance and the shading normal. Mix and Add
 * Shader resolve to one set per sample (nodes/node_shader_lib.glsl), so the
 * accumulated image converges to Cycles' weighted sum of closures. */
struct Closure {
    vec3 base_color;
    float alpha;
    float diffuse_sigma; /* < 0: Principled (Burley) diffuse; >= 0: Diffuse BSDF (Oren-Nayar) */
    float glossy_model;  /* 0: Principled specular; 1: Glossy BSDF GGX; 2: Glossy BSDF Beckmann */
    float metallic, roughness, specular, specular_tint;
    float sheen, sheen_tint, clearcoat, clearcoat_roughness;
    vec3 emission; /* radiance (colour x strength) */
    vec3 N;        /* world shading normal */
    float reflects; /* 0 for a closure that reflects nothing (Emission, none) */
    float holdout;  /* 1: Cycles' holdout closure, a hole in the image (geometry_frag.glsl) */
};

/* The shading point (Cycles' ShaderData) as the geometry pass sees it. World
 * positions are absolute here: textures need them (camera-relative ones
 * would move the pattern with the camera). */
struct ShadingPoint {
    vec3 P;          /* world position */
    vec3 N;          /* world shading normal, flipped to the viewer's side on back faces */
    vec3 Ng;         /* world true normal, facing the viewer */
    vec3 I;          /* unit vector from P towards the viewer */
    vec3 generated;  /* texture-space coordinates */
    vec3 uv;         /* active render UV map, z = 0 */
    vec3 N_object;   /* object-space shading normal (Texture Coordinate > Normal) */
    vec3 P_object;   /* object-space position */
    vec3 N_object_smooth; /* interpolated object-space normal, not normalised (Normal Map) */
    vec3 object_location;
    vec4 object_color;
    float object_index, material_index, object_random;
    float backfacing;   /* 1 on back faces */
    float view_distance, view_depth;
    vec3 dPdx, dPdy;    /* one-pixel differentials of P (camera-relative, Bump) */
    vec3 P_view;        /* Cycles' camera space: +z forward */
    vec2 window;        /* position in the unjittered frame, [0, 1] */
    vec2 barycentric;   /* weights of the triangle's corners 0 and 1 (Geometry Parametric) */
    mat3 normal_to_world; /* object -> world for normals (inverse transpose) */
    mat3 object_to_world; /* object -> world for directions */
    vec4 attr[8];       /* attribute slots of the material (CornerAttribute by name) */
    /* Bump (MATERIAL_BUMP): Cycles' compact ray differential at P (the pixel's
     * footprint, not projected onto the surface) and the screen derivatives
     * of the values node_bump_offset() moves. */
    float bump_dP;
    vec3 dgenerated_dx, dgenerated_dy, duv_dx, duv_dy;
    vec4 dattr_dx[8], dattr_dy[8];
};

ShadingPoint g_sd;
/* The uniform number Mix/Add Shader draw their choice from, rescaled after
 * each choice so nested mixes stay stratified over the film's samples. */
float g_mix_u;
/* Shader AOVs: what the graph's AOV Output nodes write (slot k: rgb Color,
 * a Value), read by the AOV pass (geometry_frag.glsl AOV_PASS). */
#define MAX_GRAPH_AOVS 8
vec4 g_aov[MAX_GRAPH_AOVS];
int g_const_base;

layout(std430, binding = SSBO_MATERIAL_CONSTANTS) readonly buffer MaterialConstants { float material_constants[]; };

float mat_const(int i) { return material_constants[g_const_base + i]; }
vec3 mat_const3(int i) { return vec3(mat_const(i), mat_const(i + 1), mat_const(i + 2)); }

/* Implicit socket conversions (Cycles ConvertNode, svm/convert.h): colour ->
 * float is the scene-linear luminance (Blender's default OCIO config: the
 * Rec.709 weights as Cycles 3.4.1 derives them, measured), vector -> float the
 * average of the components. */
float node_color_to_float(vec3 c) { return dot(c, vec3(0.2126729950, 0.7151526453, 0.0721754596)); }
float node_vector_to_float(vec3 v) { return (v.x + v.y + v.z) * (1.0 / 3.0); }

/* No closure (an unlinked shader socket): black. */
Closure closure_none() {
    Closure c;
    c.base_color = vec3(0.0);
    c.alpha = 1.0;
    c.diffuse_sigma = -1.0;
    c.glossy_model = 0.0;
    c.metallic = 0.0;
    c.roughness = 0.5;
    c.specular = 0.0;
    c.specular_tint = 0.0;
    c.sheen = 0.0;
    c.sheen_tint = 0.5;
    c.clearcoat = 0.0;
    c.clearcoat_roughness = 0.03;
    c.emission = vec3(0.0);
    c.N = g_sd.N;
    c.reflects = 0.0;
    c.holdout = 0.0;
    return c;
}

/* Cycles' safe_normalize: zero stays zero. */
vec3 safe_normalize(vec3 v) {
    float len = length(v);
    return len != 0.0 ? v / len : vec3(0.0);
}

/* Cycles kernel/closure/bsdf_util.h ensure_valid_reflection: rotate N towards
 * Ng just enough that the reflection of I stays above the surface. */
vec3 ensure_valid_reflection(vec3 Ng, vec3 I, vec3 N) {
    vec3 R = 2.0 * dot(N, I) * N - I;
    float threshold = min(0.9 * dot(Ng, I), 0.01);
    if (dot(Ng, R) >= threshold) return N;
    float NdotNg = dot(N, Ng);
    vec3 X = normalize(N - NdotNg * Ng);
    float Ix = dot(I, X), Iz = dot(I, Ng);
    float Ix2 = Ix * Ix, Iz2 = Iz * Iz;
    float a = Ix2 + Iz2;
    float b = sqrt(max(Ix2 * (a - threshold * threshold), 0.0));
    float c = Iz * threshold + a;
    float fac = 0.5 / a;
    float N1_z2 = fac * (b + c), N2_z2 = fac * (-b + c);
    bool valid1 = (N1_z2 > 1e-5) && (N1_z2 <= 1.0 + 1e-5);
    bool valid2 = (N2_z2 > 1e-5) && (N2_z2 <= 1.0 + 1e-5);
    vec2 N_new;
    if (valid1 && valid2) {
        vec2 N1 = vec2(sqrt(max(1.0 - N1_z2, 0.0)), sqrt(max(N1_z2, 0.0)));
        vec2 N2 = vec2(sqrt(max(1.0 - N2_z2, 0.0)), sqrt(max(N2_z2, 0.0)));
        float R1 = 2.0 * (N1.x * Ix + N1.y * Iz) * N1.y - Iz;
        float R2 = 2.0 * (N2.x * Ix + N2.y * Iz) * N2.y - Iz;
        valid1 = R1 >= 1e-5;
        valid2 = R2 >= 1e-5;
        if (valid1 && valid2)
            N_new = R1 < R2 ? N1 : N2;
        else
            N_new = R1 > R2 ? N1 : N2;
    } else if (valid1 || valid2) {
        float Nz2 = valid1 ? N1_z2 : N2_z2;
        N_new = vec2(sqrt(max(1.0 - Nz2, 0.0)), sqrt(max(Nz2, 0.0)));
    } else {
        return Ng;
    }
    return N_new.x * X + N_new.y * Ng;
}

#endif
