/* G-buffer layout (one block, next to the code that packs and unpacks it).
 *
 *  target        format        contents                                         allocated
 *  ------------  ------------  -----------------------------------------------  ------------------------
 *  depth         D32F          reversed Z (near 1, far 0, cleared to 0), with    always
 *                              glClipControl(LOWER_LEFT, ZERO_TO_ONE); the
 *                              position is rebuilt from it, never stored
 *  emission      RGBA32F       rgb: emission x strength, a: coverage (1)          always
 *                              (float: textured emission reaches Combined and the
 *                              Emission pass at the node library's precision)
 *  base          RGBA16F       rgb: base colour, a: closure model: -1 the        always
 *                              Principled BSDF; 0..1 a Diffuse BSDF (Oren-Nayar
 *                              sigma, 0 = Lambert); 2 a Glossy BSDF, GGX; 3 a
 *                              Glossy BSDF, Beckmann
 *  params0       RGBA16F       metallic, roughness, specular, specular tint       always
 *  normal        R32UI         world shading normal, octahedral, the two 16-bit  always
 *                              unorms of packUnorm2x16 (0.0037 deg max error),
 *                              facing the viewer
 *  params1       RGBA16F       sheen, sheen tint, clearcoat, clearcoat rough.     scene has sheen/clearcoat (GBUF_PARAMS1)
 *  ids           RG32UI        object pass index, material pass index             IndexOB/IndexMA (GBUF_IDS)
 *                (RGBA32UI)    ... z instance, w material id                      Cryptomatte (GBUF_INSTANCE_IDS)
 *  uv            RG32F         active UV map                                      UV pass (GBUF_UV)
 *  geometry      RGBA32UI      x: the interpolated (smooth) normal, octahedral    shadows, or a node material
 *                              unorm16 (closures may take another: Bump, Normal   bending its closures'
 *                              Map; light samples below its horizon give          normals (GBUF_GEOMETRY)
 *                              nothing); y: the true (triangle) normal facing
 *                              the viewer, octahedral unorm16 (shadow maps
 *                              compare against its plane); z, w: half floats:
 *                              the shadow terminator offset (Cycles'
 *                              shadow_ray_smooth_surface_offset, world, xyz)
 *                              and the object's Geometry Offset cutoff
 *
 * Half floats keep 11 significant bits (2.4e-4 relative), well inside the
 * lighting's accuracy budget; emission is float so node outputs reach the
 * film exactly, clamped at 65504 like the rest (a 6.5e4 W/m^2 emitter
 * already clips any display transform). The accumulated film and the
 * passes live in the Film, not here: the G-buffer is per sample. */

#include "octahedral_lib.glsl"

struct SurfaceParams {
    vec3 base_color;
    float diffuse_sigma; /* < 0: Burley (Principled); >= 0: Oren-Nayar sigma (Diffuse BSDF) */
    int glossy_model;    /* 0: Principled specular (Fresnel); 1: Glossy BSDF GGX; 2: Glossy BSDF Beckmann */
    float metallic, roughness, specular, specular_tint;
    float sheen, sheen_tint, clearcoat, clearcoat_roughness;
    vec3 N;
    vec3 Ns; /* the smooth normal (Cycles' sd->N); N where closures keep it */
    /* Shadow receivers (GBUF_GEOMETRY; else Ng = N and no offset): the true
     * normal facing the viewer (Cycles' sd->Ng), the shadow terminator
     * offset at full amount (world) and the object's Geometry Offset. */
    vec3 Ng;
    vec3 terminator;
    float terminator_cutoff;
};

/* What the G-buffer's storage keeps of a value: half floats for base and
 * params, 16-bit unorm for the encoded normal. The forward pass shades the
 * values it would have written through these, so a surface is lit alike
 * drawn either way. */
vec4 gbuffer_half(vec4 v) {
    return vec4(unpackHalf2x16(packHalf2x16(v.xy)), unpackHalf2x16(packHalf2x16(v.zw)));
}
vec2 gbuffer_unorm16(vec2 v) { return unpackUnorm2x16(packUnorm2x16(v)); }

SurfaceParams gbuffer_unpack(vec4 base, vec4 params0, vec4 params1, vec2 normal_enc) {
    SurfaceParams s;
    s.base_color = base.rgb;
    /* A Glossy BSDF's model (base.a > 1.5): its diffuse lobe, where it has
     * one (a Diffuse + Glossy mix, merge_diffuse_glossy), is Lambert. */
    s.diffuse_sigma = base.a >= 0.0 && base.a <= 1.0 ? base.a : base.a > 1.5 ? 0.0 : -1.0;
    s.glossy_model = base.a > 1.5 ? int(base.a + 0.5) - 1 : 0;
#ifdef CLOSURES_NO_OREN_NAYAR
    /* No Diffuse BSDF in the scene: every diffuse lobe is Burley's, a
     * constant the compiler folds (bsdf_lib.glsl's Oren-Nayar code goes). */
    s.diffuse_sigma = -1.0;
#endif
    s.metallic = params0.x;
    s.roughness = params0.y;
    s.specular = params0.z;
    s.specular_tint = params0.w;
    s.sheen = params1.x;
    s.sheen_tint = params1.y;
    s.clearcoat = params1.z;
    s.clearcoat_roughness = params1.w;
    s.N = octahedral_decode(normal_enc);
    s.Ns = s.N;
    s.Ng = s.N;
    s.terminator = vec3(0.0);
    s.terminator_cutoff = 0.0;
    return s;
}

/* The geometry target's fields into s (see the table above). */
void gbuffer_unpack_geometry(inout SurfaceParams s, uvec4 g) {
    s.Ns = octahedral_decode(unpackUnorm2x16(g.x));
    s.Ng = octahedral_decode(unpackUnorm2x16(g.y));
    vec2 zw = unpackHalf2x16(g.w);
    s.terminator = vec3(unpackHalf2x16(g.z), zw.x);
    s.terminator_cutoff = zw.y;
}
uvec4 gbuffer_pack_geometry(vec3 Ns, vec3 Ng, vec3 terminator, float cutoff) {
    return uvec4(packUnorm2x16(octahedral_encode(Ns)), packUnorm2x16(octahedral_encode(Ng)),
                 packHalf2x16(terminator.xy), packHalf2x16(vec2(terminator.z, cutoff)));
}
