#include "convex_geometry.h"

#include <algorithm>
#include <cmath>

namespace deferred {

std::vector<glm::dvec2> convex_hull(std::vector<glm::dvec2> p) {
    if (p.size() > 16) {
        const glm::dvec2 dirs[8] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
        std::array<glm::dvec2, 8> extreme;
        for (int d = 0; d < 8; ++d) {
            extreme[std::size_t(d)] = p[0];
            double best = glm::dot(p[0], dirs[d]);
            for (const glm::dvec2& q : p)
                if (glm::dot(q, dirs[d]) > best) {
                    best = glm::dot(q, dirs[d]);
                    extreme[std::size_t(d)] = q;
                }
        }
        // The extremes in order of their directions' angle: a convex
        // polygon, counter-clockwise (repeated points make zero edges,
        // which exclude nothing).
        std::vector<glm::dvec2> kept;
        kept.reserve(64);
        for (const glm::dvec2& q : p) {
            bool inside = true;
            for (std::size_t d = 0; d < 8 && inside; ++d) {
                const glm::dvec2 a = extreme[d], b = extreme[(d + 1) % 8];
                const double cross = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
                const bool edge = b != a;
                inside = !edge || cross > 0.0;
            }
            if (!inside) kept.push_back(q);
        }
        for (const glm::dvec2& q : extreme) kept.push_back(q);
        p.swap(kept);
    }
    if (p.empty()) return {};
    std::sort(p.begin(), p.end(), [](const glm::dvec2& a, const glm::dvec2& b) {
        return a.x < b.x || (a.x == b.x && a.y < b.y);
    });
    auto turn = [](const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
        return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    };
    std::vector<glm::dvec2> h(2 * p.size() + 1);
    std::size_t k = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        while (k >= 2 && turn(h[k - 2], h[k - 1], p[i]) <= 0.0) --k;
        h[k++] = p[i];
    }
    for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && turn(h[k - 2], h[k - 1], p[i]) <= 0.0) --k;
        h[k++] = p[i];
    }
    h.resize(k > 0 ? k - 1 : 0);
    return h;
}

void clip_polygon(std::vector<glm::dvec3>& poly, const std::vector<HalfSpace>& by, std::vector<glm::dvec3>& scratch) {
    for (const HalfSpace& h : by) {
        if (poly.empty()) return;
        scratch.clear();
        for (std::size_t i = 0; i < poly.size(); ++i) {
            const glm::dvec3& a = poly[i];
            const glm::dvec3& b = poly[(i + 1) % poly.size()];
            const double da = glm::dot(h.n, a) - h.o, db = glm::dot(h.n, b) - h.o;
            if (da <= 0.0) scratch.push_back(a);
            if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) scratch.push_back(a + (b - a) * (da / (da - db)));
        }
        poly.swap(scratch);
    }
}

void box_in_volume(const Box& b, const std::vector<HalfSpace>& volume,
                   const std::array<glm::dvec3, 8>& volume_corners, std::vector<glm::dvec3>& out) {
    std::array<glm::dvec3, 3> a = b.half;
    const double size = glm::length(b.center) + glm::length(a[0]) + glm::length(a[1]) + glm::length(a[2]);
    const double eps = 1e-6 * size + 1e-12;
    const double longest = std::max({glm::length(a[0]), glm::length(a[1]), glm::length(a[2])});
    // A missing axis (a flat or a one-dimensional mesh) becomes one of
    // length eps across the others.
    for (std::size_t i = 0; i < 3; ++i) {
        if (glm::length(a[i]) > 1e-9 * longest && longest > 0.0) continue;
        glm::dvec3 n = glm::cross(a[(i + 1) % 3], a[(i + 2) % 3]);
        if (!(glm::length(n) > 0.0)) {
            // Not two axes left: any direction across the one there is.
            const glm::dvec3 other = glm::length(a[(i + 1) % 3]) > 0.0 ? a[(i + 1) % 3] : a[(i + 2) % 3];
            n = glm::cross(other, std::abs(other.x) < 0.9 * glm::length(other) ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0));
            if (!(glm::length(n) > 0.0)) n = glm::dvec3(0, 0, 1);
        }
        a[i] = glm::normalize(n) * eps;
    }
    std::array<glm::dvec3, 8> corner;
    for (std::size_t c = 0; c < 8; ++c)
        corner[c] = b.center + a[0] * ((c & 1) ? 1.0 : -1.0) + a[1] * ((c & 2) ? 1.0 : -1.0) +
                    a[2] * ((c & 4) ? 1.0 : -1.0);
    // Wholly inside: its corners; wholly outside one half-space: nothing.
    bool inside = true;
    for (const HalfSpace& h : volume) {
        int out_count = 0;
        for (const glm::dvec3& p : corner) out_count += glm::dot(h.n, p) > h.o;
        if (out_count == 8) return;
        inside = inside && out_count == 0;
    }
    if (inside) {
        out.insert(out.end(), corner.begin(), corner.end());
        return;
    }
    // The box's half-spaces: across each pair of axes, at the third's
    // extent (plus eps). A box too thin to invert (axes nearly in a plane
    // after the widening) is bounded by its corners' axis-aligned box.
    std::vector<HalfSpace> box;
    const double volume3 = std::abs(glm::dot(a[0], glm::cross(a[1], a[2])));
    if (volume3 > 1e-9 * glm::length(a[0]) * glm::length(a[1]) * glm::length(a[2])) {
        for (std::size_t i = 0; i < 3; ++i) {
            const glm::dvec3 n = glm::normalize(glm::cross(a[(i + 1) % 3], a[(i + 2) % 3]));
            const double h = std::abs(glm::dot(a[i], n)) + eps, o = glm::dot(n, b.center);
            box.push_back({n, o + h});
            box.push_back({-n, -o + h});
        }
    } else {
        glm::dvec3 lo = corner[0], hi = corner[0];
        for (const glm::dvec3& p : corner) {
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        for (int i = 0; i < 3; ++i) {
            glm::dvec3 n(0.0);
            n[i] = 1.0;
            box.push_back({n, hi[i] + eps});
            box.push_back({-n, -lo[i] + eps});
        }
    }
    // Faces as corner cycles: the box's with one axis' sign fixed, the
    // volume's likewise (its corner index bits: y 1, x 2, depth 4).
    static constexpr int kBoxFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                            {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    static constexpr int kVolumeFaces[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                               {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
    std::vector<glm::dvec3> poly, scratch;
    for (const auto& f : kBoxFaces) {
        poly = {corner[std::size_t(f[0])], corner[std::size_t(f[1])], corner[std::size_t(f[2])], corner[std::size_t(f[3])]};
        clip_polygon(poly, volume, scratch);
        out.insert(out.end(), poly.begin(), poly.end());
    }
    for (const auto& f : kVolumeFaces) {
        poly = {volume_corners[std::size_t(f[0])], volume_corners[std::size_t(f[1])], volume_corners[std::size_t(f[2])],
                volume_corners[std::size_t(f[3])]};
        clip_polygon(poly, box, scratch);
        out.insert(out.end(), poly.begin(), poly.end());
    }
}

}  // namespace deferred
