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
 * coordinates (geom/primitive.h primitive_tangent), made orthogonal to N. */
/* Pointiness (per vertex, interpolated) and Random Per Island (per
 * triangle) are mesh attributes the export computes as Cycles' Blender sync
 * does (native/src/mesh_attributes.cpp); 0 where the output is unused. */
void node_geometry(vec4 pointiness_attr, vec4 island_attr, out vec3 position, out vec3 normal, out vec3 tangent,
                   out vec3 true_normal, out vec3 incoming, out vec3 parametric, out float backfacing,
                   out float pointiness, out float random_per_island) {
    pointiness = pointiness_attr.x;
    random_per_island = island_attr.x;
    /* Parametric: (1 - u - v, u, 0) with Cycles' barycentrics u, v of
     * corners 1 and 2 (geom/triangle.h: f = u f1 + v f2 + (1 - u - v) f0),
     * i.e. the weights of corners 0 and 1. */
    parametric = vec3(g_sd.barycentric, 0.0);
    position = g_sd.P;
    normal = g_sd.N;
    vec3 t = vec3(-(g_sd.generated.y - 0.5), g_sd.generated.x - 0.5, 0.0);
    t = g_sd.normal_to_world * t; /* object_normal_transform, as primitive_tangent */
    tangent = cross(g_sd.N, safe_normalize(cross(t, g_sd.N)));
    true_normal = g_sd.Ng;
    incoming = g_sd.I;
    backfacing = g_sd.backfacing;
}

/* Cycles' fresnel_dielectric_cos (kernel/closure/bsdf_util.h); g in
 * Cycles' order, `precise` (see bsdf_lib.glsl's fresnel_dielectric_cos). */
float node_fresnel_dielectric_cos(float cosi, float eta) {
    float c = abs(cosi);
    precise float g = (eta * eta - 1.0) + c * c;
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
#ifdef SHADOW_PASS
    /* A shadow-map caster (a node material that drives alpha) answers for
     * Cycles' shadow rays through transparent surfaces, whose shader runs
     * with PATH_RAY_SHADOW alone (integrate_transparent_shadow): the
     * "Is Shadow Ray" trick of shadowless glass. Ray length stays the
     * camera ray's (the shadow ray's receiver is not known here). */
    is_camera = 0.0;
    is_shadow = 1.0;
#elif defined(WORLD_LIGHTING) || defined(EMISSION_BAKE)
    /* The world, or an emissive surface, as lights see it
     * (world_bake_comp.glsl, emitter_module.h): Cycles evaluates the
     * background or the emitting surface for a light sample with
     * PATH_RAY_EMISSION alone (light_sample_shader_eval), so every ray-type
     * output is 0: the "Is Camera Ray" trick of a backdrop or a panel that
     * lights with another colour than the camera sees. */
    is_camera = 0.0;
    is_shadow = 0.0;
#else
    is_camera = 1.0;
    is_shadow = 0.0;
#endif
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
    view_distance = length(g_sd.P_view); /* from the camera position, also orthographic */
}

/* svm_node_tangent (tex_coord.h): a UV map's tangent (attribute slot, xyz)
 * or radial around an axis through the generated coordinates, transformed
 * as a normal and made orthogonal to N. A missing UV map gives 0. */
#define NODE_TANGENT_RADIAL 0
#define NODE_TANGENT_UVMAP 1
#define NODE_TANGENT_AXIS_X 0
#define NODE_TANGENT_AXIS_Y 1
#define NODE_TANGENT_AXIS_Z 2
void node_tangent(int direction_type, int axis, vec4 uv_tangent, out vec3 tangent) {
    vec3 t;
    if (direction_type == NODE_TANGENT_UVMAP) {
        if (uv_tangent == vec4(0.0)) {
            tangent = vec3(0.0);
            return;
        }
        t = uv_tangent.xyz;
    } else {
        vec3 g = g_sd.generated;
        if (axis == NODE_TANGENT_AXIS_X)
            t = vec3(0.0, -(g.z - 0.5), g.y - 0.5);
        else if (axis == NODE_TANGENT_AXIS_Y)
            t = vec3(-(g.z - 0.5), 0.0, g.x - 0.5);
        else
            t = vec3(-(g.y - 0.5), g.x - 0.5, 0.0);
    }
    t = g_sd.normal_to_world * t;
    tangent = cross(g_sd.N, normalize(cross(t, g_sd.N)));
}

/* svm_node_light_falloff (light_path.h) on a surface: the camera ray's
 * length stands for the distance. */
