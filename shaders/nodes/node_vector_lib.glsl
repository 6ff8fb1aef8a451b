/* Vector nodes: Mapping, Normal Map, Bump, Normal.
 * Cycles: intern/cycles/kernel/svm/mapping.h + mapping_util.h, tex_coord.h
 * (svm_node_normal_map), bump.h (svm_node_set_bump), normal.h. */

/* Cycles util/transform.h euler_to_transform: rows of the XYZ-Euler rotation. */
mat3 node_euler_to_rows(vec3 e) {
    float cx = cos(e.x), cy = cos(e.y), cz = cos(e.z);
    float sx = sin(e.x), sy = sin(e.y), sz = sin(e.z);
    /* GLSL matrices are column-major: these columns are Cycles' rows t.x, t.y, t.z. */
    return mat3(vec3(cy * cz, sy * sx * cz - cx * sz, sy * cx * cz + sx * sz),
                vec3(cy * sz, sy * sx * sz + cx * cz, sy * cx * sz - sx * cz),
                vec3(-sy, cy * sx, cy * cx));
}
/* transform_direction(t, a) = (t.x . a, t.y . a, t.z . a). */
vec3 node_rows_apply(mat3 rows, vec3 a) { return a * rows; }
/* transform_direction_transposed. */
vec3 node_rows_apply_transposed(mat3 rows, vec3 a) { return rows * a; }

vec3 node_safe_divide3(vec3 a, vec3 b) {
    return vec3(b.x != 0.0 ? a.x / b.x : 0.0, b.y != 0.0 ? a.y / b.y : 0.0, b.z != 0.0 ? a.z / b.z : 0.0);
}

/* Mapping node types (NodeMappingType). */
#define NODE_MAPPING_POINT 0
#define NODE_MAPPING_TEXTURE 1
#define NODE_MAPPING_VECTOR 2
#define NODE_MAPPING_NORMAL 3

/* svm_mapping (mapping_util.h). */
void node_mapping(int type, vec3 vector, vec3 location, vec3 rotation, vec3 scale, out vec3 result) {
    mat3 rows = node_euler_to_rows(rotation);
    if (type == NODE_MAPPING_POINT)
        result = node_rows_apply(rows, vector * scale) + location;
    else if (type == NODE_MAPPING_TEXTURE)
        result = node_safe_divide3(node_rows_apply_transposed(rows, vector - location), scale);
    else if (type == NODE_MAPPING_VECTOR)
        result = node_rows_apply(rows, vector * scale);
    else
        result = safe_normalize(node_rows_apply(rows, node_safe_divide3(vector, scale)));
}

/* Normal Map spaces (NodeNormalMapSpace). */
#define NODE_NORMAL_MAP_TANGENT 0
#define NODE_NORMAL_MAP_OBJECT 1
#define NODE_NORMAL_MAP_WORLD 2
#define NODE_NORMAL_MAP_BLENDER_OBJECT 3
#define NODE_NORMAL_MAP_BLENDER_WORLD 4

/* svm_node_normal_map (tex_coord.h). Tangent space works in object space
 * with the interpolated, unnormalised smooth normal and MikkTSpace tangent
 * (xyz, sign in w); `has_tangent` 0 when the mesh has no such UV map, which
 * Cycles answers with the unperturbed normal. Flat faces use the true normal. */
void node_normal_map(int space, int has_tangent, int smooth_normal, float strength, vec3 color, vec4 tangent,
                     out vec3 result) {
    color = 2.0 * (color - vec3(0.5));
    bool backfacing = g_sd.backfacing > 0.5;
    vec3 N;
    if (space == NODE_NORMAL_MAP_TANGENT) {
        if (has_tangent == 0 || tangent == vec4(0.0)) {  /* no such UV map on the mesh */
            result = g_sd.N;
            return;
        }
        vec3 normal;
        if (smooth_normal != 0) {
            normal = g_sd.N_object_smooth;
        } else {
            /* sd->Ng is already flipped towards the viewer: undo for the maths. */
            normal = backfacing ? -g_sd.Ng : g_sd.Ng;
            normal = normalize(transpose(g_sd.object_to_world) * normal);
        }
        vec3 B = tangent.w * cross(normal, tangent.xyz);
        N = safe_normalize(color.x * tangent.xyz + color.y * B + color.z * normal);
        N = normalize(g_sd.normal_to_world * N);
    } else {
        if (space == NODE_NORMAL_MAP_BLENDER_OBJECT || space == NODE_NORMAL_MAP_BLENDER_WORLD) {
            color.y = -color.y;
            color.z = -color.z;
        }
        N = color;
        if (space == NODE_NORMAL_MAP_OBJECT || space == NODE_NORMAL_MAP_BLENDER_OBJECT)
            N = normalize(g_sd.normal_to_world * N);
        else
            N = safe_normalize(N);
    }
    if (backfacing) N = -N;
    if (strength != 1.0) {
        strength = max(strength, 0.0);
        N = safe_normalize(g_sd.N + (N - g_sd.N) * strength);
    }
    if (dot(N, N) == 0.0 || any(isnan(N))) N = g_sd.N;
    result = N;
}

