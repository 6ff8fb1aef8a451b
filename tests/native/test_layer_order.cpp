// The plane test that orders partly transparent planes and convex surfaces
// for the forward pass (layer_order.h), checked against its definition:
// every ray that meets two ordered layers meets them in rank order (random
// panes and balls, perspective and orthographic rays; a ball's two hits
// together in its place), and layers that cross each other are not
// ordered. And the shapes the mesh store records (mesh_topology.h
// planar_mesh, convex_mesh).
#include "layer_order.h"
#include "mesh_topology.h"

#include "builtin_scenes.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <vector>

using namespace deferred;

namespace {

struct Quad {
    glm::dvec3 center, u, v;  // u, v: half axes (orthogonal)
    glm::dvec3 normal() const { return glm::normalize(glm::cross(u, v)); }
    Layer layer() const {
        Layer l;
        l.normal = normal();
        l.offset = glm::dot(l.normal, center);
        for (double a : {-1.0, 1.0})
            for (double b : {-1.0, 1.0}) l.corners.push_back(center + a * u + b * v);
        return l;
    }
    // The ray's distance to the quad, or -1 where it misses.
    double hit(const glm::dvec3& o, const glm::dvec3& d) const {
        const glm::dvec3 n = normal();
        const double dn = glm::dot(n, d);
        if (std::abs(dn) < 1e-12) return -1.0;
        const double t = glm::dot(n, center - o) / dn;
        if (t <= 0.0) return -1.0;
        const glm::dvec3 p = o + t * d - center;
        if (std::abs(glm::dot(p, u)) > glm::dot(u, u) || std::abs(glm::dot(p, v)) > glm::dot(v, v)) return -1.0;
        return t;
    }
};

// The mesh with coincident vertices merged (the procedural meshes split
// them by face and seam for their normals; Blender's are welded), so that
// closed_orientation sees a closed surface.
tools::MeshArrays welded(const tools::MeshArrays& m) {
    tools::MeshArrays out;
    std::map<std::array<float, 3>, std::uint32_t> index;
    std::vector<std::uint32_t> remap;
    for (std::size_t v = 0; v < m.positions.size() / 3; ++v) {
        const std::array<float, 3> p{m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
        // On a 1e-5 grid: a seam's two vertices differ by the rounding of cos(0) and cos(2 pi).
        const std::array<float, 3> key{std::round(p[0] * 1e5f), std::round(p[1] * 1e5f), std::round(p[2] * 1e5f)};
        auto [it, fresh] = index.emplace(key, std::uint32_t(out.positions.size() / 3));
        if (fresh) out.positions.insert(out.positions.end(), p.begin(), p.end());
        remap.push_back(it->second);
    }
    for (std::size_t t = 0; t < m.indices.size() / 3; ++t) {
        const std::uint32_t a = remap[m.indices[3 * t]], b = remap[m.indices[3 * t + 1]], c = remap[m.indices[3 * t + 2]];
        if (a == b || b == c || a == c) continue;  // a pole's collapsed triangle
        out.indices.insert(out.indices.end(), {a, b, c});
    }
    return out;
}

std::vector<Quad> random_panes(std::mt19937& rng, int count) {
    std::uniform_real_distribution<double> unit(-1.0, 1.0), size(0.3, 1.5);
    std::vector<Quad> quads;
    for (int i = 0; i < count; ++i) {
        Quad q;
        q.center = {3.0 * unit(rng), 3.0 * unit(rng), 3.0 + 2.0 * unit(rng)};
        glm::dvec3 n = glm::normalize(glm::dvec3(unit(rng), unit(rng), unit(rng) + 1.5));
        const glm::dvec3 a = glm::normalize(glm::cross(n, glm::dvec3(0.3, 1.0, 0.1)));
        q.u = a * size(rng);
        q.v = glm::normalize(glm::cross(n, a)) * size(rng);
        quads.push_back(q);
    }
    return quads;
}

struct Ball {
    glm::dvec3 center;
    double radius;
    Layer layer() const {
        Layer l;
        l.convex = true;
        for (int c = 0; c < 8; ++c)
            l.corners.push_back(center + radius * glm::dvec3(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1));
        l.center = center;
        l.radius = radius;
        return l;
    }
    // Both distances along the ray (t0 <= t1), false where it misses.
    bool hits(const glm::dvec3& o, const glm::dvec3& d, double& t0, double& t1) const {
        const glm::dvec3 oc = o - center;
        const double b = glm::dot(oc, d), c = glm::dot(oc, oc) - radius * radius, disc = b * b - c;
        if (disc <= 0.0) return false;
        t0 = -b - std::sqrt(disc);
        t1 = -b + std::sqrt(disc);
        return t0 > 0.0;
    }
};

struct OrderCheck {
    int ordered = 0, violations = 0, pairs_met = 0;
};

// Rays over the panes' region: from `eye`, or straight down (orthographic).
// Layers [0, quads) are the quads, then the balls.
OrderCheck check_order(const std::vector<Quad>& quads, bool orthographic, std::mt19937& rng,
                       const std::vector<Ball>& balls = {}) {
    std::vector<Layer> layers;
    for (const Quad& q : quads) layers.push_back(q.layer());
    for (const Ball& b : balls) layers.push_back(b.layer());
    RayFan rays;
    rays.eye = {0.5, -0.3, 12.0};
    rays.direction = {0.0, 0.0, -1.0};
    rays.orthographic = orthographic;
    std::vector<bool> unordered;
    const std::vector<std::uint32_t> order = order_layers(layers, rays, unordered);
    std::vector<int> rank(layers.size(), -1);
    for (std::size_t r = 0; r < order.size(); ++r) rank[order[r]] = int(r);
    OrderCheck out;
    out.ordered = int(order.size());
    for (std::size_t i = 0; i < layers.size(); ++i) EXPECT_EQ(unordered[i], rank[i] < 0);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int k = 0; k < 20000; ++k) {
        const glm::dvec3 target(4.5 * unit(rng), 4.5 * unit(rng), 0.0);
        const glm::dvec3 o = orthographic ? glm::dvec3(target.x, target.y, 12.0) : rays.eye;
        const glm::dvec3 d = glm::normalize(target - o);
        double last_t = -1.0;
        int met = 0;
        for (std::uint32_t i : order) {
            double t0 = -1.0, t1 = -1.0;
            if (i < quads.size()) t0 = t1 = quads[i].hit(o, d);
            else if (!balls[i - quads.size()].hits(o, d, t0, t1)) t0 = t1 = -1.0;
            if (t0 < 0.0) continue;
            ++met;
            if (t0 < last_t - 1e-9) ++out.violations;
            last_t = t1;
        }
        if (met >= 2) ++out.pairs_met;
    }
    return out;
}

}  // namespace

