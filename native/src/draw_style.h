// How a stage draws the instances FrameScene kept for it.
//
// By vertex: glDrawElements over the mesh's index buffer, so that a vertex
// shared by several triangles is shaded once where the driver's vertex
// cache holds it, instead of once per corner as glDrawArrays does (six
// times per vertex in a closed triangle mesh). Only programs that need no
// per-corner data in their vertex stage can (geometry_vert.glsl
// INDEXED_DRAW): the shadow maps' opaque casters, and the visibility
// buffer's one raster program, whose fragments take their triangle from
// gl_PrimitiveID (visibility_frag.glsl).
//
// Back faces: of a closed mesh (mesh_topology.h), seen from a point
// outside it, the nearest surface along every ray is a triangle facing that
// point, so leaving out the triangles that face away changes no depth a
// map or a view stores, as long as nothing of the instance is clipped by
// the near plane (then the inside would show through the cut). FaceCulling
// describes the projection for that test; the rasteriser then rejects the
// back-facing half of such a mesh's triangles before setting them up.
// Where the rasteriser snaps a sliver by a silhouette, it may turn over and
// be rejected with the back faces: the shadow maps of every benchmark
// capture at 640x360 were equal to the bit, but culled in the visibility
// buffer such slivers changed 159 of the showcase's colour values at
// 320x180, by its spheres' silhouettes, so only the shadow maps leave back
// faces out (visibility_module.h).
#pragma once

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

namespace deferred {

struct FaceCulling {
    // Perspective from `origin`, or orthographic along `axis` (unit, the
    // direction of projection).
    bool perspective = true;
    glm::dvec3 origin{0.0}, axis{0.0, 0.0, -1.0};
    // What the near plane may clip: perspective, points within `near` of the
    // origin; orthographic, points with dot(p, axis) < near.
    double near = 0.0;
    // Window-space winding (GL_CCW when true) of a triangle whose
    // right-handed normal cross(p1 - p0, p2 - p0) points back at the viewer.
    bool facing_ccw = true;

    // Whether an instance's bounding sphere lies wholly outside the near
    // region (so the viewer is outside the mesh, too).
    bool applies(const glm::dvec3& center, double radius) const {
        if (perspective) return glm::length(center - origin) - radius > near;
        return glm::dot(center, axis) - radius > near;
    }
};

// The winding the projection `view_projection` (camera-relative world ->
// clip, lower-left window origin) gives a small triangle at `at` (in front
// of it) whose normal points along `to_viewer`.
inline bool facing_is_ccw(const glm::dmat4& view_projection, const glm::dvec3& at, const glm::dvec3& to_viewer) {
    const glm::dvec3 n = glm::normalize(to_viewer);
    const glm::dvec3 a = glm::normalize(glm::cross(n, std::abs(n.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
    const glm::dvec3 b = glm::cross(n, a);  // cross(a, b) = n
    const double s = 1e-3 * std::max(1.0, glm::length(at));
    auto window = [&](const glm::dvec3& p) {
        const glm::dvec4 c = view_projection * glm::dvec4(p, 1.0);
        return glm::dvec2(c) / c.w;
    };
    const glm::dvec2 p0 = window(at), p1 = window(at + s * a), p2 = window(at + s * b);
    const glm::dvec2 e1 = p1 - p0, e2 = p2 - p0;
    return e1.x * e2.y - e1.y * e2.x > 0.0;
}

struct DrawStyle {
    bool by_vertex = false;   // glDrawElements; the program must be an INDEXED_DRAW one
    bool cull_faces = false;  // leave out the back faces of the kept instances cull() found closed
    // by_vertex: the uniform location where the program reads the drawn
    // range's first triangle (gl_PrimitiveID counts from it); -1 none.
    int first_triangle_location = -1;
};

// DEFERRED_DRAW_BY_VERTEX=off draws by corner, DEFERRED_FACE_CULLING=off
// both sides of every triangle, in the shadow maps and the visibility
// buffer alike: the tests' references for the same images.
inline bool draw_by_vertex_enabled() {
    const char* env = std::getenv("DEFERRED_DRAW_BY_VERTEX");
    return !(env && std::string(env) == "off");
}
inline bool face_culling_enabled() {
    const char* env = std::getenv("DEFERRED_FACE_CULLING");
    return !(env && std::string(env) == "off");
}
// DEFERRED_ALPHA_APART=off draws every surface of a scene with partly
// transparent constant materials, in the shadow maps and the visibility
// buffer, through those materials' program (SCENE_ALPHA: the alpha test,
// by corner, both sides) instead of only their slots: the tests' reference
// for the same images.
inline bool alpha_apart_enabled() {
    const char* env = std::getenv("DEFERRED_ALPHA_APART");
    return !(env && std::string(env) == "off");
}

}  // namespace deferred
