#include "layer_order.h"

#include "frame_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

namespace deferred {

namespace {

// The extent of dot(n, x - base) over a layer: where its corners and its
// bounding sphere (if it has one) both allow.
void extent(const Layer& l, const glm::dvec3& n, const glm::dvec3& base, double& lo, double& hi) {
    lo = 1e300;
    hi = -1e300;
    for (const glm::dvec3& c : l.corners) {
        lo = std::min(lo, glm::dot(n, c - base));
        hi = std::max(hi, glm::dot(n, c - base));
    }
    if (l.radius >= 0.0) {
        const double at = glm::dot(n, l.center - base);
        lo = std::max(lo, at - l.radius);
        hi = std::min(hi, at + l.radius);
    }
}

// Where `other` lies against `layer`'s plane, seen from the rays: +1 all
// on the side the rays come from (met before the plane), -1 all beyond it,
// 0 on both sides, 2 all on the plane (within `tolerance`).
int side_of(const Layer& layer, double eye_side, const Layer& other, double tolerance) {
    double lo, hi;
    extent(other, layer.normal * eye_side, layer.normal * (layer.offset), lo, hi);
    const bool before = hi > tolerance, beyond = lo < -tolerance;
    if (before && beyond) return 0;
    if (before) return 1;
    if (beyond) return -1;
    return 2;
}

// A length that bounds the pair's coordinates: the tolerance of the side
// tests is a relative one (float matrices, double arithmetic).
double scale_of(const Layer& a, const Layer& b, const RayFan& rays) {
    double s = std::abs(a.offset) + std::abs(b.offset) + (rays.orthographic ? 0.0 : glm::length(rays.eye));
    for (const Layer* l : {&a, &b})
        for (const glm::dvec3& c : l->corners) s = std::max(s, glm::length(c));
    return s;
}

// The rectangle holding a layer's corners on the plane across the view
// (perspective: divided by their depth along it); false when a corner is
// not in front of the eye (the image is unbounded).
struct Rect {
    glm::dvec2 lo{1e300}, hi{-1e300};
};
bool image_of(const Layer& l, const RayFan& rays, const glm::dvec3& right, const glm::dvec3& up, Rect& r) {
    for (const glm::dvec3& c : l.corners) {
        const glm::dvec3 p = rays.orthographic ? c : c - rays.eye;
        glm::dvec2 q(glm::dot(p, right), glm::dot(p, up));
        if (!rays.orthographic) {
            const double depth = glm::dot(p, rays.direction);
            if (!(depth > 1e-12 * glm::length(p))) return false;
            q /= depth;
        }
        r.lo = glm::min(r.lo, q);
        r.hi = glm::max(r.hi, q);
    }
    return true;
}

// Whether a plane through the eye (orthographic: along the rays) through
// two corners of one layer has all of that layer's corners on one side and
// all of the other's on the other: then no ray meets both (each ray lies in
// one of its half-spaces). The planes of a box's edges against a ball's
// box, say, where the box's image rectangle overlaps the ball's.
bool apart_through_eye(const Layer& a, const Layer& b, const RayFan& rays, double tolerance) {
    for (const Layer* l : {&a, &b}) {
        const Layer& other = l == &a ? b : a;
        const std::vector<glm::dvec3>& c = l->corners;
        for (std::size_t p = 0; p < c.size(); ++p)
            for (std::size_t q = p + 1; q < c.size(); ++q) {
                const glm::dvec3 base = rays.orthographic ? c[p] : rays.eye;
                glm::dvec3 n = rays.orthographic ? glm::cross(c[q] - c[p], rays.direction)
                                                 : glm::cross(c[p] - rays.eye, c[q] - rays.eye);
                const double len = glm::length(n);
                if (!(len > 0.0)) continue;
                n /= len;
                double lo, hi, other_lo, other_hi;
                extent(*l, n, base, lo, hi);
                extent(other, n, base, other_lo, other_hi);
                if ((hi <= tolerance && other_lo >= -tolerance) || (lo >= -tolerance && other_hi <= tolerance))
                    return true;
            }
    }
    return false;
}

}  // namespace

std::vector<std::uint32_t> order_layers(const std::vector<Layer>& layers, const RayFan& rays,
                                               std::vector<bool>& unordered) {
    const std::size_t n = layers.size();
    unordered.assign(n, false);
    // The side of each plane the rays start on: +1 the normal's, -1 the
    // other, 0 edge-on (the plane holds the eye, or the orthographic rays
    // run along it: the layer is never met, it needs no order).
    std::vector<double> eye_side(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        const Layer& l = layers[i];
        if (l.convex) {
            eye_side[i] = 1.0;  // no plane: never edge-on
            continue;
        }
        double e = rays.orthographic ? -glm::dot(l.normal, rays.direction) : glm::dot(l.normal, rays.eye) - l.offset;
        const double tolerance = rays.orthographic ? 1e-9 : 1e-9 * (std::abs(l.offset) + glm::length(rays.eye) + 1e-30);
        eye_side[i] = e > tolerance ? 1.0 : e < -tolerance ? -1.0 : 0.0;
    }
    // Each layer's image across the view, where it is bounded.
    const glm::dvec3 f = glm::normalize(rays.direction);
    const glm::dvec3 right = glm::normalize(glm::cross(f, std::abs(f.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
    const glm::dvec3 up = glm::cross(right, f);
    std::vector<Rect> images(n);
    std::vector<bool> bounded(n);
    for (std::size_t i = 0; i < n; ++i) bounded[i] = image_of(layers[i], rays, right, up, images[i]);
    std::vector<std::vector<std::uint32_t>> after(n);      // after[j]: layers met after j
    std::vector<std::vector<std::uint32_t>> conflicts(n);  // the layers each cannot be ordered with
    std::vector<std::uint32_t> pending(n, 0);          // how many layers come before each
    for (std::size_t i = 0; i < n; ++i) {
        if (eye_side[i] == 0.0) continue;
        for (std::size_t j = i + 1; j < n; ++j) {
            if (eye_side[j] == 0.0) continue;
            if (bounded[i] && bounded[j] &&
                (images[i].hi.x < images[j].lo.x || images[j].hi.x < images[i].lo.x ||
                 images[i].hi.y < images[j].lo.y || images[j].hi.y < images[i].lo.y))
                continue;  // no ray meets both
            const double tolerance = 1e-6 * scale_of(layers[i], layers[j], rays);
            // j against i's plane, then i against j's (a convex layer has
            // none: only the other's plane can order the two).
            int order = 0;  // +1: j first, -1: i first, 2: no order needed
            const int j_side = layers[i].convex ? 0 : side_of(layers[i], eye_side[i], layers[j], tolerance);
            if (j_side == 2 && !layers[j].convex) order = 2;  // coplanar: a ray meets both at one point
            else if (j_side == 1 || j_side == -1) order = j_side;
            else if (!layers[j].convex) {
                const int i_side = side_of(layers[j], eye_side[j], layers[i], tolerance);
                if (i_side == 2 && !layers[i].convex) order = 2;
                else if (i_side == 1 || i_side == -1) order = -i_side;
            }
            if (order == 0 && apart_through_eye(layers[i], layers[j], rays, tolerance)) order = 2;
            if (order == 0) {  // they cross each other's planes where a ray meets both
                conflicts[i].push_back(std::uint32_t(j));
                conflicts[j].push_back(std::uint32_t(i));
                continue;
            }
            if (order == 2) continue;
            const std::uint32_t first = std::uint32_t(order > 0 ? j : i), second = std::uint32_t(order > 0 ? i : j);
            after[first].push_back(second);
        }
    }
    // Conflicts: the layer in most of them is left out (a convex one, then
    // the later one, among equals) until none is left, so one pane that
    // crosses several others does not hold them all back.
    std::vector<std::uint32_t> degree(n);
    for (std::size_t i = 0; i < n; ++i) degree[i] = std::uint32_t(conflicts[i].size());
    for (;;) {
        std::size_t worst = n;
        for (std::size_t i = 0; i < n; ++i) {
            if (unordered[i] || degree[i] == 0) continue;
            if (worst == n || degree[i] > degree[worst] ||
                (degree[i] == degree[worst] && layers[i].convex >= layers[worst].convex))
                worst = i;
        }
        if (worst == n) break;
        unordered[worst] = true;
        for (std::uint32_t j : conflicts[worst])
            if (!unordered[j]) --degree[j];
    }
    // Kahn's topological sort of the ordered layers, lowest index first
    // among the ready ones; what a cycle leaves is unordered.
    for (std::size_t i = 0; i < n; ++i)
        if (!unordered[i])
            for (std::uint32_t j : after[i])
                if (!unordered[j]) ++pending[j];
    std::priority_queue<std::uint32_t, std::vector<std::uint32_t>, std::greater<>> ready;
    for (std::uint32_t i = 0; i < n; ++i)
        if (!unordered[i] && pending[i] == 0) ready.push(i);
    std::vector<std::uint32_t> order;
    while (!ready.empty()) {
        const std::uint32_t i = ready.top();
        ready.pop();
        order.push_back(i);
        for (std::uint32_t j : after[i])
            if (!unordered[j] && --pending[j] == 0) ready.push(j);
    }
    if (order.size() < n) {
        std::vector<bool> placed(n, false);
        for (std::uint32_t i : order) placed[i] = true;
        for (std::size_t i = 0; i < n; ++i)
            if (!placed[i]) unordered[i] = true;
    }
    return order;
}

ExactLayers select_exact_layers(const FrameScene& scene, const std::vector<bool>& transparent, const ViewVolume& view) {
    ExactLayers out;
    out.materials.assign(scene.material_count(), false);
    out.rank.assign(scene.instance_count(), std::numeric_limits<std::uint32_t>::max());
    // Materials held back: used in view by a surface that is not planar or
    // not ordered. Each round holds back at least one more, or ends.
    std::vector<bool> held(scene.material_count(), false);
    RayFan rays;
    rays.eye = view.eye;
    rays.orthographic = view.orthographic;
    rays.direction = glm::transpose(view.to_view) * glm::dvec3(0.0, 0.0, -1.0);
    auto candidate = [&](std::uint32_t id) { return id < transparent.size() && transparent[id] && !held[id]; };
    for (std::size_t round = 0; round <= scene.material_count(); ++round) {
        std::vector<Layer> layers;
        std::vector<std::uint32_t> layer_instance;
        std::vector<std::vector<std::uint32_t>> layer_materials;
        bool changed = false;
        for (const FrameScene::Draw& d : scene.draws()) {
            const GpuMesh& mesh = scene.mesh(d);
            std::vector<std::uint32_t> ids;
            for (std::size_t s = 0; s < mesh.slot_ranges.size(); ++s)
                if (mesh.slot_ranges[s].second > 0 && candidate(scene.slot_material(d, s)))
                    ids.push_back(scene.slot_material(d, s));
            if (ids.empty()) continue;
            for (std::uint32_t i = d.first; i < d.first + d.count; ++i) {
                const FrameScene::Bound& b = scene.bounds()[i];
                if (!view.contains(b.center, b.radius)) continue;
                const glm::dmat4 m = scene.model_matrix(i);
                const glm::dmat3 linear(m);
                const double det = glm::determinant(linear);
                // A holdout object stays in the G-buffer (its hole is the
                // deferred path's), as does what is neither planar nor convex.
                if (!(mesh.planar || mesh.convex) || scene.holdout(i) || !(std::abs(det) > 0.0) ||
                    !std::isfinite(det)) {
                    for (std::uint32_t id : ids) held[id] = true;
                    changed = true;
                    continue;
                }
                // The plane through the matrix: normals by the inverse
                // transpose, a point of it by the matrix.
                const glm::dvec3 n_obj(mesh.plane_normal[0], mesh.plane_normal[1], mesh.plane_normal[2]);
                Layer l;
                l.convex = !mesh.planar;
                if (mesh.planar) {
                    l.normal = glm::normalize(glm::transpose(glm::inverse(linear)) * n_obj);
                    l.offset = glm::dot(l.normal, glm::dvec3(m * glm::dvec4(n_obj * mesh.plane_offset, 1.0)));
                }
                const Box box = scene.instance_box(i, mesh);
                for (int c = 0; c < 8; ++c) {
                    glm::dvec3 p = box.center;
                    for (int k = 0; k < 3; ++k) p += (c >> k & 1 ? 1.0 : -1.0) * box.half[std::size_t(k)];
                    l.corners.push_back(p);
                }
                l.center = b.center;
                l.radius = b.radius;
                layers.push_back(std::move(l));
                layer_instance.push_back(i);
                layer_materials.push_back(ids);
            }
        }
        if (changed) continue;  // the candidates shrank: gather again
        if (layers.size() > kMaxExactLayers) return ExactLayers{std::vector<bool>(scene.material_count(), false),
                                                                out.rank, 0};
        std::vector<bool> unordered;
        const std::vector<std::uint32_t> order = order_layers(layers, rays, unordered);
        for (std::size_t k = 0; k < layers.size(); ++k)
            if (unordered[k])
                for (std::uint32_t id : layer_materials[k]) {
                    changed = changed || !held[id];
                    held[id] = true;
                }
        if (changed) continue;
        // Every layer is ordered: their materials are drawn forward (only
        // those some instance in view uses: no program for the others).
        for (std::size_t r = 0; r < order.size(); ++r) {
            out.rank[layer_instance[order[r]]] = std::uint32_t(r);
            for (std::uint32_t id : layer_materials[order[r]]) out.materials[id] = true;
        }
        out.instances = std::uint32_t(order.size());
        return out;
    }
    out.materials.assign(scene.material_count(), false);
    return out;
}

}  // namespace deferred
