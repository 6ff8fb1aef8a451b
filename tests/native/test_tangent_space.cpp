// compute_tangents (native/src/tangent_space.cpp), MikkTSpace over
// triangles, on meshes whose tangents follow from the definition: the
// direction of dP/du in the normal's plane, the bitangent sign from the UV
// orientation, a shared vertex's tangent as its corners' angle-weighted sum,
// degenerate triangles copying a neighbour. tests/blender/test_tangents.py
// compares it with Blender's own MikkTSpace (Mesh.calc_tangents).
#include <deferred/tangent_space.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <vector>

namespace {

struct Mesh {
    std::vector<float> positions;         // V x 3
    std::vector<std::uint32_t> indices;   // T x 3
    std::vector<float> normals;           // 3T x 3
    std::vector<float> uvs;               // 3T x 2
    std::vector<std::uint8_t> flat;       // T flat-shading flags, or empty

    std::size_t triangles() const { return indices.size() / 3; }

    std::uint32_t vertex(float x, float y, float z) {
        for (float c : {x, y, z}) positions.push_back(c);  // (insert of a list: a GCC 12 false overflow warning)
        return std::uint32_t(positions.size() / 3 - 1);
    }
    // A triangle with +Z normals and UVs from the corner positions.
    void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c,
                  const std::function<std::pair<float, float>(const float*)>& uv) {
        for (std::uint32_t v : {a, b, c}) {
            indices.push_back(v);
            normals.insert(normals.end(), {0.0f, 0.0f, 1.0f});
            const auto [u, w] = uv(&positions[3 * std::size_t(v)]);
            uvs.insert(uvs.end(), {u, w});
        }
    }

    std::vector<float> tangents() const {
        std::vector<float> out(4 * indices.size(), NAN);
        std::unique_ptr<bool[]> flags;
        if (!flat.empty()) {
            flags.reset(new bool[flat.size()]);
            for (std::size_t t = 0; t < flat.size(); ++t) flags[t] = flat[t] != 0;
        }
        deferred::compute_tangents(positions.data(), positions.size() / 3, indices.data(), triangles(),
                                   normals.data(), uvs.data(), flags.get(), out.data());
        return out;
    }
};

// An n x n grid of unit squares in the XY plane, two triangles each, shared vertices.
Mesh grid(int n, const std::function<std::pair<float, float>(const float*)>& uv) {
    Mesh m;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) m.vertex(float(x), float(y), 0.0f);
    auto id = [&](int x, int y) { return std::uint32_t(y * (n + 1) + x); };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            m.triangle(id(x, y), id(x + 1, y), id(x + 1, y + 1), uv);
            m.triangle(id(x, y), id(x + 1, y + 1), id(x, y + 1), uv);
        }
    return m;
}

void expect_all(const std::vector<float>& t, float x, float y, float z, float sign, const char* what) {
    for (std::size_t c = 0; c < t.size() / 4; ++c) {
        EXPECT_NEAR(t[4 * c + 0], x, 1e-6f) << what << ", corner " << c;
        EXPECT_NEAR(t[4 * c + 1], y, 1e-6f) << what << ", corner " << c;
        EXPECT_NEAR(t[4 * c + 2], z, 1e-6f) << what << ", corner " << c;
        EXPECT_EQ(t[4 * c + 3], sign) << what << ", corner " << c;
    }
}

// Two triangles with one continuous UV map but different gradients, both
// keeping the UV orientation, +Z normals:
// A = O, (1,0), (0,1) with uv = (x, y): T_A = +X;
// B = O, (0,1), (-1,1) with uv (0,0), (0,1), (-1,2): dP/du = (1,1,0), T_B = (1,1,0)/sqrt(2).
// Corners 0..2 are A's (O, (1,0), (0,1)), 3..5 B's (O, (0,1), (-1,1)).
Mesh two_triangles_bent_in_uv() {
    Mesh m;
    const auto o = m.vertex(0, 0, 0), x = m.vertex(1, 0, 0), y = m.vertex(0, 1, 0), w = m.vertex(-1, 1, 0);
    auto uv = [](const float* p) {
        if (p[0] < 0) return std::pair{-1.0f, 2.0f};
        return std::pair{p[0], p[1]};
    };
    m.triangle(o, x, y, uv);
    m.triangle(o, y, w, uv);
    return m;
}

}  // namespace

