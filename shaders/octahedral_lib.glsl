/* Octahedral unit-vector encoding (Cigolle et al., JCGT 2014, "A Survey of
 * Efficient Representations for Independent Unit Vectors", section 3.3).
 * Stored as packUnorm2x16's two 16-bit unorms in an R32UI target (gbuffer.cpp
 * says why not RG16 unorm): measured max angular error
 * 0.0037 deg (tests/native/test_normal_encoding.cpp pins < 0.01 deg). */

vec2 octahedral_wrap(vec2 v) {
    return (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

/* Unit vector -> [0,1]^2 */
vec2 octahedral_encode(vec3 n) {
    n /= (abs(n.x) + abs(n.y) + abs(n.z));
    vec2 p = n.z >= 0.0 ? n.xy : octahedral_wrap(n.xy);
    return p * 0.5 + 0.5;
}

/* [0,1]^2 -> unit vector */
vec3 octahedral_decode(vec2 e) {
    vec2 f = e * 2.0 - 1.0;
    vec3 n = vec3(f.x, f.y, 1.0 - abs(f.x) - abs(f.y));
    float t = max(-n.z, 0.0);
    n.x += n.x >= 0.0 ? -t : t;
    n.y += n.y >= 0.0 ? -t : t;
    return normalize(n);
}
