#include "ray_scene.h"

#include "scene_store.h"

#include <deferred/renderer.h>

#include "../../shaders/shader_defines.h"
#include "../../shaders/shader_shared.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numeric>
#include <unordered_map>

namespace deferred {

namespace {

std::uint32_t bits(float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}
float from_bits(std::uint32_t u) {
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

struct Item {
    glm::vec3 lo, hi, centroid;
};
struct Node {
    glm::vec3 lo, hi;
    std::uint32_t left_or_first = 0, count = 0;
};

float half_area(const glm::vec3& lo, const glm::vec3& hi) {
    const glm::vec3 e = glm::max(hi - lo, glm::vec3(0.0f));
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

// Binned SAH (Wald 2007): per node, each axis's centroid range in kBins
// bins; the split between bins with the least A_L N_L + A_R N_R (a
// traversal step costing about one triangle test), a leaf where splitting
// costs more and few items remain. Children are stored as pairs; `order`
// is the items' order, leaves hold consecutive runs of it.
constexpr int kBins = 16;
constexpr std::uint32_t kMaxLeafItems = 8;

int build_hierarchy(const std::vector<Item>& items, std::uint32_t max_leaf, std::vector<Node>& nodes,
                    std::vector<std::uint32_t>& order) {
    const std::uint32_t n = std::uint32_t(items.size());
    order.resize(n);
    std::iota(order.begin(), order.end(), 0u);
    nodes.clear();
    nodes.reserve(std::size_t(n) * 2 + 1);
    nodes.push_back({});
    struct Task {
        std::uint32_t node, begin, end;
        int depth;
    };
    std::vector<Task> tasks{{0, 0, n, 0}};
    int max_depth = 0;
    while (!tasks.empty()) {
        const Task t = tasks.back();
        tasks.pop_back();
        max_depth = std::max(max_depth, t.depth + 1);
        glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
        glm::vec3 clo = lo, chi = hi;
        for (std::uint32_t i = t.begin; i < t.end; ++i) {
            const Item& it = items[order[i]];
            lo = glm::min(lo, it.lo);
            hi = glm::max(hi, it.hi);
            clo = glm::min(clo, it.centroid);
            chi = glm::max(chi, it.centroid);
        }
        if (t.begin == t.end) lo = hi = glm::vec3(0.0f);
        Node& node = nodes[t.node];
        node.lo = lo;
        node.hi = hi;
        const std::uint32_t count = t.end - t.begin;
        auto make_leaf = [&] {
            nodes[t.node].left_or_first = t.begin;
            nodes[t.node].count = count;
        };
        if (count <= max_leaf || t.depth >= RAY_MAX_DEPTH - 1) {
            make_leaf();
            continue;
        }
        // Best split over the three axes.
        float best_cost = std::numeric_limits<float>::max();
        int best_axis = -1, best_bin = 0;
        for (int axis = 0; axis < 3; ++axis) {
            const float extent = chi[axis] - clo[axis];
            if (!(extent > 0.0f)) continue;
            struct Bin {
                glm::vec3 lo{std::numeric_limits<float>::max()}, hi{-std::numeric_limits<float>::max()};
                std::uint32_t count = 0;
            };
            std::array<Bin, kBins> bins;
            const float scale = float(kBins) / extent;
            for (std::uint32_t i = t.begin; i < t.end; ++i) {
                const Item& it = items[order[i]];
                const int b = std::min(kBins - 1, int((it.centroid[axis] - clo[axis]) * scale));
                bins[std::size_t(b)].lo = glm::min(bins[std::size_t(b)].lo, it.lo);
                bins[std::size_t(b)].hi = glm::max(bins[std::size_t(b)].hi, it.hi);
                ++bins[std::size_t(b)].count;
            }
            // Sweep: right sides from the top, then left sides.
            std::array<float, kBins> right_cost{};
            glm::vec3 rlo(std::numeric_limits<float>::max()), rhi(-std::numeric_limits<float>::max());
            std::uint32_t rcount = 0;
            for (int b = kBins - 1; b > 0; --b) {
                rlo = glm::min(rlo, bins[std::size_t(b)].lo);
                rhi = glm::max(rhi, bins[std::size_t(b)].hi);
                rcount += bins[std::size_t(b)].count;
                right_cost[std::size_t(b)] = rcount ? half_area(rlo, rhi) * float(rcount) : 0.0f;
            }
            glm::vec3 llo(std::numeric_limits<float>::max()), lhi(-std::numeric_limits<float>::max());
            std::uint32_t lcount = 0;
            for (int b = 0; b < kBins - 1; ++b) {
                llo = glm::min(llo, bins[std::size_t(b)].lo);
                lhi = glm::max(lhi, bins[std::size_t(b)].hi);
                lcount += bins[std::size_t(b)].count;
                if (lcount == 0 || lcount == count) continue;
                const float cost = half_area(llo, lhi) * float(lcount) + right_cost[std::size_t(b + 1)];
                if (cost < best_cost) {
                    best_cost = cost;
                    best_axis = axis;
                    best_bin = b;
                }
            }
        }
        const float parent = half_area(lo, hi);
        std::uint32_t mid = t.begin;
        if (best_axis < 0) {
            // Every centroid in one point: halves by index.
            mid = t.begin + count / 2;
        } else {
            if (count <= kMaxLeafItems && best_cost >= parent * (float(count) - 1.0f)) {
                make_leaf();
                continue;
            }
            const float scale = float(kBins) / (chi[best_axis] - clo[best_axis]);
            const float base = clo[best_axis];
            const int axis = best_axis, split = best_bin;
            auto it = std::partition(order.begin() + t.begin, order.begin() + t.end, [&](std::uint32_t k) {
                return std::min(kBins - 1, int((items[k].centroid[axis] - base) * scale)) <= split;
            });
            mid = std::uint32_t(it - order.begin());
            if (mid == t.begin || mid == t.end) mid = t.begin + count / 2;
        }
        const std::uint32_t left = std::uint32_t(nodes.size());
        nodes.push_back({});
        nodes.push_back({});
        nodes[t.node].left_or_first = left;
        nodes[t.node].count = 0;
        tasks.push_back({left, t.begin, mid, t.depth + 1});
        tasks.push_back({left + 1, mid, t.end, t.depth + 1});
    }
    return max_depth;
}

void append_nodes(const std::vector<Node>& nodes, std::vector<glm::uvec4>& out) {
    for (const Node& n : nodes) {
        out.emplace_back(bits(n.lo.x), bits(n.lo.y), bits(n.lo.z), n.left_or_first);
        out.emplace_back(bits(n.hi.x), bits(n.hi.y), bits(n.hi.z), n.count);
    }
}

glm::vec3 vec_at(const glm::uvec4& u) { return {from_bits(u.x), from_bits(u.y), from_bits(u.z)}; }

// Slab test of the ray against [lo, hi] over t in [0, tmax].
bool slab_hit(const glm::vec3& lo, const glm::vec3& hi, const glm::vec3& o, const glm::vec3& inv, float tmax) {
    const glm::vec3 t0 = (lo - o) * inv, t1 = (hi - o) * inv;
    const glm::vec3 tn = glm::min(t0, t1), tf = glm::max(t0, t1);
    const float enter = std::max(std::max(tn.x, tn.y), std::max(tn.z, 0.0f));
    const float leave = std::min(std::min(tf.x, tf.y), std::min(tf.z, tmax));
    return enter <= leave;
}

glm::vec3 safe_inverse(const glm::vec3& d) {
    glm::vec3 r;
    for (int k = 0; k < 3; ++k) r[k] = std::abs(d[k]) > 1e-30f ? 1.0f / d[k] : std::copysign(1e30f, d[k]);
    return r;
}

}  // namespace

MeshBvh build_mesh_bvh(const float* corners, const std::uint32_t* slots, std::size_t triangle_count) {
    MeshBvh bvh;
    if (triangle_count == 0) return bvh;
    std::vector<Item> items(triangle_count);
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const glm::vec3 a(corners[t * 9], corners[t * 9 + 1], corners[t * 9 + 2]);
        const glm::vec3 b(corners[t * 9 + 3], corners[t * 9 + 4], corners[t * 9 + 5]);
        const glm::vec3 c(corners[t * 9 + 6], corners[t * 9 + 7], corners[t * 9 + 8]);
        items[t].lo = glm::min(a, glm::min(b, c));
        items[t].hi = glm::max(a, glm::max(b, c));
        items[t].centroid = (items[t].lo + items[t].hi) * 0.5f;
    }
    std::vector<Node> nodes;
    std::vector<std::uint32_t> order;
    bvh.depth = build_hierarchy(items, 2, nodes, order);
    bvh.nodes.reserve(nodes.size() * 2);
    append_nodes(nodes, bvh.nodes);
    bvh.lo = nodes[0].lo;
    bvh.hi = nodes[0].hi;
    bvh.triangles.reserve(triangle_count * 3);
    for (std::uint32_t k : order) {
        const float* p = corners + std::size_t(k) * 9;
        const glm::vec3 a(p[0], p[1], p[2]), b(p[3], p[4], p[5]), c(p[6], p[7], p[8]);
        const glm::vec3 e1 = b - a, e2 = c - a;
        bvh.triangles.emplace_back(bits(a.x), bits(a.y), bits(a.z), slots ? slots[k] : 0u);
        bvh.triangles.emplace_back(bits(e1.x), bits(e1.y), bits(e1.z), 0u);
        bvh.triangles.emplace_back(bits(e2.x), bits(e2.y), bits(e2.z), 0u);
    }
    return bvh;
}

std::shared_ptr<const MeshBvh> mesh_bvh(const GpuMesh& mesh) {
    if (mesh.bvh) return mesh.bvh;
    const std::size_t nt = mesh.triangle_count;
    std::vector<float> corners(nt * 9);
    std::vector<std::uint32_t> slots(nt, 0u);
    if (nt > 0) {
        GLint64 position_bytes = 0;
        glGetNamedBufferParameteri64v(mesh.positions.get(), GL_BUFFER_SIZE, &position_bytes);
        std::vector<float> positions(std::size_t(position_bytes) / sizeof(float));
        std::vector<std::uint32_t> indices(nt * 3);
        glGetNamedBufferSubData(mesh.positions.get(), 0, GLsizeiptr(positions.size() * sizeof(float)), positions.data());
        glGetNamedBufferSubData(mesh.indices.get(), 0, GLsizeiptr(indices.size() * 4), indices.data());
        check_gl("reading a mesh for its ray hierarchy");
        const std::size_t vertices = positions.size() / 3;
        for (std::size_t i = 0; i < nt * 3; ++i) {
            const std::size_t v = std::min<std::size_t>(indices[i], vertices - 1);
            std::copy(positions.begin() + long(v * 3), positions.begin() + long(v * 3 + 3), corners.begin() + long(i * 3));
        }
        // The triangles are stored in slot order (SceneStore::add_mesh).
        for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s)
            for (std::uint32_t t = 0; t < mesh.slot_ranges[s].second; ++t)
                if (mesh.slot_ranges[s].first + t < nt) slots[mesh.slot_ranges[s].first + t] = std::uint32_t(s);
    }
    mesh.bvh = std::make_shared<const MeshBvh>(build_mesh_bvh(corners.data(), slots.data(), nt));
    return mesh.bvh;
}

void RayScene::build(const std::vector<Instance>& instances) {
    data_.assign(1, glm::uvec4(0u));
    instance_count_ = triangle_count_ = 0;
    // Each mesh's block once.
    struct Block {
        std::uint32_t nodes, triangles;
    };
    std::unordered_map<const MeshBvh*, Block> blocks;
    std::vector<std::size_t> used;  // instances kept
    std::vector<Item> items;
    for (std::size_t i = 0; i < instances.size(); ++i) {
        const Instance& inst = instances[i];
        if (!inst.bvh || inst.bvh->triangles.empty()) continue;
        const double det = glm::determinant(glm::dmat3(inst.model));
        if (!(std::abs(det) > 1e-300) || !std::isfinite(det)) continue;  // flattened to nothing: no inverse
        // The world box of the mesh's root box.
        glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
        for (int c = 0; c < 8; ++c) {
            const glm::dvec3 p((c & 1) ? inst.bvh->hi.x : inst.bvh->lo.x, (c & 2) ? inst.bvh->hi.y : inst.bvh->lo.y,
                               (c & 4) ? inst.bvh->hi.z : inst.bvh->lo.z);
            const glm::dvec3 w(inst.model * glm::dvec4(p, 1.0));
            lo = glm::min(lo, w);
            hi = glm::max(hi, w);
        }
        // Outward rounding of the float box (a ray grazing the box's face
        // must not miss what lies on it).
        Item it;
        it.lo = glm::vec3(lo - (hi - lo) * 1e-6 - 1e-7);
        it.hi = glm::vec3(hi + (hi - lo) * 1e-6 + 1e-7);
        for (int k = 0; k < 3; ++k) {  // and at least one float step (a small object far from the camera)
            it.lo[k] = std::nextafter(it.lo[k], -std::numeric_limits<float>::infinity());
            it.hi[k] = std::nextafter(it.hi[k], std::numeric_limits<float>::infinity());
        }
        it.centroid = (it.lo + it.hi) * 0.5f;
        items.push_back(it);
        used.push_back(i);
        if (!blocks.count(inst.bvh.get())) {
            Block b{std::uint32_t(data_.size()), 0};
            data_.insert(data_.end(), inst.bvh->nodes.begin(), inst.bvh->nodes.end());
            b.triangles = std::uint32_t(data_.size());
            data_.insert(data_.end(), inst.bvh->triangles.begin(), inst.bvh->triangles.end());
            blocks.emplace(inst.bvh.get(), b);
        }
    }
    if (used.empty()) {
        data_.assign(1, glm::uvec4(0u));
        return;
    }
    // The instances' hierarchy orders them; their records follow in that order.
    std::vector<Node> nodes;
    std::vector<std::uint32_t> order;
    build_hierarchy(items, 1, nodes, order);
    const std::uint32_t instance_base = std::uint32_t(data_.size());
    data_.resize(data_.size() + used.size() * 4);
    for (std::size_t k = 0; k < order.size(); ++k) {
        const Instance& inst = instances[used[order[k]]];
        const glm::dmat4 inv = glm::inverse(inst.model);
        glm::uvec4* r = &data_[instance_base + k * 4];
        for (int row = 0; row < 3; ++row)
            r[row] = glm::uvec4(bits(float(inv[0][row])), bits(float(inv[1][row])), bits(float(inv[2][row])),
                                bits(float(inv[3][row])));
        const Block block = blocks.at(inst.bvh.get());
        std::uint32_t alpha_base = 0;
        const bool transparent = std::any_of(inst.slot_alpha.begin(), inst.slot_alpha.end(), [](float a) { return a < 1.0f; });
        if (transparent) {
            alpha_base = std::uint32_t(data_.size());
            for (std::size_t s = 0; s < inst.slot_alpha.size(); s += 4) {
                glm::uvec4 a(bits(1.0f));
                for (std::size_t j = 0; j < 4 && s + j < inst.slot_alpha.size(); ++j)
                    a[int(j)] = bits(std::clamp(inst.slot_alpha[s + j], 0.0f, 1.0f));
                data_.push_back(a);
            }
            r = &data_[instance_base + k * 4];  // the vector may have moved
        }
        r[3] = glm::uvec4(block.nodes, block.triangles, alpha_base, 0u);
        triangle_count_ += inst.bvh->triangles.size() / 3;
    }
    const std::uint32_t tlas_base = std::uint32_t(data_.size());
    append_nodes(nodes, data_);
    data_[0] = glm::uvec4(tlas_base, instance_base, std::uint32_t(nodes.size()), 0u);
    instance_count_ = used.size();
}

void RayScene::upload() {
    buffer_ = make_storage_buffer(data_.data(), data_.size() * sizeof(glm::uvec4), "ray scene");
}

void RayScene::bind() const {
    if (buffer_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_RAY_SCENE, buffer_.get());
}

void RayScene::release() {
    buffer_ = Buffer();
    data_.clear();
    instance_count_ = triangle_count_ = 0;
}

float trace_transmittance(const std::vector<glm::uvec4>& scene, const glm::vec3& origin, const glm::vec3& dir,
                          float tmax) {
    if (scene.empty() || scene[0].z == 0u) return 1.0f;
    const glm::uvec4 header = scene[0];
    float T = 1.0f;
    const glm::vec3 inv = safe_inverse(dir);
    std::vector<std::uint32_t> stack{0u};
    while (!stack.empty()) {
        const std::uint32_t node = stack.back();
        stack.pop_back();
        const glm::uvec4 a = scene[header.x + 2 * node], b = scene[header.x + 2 * node + 1];
        if (!slab_hit(vec_at(a), vec_at(b), origin, inv, tmax)) continue;
        if (b.w == 0u) {
            stack.push_back(a.w + 1);
            stack.push_back(a.w);
            continue;
        }
        for (std::uint32_t i = a.w; i < a.w + b.w; ++i) {
            const glm::uvec4* r = &scene[header.y + i * 4];
            const glm::vec4 m0(vec_at(r[0]), from_bits(r[0].w)), m1(vec_at(r[1]), from_bits(r[1].w)),
                m2(vec_at(r[2]), from_bits(r[2].w));
            const glm::vec3 o(glm::dot(glm::vec3(m0), origin) + m0.w, glm::dot(glm::vec3(m1), origin) + m1.w,
                              glm::dot(glm::vec3(m2), origin) + m2.w);
            const glm::vec3 d(glm::dot(glm::vec3(m0), dir), glm::dot(glm::vec3(m1), dir), glm::dot(glm::vec3(m2), dir));
            const glm::vec3 dinv = safe_inverse(d);
            // As ray_lib.glsl: hits within the float precision of the object-space origin are its own surface.
            const float tmin = 1e-6f * std::max({std::abs(o.x), std::abs(o.y), std::abs(o.z)}) / glm::length(d);
            const std::uint32_t nodes = r[3].x, tris = r[3].y, alpha = r[3].z;
            std::vector<std::uint32_t> inner{0u};
            while (!inner.empty()) {
                const std::uint32_t n = inner.back();
                inner.pop_back();
                const glm::uvec4 na = scene[nodes + 2 * n], nb = scene[nodes + 2 * n + 1];
                if (!slab_hit(vec_at(na), vec_at(nb), o, dinv, tmax)) continue;
                if (nb.w == 0u) {
                    inner.push_back(na.w + 1);
                    inner.push_back(na.w);
                    continue;
                }
                for (std::uint32_t t = na.w; t < na.w + nb.w; ++t) {
                    const glm::uvec4* tr = &scene[tris + 3 * t];
                    const glm::vec3 v0 = vec_at(tr[0]), e1 = vec_at(tr[1]), e2 = vec_at(tr[2]);
                    // Moller-Trumbore, as ray_lib.glsl.
                    const glm::vec3 p = glm::cross(d, e2);
                    const float det = glm::dot(e1, p);
                    if (det == 0.0f) continue;
                    const float inv_det = 1.0f / det;
                    const glm::vec3 s = o - v0;
                    const float u = glm::dot(s, p) * inv_det;
                    if (u < 0.0f || u > 1.0f) continue;
                    const glm::vec3 q = glm::cross(s, e1);
                    const float v = glm::dot(d, q) * inv_det;
                    if (v < 0.0f || u + v > 1.0f) continue;
                    const float th = glm::dot(e2, q) * inv_det;
                    if (!(th > tmin && th < tmax)) continue;
                    if (alpha == 0u) return 0.0f;
                    const std::uint32_t slot = tr[0].w;
                    T *= 1.0f - from_bits(scene[alpha + slot / 4][int(slot % 4)]);
                    if (T <= 0.0f) return 0.0f;
                }
            }
        }
    }
    return T;
}

void add_ray_traversal_define(std::vector<std::string>& defines) {
    const char* call = std::getenv("DEFERRED_RAY_CALL");
    if (call && std::string(call) == "inline") return;
    defines.push_back("RAY_SUBROUTINE");
}

void use_ray_traversal(GLuint program, GLenum stage) {
    GLint locations = 0;
    glGetProgramStageiv(program, stage, GL_ACTIVE_SUBROUTINE_UNIFORM_LOCATIONS, &locations);
    if (locations <= 0) return;
    // The traversal is the stage's one subroutine uniform (ray_lib.glsl).
    const GLuint index = glGetSubroutineIndex(program, stage, "ray_transmittance_bvh");
    if (index == GL_INVALID_INDEX || locations != 1) throw Error("a ray-tracing program's subroutines are not the traversal's");
    glUniformSubroutinesuiv(stage, 1, &index);
}

}  // namespace deferred