void node_light_falloff(float strength, float smooth_width, out float quadratic, out float linear_falloff,
                        out float constant_falloff) {
    float r = g_sd.view_distance;
    float squared = r * r;
    float s = 1.0;
    if (smooth_width > 0.0 && !isinf(squared)) s = squared / (smooth_width + squared);
    quadratic = strength * s;
    linear_falloff = strength * r * s;
    constant_falloff = strength * squared * s;
}

/* svm_node_vector_transform (vector_transform.h). Spaces: 0 world, 1 object,
 * 2 camera (Cycles' camera space, +z forward); types: 0 vector, 1 point,
 * 2 normal (a direction, normalised after). */
#define NODE_VECTOR_TRANSFORM_TYPE_VECTOR 0
#define NODE_VECTOR_TRANSFORM_TYPE_POINT 1
#define NODE_VECTOR_TRANSFORM_TYPE_NORMAL 2
#define NODE_VECTOR_TRANSFORM_SPACE_WORLD 0
#define NODE_VECTOR_TRANSFORM_SPACE_OBJECT 1
#define NODE_VECTOR_TRANSFORM_SPACE_CAMERA 2
vec3 node_world_to_camera(vec3 v, bool direction) {
    vec3 w = direction ? mat3(frame.view) * v : mat3(frame.view) * (v - frame.camera_position.xyz);
    return vec3(w.xy, -w.z);
}
vec3 node_camera_to_world(vec3 v, bool direction) {
    vec3 w = mat3(frame.inv_view) * vec3(v.xy, -v.z);
    return direction ? w : w + frame.camera_position.xyz;
}
vec3 node_world_to_object(vec3 v, bool direction) {
    mat3 inv = inverse(g_sd.object_to_world);
    return direction ? inv * v : inv * (v - g_sd.object_location);
}
vec3 node_object_to_world(vec3 v, bool direction) {
    return direction ? g_sd.object_to_world * v : g_sd.object_to_world * v + g_sd.object_location;
}
void node_vector_transform(int type, int from_space, int to_space, vec3 v, out vec3 result) {
    bool direction = type != NODE_VECTOR_TRANSFORM_TYPE_POINT;
    if (from_space == NODE_VECTOR_TRANSFORM_SPACE_WORLD) {
        if (to_space == NODE_VECTOR_TRANSFORM_SPACE_CAMERA) v = node_world_to_camera(v, direction);
        else if (to_space == NODE_VECTOR_TRANSFORM_SPACE_OBJECT) v = node_world_to_object(v, direction);
    } else if (from_space == NODE_VECTOR_TRANSFORM_SPACE_CAMERA) {
        if (to_space != NODE_VECTOR_TRANSFORM_SPACE_CAMERA) v = node_camera_to_world(v, direction);
        if (to_space == NODE_VECTOR_TRANSFORM_SPACE_OBJECT) v = node_world_to_object(v, direction);
    } else {
        if (to_space != NODE_VECTOR_TRANSFORM_SPACE_OBJECT) v = node_object_to_world(v, direction);
        if (to_space == NODE_VECTOR_TRANSFORM_SPACE_CAMERA) v = node_world_to_camera(v, direction);
    }
    if (type == NODE_VECTOR_TRANSFORM_TYPE_NORMAL) v = normalize(v);
    result = v;
}

/* Displacement node (displace.h svm_node_displacement): (height - midlevel)
 * * scale along the normal; in object space (space 0) the normal goes to
 * object space (object_inverse_normal_transform: normalize(M^T N)) and the
 * offset back (object_dir_transform: M), so the object's scale scales it.
 * Its consumer is the Material Output's Displacement, which the add-on turns
 * into a bump of the shading normal (node_displacement_bump) as Cycles'
 * Displacement Method "Bump Only" does. */
void node_displacement(int space, float height, float midlevel, float scale, vec3 normal, out vec3 displacement) {
    float h = (height - midlevel) * scale;
    if (space == 0) {
        vec3 n = transpose(g_sd.object_to_world) * normal;
        float len2 = dot(n, n);
        n = len2 > 0.0 ? n * inversesqrt(len2) : vec3(0.0);
        displacement = g_sd.object_to_world * (n * h);
    } else {
        displacement = normal * h;
    }
}
/* The node without its space, as graphs exported before it was read (scene
 * captures) call it. */
void node_displacement(float height, float midlevel, float scale, vec3 normal, out vec3 displacement) {
    displacement = (height - midlevel) * scale * normalize(normal);
}
