// The geometry behind the shadow maps' receiver culling (convex_geometry.h):
// the plane hull that slice_casters widens, and the boxes' parts inside a
// view slice that stand for where a slice's lookups can be. Checked against
// their definitions on random input, flat and sheared boxes included.
#include "convex_geometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace deferred;

namespace {

double cross2(const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// How far q lies outside the counter-clockwise convex polygon h (<= 0
// inside), from its edges' lines.
double outside(const std::vector<glm::dvec2>& h, const glm::dvec2& q) {
    if (h.size() == 1) return glm::length(q - h[0]);
    double worst = -1e300;
    for (std::size_t i = 0; i < h.size(); ++i) {
        const glm::dvec2 a = h[i], b = h[(i + 1) % h.size()];
        const double len = glm::length(b - a);
        if (len > 0.0) worst = std::max(worst, -cross2(a, b, q) / len);
    }
    if (h.size() == 2) {  // a segment: also beyond its ends
        const glm::dvec2 d = glm::normalize(h[1] - h[0]);
        worst = std::max({worst, glm::dot(h[0] - q, d), glm::dot(q - h[1], d)});
    }
    return worst;
}

}  // namespace

// The hull is convex, counter-clockwise, made of input points, and holds
// every input point: so it is the convex hull, with the octagon's
// prefilter (over 16 points) or without it.
TEST(ConvexGeometry, HullOfPointsHoldsThemAllWithItsVerticesAmongThem) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 300; ++trial) {
        const int n = 3 + trial * 7 % 400;
        std::vector<glm::dvec2> p;
        for (int i = 0; i < n; ++i) {
            glm::dvec2 q(u(rng), u(rng));
            if (trial % 3 == 1) q = glm::normalize(q) * (0.5 + 0.5 * std::abs(u(rng)));  // a ring
            if (trial % 5 == 2) q.y = 0.25 * q.x;                                            // collinear
            if (trial % 7 == 3 && i % 2 == 1) {  // repeats
                p.push_back(p.back());
                continue;
            }
            p.push_back(q * (1.0 + 100.0 * (trial % 4)) + glm::dvec2(trial, -trial));
        }
        const std::vector<glm::dvec2> h = convex_hull(p);
        ASSERT_FALSE(h.empty()) << "trial " << trial;
        for (const glm::dvec2& v : h) EXPECT_NE(std::find(p.begin(), p.end(), v), p.end()) << "trial " << trial;
        // Convex (no turn clockwise; nearly collinear input may round a
        // turn to 0 in one corner and not in another).
        const double scale = 1.0 + 100.0 * (trial % 4) + trial;
        for (std::size_t i = 0; h.size() >= 3 && i < h.size(); ++i)
            EXPECT_GE(cross2(h[i], h[(i + 1) % h.size()], h[(i + 2) % h.size()]), -1e-12 * scale * scale)
                << "trial " << trial;
        for (const glm::dvec2& q : p) EXPECT_LE(outside(h, q), 1e-12 * scale) << "trial " << trial;
    }
    EXPECT_TRUE(convex_hull({}).empty());
}

