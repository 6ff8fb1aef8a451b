/* Coverage of a constant material (GpuMaterial.mix.w), for the programs that
 * declare the Materials buffer before including this file. */
#ifndef MATERIAL_ALPHA_LIB
#define MATERIAL_ALPHA_LIB

/* Alpha of a material, a stochastic mix chain averaged (the chain's
 * components are picked with their weights in the geometry pass; coverage
 * is linear in them, as Cycles' transparent closure weight). */
float material_chain_alpha(uint id) {
    float alpha = 0.0, weight = 1.0;
    GpuMaterial m = materials[id];
    for (int k = 0; k < 16; ++k) {
        float p = m.mix.x >= 0.0 ? m.mix.y : 0.0;
        alpha += weight * (1.0 - p) * m.mix.w;
        weight *= p;
        if (m.mix.x < 0.0) break;
        m = materials[uint(m.mix.x)];
    }
    return alpha + weight * m.mix.w;
}

#endif