TEST(Tangents, FollowTheUVGradientAndItsOrientation) {
    // u = x: T = dP/du = +X, UVs wound like the triangles: sign +1.
    expect_all(grid(4, [](const float* p) { return std::pair{p[0], p[1]}; }).tangents(), 1, 0, 0, 1.0f, "u = x");
    // u = -x mirrors the UVs: T = -X and sign -1, so B = sign N x T = +Y = dP/dv still.
    expect_all(grid(4, [](const float* p) { return std::pair{-p[0], p[1]}; }).tangents(), -1, 0, 0, -1.0f,
               "u = -x");
    // u = y, v = x (swapped axes, mirrored): T = +Y, sign -1.
    expect_all(grid(4, [](const float* p) { return std::pair{p[1], p[0]}; }).tangents(), 0, 1, 0, -1.0f,
               "u = y, v = x");
    // Scaled and rotated UVs: u = 2 (x cos a + y sin a) - only the direction of dP/du counts.
    const float a = 0.3f;
    expect_all(grid(4, [&](const float* p) {
                   return std::pair{2.0f * (p[0] * std::cos(a) + p[1] * std::sin(a)),
                                    3.0f * (-p[0] * std::sin(a) + p[1] * std::cos(a))};
               }).tangents(),
               std::cos(a), std::sin(a), 0, 1.0f, "rotated UVs");
}

TEST(Tangents, AMirroredHalfKeepsItsOwnTangentAcrossTheSeam) {
    // Left half u = x, right half u = -x (a mirror modifier's UVs): at the
    // seam the corners weld (u = 0 on both sides) but the halves' UV
    // orientations differ, so they form separate groups and neither bleeds
    // into the other.
    const Mesh m = grid(4, [](const float* p) { return std::pair{-std::fabs(p[0] - 2.0f), p[1]}; });
    const auto t = m.tangents();
    for (std::size_t tri = 0; tri < m.triangles(); ++tri) {
        float cx = 0;
        for (int k = 0; k < 3; ++k) cx += m.positions[3 * m.indices[3 * tri + std::size_t(k)]] / 3.0f;
        const bool right = cx > 2.0f;  // u = -(x - 2): mirrored, T = -X, sign -1
        for (int k = 0; k < 3; ++k) {
            const float* c = &t[4 * (3 * tri + std::size_t(k))];
            EXPECT_NEAR(c[0], right ? -1.0f : 1.0f, 1e-6f) << "triangle " << tri;
            EXPECT_NEAR(c[1], 0.0f, 1e-6f) << "triangle " << tri;
            EXPECT_EQ(c[3], right ? -1.0f : 1.0f) << "triangle " << tri;
        }
    }
}

