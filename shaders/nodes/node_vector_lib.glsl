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

/* Cycles util/math.h make_orthonormals. */
void node_make_orthonormals(vec3 N, out vec3 a, out vec3 b) {
    if (N.x != N.y || N.x != N.z)
        a = vec3(N.z - N.y, N.x - N.z, N.y - N.x);
    else
        a = vec3(N.z - N.y, N.x + N.z, -N.y - N.x);
    a = normalize(a);
    b = cross(N, a);
}

/* Cycles' bump offsets (kernel/util/differential.h differential_from_compact):
 * two vectors of the compact ray differential's length along an orthonormal
 * basis of Ng. */
void node_bump_differentials(out vec3 dx, out vec3 dy) {
    vec3 a, b;
    node_make_orthonormals(g_sd.Ng, a, b);
    dx = g_sd.bump_dP * a;
    dy = g_sd.bump_dP * b;
}

/* Bump evaluation, as Cycles' svm_node_*_bump_dx/dy variants: the height
 * graph is evaluated again with the shading point moved to P + dP.dx (axis 0)
 * or P + dP.dy (axis 1). Values linear over the triangle (UVs, generated,
 * attributes) move by their gradient along the offset, found from their
 * screen derivatives; object and camera positions are transformed exactly.
 * node_bump_restore() puts the point back. */
/* A Bump inside another Bump's height nests offsets: the points to restore
 * are kept on a small stack (the add-on nests at most NODE_BUMP_DEPTH). */
#define NODE_BUMP_DEPTH 4
ShadingPoint g_sd_unbumped[NODE_BUMP_DEPTH];
int g_bump_depth = 0;
void node_bump_offset(int axis) {
    g_sd_unbumped[min(g_bump_depth, NODE_BUMP_DEPTH - 1)] = g_sd;
    g_bump_depth = min(g_bump_depth + 1, NODE_BUMP_DEPTH);
#ifdef MATERIAL_BUMP
    vec3 dx, dy;
    node_bump_differentials(dx, dy);
    vec3 d = axis == 0 ? dx : dy;
    /* Screen offsets (s, t) with s dP/dx + t dP/dy = d (d lies in the plane). */
    vec3 ex = g_sd.dPdx, ey = g_sd.dPdy;
    float xx = dot(ex, ex), xy = dot(ex, ey), yy = dot(ey, ey);
    float det = xx * yy - xy * xy;
    vec2 st = det > 0.0 ? vec2(yy * dot(ex, d) - xy * dot(ey, d), xx * dot(ey, d) - xy * dot(ex, d)) / det
                        : vec2(0.0);
    g_sd.P += d;
    g_sd.P_object += inverse(g_sd.object_to_world) * d;
    g_sd.generated += st.x * g_sd.dgenerated_dx + st.y * g_sd.dgenerated_dy;
    g_sd.uv += st.x * g_sd.duv_dx + st.y * g_sd.duv_dy;
    for (int k = 0; k < 8; ++k) g_sd.attr[k] += st.x * g_sd.dattr_dx[k] + st.y * g_sd.dattr_dy[k];
    vec3 view = mat3(frame.view) * (g_sd.P - frame.camera_position.xyz);
    g_sd.P_view = vec3(view.xy, -view.z);
    g_sd.window += st * frame.viewport.zw;
#endif
}
void node_bump_restore() {
    g_bump_depth = max(g_bump_depth - 1, 0);
    g_sd = g_sd_unbumped[g_bump_depth];
}

/* svm_node_set_bump (displace.h), Mikkelsen's surface gradient with the
 * heights at P, P + dP.dx and P + dP.dy. */
void node_bump(int invert, float strength, float dist, float h_c, float h_x, float h_y, vec3 normal_in,
               out vec3 result) {
    vec3 dx, dy;
    node_bump_differentials(dx, dy);
    vec3 Rx = cross(dy, normal_in);
    vec3 Ry = cross(normal_in, dx);
    float det = dot(dx, Rx);
    vec3 surfgrad = (h_x - h_c) * Rx + (h_y - h_c) * Ry;
    float absdet = abs(det);
    if (invert != 0) dist = -dist;
    strength = max(strength, 0.0);
    vec3 n = safe_normalize(absdet * normal_in - dist * sign(det) * surfgrad);
    if (dot(n, n) == 0.0 || any(isnan(n)))
        n = normal_in;
    else
        n = normalize(strength * n + (1.0 - strength) * normal_in);
    result = ensure_valid_reflection(g_sd.Ng, g_sd.I, n);
}

/* Bump from displacement (Cycles' ShaderGraph::bump_from_displacement, the
 * Material Output's Displacement at Displacement Method "Bump Only" or
 * "Displacement and Bump"): the displacement vector's height along the
 * unbumped normal, dot(D, N), at P, P + dP.dx and P + dP.dy ... */
void node_displacement_height(vec3 displacement, out float height) {
    height = dot(displacement, g_sd.N);
}
/* ... into a Bump node of strength 1 and distance 1 on the normal, whose
 * result becomes the shading normal (SetNormal into the output's Normal:
 * Cycles' sd->N) for everything the surface evaluates after it, and for the
 * lighting's smooth normal (geometry_frag.glsl). */
void node_displacement_bump(float h_c, float h_x, float h_y) {
    vec3 n;
    node_bump(0, 1.0, 1.0, h_c, h_x, h_y, g_sd.N, n);
    if (any(isnan(n)) || any(isinf(n)) || dot(n, n) == 0.0) return;
    g_sd.N = normalize(n);
    /* Texture Coordinate > Normal reads sd->N in object space. */
    g_sd.N_object = safe_normalize(transpose(g_sd.object_to_world) * g_sd.N);
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
