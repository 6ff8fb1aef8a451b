// Pointiness and Random Per Island as Cycles 3.4's Blender sync computes them
// (intern/cycles/blender/mesh.cpp: attr_create_pointiness,
// attr_create_random_per_island; util/disjoint_set.h; util/hash.h), written
// from those functions' algorithms in Cycles' float arithmetic (its SSE
// float3: separate products, true divisions).
#include <deferred/mesh_attributes.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace deferred {

namespace {

struct F3 {
    float x, y, z;
};
F3 operator-(F3 a, F3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
F3 operator+(F3 a, F3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
float dot(F3 a, F3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
F3 divide(F3 a, float f) { return {a.x / f, a.y / f, a.z / f}; }
F3 normalize(F3 a) { return divide(a, std::sqrt(dot(a, a))); }

void check_indices(const std::uint32_t* indices, std::size_t count, std::size_t vertex_count, const char* what) {
    for (std::size_t i = 0; i < count; ++i)
        if (indices[i] >= vertex_count)
            throw std::invalid_argument(std::string(what) + ": vertex index " + std::to_string(indices[i]) +
                                        " is out of range (" + std::to_string(vertex_count) + " vertices)");
}

// util/hash.h hash_uint (Jenkins' lookup3 final mix) and hash_uint_to_float.
std::uint32_t rot(std::uint32_t x, int k) { return (x << k) | (x >> (32 - k)); }
std::uint32_t hash_uint(std::uint32_t kx) {
    std::uint32_t a, b, c;
    a = b = c = 0xdeadbeefu + (1u << 2) + 13u;
    a += kx;
    c ^= b; c -= rot(b, 14);
    a ^= c; a -= rot(c, 11);
    b ^= a; b -= rot(a, 25);
    c ^= b; c -= rot(b, 16);
    a ^= c; a -= rot(c, 4);
    b ^= a; b -= rot(a, 14);
    c ^= b; c -= rot(b, 24);
    return c;
}
float hash_uint_to_float(std::uint32_t kx) { return float(hash_uint(kx)) / float(0xFFFFFFFFu); }

}  // namespace

void compute_pointiness(const float* positions, const float* vertex_normals, std::size_t vertex_count,
                        const std::uint32_t* edges, std::size_t edge_count, float* out) {
    check_indices(edges, 2 * edge_count, vertex_count, "compute_pointiness");
    if (vertex_count == 0) return;
    auto co = [&](std::size_t v) { return F3{positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]}; };
    // STEP 1: duplicates. Sorted by coordinate sum (equal positions: the
    // higher index first); a vertex points at the first later vertex in that
    // order within 3 FLT_EPSILON of its sum and FLT_EPSILON of squared
    // distance, then chains resolve to their end.
    std::vector<std::size_t> sorted(vertex_count);
    std::iota(sorted.begin(), sorted.end(), std::size_t(0));
    auto sum = [&](std::size_t v) {
        const F3 p = co(v);
        return p.x + p.y + p.z;
    };
    // Cycles' comparator leaves equal sums of different positions unordered
    // (and is not a strict weak order there); these are ordered by their
    // coordinates, so the sort is well defined.
    std::sort(sorted.begin(), sorted.end(), [&](std::size_t a, std::size_t b) {
        const float sa = sum(a), sb = sum(b);
        if (sa != sb) return sa < sb;
        const F3 pa = co(a), pb = co(b);
        if (pa.x != pb.x) return pa.x < pb.x;
        if (pa.y != pb.y) return pa.y < pb.y;
        if (pa.z != pb.z) return pa.z < pb.z;
        return a > b;  // equal positions: the higher index first, as Cycles
    });
    std::vector<std::size_t> orig(vertex_count);
    for (std::size_t i = 0; i < vertex_count; ++i) {
        const std::size_t v = sorted[i];
        const F3 p = co(v);
        orig[v] = v;
        for (std::size_t j = i + 1; j < vertex_count; ++j) {
            const std::size_t o = sorted[j];
            if (sum(o) - sum(v) > 3 * FLT_EPSILON) break;
            const F3 d = co(o) - p;
            if (dot(d, d) < FLT_EPSILON) {
                orig[v] = o;
                break;
            }
        }
    }
    for (std::size_t v = 0; v < vertex_count; ++v) {
        std::size_t o = orig[v];
        while (o != orig[o]) o = orig[o];
        orig[v] = o;
    }
    // STEP 2: welded vertex normals.
    std::vector<F3> normal(vertex_count, F3{0, 0, 0});
    for (std::size_t v = 0; v < vertex_count; ++v)
        normal[orig[v]] = normal[orig[v]] + F3{vertex_normals[3 * v], vertex_normals[3 * v + 1], vertex_normals[3 * v + 2]};
    for (std::size_t v = 0; v < vertex_count; ++v)
        if (orig[v] == v) normal[v] = normalize(normal[v]);
    // STEP 3: the one-ring's mean edge direction against the normal.
    std::vector<std::pair<std::size_t, std::size_t>> unique_edges;
    {
        std::set<std::pair<std::size_t, std::size_t>> visited;
        for (std::size_t e = 0; e < edge_count; ++e) {
            const std::size_t v0 = orig[edges[2 * e]], v1 = orig[edges[2 * e + 1]];
            if (!visited.insert({std::min(v0, v1), std::max(v0, v1)}).second) continue;
            unique_edges.push_back({v0, v1});
        }
    }
    std::vector<int> counter(vertex_count, 0);
    std::vector<F3> accum(vertex_count, F3{0, 0, 0});
    for (const auto& [v0, v1] : unique_edges) {
        const F3 edge = normalize(co(v1) - co(v0));
        accum[v0] = accum[v0] + edge;
        accum[v1] = accum[v1] - edge;
        ++counter[v0];
        ++counter[v1];
    }
    std::vector<float> raw(vertex_count, 0.0f);
    for (std::size_t v = 0; v < vertex_count; ++v) {
        if (orig[v] != v || counter[v] == 0) continue;
        // safe_acosf: acosf(clamp(x, -1, 1)) with Cycles' clamp, min(max(x,
        // -1), 1) by comparisons, which turns NaN into -1: a vertex with an
        // edge to itself (its two ends welded: a zero vector normalised)
        // reads pi, i.e. 1.
        const float x = dot(normal[v], divide(accum[v], float(counter[v])));
        const float lo = x > -1.0f ? x : -1.0f;
        const float c = lo < 1.0f ? lo : 1.0f;
        raw[v] = std::acos(c) * float(M_1_PI);
    }
    // STEP 4: one blur step over the same edges, then the duplicates copy.
    std::vector<float> data(raw);
    std::fill(counter.begin(), counter.end(), 0);
    for (const auto& [v0, v1] : unique_edges) {
        data[v0] += raw[v1];
        data[v1] += raw[v0];
        ++counter[v0];
        ++counter[v1];
    }
    for (std::size_t v = 0; v < vertex_count; ++v) data[v] /= float(counter[v] + 1);
    for (std::size_t v = 0; v < vertex_count; ++v) out[v] = data[orig[v]];
}

void compute_random_per_island(std::size_t vertex_count, const std::uint32_t* edges, std::size_t edge_count,
                               const std::uint32_t* first_vertices, std::size_t triangle_count, float* out) {
    check_indices(edges, 2 * edge_count, vertex_count, "compute_random_per_island");
    check_indices(first_vertices, triangle_count, vertex_count, "compute_random_per_island");
    std::vector<std::size_t> parent(vertex_count), rank(vertex_count, 0);
    std::iota(parent.begin(), parent.end(), std::size_t(0));
    auto find = [&](std::size_t x) {
        std::size_t root = x;
        while (parent[root] != root) root = parent[root];
        while (parent[x] != root) {
            const std::size_t next = parent[x];
            parent[x] = root;
            x = next;
        }
        return root;
    };
    for (std::size_t e = 0; e < edge_count; ++e) {
        std::size_t x = find(edges[2 * e]), y = find(edges[2 * e + 1]);
        if (x == y) continue;
        if (rank[x] < rank[y]) std::swap(x, y);
        parent[y] = x;
        if (rank[x] == rank[y]) ++rank[x];
    }
    for (std::size_t t = 0; t < triangle_count; ++t)
        out[t] = hash_uint_to_float(std::uint32_t(find(first_vertices[t])));
}

}  // namespace deferred