TEST(LayerOrder, RaysMeetTheOrderedPanesInRankOrder) {
    std::mt19937 rng(7);
    int ordered = 0, total = 0, pairs = 0;
    for (int scene = 0; scene < 40; ++scene)
        for (bool orthographic : {false, true}) {
            const std::vector<Quad> quads = random_panes(rng, 10);
            const OrderCheck c = check_order(quads, orthographic, rng);
            EXPECT_EQ(c.violations, 0) << "scene " << scene << (orthographic ? " orthographic" : " perspective");
            ordered += c.ordered;
            total += int(quads.size());
            pairs += c.pairs_met;
        }
    std::printf("random panes: %d of %d ordered, %d rays met two or more of them\n", ordered, total, pairs);
    // Not a vacuous pass: most panes are ordered and rays do cross them.
    EXPECT_GT(ordered, total / 2);
    EXPECT_GT(pairs, 10000);
}

TEST(LayerOrder, RaysMeetTheOrderedBallsAndPanesInRankOrder) {
    // Balls (convex layers: the near side, then the far side) among panes.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    int ordered = 0, balls_ordered = 0, pairs = 0;
    for (int scene = 0; scene < 30; ++scene)
        for (bool orthographic : {false, true}) {
            const std::vector<Quad> quads = random_panes(rng, 6);
            std::vector<Ball> balls;
            for (int k = 0; k < 3; ++k)
                balls.push_back({{3.0 * unit(rng), 3.0 * unit(rng), 3.0 + 2.0 * unit(rng)}, 0.3 + 0.4 * (unit(rng) + 1)});
            std::vector<Layer> layers;
            for (const Quad& q : quads) layers.push_back(q.layer());
            for (const Ball& b : balls) layers.push_back(b.layer());
            const OrderCheck c = check_order(quads, orthographic, rng, balls);
            EXPECT_EQ(c.violations, 0) << "scene " << scene << (orthographic ? " orthographic" : " perspective");
            std::vector<bool> unordered;
            RayFan rays;
            rays.eye = {0.5, -0.3, 12.0};
            rays.orthographic = orthographic;
            order_layers(layers, rays, unordered);
            for (std::size_t k = quads.size(); k < layers.size(); ++k) balls_ordered += !unordered[k];
            ordered += c.ordered;
            pairs += c.pairs_met;
        }
    std::printf("balls among panes: %d layers ordered (%d of 180 balls), %d rays met two or more\n", ordered,
                balls_ordered, pairs);
    EXPECT_GT(balls_ordered, 180 / 3);
    EXPECT_GT(pairs, 5000);
}

