// MikkTSpace over triangles (see deferred/tangent_space.h), written from the
// algorithm Blender 3.4 runs: its C++ port of Mikkelsen's reference
// implementation (intern/mikktspace/mikktspace.hh, Apache-2.0), which both
// Mesh.calc_tangents and Cycles call. The steps carry the port's names:
//
//  1. Weld (generateSharedVerticesIndexList): corners equal in position,
//     normal and UV are one vertex. The port starts its search at a hash of
//     the values' bits and compares with ==, so two corners equal in value
//     but not in bits (a zero of either sign: the normals Cycles computes
//     for flat triangles carry both, which splits a flat n-gon's tangents)
//     weld only where one's linear probe happens to reach the other in its
//     hash table, which depends on the table's layout and, above 10 000
//     triangles, on thread timing. This welds by bits and value: the port's
//     result wherever the probes do not meet (a random 12-gon differs in
//     about 1 of 1 000, by a helper's differential test). NaN never welds.
//  2. A triangle with two corners at one position (==) is degenerate
//     (degenPrologue); the others get their tangent from the UV gradient
//     (initTriangle, the paper's eq. 18), flipped on UV-mirrored triangles;
//     one with no UV area or a zero gradient "groups with any".
//  3. Neighbours across each edge of welded vertices, wound oppositely, the
//     first later unpaired edge in (triangle, edge) order (buildNeighbors).
//  4. Groups (build4RuleGroups / assignRecur): around each welded vertex,
//     the triangles reachable over shared edges with the same UV
//     orientation. Only good triangles seed a group; a "group with any"
//     triangle takes the orientation of the first group that reaches it (the
//     algorithm's one order dependency).
//  5. A group's tangent (accumulateTSpaces): the sum, in triangle order, of
//     its good triangles' tangents projected into the corner normal's plane
//     and weighted by the corner's angle in that plane (fast_acosf),
//     normalised. A corner no group reached keeps (1, 0, 0) and sign -1.
//  6. A degenerate triangle's corner copies the first good corner at its
//     welded vertex (degenEpilogue).
//
// Welding, steps 2, 3 and 5 run on parallel_for's threads; the grouping,
// the port's order dependency, on one.
#include <deferred/tangent_space.h>

#include "parallel.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace deferred {