/* svm_node_set_bump (bump.h), Mikkelsen's surface gradient. Cycles samples
 * the height at P + dP/dx and P + dP/dy (one pixel along the camera ray
 * differentials); the fragment shader's fine derivatives are the same one-
 * pixel differences, taken between the two pixels of a quad. */
void node_bump(int invert, float strength, float dist, float height, vec3 normal_in, out vec3 result) {
    vec3 dPdx = g_sd.dPdx, dPdy = g_sd.dPdy;
    float dhdx = dFdxFine(height), dhdy = dFdyFine(height);
    vec3 Rx = cross(dPdy, normal_in);
    vec3 Ry = cross(normal_in, dPdx);
    float det = dot(dPdx, Rx);
    vec3 surfgrad = dhdx * Rx + dhdy * Ry;
    float absdet = abs(det);
    if (invert != 0) dist = -dist;
    strength = max(strength, 0.0);
    vec3 n = safe_normalize(absdet * normal_in - dist * sign(det) * surfgrad);
    if (dot(n, n) == 0.0 || any(isnan(n)))
        n = normal_in;
    else
        n = normalize(strength * n + (1.0 - strength) * normal_in);
    result = n;
}

/* Normal node (normal.h): the direction set on the node, and its dot product. */
void node_normal(vec3 direction, vec3 normal, out vec3 out_normal, out float out_dot) {
    out_normal = normalize(direction);
    out_dot = dot(out_normal, normalize(normal));
}

/* Vector Rotate (vector_rotate.h svm_node_vector_rotate, util/math
 * rotate_around_axis). Types: 0 axis-angle, 1 X, 2 Y, 3 Z, 4 Euler XYZ. */
#define NODE_VECTOR_ROTATE_TYPE_AXIS 0
#define NODE_VECTOR_ROTATE_TYPE_AXIS_X 1
#define NODE_VECTOR_ROTATE_TYPE_AXIS_Y 2
#define NODE_VECTOR_ROTATE_TYPE_AXIS_Z 3
#define NODE_VECTOR_ROTATE_TYPE_EULER_XYZ 4
vec3 node_rotate_around_axis(vec3 p, vec3 axis, float angle) {
    float c = cos(angle), s = sin(angle), t = 1.0 - c;
    vec3 r;
    r.x = ((c + t * axis.x * axis.x) * p.x) + ((t * axis.x * axis.y - axis.z * s) * p.y) +
          ((t * axis.x * axis.z + axis.y * s) * p.z);
    r.y = ((t * axis.x * axis.y + axis.z * s) * p.x) + ((c + t * axis.y * axis.y) * p.y) +
          ((t * axis.y * axis.z - axis.x * s) * p.z);
    r.z = ((t * axis.x * axis.z - axis.y * s) * p.x) + ((t * axis.y * axis.z + axis.x * s) * p.y) +
          ((c + t * axis.z * axis.z) * p.z);
    return r;
}
void node_vector_rotate(int type, int invert, vec3 vector, vec3 center, vec3 axis, float angle, vec3 rotation,
                        out vec3 result) {
    if (type == NODE_VECTOR_ROTATE_TYPE_EULER_XYZ) {
        mat3 rows = node_euler_to_rows(rotation);
        result = (invert != 0 ? node_rows_apply_transposed(rows, vector - center)
                              : node_rows_apply(rows, vector - center)) + center;
        return;
    }
    vec3 a;
    if (type == NODE_VECTOR_ROTATE_TYPE_AXIS_X) a = vec3(1.0, 0.0, 0.0);
    else if (type == NODE_VECTOR_ROTATE_TYPE_AXIS_Y) a = vec3(0.0, 1.0, 0.0);
    else if (type == NODE_VECTOR_ROTATE_TYPE_AXIS_Z) a = vec3(0.0, 0.0, 1.0);
    else a = normalize(axis);
    angle = invert != 0 ? -angle : angle;
    result = dot(a, a) != 0.0 ? node_rotate_around_axis(vector - center, a, angle) + center : vector;
}
