// Whether a mesh encloses volume, and on which side of its triangles: what
// back-face culling needs to leave its image unchanged (draw_style.h).
#pragma once

#include <cstddef>
#include <cstdint>

namespace deferred {

// +1: closed and facing out: every edge is shared by exactly two triangles
// that run along it in opposite directions (a consistently oriented
// 2-manifold without boundary), and every connected part encloses positive
// volume with the right-handed normals cross(p1 - p0, p2 - p0) pointing out
// of it. Seen from any point outside such a mesh, the first surface a ray
// meets is a triangle whose normal points back at that point.
// -1: the same with every part facing in (a room modelled from inside).
// 0: open, non-manifold, inconsistently wound, degenerate (an edge from a
// vertex to itself), without volume, or with parts facing both ways.
int closed_orientation(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                       std::size_t triangle_count);

// A mesh whose triangles all lie in one plane: dot(normal, p) = offset for
// every vertex a triangle uses, within 1e-5 of the vertices' extent (float
// positions carry ~1e-7 of it). A view ray meets such a surface at most
// once, so its layers can be composited in one draw (layer_order.h).
// `normal` is unit length, the largest triangle's (right-handed winding).
// False for a mesh without a triangle of non-zero area.
bool planar_mesh(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                 std::size_t triangle_count, double normal[3], double& offset);

// A closed mesh (closed_orientation() = `closed`, +1 or -1) that bounds a
// convex solid: every vertex a triangle uses lies on the solid's side of
// every triangle's plane, within 1e-5 of the vertices' extent. A view ray
// from outside meets such a surface at most twice, first where it faces
// the eye (layer_order.h). The test is vertices x triangles: meshes over
// kMaxConvexTestWork of it are not tested (false).
constexpr double kMaxConvexTestWork = 2e7;
bool convex_mesh(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                 std::size_t triangle_count, int closed);

}  // namespace deferred