namespace {

struct V3 {
    float x, y, z;
};

V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator*(V3 v, float s) { return {v.x * s, v.y * s, v.z * s}; }
bool operator==(V3 a, V3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
bool not_zero(float x) { return std::fabs(x) > FLT_MIN; }
// The port's float3::normalize: a zero vector stays zero.
V3 normalize(V3 v) {
    const float len = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return len != 0.0f ? v * (1.0f / len) : v;
}
// v without its component along the unit n, normalised (the port's project).
V3 project(V3 n, V3 v) { return normalize(v - n * dot(n, v)); }

// The port's corner-angle weight: Cycles' fast_acosf (util/math_fast.h), a
// polynomial in sqrt(1 - |x|) with at most 4.5e-5 rad of error; acos itself
// would move a tangent by about that much.
float fast_acosf(float x) {
    const float f = std::fabs(x);
    const float m = (f < 1.0f) ? 1.0f - (1.0f - f) : 1.0f;  // clamp and crush denormals
    const float a =
        std::sqrt(1.0f - m) * (1.5707963267f + m * (-0.213300989f + m * (0.077980478f + m * -0.02164095f)));
    return x < 0 ? 3.1415926535897932f - a : a;
}

// Work items per parallel_for index: big enough that the atomic counter is noise.
constexpr std::size_t kChunk = 16384;

template <typename Work>
void parallel_chunks(std::size_t count, const Work& work) {
    parallel_for((count + kChunk - 1) / kChunk, [&](std::size_t chunk) {
        const std::size_t end = std::min(count, (chunk + 1) * kChunk);
        for (std::size_t i = chunk * kChunk; i < end; ++i) work(i);
    });
}

std::uint32_t bits(float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

constexpr std::uint32_t kNone = UINT32_MAX;

struct Triangle {
    V3 tangent{0, 0, 0};  // unit dP/du (zero where the gradient is)
    std::uint32_t neighbour[3] = {kNone, kNone, kNone};  // across edge (corner i, corner i + 1)
    std::uint32_t group[3] = {kNone, kNone, kNone};      // the group of corner i
    bool degenerate = false;
    bool group_with_any = true;
    bool orient_preserving = false;
};

struct Group {
    std::uint32_t vertex;  // welded vertex (a representative corner)
    bool orient_preserving;
    std::uint32_t first, count;  // its triangles: members[first .. first + count)
};

class TangentSolver {
public:
    TangentSolver(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                  std::size_t triangle_count, const float* normals, const float* uvs, const bool* flat)
        : positions_(positions), vertex_count_(vertex_count), indices_(indices), tri_count_(triangle_count),
          normals_(normals), uvs_(uvs), corner_count_(3 * triangle_count) {
        if (flat && std::any_of(flat, flat + triangle_count, [](bool f) { return f; })) use_flat_normals(flat);
    }

    void run(float* out) {
        weld();
        init_triangles();
        build_neighbours();
        build_groups();
        write_tangents(out);
        write_degenerate(out);
    }

private:
    V3 position(std::size_t corner) const {
        const float* p = positions_ + 3 * std::size_t(indices_[corner]);
        return {p[0], p[1], p[2]};
    }
    V3 normal(std::size_t corner) const {
        if (flat_ && flat_[corner / 3]) return flat_normals_[corner / 3];
        const float* n = normals_ + 3 * corner;
        return {n[0], n[1], n[2]};
    }
    float u(std::size_t corner) const { return uvs_[2 * corner]; }
    float v(std::size_t corner) const { return uvs_[2 * corner + 1]; }
    std::uint32_t weld(std::size_t tri, int i) const { return welded_[3 * tri + std::size_t(i)]; }

    // A flat triangle's normal as Cycles computes it, which MikkTSpace
    // reads at its corners: cross(v1 - v0, v2 - v0) divided by its length
    // sqrt((x x + y y) + z z) component by component, (1, 0, 0) for a
    // zero-area triangle (Triangle::compute_normal; Cycles' SSE float3 is
    // plain products and a true division, so the signs of zero match).
    void use_flat_normals(const bool* flat) {
        flat_ = flat;
        flat_normals_.resize(tri_count_);
        parallel_chunks(tri_count_, [&](std::size_t t) {
            if (!flat[t]) return;
            const V3 v0 = position(3 * t), a = position(3 * t + 1) - v0, b = position(3 * t + 2) - v0;
            const V3 n{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
            const float len = std::sqrt((n.x * n.x + n.y * n.y) + n.z * n.z);
            flat_normals_[t] = len == 0.0f ? V3{1.0f, 0.0f, 0.0f} : V3{n.x / len, n.y / len, n.z / len};
        });
    }

    // welded_[corner]: the first corner with the same bits of position,
    // normal and UV that also compares equal (the port's hash of the bits,
    // then its VertexEqual: NaN is never equal). First the vertices: each
    // gets the first vertex at the same position (an open-addressing hash);
    // then the corners, bucketed by that vertex (a counting sort, which
    // keeps a bucket in corner order), join the first earlier representative
    // in their bucket with the same normal and UV.
    void weld() {
        std::vector<std::uint32_t> position_id(vertex_count_);
        {
            std::size_t size = 16;
            while (size < 2 * vertex_count_) size *= 2;
            std::vector<std::uint32_t> table(size, kNone);
            for (std::uint32_t vert = 0; vert < vertex_count_; ++vert) {
                const float* p = positions_ + 3 * std::size_t(vert);
                std::uint64_t h = bits(p[0]) * 0x9E3779B97F4A7C15ull;
                h ^= bits(p[1]) * 0xC2B2AE3D27D4EB4Full;
                h ^= bits(p[2]) * 0x165667B19E3779F9ull;
                std::size_t slot = std::size_t(h ^ (h >> 29)) & (size - 1);
                for (;; slot = (slot + 1) & (size - 1)) {
                    const std::uint32_t other = table[slot];
                    if (other == kNone) {
                        table[slot] = vert;
                        position_id[vert] = vert;
                        break;
                    }
                    const float* q = positions_ + 3 * std::size_t(other);
                    if (bits(p[0]) == bits(q[0]) && bits(p[1]) == bits(q[1]) && bits(p[2]) == bits(q[2]) &&
                        p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) {
                        position_id[vert] = other;
                        break;
                    }
                }
            }
        }
        std::vector<std::uint32_t> start(vertex_count_ + 1, 0);
        for (std::size_t c = 0; c < corner_count_; ++c) ++start[position_id[indices_[c]] + 1];
        for (std::size_t i = 0; i < vertex_count_; ++i) start[i + 1] += start[i];
        std::vector<std::uint32_t> bucket(corner_count_);
        {
            std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
            for (std::uint32_t c = 0; c < corner_count_; ++c) bucket[fill[position_id[indices_[c]]]++] = c;
        }
        welded_.resize(corner_count_);
        auto same_bits_and_value = [](float x, float y) { return bits(x) == bits(y) && x == y; };
        auto same = [&](std::uint32_t a, std::uint32_t b) {
            const V3 na = normal(a), nb = normal(b);
            return same_bits_and_value(na.x, nb.x) && same_bits_and_value(na.y, nb.y) &&
                   same_bits_and_value(na.z, nb.z) && same_bits_and_value(u(a), u(b)) &&
                   same_bits_and_value(v(a), v(b));
        };
        // A corner joins the first earlier representative in its bucket with
        // the same bits and values. Buckets are a vertex's few corners; a
        // point many corners share (a collapsed mesh, a cone's tip with a
        // UV seam per face) is sorted by its corners' bits instead, so the
        // search stays O(k log k), not O(k^2).
        constexpr std::ptrdiff_t kLinearBucket = 16;
        parallel_chunks(vertex_count_, [&](std::size_t vert) {
            std::uint32_t* first = bucket.data() + start[vert];
            std::uint32_t* last = bucket.data() + start[vert + 1];
            if (last - first <= kLinearBucket) {
                for (const std::uint32_t* it = first; it != last; ++it) {
                    welded_[*it] = *it;
                    for (const std::uint32_t* rep = first; rep != it; ++rep)
                        if (welded_[*rep] == *rep && same(*rep, *it)) {
                            welded_[*it] = *rep;
                            break;
                        }
                }
                return;
            }
            struct Keyed {
                std::uint32_t key[5];
                std::uint32_t corner;
            };
            std::vector<Keyed> keyed(std::size_t(last - first));
            for (std::size_t i = 0; i < keyed.size(); ++i) {
                const std::uint32_t c = first[i];
                const V3 n = normal(c);
                keyed[i] = {{bits(n.x), bits(n.y), bits(n.z), bits(u(c)), bits(v(c))}, c};
            }
            std::sort(keyed.begin(), keyed.end(), [](const Keyed& a, const Keyed& b) {
                for (int k = 0; k < 5; ++k)
                    if (a.key[k] != b.key[k]) return a.key[k] < b.key[k];
                return a.corner < b.corner;
            });
            // A run of equal bits in corner order: each joins the run's first
            // corner unless a value is NaN (never equal), which stays alone.
            for (std::size_t i = 0; i < keyed.size();) {
                std::size_t end = i + 1;
                while (end < keyed.size() && std::equal(keyed[i].key, keyed[i].key + 5, keyed[end].key)) ++end;
                const std::uint32_t rep = keyed[i].corner;
                welded_[rep] = rep;
                for (std::size_t j = i + 1; j < end; ++j)
                    welded_[keyed[j].corner] = same(rep, keyed[j].corner) ? rep : keyed[j].corner;
                i = end;
            }
        });
    }

    // degenPrologue's marking and initTriangle (triangles only).
    void init_triangles() {
        tris_.resize(tri_count_);
        parallel_chunks(tri_count_, [&](std::size_t t) {
            Triangle& tri = tris_[t];
            const std::size_t c0 = 3 * t, c1 = c0 + 1, c2 = c0 + 2;
            const V3 v1 = position(c0), v2 = position(c1), v3 = position(c2);
            if (v1 == v2 || v1 == v3 || v2 == v3) {
                tri.degenerate = true;
                return;
            }
            const float t21x = u(c1) - u(c0), t21y = v(c1) - v(c0);
            const float t31x = u(c2) - u(c0), t31y = v(c2) - v(c0);
            const V3 d1 = v2 - v1, d2 = v3 - v1;
            const float signed_area_x2 = t21x * t31y - t21y * t31x;
            const V3 os = d1 * t31y - d2 * t21y;   // eq. 18
            const V3 ot = d1 * -t31x + d2 * t21x;  // eq. 19
            tri.orient_preserving = signed_area_x2 > 0;
            if (not_zero(signed_area_x2)) {
                const float len_os2 = dot(os, os), len_ot2 = dot(ot, ot);
                const float s = tri.orient_preserving ? 1.0f : -1.0f;
                if (not_zero(len_os2)) tri.tangent = os * (s / std::sqrt(len_os2));
                if (not_zero(len_os2) && not_zero(len_ot2)) tri.group_with_any = false;
            }
        });
    }

    // buildNeighbors: edges bucketed by their smaller welded vertex, a
    // bucket ordered by (larger vertex, edge number); an edge pairs with the
    // first later unpaired edge of the same two vertices wound the other way.
    void build_neighbours() {
        std::vector<std::uint32_t> start(corner_count_ + 1, 0);
        for (std::size_t t = 0; t < tri_count_; ++t) {
            if (tris_[t].degenerate) continue;
            for (int i = 0; i < 3; ++i) ++start[std::min(weld(t, i), weld(t, (i + 1) % 3)) + 1];
        }
        for (std::size_t i = 0; i < corner_count_; ++i) start[i + 1] += start[i];
        struct Edge {
            std::uint32_t other;   // the larger welded vertex
            std::uint32_t number;  // 3 t + i
        };
        std::vector<Edge> edges(start[corner_count_]);
        {
            std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
            for (std::size_t t = 0; t < tri_count_; ++t) {
                if (tris_[t].degenerate) continue;
                for (int i = 0; i < 3; ++i) {
                    const std::uint32_t a = weld(t, i), b = weld(t, (i + 1) % 3);
                    edges[fill[std::min(a, b)]++] = {std::max(a, b), std::uint32_t(3 * t + std::size_t(i))};
                }
            }
        }
        // Filled in ascending edge number, so a stable sort by the larger
        // vertex gives (min, max, number) order. An edge's neighbour slot is
        // written only from its own bucket.
        parallel_chunks(corner_count_, [&](std::size_t vert) {
            Edge* first = edges.data() + start[vert];
            Edge* last = edges.data() + start[vert + 1];
            if (last - first < 2) return;
            std::stable_sort(first, last, [](const Edge& a, const Edge& b) { return a.other < b.other; });
            for (Edge* a = first; a != last; ++a) {
                const std::uint32_t ta = a->number / 3, ia = a->number % 3;
                if (tris_[ta].neighbour[ia] != kNone) continue;
                const std::uint32_t a0 = weld(ta, int(ia)), a1 = weld(ta, int(ia + 1) % 3);
                for (Edge* b = a + 1; b != last && b->other == a->other; ++b) {
                    const std::uint32_t tb = b->number / 3, ib = b->number % 3;
                    if (tris_[tb].neighbour[ib] != kNone) continue;
                    if (weld(tb, int(ib)) == a1 && weld(tb, int(ib + 1) % 3) == a0) {
                        tris_[ta].neighbour[ia] = tb;
                        tris_[tb].neighbour[ib] = ta;
                        break;
                    }
                }
            }
        });
    }

    // build4RuleGroups with assignRecur's recursion as an explicit stack
    // (the left neighbour's whole subtree before the right one, as the
    // recursion visits them).
    void build_groups() {
        members_.reserve(corner_count_);
        std::vector<std::uint32_t> stack;
        for (std::size_t t = 0; t < tri_count_; ++t) {
            const Triangle& seed = tris_[t];
            if (seed.degenerate || seed.group_with_any) continue;
            for (int i = 0; i < 3; ++i) {
                if (tris_[t].group[i] != kNone) continue;
                const std::uint32_t g = std::uint32_t(groups_.size());
                groups_.push_back({weld(t, i), seed.orient_preserving, std::uint32_t(members_.size()), 0});
                tris_[t].group[i] = g;
                members_.push_back(std::uint32_t(t));
                stack.clear();
                push_neighbours(stack, tris_[t], i);
                while (!stack.empty()) {
                    const std::uint32_t n = stack.back();
                    stack.pop_back();
                    assign(stack, n, g);
                }
                groups_[g].count = std::uint32_t(members_.size()) - groups_[g].first;
            }
        }
    }

    static void push_neighbours(std::vector<std::uint32_t>& stack, const Triangle& tri, int i) {
        const std::uint32_t left = tri.neighbour[i], right = tri.neighbour[i > 0 ? i - 1 : 2];
        if (right != kNone) stack.push_back(right);
        if (left != kNone) stack.push_back(left);
    }

    void assign(std::vector<std::uint32_t>& stack, std::uint32_t t, std::uint32_t g) {
        const Group& group = groups_[g];
        Triangle& tri = tris_[t];
        int i = 0;
        while (i < 3 && weld(t, i) != group.vertex) ++i;
        if (i == 3 || tri.group[i] != kNone) return;  // not around this vertex (cannot happen), or grouped
        // The first group to reach a "group with any" triangle sets its orientation.
        if (tri.group_with_any && tri.group[0] == kNone && tri.group[1] == kNone && tri.group[2] == kNone)
            tri.orient_preserving = group.orient_preserving;
        if (tri.orient_preserving != group.orient_preserving) return;
        tri.group[i] = g;
        members_.push_back(t);
        push_neighbours(stack, tri, i);
    }

    // accumulateTSpaces + generateTSpaces, by group: a group's good
    // triangles in ascending order (the port's serial order), each corner's
    // tangent weighted by its angle.
    void write_tangents(float* out) {
        parallel_chunks(corner_count_, [&](std::size_t c) {  // a corner no group reaches
            float* o = out + 4 * c;
            o[0] = 1.0f;
            o[1] = o[2] = 0.0f;
            o[3] = -1.0f;
        });
        const std::size_t chunks = (groups_.size() + kChunk - 1) / kChunk;
        parallel_for(chunks, [&](std::size_t chunk) {
            std::vector<std::uint32_t> faces;
            const std::size_t end = std::min(groups_.size(), (chunk + 1) * kChunk);
            for (std::size_t g = chunk * kChunk; g < end; ++g) {
                const Group& group = groups_[g];
                faces.assign(members_.begin() + group.first, members_.begin() + group.first + group.count);
                std::sort(faces.begin(), faces.end());
                V3 sum{0, 0, 0};
                for (const std::uint32_t f : faces) {
                    if (tris_[f].group_with_any) continue;
                    const int i = corner_of(f, group.vertex);
                    const V3 n = normal(3 * std::size_t(f) + std::size_t(i));
                    sum = sum + project(n, tris_[f].tangent) * fast_acosf(std::clamp(corner_cos(f, i, n), -1.0f, 1.0f));
                }
                const V3 tangent = normalize(sum);
                for (const std::uint32_t f : faces) {
                    float* o = out + 4 * (3 * std::size_t(f) + std::size_t(corner_of(f, group.vertex)));
                    o[0] = tangent.x;
                    o[1] = tangent.y;
                    o[2] = tangent.z;
                    o[3] = group.orient_preserving ? 1.0f : -1.0f;
                }
            }
        });
    }

    int corner_of(std::size_t t, std::uint32_t vertex) const {
        int i = 0;
        while (weld(t, i) != vertex) ++i;
        return i;
    }

    // The cosine of triangle f's angle at corner i, its edges projected
    // into the plane of n (accumulateTSpaces' fCos).
    float corner_cos(std::uint32_t f, int i, V3 n) const {
        const std::size_t c = 3 * std::size_t(f);
        const V3 p = position(c + std::size_t(i));
        const V3 next = position(c + std::size_t(i < 2 ? i + 1 : 0));
        const V3 prev = position(c + std::size_t(i > 0 ? i - 1 : 2));
        return dot(project(n, next - p), project(n, prev - p));
    }

    // degenEpilogue: a degenerate triangle's corner copies the first good
    // corner (in triangle order) at its welded vertex.
    void write_degenerate(float* out) {
        std::vector<std::uint32_t> degenerate;
        for (std::size_t t = 0; t < tri_count_; ++t)
            if (tris_[t].degenerate) degenerate.push_back(std::uint32_t(t));
        if (degenerate.empty()) return;
        std::vector<std::uint32_t> first_good(corner_count_, kNone);
        for (std::size_t t = 0; t < tri_count_; ++t) {
            if (tris_[t].degenerate) continue;
            for (int i = 0; i < 3; ++i) {
                std::uint32_t& slot = first_good[weld(t, i)];
                if (slot == kNone) slot = std::uint32_t(3 * t + std::size_t(i));
            }
        }
        for (const std::uint32_t t : degenerate)
            for (int i = 0; i < 3; ++i) {
                const std::uint32_t source = first_good[weld(t, i)];
                if (source != kNone)
                    std::memcpy(out + 4 * (3 * std::size_t(t) + std::size_t(i)), out + 4 * std::size_t(source),
                                4 * sizeof(float));
            }
    }

    const float* positions_;
    std::size_t vertex_count_;
    const std::uint32_t* indices_;
    std::size_t tri_count_;
    const float* normals_;
    const float* uvs_;
    std::size_t corner_count_;

    const bool* flat_ = nullptr;       // flat-shaded triangles, when any
    std::vector<V3> flat_normals_;     // their normals (Cycles' computation), by triangle
    std::vector<std::uint32_t> welded_;
    std::vector<Triangle> tris_;
    std::vector<Group> groups_;
    std::vector<std::uint32_t> members_;
};

}  // namespace

void compute_tangents(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                      std::size_t triangle_count, const float* corner_normals, const float* corner_uvs,
                      const bool* flat_triangles, float* tangents) {
    if (triangle_count >= std::size_t(INT32_MAX) / 3)
        throw std::invalid_argument("compute_tangents: " + std::to_string(triangle_count) +
                                    " triangles; at most " + std::to_string(INT32_MAX / 3 - 1) + " are supported");
    if (vertex_count >= std::size_t(UINT32_MAX))
        throw std::invalid_argument("compute_tangents: too many vertices");
    for (std::size_t c = 0; c < 3 * triangle_count; ++c)
        if (indices[c] >= vertex_count)
            throw std::invalid_argument("compute_tangents: index " + std::to_string(indices[c]) + " at corner " +
                                        std::to_string(c) + " is out of range (" + std::to_string(vertex_count) +
                                        " vertices)");
    if (triangle_count == 0) return;
    TangentSolver(positions, vertex_count, indices, triangle_count, corner_normals, corner_uvs, flat_triangles)
        .run(tangents);
}

}  // namespace deferred