// Every point of box ∩ volume lies in the hull of what box_in_volume
// appends (checked through projections along random axes), every appended
// point lies in both (within the box's widening), and a box outside gets
// nothing. Boxes: random, sheared, flat (a plane's), thin as a line, larger
// than the volume, crossing its corners.
TEST(ConvexGeometry, BoxPartsInsideAVolumeHoldEveryPointOfIt) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    // A perspective slice, view space: depths 2..9, sides at tan 0.6 / 0.4.
    const double near = 2.0, far = 9.0, l = -0.6, r = 0.6, b = -0.4, t = 0.4;
    const std::vector<HalfSpace> volume = {{{0, 0, 1}, -near},  {{0, 0, -1}, far}, {{-1, 0, -l}, 0.0},
                                           {{1, 0, r}, 0.0},    {{0, -1, -b}, 0.0}, {{0, 1, t}, 0.0}};
    std::array<glm::dvec3, 8> corners;
    std::size_t ci = 0;
    for (double d : {near, far})
        for (double x : {l, r})
            for (double y : {b, t}) corners[ci++] = glm::dvec3(x * d, y * d, -d);
    auto in_volume = [&](const glm::dvec3& p, double tol) {
        for (const HalfSpace& h : volume)
            if (glm::dot(h.n, p) - h.o > tol * glm::length(h.n)) return false;
        return true;
    };
    std::vector<glm::dvec3> axes;
    for (int i = 0; i < 24; ++i) axes.push_back(glm::normalize(glm::dvec3(u(rng), u(rng), u(rng))));
    int met = 0, missed = 0;
    for (int trial = 0; trial < 400; ++trial) {
        Box box;
        box.center = glm::dvec3(4.0 * u(rng), 3.0 * u(rng), -5.5 + 5.0 * u(rng));
        const double size = trial % 10 == 0 ? 20.0 : 0.2 + 3.0 * std::abs(u(rng));
        for (auto& a : box.half) a = glm::dvec3(u(rng), u(rng), u(rng)) * size;
        if (trial % 4 == 1) box.half[2] = glm::dvec3(0.0);                          // flat
        if (trial % 8 == 3) box.half[1] = box.half[2] = glm::dvec3(0.0);            // a segment
        if (trial % 6 == 5) box.half[1] = box.half[0] * 0.5 + box.half[2] * 1e-12;  // nearly flat
        std::vector<glm::dvec3> out;
        box_in_volume(box, volume, corners, out);
        const double eps = 1e-5 * (glm::length(box.center) + size * 3.0);
        // Appended points: in the volume and in the box (solved in its axes
        // where they are independent; else within the widening of a corner's span).
        for (const glm::dvec3& q : out) EXPECT_TRUE(in_volume(q, eps)) << "trial " << trial;
        // Points of box ∩ volume: the box's corners, random interior and face points.
        std::vector<glm::dvec3> inside;
        for (int i = 0; i < 600; ++i) {
            glm::dvec3 s(u(rng), u(rng), u(rng));
            if (i < 8) s = glm::dvec3((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
            else if (i % 3 == 0) s[i % 3 + 0] = (i & 8) ? 1.0 : -1.0;
            const glm::dvec3 p = box.center + box.half[0] * s.x + box.half[1] * s.y + box.half[2] * s.z;
            if (in_volume(p, 0.0)) inside.push_back(p);
        }
        // The volume's corners inside a box larger than it.
        if (trial % 10 == 0 && std::abs(glm::determinant(glm::dmat3(box.half[0], box.half[1], box.half[2]))) > 0.0)
            for (const glm::dvec3& c : corners) {
                const glm::dvec3 s = glm::inverse(glm::dmat3(box.half[0], box.half[1], box.half[2])) * (c - box.center);
                if (std::max({std::abs(s.x), std::abs(s.y), std::abs(s.z)}) <= 1.0) inside.push_back(c);
            }
        if (inside.empty()) {
            ++missed;
            continue;
        }
        ++met;
        ASSERT_FALSE(out.empty()) << "trial " << trial << ": the box meets the volume";
        for (const glm::dvec3& axis : axes) {
            const glm::dvec3 R = glm::normalize(glm::cross(axis, std::abs(axis.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
            const glm::dvec3 U = glm::cross(axis, R);
            std::vector<glm::dvec2> projected;
            for (const glm::dvec3& q : out) projected.emplace_back(glm::dot(q, R), glm::dot(q, U));
            const std::vector<glm::dvec2> h = convex_hull(projected);
            for (const glm::dvec3& p : inside)
                ASSERT_LE(outside(h, {glm::dot(p, R), glm::dot(p, U)}), eps) << "trial " << trial;
        }
    }
    // Most random boxes meet the slice; some do not.
    EXPECT_GT(met, 100);
    EXPECT_GT(missed, 10);
    // Wholly beyond the far plane: nothing.
    std::vector<glm::dvec3> out;
    box_in_volume({{0.0, 0.0, -20.0}, {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)}}, volume, corners, out);
    EXPECT_TRUE(out.empty());
}
