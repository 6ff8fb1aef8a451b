// Geometry for deciding which shadow casters a lookup can see
// (shadow_module.cpp): the convex hull of points in a plane, and the part
// of a box inside a convex volume, as the vertices of that part.
#pragma once

#include <glm/glm.hpp>

#include <array>
#include <vector>

namespace deferred {

// A half-space dot(n, p) <= o.
struct HalfSpace {
    glm::dvec3 n;
    double o;
};

// A parallelepiped: centre and three edge half-vectors (any, even zero or
// sheared): the points c + s0 a0 + s1 a1 + s2 a2 with |s_i| <= 1.
struct Box {
    glm::dvec3 center{0.0};
    std::array<glm::dvec3, 3> half{};
};

// The convex hull of `p` (counter-clockwise, Andrew's monotone chain;
// collinear points dropped). Points strictly inside the octagon of the
// extreme points along x, y and the diagonals are dropped first (Akl and
// Toussaint 1978): they are no hull vertex, and the receivers' clipped boxes
// (ShadowModule::fit) give thousands of points, most of them inside.
std::vector<glm::dvec2> convex_hull(std::vector<glm::dvec2> p);

// Sutherland and Hodgman's clipping of the convex polygon `poly` by each
// half-space in turn (what is left may be empty, a point or a segment).
void clip_polygon(std::vector<glm::dvec3>& poly, const std::vector<HalfSpace>& by, std::vector<glm::dvec3>& scratch);

// Appends the vertices of the box's part inside a convex hexahedron (a
// view frustum's slice): its six half-spaces and its eight corners, index
// 4 depth + 2 x + y over (near, far), (left, right), (bottom, top), whose
// faces are those corners with one index bit fixed. Nothing where they do
// not meet. The part's vertices are the box's corners inside the volume, the
// volume's corners inside the box, and where the edges of one cross the
// faces of the other: all of them are vertices of the box's faces clipped by
// the volume or of the volume's faces clipped by the box, so the convex hull
// of what it appends is the part. A missing axis (a flat box, a plane's)
// gets a millionth of the box's size as thickness, and the box's own
// half-spaces (which clip the volume's faces) lie that much outside it.
void box_in_volume(const Box& b, const std::vector<HalfSpace>& volume, const std::array<glm::dvec3, 8>& volume_corners,
                   std::vector<glm::dvec3>& out);

}  // namespace deferred