TEST(Tangents, ASharedVertexAveragesItsCornersByAngle) {
    // two_triangles_bent_in_uv: at O, A's angle is 90 degrees and B's 45;
    // at (0,1), A's is 45 and B's 90. MikkTSpace weights each face's
    // tangent by its corner angle there.
    Mesh m = two_triangles_bent_in_uv();
    const auto t = m.tangents();
    const double pi = 3.14159265358979323846, s = 1.0 / std::sqrt(2.0);
    auto expected = [&](double weight_a, double weight_b) {
        const double tx = weight_a + weight_b * s, ty = weight_b * s, len = std::hypot(tx, ty);
        return std::pair{tx / len, ty / len};
    };
    // The weights are Cycles' fast_acosf, within 4.52e-5 rad of the angle:
    // each weight's error turns the unit sum by at most its share of the
    // total weight (3 pi / 4), so 2 x 4.52e-5 / 2.36 < 4e-5 per component.
    const double tolerance = 4e-5;
    auto check = [&](std::size_t corner, std::pair<double, double> want, const char* what) {
        EXPECT_NEAR(t[4 * corner + 0], want.first, tolerance) << what;
        EXPECT_NEAR(t[4 * corner + 1], want.second, tolerance) << what;
        EXPECT_NEAR(t[4 * corner + 2], 0.0, 1e-6) << what;
        EXPECT_EQ(t[4 * corner + 3], 1.0f) << what;
    };
    const auto at_o = expected(pi / 2, pi / 4), at_y = expected(pi / 4, pi / 2);
    check(0, at_o, "O in A");
    check(3, at_o, "O in B");
    check(2, at_y, "(0,1) in A");
    check(4, at_y, "(0,1) in B");
    check(1, {1.0, 0.0}, "(1,0): A alone");
    check(5, {s, s}, "(-1,1): B alone");
}

TEST(Tangents, CornersWeldOnlyWithTheSameBitsSoMinusZeroSplits) {
    // Blender's MikkTSpace (the C++ port Cycles runs) finds equal corners by
    // a hash of their bits: a normal (-0, 0, 1) is not (0, 0, 1). Cycles'
    // flat-triangle normals carry either sign of zero, so the triangles of
    // a flat n-gon keep their own tangents there; with equal bits, the
    // shared corners average (the test above).
    Mesh m = two_triangles_bent_in_uv();
    for (int k = 3; k < 6; ++k) m.normals[3 * std::size_t(k)] = -0.0f;  // the second triangle's normals
    const auto t = m.tangents();
    const float s = float(1.0 / std::sqrt(2.0));
    for (std::size_t corner = 0; corner < 3; ++corner) {
        EXPECT_NEAR(t[4 * corner + 0], 1.0f, 1e-6f) << corner;  // A alone: +X
        EXPECT_NEAR(t[4 * corner + 1], 0.0f, 1e-6f) << corner;
    }
    for (std::size_t corner = 3; corner < 6; ++corner) {
        EXPECT_NEAR(t[4 * corner + 0], s, 1e-6f) << corner;  // B alone: (1, 1, 0) / sqrt(2)
        EXPECT_NEAR(t[4 * corner + 1], s, 1e-6f) << corner;
    }
}

TEST(Tangents, FlatTrianglesReadTheirOwnNormalAsCyclesComputesIt) {
    // The two triangles above, flat-shaded: Cycles hands MikkTSpace each
    // triangle's computed normal, and B's is (0, -0, 1) (its y is
    // 0 * -1 - 0 * 0 = -0), A's (0, 0, 1). So the two do not weld at their
    // shared corners and each keeps its own tangent: Cycles' image of a flat
    // n-gon. With smooth shading (the same +Z normals given) they average.
    Mesh m = two_triangles_bent_in_uv();
    const auto smooth = m.tangents();
    EXPECT_GT(smooth[4 * 3 + 0] - smooth[4 * 3 + 1], 0.1f);  // O in B leans towards A's +X
    m.flat = {1, 1};
    const auto t = m.tangents();
    const float s = float(1.0 / std::sqrt(2.0));
    for (std::size_t corner = 0; corner < 3; ++corner) {
        EXPECT_NEAR(t[4 * corner + 0], 1.0f, 1e-6f) << corner;
        EXPECT_NEAR(t[4 * corner + 1], 0.0f, 1e-6f) << corner;
    }
    for (std::size_t corner = 3; corner < 6; ++corner) {
        EXPECT_NEAR(t[4 * corner + 0], s, 1e-6f) << corner;
        EXPECT_NEAR(t[4 * corner + 1], s, 1e-6f) << corner;
    }
    // A flat grid in the plane: every computed normal is (+0, +0, 1), so it welds as before.
    Mesh g = grid(3, [](const float* p) { return std::pair{p[0] + 0.1f * p[1] * p[1], p[1]}; });
    const auto g_smooth = g.tangents();
    g.flat.assign(g.triangles(), 1);
    const auto g_flat = g.tangents();
    for (std::size_t i = 0; i < g_flat.size(); ++i) EXPECT_EQ(g_flat[i], g_smooth[i]) << i;
}