TEST(LayerOrder, OfPanesThatCrossOneIsLeftOut) {
    // Two panes crossing in an X (each cuts the other's plane inside both),
    // and a third above both: one of the pair is left out (the later one),
    // the other and the third are ordered, the third first.
    const Quad a{{0, 0, 2}, {1, 0, 0.5}, {0, 1, 0}}, b{{0, 0, 2}, {1, 0, -0.5}, {0, 1, 0}},
               c{{0, 0, 4}, {1, 0, 0}, {0, 1, 0}};
    std::vector<bool> unordered;
    RayFan rays;
    rays.eye = {0, 0, 10};
    const std::vector<std::uint32_t> order = order_layers({a.layer(), b.layer(), c.layer()}, rays, unordered);
    EXPECT_FALSE(unordered[0]);
    EXPECT_TRUE(unordered[1]);
    EXPECT_FALSE(unordered[2]);
    ASSERT_EQ(order.size(), 2u);
    EXPECT_EQ(order[0], 2u);
}

TEST(LayerOrder, CoplanarAndEdgeOnPanesNeedNoOrder) {
    // Windows side by side in one plane, a pane in front of them, and one
    // seen edge-on from the eye (its plane holds the eye): all ordered, the
    // front pane first.
    const Quad left{{-1.5, 0, 2}, {1, 0, 0}, {0, 1, 0}}, right{{1.5, 0, 2}, {1, 0, 0}, {0, 1, 0}},
               front{{0, 0, 3}, {2.5, 0, 0}, {0, 1, 0}}, edge_on{{0, 3, 2}, {0, 0, 1}, {0, 1, 0}};
    RayFan rays;
    rays.eye = {0, 3, 10};
    std::vector<bool> unordered;
    const std::vector<std::uint32_t> order =
        order_layers({left.layer(), right.layer(), front.layer(), edge_on.layer()}, rays, unordered);
    ASSERT_EQ(order.size(), 4u);
    EXPECT_EQ(order[0], 2u);
}

TEST(LayerOrder, PlanarMeshesAreRecognised) {
    auto planar = [](const tools::MeshArrays& m, double* n = nullptr) {
        double normal[3], offset = 0;
        const bool p = planar_mesh(m.positions.data(), m.positions.size() / 3, m.indices.data(), m.indices.size() / 3,
                                   normal, offset);
        if (p && n)
            for (int k = 0; k < 3; ++k) n[k] = normal[k];
        return p;
    };
    tools::MeshArrays plane = tools::make_plane(2.0f, 4);
    double n[3] = {0, 0, 0};
    EXPECT_TRUE(planar(plane, n));
    EXPECT_NEAR(std::abs(n[2]), 1.0, 1e-12);
    // One vertex lifted by 1e-3 of the plane's size: not planar.
    plane.positions[3 * 7 + 2] += 4e-3f;
    EXPECT_FALSE(planar(plane));
    EXPECT_FALSE(planar(tools::make_box(1.0f, 1.0f, 1.0f)));
    EXPECT_FALSE(planar(tools::make_uv_sphere(1.0f, 12, 6)));
    // Convex: closed boxes and spheres; a box with a dent is not; an open
    // plane is not closed.
    auto convex = [](const tools::MeshArrays& m) {
        const int closed = closed_orientation(m.positions.data(), m.positions.size() / 3, m.indices.data(),
                                              m.indices.size() / 3);
        return convex_mesh(m.positions.data(), m.positions.size() / 3, m.indices.data(), m.indices.size() / 3, closed);
    };
    EXPECT_TRUE(convex(welded(tools::make_box(1.0f, 2.0f, 0.5f))));
    EXPECT_TRUE(convex(welded(tools::make_uv_sphere(1.0f, 24, 12))));
    EXPECT_FALSE(convex(tools::make_box(1.0f, 2.0f, 0.5f)));  // its faces apart: not closed
    EXPECT_FALSE(convex(tools::make_plane(1.0f, 2)));
    tools::MeshArrays sphere = welded(tools::make_uv_sphere(1.0f, 24, 12));
    for (std::size_t v = 0; v < sphere.positions.size() / 3; ++v)
        if (sphere.positions[3 * v + 2] > 0.99f) sphere.positions[3 * v + 2] = 0.5f;  // the pole pushed in
    EXPECT_FALSE(convex(sphere));
    tools::MeshArrays degenerate;
    degenerate.positions = {0, 0, 0, 1, 1, 1, 2, 2, 2};
    degenerate.indices = {0, 1, 2};
    EXPECT_FALSE(planar(degenerate));  // no area: no plane
}
