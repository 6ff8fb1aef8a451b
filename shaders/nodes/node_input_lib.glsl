/* Input nodes: values of the shading point (Cycles ShaderData) as the camera
 * ray sees it. Cycles: intern/cycles/kernel/svm/tex_coord.h, attribute.h,
 * geometry.h (svm_node_geometry, svm_node_object_info), fresnel.h
 * (svm_node_fresnel, svm_node_layer_weight), light_path.h, value.h. */

void node_value(float value, out float result) { result = value; }
void node_rgb(vec3 color, out vec3 result) { result = color; }

/* svm_node_tex_coord. Object: the object's own space, or (has_object) the
 * chosen object's through the 3x4 rows of its inverse world matrix in a
 * constant block. Camera: Cycles' camera space (+z forward). Window: the
 * position in the unjittered frame, z = 0. */
void node_tex_coord(int has_object, int object_block, out vec3 generated, out vec3 normal, out vec3 uv,
                    out vec3 object, out vec3 camera, out vec3 window, out vec3 reflection) {
    generated = g_sd.generated;
    normal = g_sd.N_object;
    uv = g_sd.uv;
    if (has_object != 0) {
        vec4 P = vec4(g_sd.P, 1.0);
        vec4 r0 = vec4(mat_const(object_block), mat_const(object_block + 1), mat_const(object_block + 2),
                       mat_const(object_block + 3));
        vec4 r1 = vec4(mat_const(object_block + 4), mat_const(object_block + 5), mat_const(object_block + 6),
                       mat_const(object_block + 7));
        vec4 r2 = vec4(mat_const(object_block + 8), mat_const(object_block + 9), mat_const(object_block + 10),
                       mat_const(object_block + 11));
        object = vec3(dot(r0, P), dot(r1, P), dot(r2, P));
    } else {
        object = g_sd.P_object;
    }
    camera = g_sd.P_view;
    window = vec3(g_sd.window, 0.0);
    reflection = 2.0 * dot(g_sd.N, g_sd.I) * g_sd.N - g_sd.I;
}

/* Attribute / UV Map / Color Attribute: an attribute slot, vec4 with the
 * value in xyz(w) (svm_node_attr: Color/Vector = xyz, Fac = the average of
 * xyz (the value itself for a float attribute, stored broadcast), Alpha = w,
 * 1 for attributes without alpha). A missing attribute is 0. */
void node_attribute(vec4 value, out vec3 color, out vec3 vector, out float fac, out float alpha) {
    color = value.xyz;
    vector = value.xyz;
    fac = (value.x + value.y + value.z) * (1.0 / 3.0);
    alpha = value.w;
}
void node_uvmap(vec4 value, out vec3 uv) { uv = vec3(value.xy, 0.0); }
void node_vertex_color(vec4 value, out vec3 color, out float alpha) {
    color = value.xyz;
    alpha = value.w;
}

/* svm_node_object_info. */
void node_object_info(out vec3 location, out vec3 color, out float alpha, out float object_index,
                      out float material_index, out float random) {
    location = g_sd.object_location;
    color = g_sd.object_color.rgb;
    alpha = g_sd.object_color.a;
    object_index = g_sd.object_index;
    material_index = g_sd.material_index;
    random = g_sd.object_random;
}

/* svm_node_geometry. Tangent: radial around Z through the generated
 * coordinates (primitive_tangent), made orthogonal to N. */
void node_geometry(out vec3 position, out vec3 normal, out vec3 tangent, out vec3 true_normal,
                   out vec3 incoming, out float backfacing) {
    position = g_sd.P;
    normal = g_sd.N;
    vec3 t = vec3(-(g_sd.generated.y - 0.5), g_sd.generated.x - 0.5, 0.0);
    t = g_sd.object_to_world * t;
    tangent = cross(g_sd.N, safe_normalize(cross(t, g_sd.N)));
    true_normal = g_sd.Ng;
    incoming = g_sd.I;
    backfacing = g_sd.backfacing;
}

/* Cycles' fresnel_dielectric_cos (kernel/closure/bsdf_util.h). */
float node_fresnel_dielectric_cos(float cosi, float eta) {
    float c = abs(cosi);
    float g = eta * eta - 1.0 + c * c;
    if (g > 0.0) {
        g = sqrt(g);
        float A = (g - c) / (g + c);
        float B = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
        return 0.5 * A * A * (1.0 + B * B);
    }
    return 1.0; /* total internal reflection */
}

/* svm_node_fresnel. */
void node_fresnel(float ior, vec3 normal, out float fac) {
    float eta = max(ior, 1e-5);
    eta = g_sd.backfacing > 0.5 ? 1.0 / eta : eta;
    fac = node_fresnel_dielectric_cos(dot(g_sd.I, normal), eta);
}

/* svm_node_layer_weight. */
void node_layer_weight(float blend, vec3 normal, out float fresnel, out float facing) {
    float eta = max(1.0 - blend, 1e-5);
    eta = g_sd.backfacing > 0.5 ? eta : 1.0 / eta;
    fresnel = node_fresnel_dielectric_cos(dot(g_sd.I, normal), eta);
    float f = abs(dot(g_sd.I, normal));
    if (blend != 0.5) {
        float b = clamp(blend, 0.0, 1.0 - 1e-5);
        b = b < 0.5 ? 2.0 * b : 0.5 / (1.0 - b);
        f = pow(f, b);
    }
    facing = 1.0 - f;
}

/* svm_node_light_path for the ray this engine shades: a camera ray (the
 * surface is shaded once per camera sample; direct light is evaluated on
 * that closure). Ray length is the camera ray's: the distance to P. */
void node_light_path(out float is_camera, out float is_shadow, out float is_diffuse, out float is_glossy,
                     out float is_singular, out float is_reflection, out float is_transmission,
                     out float ray_length, out float ray_depth, out float diffuse_depth, out float glossy_depth,
                     out float transparent_depth, out float transmission_depth) {
    is_camera = 1.0;
    is_shadow = 0.0;
    is_diffuse = 0.0;
    is_glossy = 0.0;
    is_singular = 0.0;
    is_reflection = 0.0;
    is_transmission = 0.0;
    ray_length = g_sd.view_distance;
    ray_depth = 0.0;
    diffuse_depth = 0.0;
    glossy_depth = 0.0;
    transparent_depth = 0.0;
    transmission_depth = 0.0;
}

/* Camera Data node (svm_node_camera): view vector in camera space, view
 * depth (positive along the camera axis) and distance. */
void node_camera_data(out vec3 view_vector, out float view_z_depth, out float view_distance) {
    view_vector = normalize(g_sd.P_view);
    view_z_depth = g_sd.view_depth;
    view_distance = g_sd.view_distance;
}
