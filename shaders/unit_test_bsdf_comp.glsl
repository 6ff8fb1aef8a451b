/* GPU unit test (tests/native/test_gpu_bsdf.cpp): evaluates the Principled
 * BSDF of bsdf_lib.glsl for a buffer of (N, V, L, material) cases. */
#include "shader_shared.h"
#include "bsdf_lib.glsl"

layout(local_size_x = 64) in;

struct BsdfCase {
    vec4 N, V, L;
    vec4 base_diffuse, params0, params1;
};
layout(std430, binding = 0) readonly buffer Cases { BsdfCase cases[]; };
layout(std430, binding = 1) writeonly buffer Results { vec4 results[]; }; /* diffuse, glossy per case */

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(cases.length())) return;
    BsdfCase c = cases[i];
    SurfaceParams s = gbuffer_unpack(c.base_diffuse, c.params0, c.params1, vec2(0.5));
    s.N = s.Ns = c.N.xyz; /* the case's normal; no bump */
    PrincipledWeights w = principled_weights(s);
    LobeEval e = principled_eval(s, w, c.N.xyz, c.V.xyz, c.L.xyz);
    results[2u * i] = vec4(e.diffuse, 0.0);
    results[2u * i + 1u] = vec4(e.glossy, 0.0);
}