TEST(Tangents, ATriangleWithoutUVAreaTakesItsNeighboursTangentOrTheDefault) {
    // A triangle whose UVs have no area has no tangent of its own ("group
    // with any"): reached from a good neighbour, its corners there take
    // that group's tangent; a corner no good triangle reaches keeps the
    // port's initial (1, 0, 0) with sign -1.
    Mesh m = grid(1, [](const float* p) { return std::pair{p[0], p[1]}; });
    const auto apex = m.vertex(0.5f, -1.0f, 0.0f);
    // On the grid's bottom edge (vertices 1 -> 0 reversed, so it is a neighbour), UVs on a line.
    m.triangle(1, 0, apex, [](const float* p) { return std::pair{p[0], 0.0f}; });
    const auto t = m.tangents();
    // Its corners at vertices 1 and 0 would weld only with equal UVs: (1,0) and (0,0) are the grid's.
    for (std::size_t corner : {6u, 7u}) {
        EXPECT_NEAR(t[4 * corner], 1.0f, 1e-6f) << corner;
        EXPECT_EQ(t[4 * corner + 3], 1.0f) << corner;
    }
    EXPECT_EQ(t[4 * 8 + 0], 1.0f);  // the apex: no good triangle there
    EXPECT_EQ(t[4 * 8 + 1], 0.0f);
    EXPECT_EQ(t[4 * 8 + 3], -1.0f);
}

TEST(Tangents, AreProjectedIntoTheNormalsPlane) {
    // A smooth bump (z = h(x, y)) with analytic normals and uv = (x, y): T is
    // dP/du = (1, 0, dh/dx) made orthogonal to N and unit, wherever the
    // corners' faces agree; check the invariant that holds at every corner.
    Mesh m = grid(8, [](const float* p) { return std::pair{p[0], p[1]}; });
    for (std::size_t v = 0; v < m.positions.size() / 3; ++v) {
        const float x = m.positions[3 * v], y = m.positions[3 * v + 1];
        m.positions[3 * v + 2] = 0.3f * std::sin(0.7f * x) * std::cos(0.5f * y);
    }
    for (std::size_t c = 0; c < m.indices.size(); ++c) {
        const float* p = &m.positions[3 * std::size_t(m.indices[c])];
        const float dx = 0.3f * 0.7f * std::cos(0.7f * p[0]) * std::cos(0.5f * p[1]);
        const float dy = -0.3f * 0.5f * std::sin(0.7f * p[0]) * std::sin(0.5f * p[1]);
        const float len = std::sqrt(dx * dx + dy * dy + 1.0f);
        m.normals[3 * c + 0] = -dx / len;
        m.normals[3 * c + 1] = -dy / len;
        m.normals[3 * c + 2] = 1.0f / len;
    }
    const auto t = m.tangents();
    for (std::size_t c = 0; c < m.indices.size(); ++c) {
        const float* tc = &t[4 * c];
        const float* n = &m.normals[3 * c];
        EXPECT_NEAR(tc[0] * tc[0] + tc[1] * tc[1] + tc[2] * tc[2], 1.0f, 1e-5f) << "corner " << c;
        EXPECT_NEAR(tc[0] * n[0] + tc[1] * n[1] + tc[2] * n[2], 0.0f, 1e-5f) << "corner " << c;
        EXPECT_GT(tc[0], 0.9f) << "corner " << c;  // still mostly along +X, the way u grows
        EXPECT_EQ(tc[3], 1.0f) << "corner " << c;
    }
}

