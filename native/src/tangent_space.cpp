// MikkTSpace over triangles (see deferred/tangent_space.h), written from the
// algorithm of Mikkelsen's reference implementation (mikktspace.c, zlib
// licence; the steps below carry its function names) so that a corner gets
// the tangent Blender and Cycles compute, up to float summation order:
//
//  1. Weld: corners equal in position, normal and UV are one vertex
//     (GenerateSharedVerticesIndexList).
//  2. A triangle with two corners at one position is degenerate
//     (DegenPrologue); the others get their tangent and bitangent from the
//     UV gradient (InitTriInfo, the paper's eq. 18/19), normalised and
//     flipped on UV-mirrored triangles, and "group with any" when their UV
//     area or gradient is zero.
//  3. Neighbours across each edge of welded vertices, wound oppositely
//     (BuildNeighborsFast: edges ordered by (min, max, edge number)).
//  4. Groups: around each welded vertex, the triangles reachable over shared
//     edges with the same UV orientation (Build4RuleGroups / AssignRecur; a
//     "group with any" triangle takes the orientation of the first group
//     that reaches it, the algorithm's one order dependency).
//  5. Within a group, subgroups of compatible tangents (the default angular
//     threshold of 180 degrees separates only exactly opposite ones), and a
//     subgroup's tangent is the corner-angle-weighted sum of its triangles'
//     tangents projected into the normal's plane (GenerateTSpaces,
//     EvalTspace).
//  6. A degenerate triangle's corner copies the tangent of the first good
//     corner at its welded vertex, or keeps (1, 0, 0) with sign -1
//     (DegenEpilogue, genTangSpace's initial value).
//
// The corner welding and steps 2, 3 and 5 run on parallel_for's threads;
// the rest, the grouping among it, on one.
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
V3 scale(float s, V3 v) { return {s * v.x, s * v.y, s * v.z}; }
float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
float length(V3 v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
bool not_zero(float x) { return std::fabs(x) > FLT_MIN; }
bool not_zero(V3 v) { return not_zero(v.x) || not_zero(v.y) || not_zero(v.z); }
V3 normalize(V3 v) { return scale(1.0f / length(v), v); }
// v without its component along the unit n, normalised unless zero.
V3 project(V3 v, V3 n) {
    const V3 p = v - scale(dot(n, v), n);
    return not_zero(p) ? normalize(p) : p;
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

// Bits of a float with -0 read as +0, so that equal values (MikkTSpace
// compares with ==) have equal keys.
std::uint32_t key_bits(float f) {
    if (f == 0.0f) f = 0.0f;
    std::uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

enum : std::uint8_t {
    kOrientPreserving = 1,
    kGroupWithAny = 2,
    kDegenerate = 4,
};

struct TriangleInfo {
    V3 os{0, 0, 0}, ot{0, 0, 0};  // unit tangent and bitangent from the UV gradient (or zero)
    std::int32_t neighbour[3] = {-1, -1, -1};  // across edge (corner i, corner i+1)
    std::int32_t group[3] = {-1, -1, -1};      // the group of corner i
    std::uint8_t flags = kGroupWithAny;
};

struct Group {
    std::uint32_t vertex;  // welded vertex (a representative corner)
    bool orient_preserving;
    std::uint32_t first, count;  // triangles: members[first .. first + count)
};

class TangentSolver {
public:
    TangentSolver(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                  std::size_t triangle_count, const float* normals, const float* uvs)
        : positions_(positions), vertex_count_(vertex_count), indices_(indices), tri_count_(triangle_count),
          normals_(normals), uvs_(uvs), corner_count_(3 * triangle_count) {}

    void run(float* out) {
        weld_positions();
        weld_corners();
        init_triangles();
        build_neighbours();
        build_groups();
        write_tangents(out);
        write_degenerate(out);
    }

private:
    V3 position(std::uint32_t corner) const {
        const float* p = positions_ + 3 * std::size_t(indices_[corner]);
        return {p[0], p[1], p[2]};
    }
    V3 normal(std::uint32_t corner) const {
        const float* n = normals_ + 3 * std::size_t(corner);
        return {n[0], n[1], n[2]};
    }
    float u(std::uint32_t corner) const { return uvs_[2 * std::size_t(corner)]; }
    float v(std::uint32_t corner) const { return uvs_[2 * std::size_t(corner) + 1]; }
    std::uint32_t weld(std::size_t tri, int i) const { return welded_[3 * tri + std::size_t(i)]; }

    // position_id_[vertex]: the first vertex at the same position (== on all
    // three coordinates), by an open-addressing hash over the vertices.
    void weld_positions() {
        position_id_.resize(vertex_count_);
        std::size_t size = 16;
        while (size < 2 * vertex_count_) size *= 2;
        std::vector<std::uint32_t> table(size, UINT32_MAX);
        for (std::uint32_t vert = 0; vert < vertex_count_; ++vert) {
            const float* p = positions_ + 3 * std::size_t(vert);
            std::uint64_t h = key_bits(p[0]) * 0x9E3779B97F4A7C15ull;
            h ^= key_bits(p[1]) * 0xC2B2AE3D27D4EB4Full;
            h ^= key_bits(p[2]) * 0x165667B19E3779F9ull;
            std::size_t slot = std::size_t(h ^ (h >> 29)) & (size - 1);
            for (;; slot = (slot + 1) & (size - 1)) {
                const std::uint32_t other = table[slot];
                if (other == UINT32_MAX) {
                    table[slot] = vert;
                    position_id_[vert] = vert;
                    break;
                }
                const float* q = positions_ + 3 * std::size_t(other);
                if (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) {
                    position_id_[vert] = other;
                    break;
                }
            }
        }
    }

    // welded_[corner]: the first corner equal in position, normal and UV.
    // Corners are bucketed by position (counting sort), then each bucket is
    // sorted by (normal, UV, corner) so equal corners are adjacent.
    void weld_corners() {
        std::vector<std::uint32_t> start(vertex_count_ + 1, 0);
        for (std::size_t c = 0; c < corner_count_; ++c) ++start[position_id_[indices_[c]] + 1];
        for (std::size_t i = 0; i < vertex_count_; ++i) start[i + 1] += start[i];
        std::vector<std::uint32_t> bucket(corner_count_);
        {
            std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
            for (std::uint32_t c = 0; c < corner_count_; ++c) bucket[fill[position_id_[indices_[c]]]++] = c;
        }
        welded_.resize(corner_count_);
        auto key = [&](std::uint32_t c, int k) {
            return k < 3 ? key_bits(normals_[3 * std::size_t(c) + std::size_t(k)])
                         : key_bits(uvs_[2 * std::size_t(c) + std::size_t(k - 3)]);
        };
        auto less = [&](std::uint32_t a, std::uint32_t b) {
            for (int k = 0; k < 5; ++k) {
                const std::uint32_t ka = key(a, k), kb = key(b, k);
                if (ka != kb) return ka < kb;
            }
            return a < b;
        };
        auto same = [&](std::uint32_t a, std::uint32_t b) {
            const float* na = normals_ + 3 * std::size_t(a);
            const float* nb = normals_ + 3 * std::size_t(b);
            return na[0] == nb[0] && na[1] == nb[1] && na[2] == nb[2] && u(a) == u(b) && v(a) == v(b);
        };
        parallel_chunks(vertex_count_, [&](std::size_t vert) {
            std::uint32_t* first = bucket.data() + start[vert];
            std::uint32_t* last = bucket.data() + start[vert + 1];
            if (first == last) return;
            std::sort(first, last, less);
            std::uint32_t rep = *first;
            for (std::uint32_t* it = first; it != last; ++it) {
                if (it != first && !same(rep, *it)) rep = *it;
                welded_[*it] = rep;
            }
        });
    }

    // InitTriInfo (triangles only) and DegenPrologue's marking.
    void init_triangles() {
        tris_.assign(tri_count_, TriangleInfo{});
        parallel_chunks(tri_count_, [&](std::size_t t) {
            TriangleInfo& tri = tris_[t];
            const std::uint32_t c0 = std::uint32_t(3 * t), c1 = c0 + 1, c2 = c0 + 2;
            const std::uint32_t p0 = position_id_[indices_[c0]], p1 = position_id_[indices_[c1]],
                                p2 = position_id_[indices_[c2]];
            if (p0 == p1 || p0 == p2 || p1 == p2) {
                tri.flags |= kDegenerate;
                return;
            }
            const V3 v1 = position(c0), v2 = position(c1), v3 = position(c2);
            const float t21x = u(c1) - u(c0), t21y = v(c1) - v(c0);
            const float t31x = u(c2) - u(c0), t31y = v(c2) - v(c0);
            const V3 d1 = v2 - v1, d2 = v3 - v1;
            const float signed_area_x2 = t21x * t31y - t21y * t31x;
            const V3 os = scale(t31y, d1) - scale(t21y, d2);   // eq. 18
            const V3 ot = scale(-t31x, d1) + scale(t21x, d2);  // eq. 19
            if (signed_area_x2 > 0) tri.flags |= kOrientPreserving;
            if (not_zero(signed_area_x2)) {
                const float abs_area = std::fabs(signed_area_x2);
                const float len_os = length(os), len_ot = length(ot);
                const float s = (tri.flags & kOrientPreserving) ? 1.0f : -1.0f;
                if (not_zero(len_os)) tri.os = scale(s / len_os, os);
                if (not_zero(len_ot)) tri.ot = scale(s / len_ot, ot);
                // The magnitudes before normalisation decide whether the triangle is good.
                if (not_zero(len_os / abs_area) && not_zero(len_ot / abs_area)) tri.flags &= ~kGroupWithAny;
            }
        });
    }

    // BuildNeighborsFast: edges bucketed by their smaller welded vertex, a
    // bucket ordered by (larger vertex, edge number); an edge pairs with the
    // first later unpaired edge of the same two vertices wound the other way.
    void build_neighbours() {
        std::vector<std::uint32_t> start(corner_count_ + 1, 0);
        for (std::size_t t = 0; t < tri_count_; ++t) {
            if (tris_[t].flags & kDegenerate) continue;
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
                if (tris_[t].flags & kDegenerate) continue;
                for (int i = 0; i < 3; ++i) {
                    const std::uint32_t a = weld(t, i), b = weld(t, (i + 1) % 3);
                    edges[fill[std::min(a, b)]++] = {std::max(a, b), std::uint32_t(3 * t + std::size_t(i))};
                }
            }
        }
        // Filled in ascending edge number, so a stable sort by the larger
        // vertex gives MikkTSpace's (min, max, number) order.
        parallel_chunks(corner_count_, [&](std::size_t vert) {
            Edge* first = edges.data() + start[vert];
            Edge* last = edges.data() + start[vert + 1];
            if (last - first < 2) return;
            std::stable_sort(first, last, [](const Edge& a, const Edge& b) { return a.other < b.other; });
            for (Edge* a = first; a != last; ++a) {
                const std::uint32_t ta = a->number / 3, ia = a->number % 3;
                if (tris_[ta].neighbour[ia] >= 0) continue;
                const std::uint32_t a0 = weld(ta, int(ia)), a1 = weld(ta, int(ia + 1) % 3);
                for (Edge* b = a + 1; b != last && b->other == a->other; ++b) {
                    const std::uint32_t tb = b->number / 3, ib = b->number % 3;
                    if (tris_[tb].neighbour[ib] >= 0) continue;
                    if (weld(tb, int(ib)) == a1 && weld(tb, int(ib + 1) % 3) == a0) {
                        tris_[ta].neighbour[ia] = std::int32_t(tb);
                        tris_[tb].neighbour[ib] = std::int32_t(ta);
                        break;
                    }
                }
            }
        });
    }

    // Build4RuleGroups with AssignRecur's recursion as an explicit stack
    // (left neighbour's subtree before the right one's, as the recursion).
    void build_groups() {
        members_.reserve(corner_count_);
        std::vector<std::int32_t> stack;
        for (std::size_t t = 0; t < tri_count_; ++t) {
            if (tris_[t].flags & kDegenerate) continue;
            for (int i = 0; i < 3; ++i) {
                if (tris_[t].group[i] >= 0) continue;
                const std::int32_t g = std::int32_t(groups_.size());
                groups_.push_back({weld(t, i), (tris_[t].flags & kOrientPreserving) != 0,
                                   std::uint32_t(members_.size()), 0});
                tris_[t].group[i] = g;
                members_.push_back(std::uint32_t(t));
                stack.clear();
                push_neighbours(stack, tris_[t], i);
                while (!stack.empty()) {
                    const std::int32_t n = stack.back();
                    stack.pop_back();
                    assign(stack, std::size_t(n), g);
                }
                groups_[std::size_t(g)].count = std::uint32_t(members_.size()) - groups_[std::size_t(g)].first;
            }
        }
    }

    static void push_neighbours(std::vector<std::int32_t>& stack, const TriangleInfo& tri, int i) {
        const std::int32_t left = tri.neighbour[i], right = tri.neighbour[i > 0 ? i - 1 : 2];
        if (right >= 0) stack.push_back(right);
        if (left >= 0) stack.push_back(left);
    }

    void assign(std::vector<std::int32_t>& stack, std::size_t t, std::int32_t g) {
        Group& group = groups_[std::size_t(g)];
        TriangleInfo& tri = tris_[t];
        int i = 0;
        while (i < 3 && weld(t, i) != group.vertex) ++i;
        if (i == 3 || tri.group[i] >= 0) return;  // not around this vertex (cannot happen), or grouped
        if (tri.flags & kGroupWithAny) {
            // The first group to reach a "group with any" triangle sets its orientation.
            if (tri.group[0] < 0 && tri.group[1] < 0 && tri.group[2] < 0) {
                tri.flags = std::uint8_t((tri.flags & ~kOrientPreserving) |
                                         (group.orient_preserving ? kOrientPreserving : 0));
            }
        }
        if (((tri.flags & kOrientPreserving) != 0) != group.orient_preserving) return;
        members_.push_back(std::uint32_t(t));
        tri.group[i] = g;
        push_neighbours(stack, tri, i);
    }

    // GenerateTSpaces + EvalTspace, groups in chunks over parallel_for.
    void write_tangents(float* out) {
        const std::size_t chunks = (groups_.size() + kChunk - 1) / kChunk;
        parallel_for(chunks, [&](std::size_t chunk) {
            GroupScratch scratch;
            const std::size_t end = std::min(groups_.size(), (chunk + 1) * kChunk);
            for (std::size_t g = chunk * kChunk; g < end; ++g) write_group(groups_[g], scratch, out);
        });
    }

    // A group member's part in GenerateTSpaces / EvalTspace, computed once.
    struct Member {
        std::uint32_t face;
        int corner;       // the group's vertex in the face (0..2)
        V3 os, ot;        // the face's tangent and bitangent in the normal's plane
        V3 weighted_os;   // os times the corner's angle in that plane; zero for "group with any"
        bool any;         // kGroupWithAny
    };

    struct GroupScratch {
        std::vector<Member> members;               // sorted by face
        std::vector<std::uint32_t> candidate;      // indices into members
        std::vector<std::vector<std::uint32_t>> subgroups;
        std::vector<V3> subgroup_tangent;
    };

    // Groups larger than this (a fan of thousands of triangles around one
    // vertex) skip the quadratic subgroup search and form one subgroup,
    // which is the search's result unless two of their tangents are exactly
    // opposite.
    static constexpr std::size_t kExactSubgroupLimit = 64;

    void write_group(const Group& group, GroupScratch& scratch, float* out) const {
        const V3 n = normal(group.vertex);
        const float sign = group.orient_preserving ? 1.0f : -1.0f;
        auto& members = scratch.members;
        members.resize(group.count);
        for (std::size_t k = 0; k < group.count; ++k) {
            Member& m = members[k];
            m.face = members_[group.first + k];
            m.corner = corner_of(m.face, group.vertex);
            const TriangleInfo& tri = tris_[m.face];
            m.os = project(tri.os, n);
            m.ot = project(tri.ot, n);
            m.any = (tri.flags & kGroupWithAny) != 0;
            m.weighted_os = m.any ? V3{0, 0, 0} : scale(corner_angle(m.face, m.corner, n), m.os);
        }
        // EvalTspace sums a subgroup in ascending face order.
        std::sort(members.begin(), members.end(), [](const Member& a, const Member& b) { return a.face < b.face; });
        auto emit = [&](const Member& m, V3 tangent) {
            float* o = out + 4 * (3 * std::size_t(m.face) + std::size_t(m.corner));
            o[0] = tangent.x;
            o[1] = tangent.y;
            o[2] = tangent.z;
            o[3] = sign;
        };
        // cos(180 degrees), the default threshold: only exactly opposite tangents are incompatible.
        const float threshold = -1.0f;
        auto compatible = [&](std::size_t k, std::size_t j) {
            const Member &a = members[k], &b = members[j];
            return a.any || b.any || k == j || (dot(a.os, b.os) > threshold && dot(a.ot, b.ot) > threshold);
        };
        const std::size_t count = members.size();
        bool one_subgroup = true;  // the common case: every member's subgroup is the whole group
        if (count <= kExactSubgroupLimit)
            for (std::size_t k = 0; k < count && one_subgroup; ++k)
                for (std::size_t j = k + 1; j < count && one_subgroup; ++j) one_subgroup = compatible(k, j);
        if (one_subgroup) {
            V3 sum{0, 0, 0};
            for (const Member& m : members) sum = sum + m.weighted_os;
            const V3 tangent = not_zero(sum) ? normalize(sum) : sum;
            for (const Member& m : members) emit(m, tangent);
            return;
        }
        std::size_t subgroup_count = 0;
        for (std::size_t k = 0; k < count; ++k) {
            auto& candidate = scratch.candidate;
            candidate.clear();
            for (std::size_t j = 0; j < count; ++j)
                if (compatible(k, j)) candidate.push_back(std::uint32_t(j));  // ascending face order
            std::size_t s = 0;
            while (s < subgroup_count && scratch.subgroups[s] != candidate) ++s;
            if (s == subgroup_count) {
                if (scratch.subgroups.size() <= s) {
                    scratch.subgroups.resize(s + 1);
                    scratch.subgroup_tangent.resize(s + 1);
                }
                scratch.subgroups[s] = candidate;
                V3 sum{0, 0, 0};
                for (const std::uint32_t j : candidate) sum = sum + members[j].weighted_os;
                scratch.subgroup_tangent[s] = not_zero(sum) ? normalize(sum) : sum;
                ++subgroup_count;
            }
            emit(members[k], scratch.subgroup_tangent[s]);
        }
    }

    int corner_of(std::size_t t, std::uint32_t vertex) const {
        int i = 0;
        while (weld(t, i) != vertex) ++i;
        return i;
    }

    // EvalTspace's weight: the face's angle at corner i, between its two
    // edges projected into the plane of the normal n.
    float corner_angle(std::uint32_t f, int i, V3 n) const {
        const std::uint32_t c = 3 * f;
        const V3 p0 = position(c + std::uint32_t(i > 0 ? i - 1 : 2));
        const V3 p1 = position(c + std::uint32_t(i));
        const V3 p2 = position(c + std::uint32_t(i < 2 ? i + 1 : 0));
        const V3 v1 = project(p0 - p1, n), v2 = project(p2 - p1, n);
        const float cos_angle = std::clamp(dot(v1, v2), -1.0f, 1.0f);
        return float(std::acos(double(cos_angle)));
    }

    // DegenEpilogue: a degenerate triangle's corner copies the first good
    // corner (in triangle order) at its welded vertex.
    void write_degenerate(float* out) {
        std::vector<std::uint32_t> degenerate;
        for (std::size_t t = 0; t < tri_count_; ++t)
            if (tris_[t].flags & kDegenerate) degenerate.push_back(std::uint32_t(t));
        if (degenerate.empty()) return;
        std::vector<std::uint32_t> first_good(corner_count_, UINT32_MAX);
        for (std::size_t t = 0; t < tri_count_; ++t) {
            if (tris_[t].flags & kDegenerate) continue;
            for (int i = 0; i < 3; ++i) {
                std::uint32_t& slot = first_good[weld(t, i)];
                if (slot == UINT32_MAX) slot = std::uint32_t(3 * t + std::size_t(i));
            }
        }
        for (const std::uint32_t t : degenerate) {
            for (int i = 0; i < 3; ++i) {
                const std::size_t corner = 3 * std::size_t(t) + std::size_t(i);
                const std::uint32_t source = first_good[weld(t, i)];
                float* o = out + 4 * corner;
                if (source != UINT32_MAX) {
                    std::memcpy(o, out + 4 * std::size_t(source), 4 * sizeof(float));
                } else {
                    o[0] = 1.0f;
                    o[1] = 0.0f;
                    o[2] = 0.0f;
                    o[3] = -1.0f;
                }
            }
        }
    }

    const float* positions_;
    std::size_t vertex_count_;
    const std::uint32_t* indices_;
    std::size_t tri_count_;
    const float* normals_;
    const float* uvs_;
    std::size_t corner_count_;

    std::vector<std::uint32_t> position_id_;
    std::vector<std::uint32_t> welded_;
    std::vector<TriangleInfo> tris_;
    std::vector<Group> groups_;
    std::vector<std::uint32_t> members_;
};

}  // namespace

void compute_tangents(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                      std::size_t triangle_count, const float* corner_normals, const float* corner_uvs,
                      float* tangents) {
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
    TangentSolver(positions, vertex_count, indices, triangle_count, corner_normals, corner_uvs).run(tangents);
}

}  // namespace deferred
