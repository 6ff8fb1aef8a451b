// The plane test that orders partly transparent planes for the forward pass
// (layer_order.h), checked against its definition: every ray that meets two
// ordered layers meets them in rank order (random panes, perspective and
// orthographic rays), and layers that cross each other are not ordered.
// And the planarity the mesh store records (mesh_topology.h planar_mesh).
#include "layer_order.h"
#include "mesh_topology.h"

#include "builtin_scenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace deferred;

namespace {

struct Quad {
    glm::dvec3 center, u, v;  // u, v: half axes (orthogonal)
    glm::dvec3 normal() const { return glm::normalize(glm::cross(u, v)); }
    PlanarLayer layer() const {
        PlanarLayer l;
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

struct OrderCheck {
    int ordered = 0, violations = 0, pairs_met = 0;
};

// Rays over the panes' region: from `eye`, or straight down (orthographic).
OrderCheck check_order(const std::vector<Quad>& quads, bool orthographic, std::mt19937& rng) {
    std::vector<PlanarLayer> layers;
    for (const Quad& q : quads) layers.push_back(q.layer());
    RayFan rays;
    rays.eye = {0.5, -0.3, 12.0};
    rays.direction = {0.0, 0.0, -1.0};
    rays.orthographic = orthographic;
    std::vector<bool> unordered;
    const std::vector<std::uint32_t> order = order_planar_layers(layers, rays, unordered);
    std::vector<int> rank(quads.size(), -1);
    for (std::size_t r = 0; r < order.size(); ++r) rank[order[r]] = int(r);
    OrderCheck out;
    out.ordered = int(order.size());
    for (std::size_t i = 0; i < quads.size(); ++i) EXPECT_EQ(unordered[i], rank[i] < 0);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int k = 0; k < 20000; ++k) {
        const glm::dvec3 target(4.5 * unit(rng), 4.5 * unit(rng), 0.0);
        const glm::dvec3 o = orthographic ? glm::dvec3(target.x, target.y, 12.0) : rays.eye;
        const glm::dvec3 d = glm::normalize(target - o);
        double last_t = -1.0;
        int met = 0;
        for (std::uint32_t i : order) {
            const double t = quads[i].hit(o, d);
            if (t < 0.0) continue;
            ++met;
            if (t < last_t - 1e-9) ++out.violations;
            last_t = t;
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

TEST(LayerOrder, PanesThatCrossAreLeftUnordered) {
    // Two panes crossing in an X (each cuts the other's plane inside both),
    // and a third above both: the third is ordered, the pair is not.
    const Quad a{{0, 0, 2}, {1, 0, 0.5}, {0, 1, 0}}, b{{0, 0, 2}, {1, 0, -0.5}, {0, 1, 0}},
               c{{0, 0, 4}, {1, 0, 0}, {0, 1, 0}};
    std::vector<bool> unordered;
    RayFan rays;
    rays.eye = {0, 0, 10};
    const std::vector<std::uint32_t> order = order_planar_layers({a.layer(), b.layer(), c.layer()}, rays, unordered);
    EXPECT_TRUE(unordered[0]);
    EXPECT_TRUE(unordered[1]);
    EXPECT_FALSE(unordered[2]);
    ASSERT_EQ(order.size(), 1u);
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
        order_planar_layers({left.layer(), right.layer(), front.layer(), edge_on.layer()}, rays, unordered);
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
    tools::MeshArrays degenerate;
    degenerate.positions = {0, 0, 0, 1, 1, 1, 2, 2, 2};
    degenerate.indices = {0, 1, 2};
    EXPECT_FALSE(planar(degenerate));  // no area: no plane
}