TEST(Tangents, TriangleOrderChangesNothingButRounding) {
    Mesh m = grid(6, [](const float* p) { return std::pair{p[0] * p[0] * 0.2f + p[1], p[1] - 0.1f * p[0]}; });
    for (std::size_t v = 0; v < m.positions.size() / 3; ++v)
        m.positions[3 * v + 2] = 0.2f * std::sin(float(v));
    const auto forward = m.tangents();
    Mesh reversed = m;
    const std::size_t n = m.triangles();
    for (std::size_t t = 0; t < n; ++t)
        for (int k = 0; k < 3; ++k) {
            const std::size_t from = 3 * (n - 1 - t) + std::size_t(k), to = 3 * t + std::size_t(k);
            reversed.indices[to] = m.indices[from];
            std::copy_n(&m.normals[3 * from], 3, &reversed.normals[3 * to]);
            std::copy_n(&m.uvs[2 * from], 2, &reversed.uvs[2 * to]);
        }
    const auto backward = reversed.tangents();
    for (std::size_t t = 0; t < n; ++t)
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 4; ++i)
                EXPECT_NEAR(forward[4 * (3 * t + std::size_t(k)) + std::size_t(i)],
                            backward[4 * (3 * (n - 1 - t) + std::size_t(k)) + std::size_t(i)], 1e-6f)
                    << "triangle " << t << " corner " << k;
}

TEST(Tangents, ADegenerateTriangleCopiesAGoodCornerOrKeepsTheDefault) {
    Mesh m = grid(1, [](const float* p) { return std::pair{p[0], p[1]}; });
    // A sliver with two corners at one position, on the grid's vertices 0 and 1 (both in good triangles).
    const auto same_as_0 = m.vertex(0, 0, 0);
    m.triangle(0, 1, same_as_0, [](const float* p) { return std::pair{p[0], p[1]}; });
    // An isolated degenerate triangle: nothing to copy from.
    const auto a = m.vertex(5, 5, 0), b = m.vertex(5, 5, 0), c = m.vertex(6, 5, 0);
    m.triangle(a, b, c, [](const float* p) { return std::pair{p[0], p[1]}; });
    const auto t = m.tangents();
    for (std::size_t corner = 6; corner < 9; ++corner) {  // the sliver: copies of +X
        EXPECT_NEAR(t[4 * corner], 1.0f, 1e-6f) << corner;
        EXPECT_EQ(t[4 * corner + 3], 1.0f) << corner;
    }
    for (std::size_t corner = 9; corner < 12; ++corner) {  // genTangSpace's initial (1,0,0), sign -1
        EXPECT_EQ(t[4 * corner], 1.0f) << corner;
        EXPECT_EQ(t[4 * corner + 1], 0.0f) << corner;
        EXPECT_EQ(t[4 * corner + 3], -1.0f) << corner;
    }
}

TEST(Tangents, AFanOfManyTrianglesAroundOneVertex) {
    // 200 triangles around a centre: 200 corners at one point (a bucket the
    // weld sorts instead of scanning) and one group of 200 triangles; the
    // centre's tangent is still +X for uv = (x, y).
    Mesh m;
    const auto centre = m.vertex(0, 0, 0);
    const int n = 200;
    std::vector<std::uint32_t> rim;
    for (int i = 0; i < n; ++i) {
        const float a = 2.0f * 3.14159265f * float(i) / float(n);
        rim.push_back(m.vertex(std::cos(a), std::sin(a), 0));
    }
    for (int i = 0; i < n; ++i)
        m.triangle(centre, rim[std::size_t(i)], rim[std::size_t((i + 1) % n)],
                   [](const float* p) { return std::pair{p[0], p[1]}; });
    expect_all(m.tangents(), 1, 0, 0, 1.0f, "fan");
}

TEST(Tangents, BadInputIsAClearError) {
    Mesh m = grid(1, [](const float* p) { return std::pair{p[0], p[1]}; });
    m.indices[4] = 99;
    EXPECT_THROW(m.tangents(), std::invalid_argument);
    Mesh empty;
    EXPECT_NO_THROW(empty.tangents());
}
