#include "mesh_topology.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include <glm/glm.hpp>

namespace deferred {

namespace {

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t v) {
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];  // path halving
        v = parent[v];
    }
    return v;
}

}  // namespace

int closed_orientation(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                       std::size_t triangle_count) {
    if (triangle_count == 0 || !positions || !indices) return 0;
    // Directed edges a -> b as (a << 32 | b): closed and consistently wound
    // when each occurs once and so does its reverse.
    std::vector<std::uint64_t> edges(triangle_count * 3);
    for (std::size_t t = 0; t < triangle_count; ++t)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = indices[3 * t + std::size_t(k)], b = indices[3 * t + std::size_t((k + 1) % 3)];
            if (a == b || a >= vertex_count || b >= vertex_count) return 0;
            edges[3 * t + std::size_t(k)] = (std::uint64_t(a) << 32) | b;
        }
    std::sort(edges.begin(), edges.end());
    if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return 0;
    for (std::uint64_t e : edges) {
        const std::uint64_t reverse = (e << 32) | (e >> 32);
        if (!std::binary_search(edges.begin(), edges.end(), reverse)) return 0;
    }
    // Connected parts (vertices joined by edges), each with its own signed
    // volume: the sum over its triangles of det(p0 - o, p1 - o, p2 - o) / 6
    // for any point o (the divergence theorem), taken at one of its own
    // vertices so that a part far from the origin keeps its digits.
    std::vector<std::uint32_t> parent(vertex_count);
    std::iota(parent.begin(), parent.end(), 0u);
    for (std::size_t t = 0; t < triangle_count; ++t)
        for (int k = 1; k < 3; ++k) {
            const std::uint32_t a = find_root(parent, indices[3 * t]), b = find_root(parent, indices[3 * t + std::size_t(k)]);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
    auto position = [&](std::uint32_t v) {
        return glm::dvec3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    };
    std::vector<double> volume(vertex_count, 0.0), magnitude(vertex_count, 0.0);
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const std::uint32_t root = find_root(parent, indices[3 * t]);
        const glm::dvec3 o = position(root);
        const double v = glm::dot(position(indices[3 * t]) - o,
                                  glm::cross(position(indices[3 * t + 1]) - o, position(indices[3 * t + 2]) - o));
        volume[root] += v;
        magnitude[root] += std::abs(v);
    }
    int sign = 0;
    for (std::uint32_t v = 0; v < vertex_count; ++v) {
        if (parent[v] != v || magnitude[v] == 0.0) continue;  // not a root, or a vertex no triangle uses
        // A part whose volume is lost in its rounding (coincident faces
        // wound both ways) has no inside to speak of.
        if (std::abs(volume[v]) <= 1e-9 * magnitude[v]) return 0;
        const int s = volume[v] > 0 ? 1 : -1;
        if (sign != 0 && s != sign) return 0;
        sign = s;
    }
    return sign;
}

bool planar_mesh(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                 std::size_t triangle_count, double normal[3], double& offset) {
    if (triangle_count == 0 || !positions || !indices) return false;
    auto vertex = [&](std::uint32_t i) {
        return glm::dvec3(positions[3 * std::size_t(i)], positions[3 * std::size_t(i) + 1],
                          positions[3 * std::size_t(i) + 2]);
    };
    glm::dvec3 lo(1e300), hi(-1e300), best(0.0), origin(0.0);
    double best_area2 = 0.0;
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const std::uint32_t* tri = indices + 3 * t;
        if (tri[0] >= vertex_count || tri[1] >= vertex_count || tri[2] >= vertex_count) return false;
        const glm::dvec3 a = vertex(tri[0]), b = vertex(tri[1]), c = vertex(tri[2]);
        for (const glm::dvec3& v : {a, b, c}) {
            lo = glm::min(lo, v);
            hi = glm::max(hi, v);
        }
        const glm::dvec3 n = glm::cross(b - a, c - a);
        if (glm::dot(n, n) > best_area2) {
            best_area2 = glm::dot(n, n);
            best = n;
            origin = a;
        }
    }
    if (!(best_area2 > 0.0)) return false;
    const glm::dvec3 n = best / std::sqrt(best_area2);
    const double d = glm::dot(n, origin), tolerance = 1e-5 * glm::length(hi - lo);
    for (std::size_t i = 0; i < 3 * triangle_count; ++i)
        if (!(std::abs(glm::dot(n, vertex(indices[i])) - d) <= tolerance)) return false;
    for (int k = 0; k < 3; ++k) normal[k] = n[k];
    offset = d;
    return true;
}

bool convex_mesh(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                 std::size_t triangle_count, int closed) {
    if (closed == 0 || triangle_count == 0 || !positions || !indices) return false;
    if (double(vertex_count) * double(triangle_count) > kMaxConvexTestWork) return false;
    auto vertex = [&](std::uint32_t i) {
        return glm::dvec3(positions[3 * std::size_t(i)], positions[3 * std::size_t(i) + 1],
                          positions[3 * std::size_t(i) + 2]);
    };
    std::vector<bool> used(vertex_count, false);
    glm::dvec3 lo(1e300), hi(-1e300);
    for (std::size_t i = 0; i < 3 * triangle_count; ++i) {
        if (indices[i] >= vertex_count) return false;
        used[indices[i]] = true;
        lo = glm::min(lo, vertex(indices[i]));
        hi = glm::max(hi, vertex(indices[i]));
    }
    const double tolerance = 1e-5 * glm::length(hi - lo);
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const glm::dvec3 a = vertex(indices[3 * t]), b = vertex(indices[3 * t + 1]), c = vertex(indices[3 * t + 2]);
        glm::dvec3 n = glm::cross(b - a, c - a);
        const double len = glm::length(n);
        if (!(len > 0.0)) continue;  // a degenerate triangle bounds nothing
        n *= double(closed) / len;   // outward
        for (std::size_t v = 0; v < vertex_count; ++v)
            if (used[v] && glm::dot(n, vertex(std::uint32_t(v)) - a) > tolerance) return false;
    }
    return true;
}

}  // namespace deferred
