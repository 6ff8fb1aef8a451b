/* Geometry pass, fragment stage: fills the G-buffer (layout in gbuffer_lib.glsl). */
#include "frame_lib.glsl"
#include "octahedral_lib.glsl"

layout(std430, binding = SSBO_MATERIALS) readonly buffer Materials { GpuMaterial materials[]; };

in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
flat in uint v_material;
flat in uint v_object_index;
flat in uint v_mirrored;

layout(location = OUT_EMISSION) out vec4 out_emission;
layout(location = OUT_BASE) out vec4 out_base;
layout(location = OUT_PARAMS0) out vec4 out_params0;
layout(location = OUT_NORMAL) out vec2 out_normal;
#ifdef GBUF_PARAMS1
layout(location = OUT_PARAMS1) out vec4 out_params1;
#endif
#ifdef GBUF_IDS
layout(location = OUT_IDS) out uvec2 out_ids;
#endif
#ifdef GBUF_UV
layout(location = OUT_UV) out vec2 out_uv;
#endif

/* A per-pixel value in [0, 1) (integer hash, Jarzynski & Olano 2020, pcg). */
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
    float u = fract(pixel_hash(uvec2(gl_FragCoord.xy)) + frame.sample_shift.z);
    for (int k = 0; k < 16 && m.mix.x >= 0.0; ++k) {
        float p = m.mix.y;
        if (u >= p) break;
        u = u / max(p, 1e-30);
        m = materials[uint(m.mix.x)];
    }
    return m;
}

void main() {
    GpuMaterial m = pick_material(v_material);

    /* Geometric normal from the triangle's winding, in world space. Cycles
     * flips the normals of a surface hit from behind; a mirrored instance
     * (negative determinant) reverses the screen winding, hence the xor. */
    const bool back = gl_FrontFacing == (v_mirrored != 0u);
    vec3 Ng = normalize(cross(dFdx(v_position), dFdy(v_position)));
    vec3 V = frame_view_vector(v_position);
    if (dot(Ng, V) < 0.0) Ng = -Ng;
    vec3 N = Ng;
    float len2 = dot(v_normal, v_normal);
    if (len2 > 1e-20 && !isnan(len2) && !isinf(len2)) {
        N = v_normal * inversesqrt(len2);
        if (back) N = -N;
    }

    out_emission = vec4(min(m.emission.rgb, vec3(65504.0)), 1.0);
    out_base = m.base_alpha;
    out_params0 = m.params0;
    out_normal = octahedral_encode(N);
#ifdef GBUF_PARAMS1
    out_params1 = m.params1;
#endif
#ifdef GBUF_IDS
    out_ids = uvec2(v_object_index, uint(m.emission.w));
#endif
#ifdef GBUF_UV
    out_uv = v_uv;
#endif
}
