// Shadow casters and the visibility buffer drawn by vertex (glDrawElements),
// and closed casters seen from outside without their back faces
// (draw_style.h): the maps and the visibility buffer hold the same nearest
// surfaces, so the image is the same to the bit as with every corner drawn
// and both sides (DEFERRED_DRAW_BY_VERTEX=off, DEFERRED_FACE_CULLING=off).
// Which meshes are closed, and which way they face, is mesh_topology.h's.
#include "mesh_topology.h"
#include "scene_store.h"
#include "shadow_module.h"
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

using namespace deferred;

namespace {

// A box with its 8 corners shared by its 12 triangles, wound
// counter-clockwise seen from outside (closed, facing out); `inward`
// reverses every triangle (facing in). `offset` moves its vertices.
tools::MeshArrays welded_box(float h, bool inward = false, float offset = 0.0f) {
    tools::MeshArrays m;
    for (int i = 0; i < 8; ++i)
        m.positions.insert(m.positions.end(), {offset + ((i & 1) ? h : -h), offset + ((i & 2) ? h : -h),
                                               offset + ((i & 4) ? h : -h)});
    const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                       {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        const std::uint32_t tris[2][3] = {{q[0], q[1], q[2]}, {q[0], q[2], q[3]}};
        for (const auto& t : tris) {
            if (inward) m.indices.insert(m.indices.end(), {t[0], t[2], t[1]});
            else m.indices.insert(m.indices.end(), {t[0], t[1], t[2]});
        }
    }
    return m;
}

int orientation(const tools::MeshArrays& m) {
    return closed_orientation(m.positions.data(), m.positions.size() / 3, m.indices.data(), m.indices.size() / 3);
}

// Two meshes as one: b's vertices after a's.
tools::MeshArrays joined(tools::MeshArrays a, const tools::MeshArrays& b) {
    const std::uint32_t base = std::uint32_t(a.positions.size() / 3);
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    for (std::uint32_t i : b.indices) a.indices.push_back(base + i);
    return a;
}

Material grey() {
    Material m;
    m.base_color = {0.5f, 0.5f, 0.5f};
    m.roughness = 0.4f;
    return m;
}

Mat4d scaled(double sx, double sy, double sz, double x, double y, double z) {
    Mat4d m = tools::translation(x, y, z);
    m[0] = sx;
    m[5] = sy;
    m[10] = sz;
    return m;
}

// An open floor; closed boxes facing out (two of them mirrored by their
// instances), a closed box facing in, a box welded shut around a spot light
// (its maps' origin inside: both sides), an unwelded box (open: its faces
// do not share corners). A sun with an angle (cascades), a sphere light and
// a tilted area light (cubes, the area light's clip plane), the spot; the
// world's occlusion maps (both sides always). Around it all, a closed room
// facing in that casts no shadow.
// `transparent`: the tall mirrored box and the open box partly transparent
// (alpha 0.4 and a stochastic mix of it with an opaque one), so the maps
// and the visibility buffer draw them with the alpha test.
FrameResult casters_frame(const char* by_vertex, const char* face_culling, bool transparent = false) {
    setenv("DEFERRED_DRAW_BY_VERTEX", by_vertex, 1);
    setenv("DEFERRED_FACE_CULLING", face_culling, 1);
    Renderer r;
    const std::uint32_t mat = deferred::testing::add_plane(r, grey(), 6.0f, 4);
    Material glass = grey();
    glass.base_color = {0.2f, 0.6f, 0.8f};
    glass.alpha = 0.4f;
    const std::uint32_t glass_mat = transparent ? r.add_material(glass) : mat;
    Material mixed = grey();
    mixed.mix_with = std::int32_t(glass_mat);
    mixed.mix_probability = 0.5f;
    const std::uint32_t mixed_mat = transparent ? r.add_material(mixed) : mat;
    const tools::MeshArrays out = welded_box(0.3f), in = welded_box(0.3f, true), open = tools::make_box(0.3f, 0.3f, 0.3f);
    const std::uint32_t out_mesh = r.add_mesh(out.view()), in_mesh = r.add_mesh(in.view()),
                        open_mesh = r.add_mesh(open.view());
    // Resting on the floor; mirrored and resting; mirrored, tall, through
    // the area light's plane.
    const Mat4d out_at[] = {tools::translation(0.0, 0.0, 0.3), scaled(-1.0, 1.5, 1.0, 1.5, 0.5, 0.3),
                            scaled(-0.5, 0.5, 4.0, -0.6, 0.4, 1.5)};
    for (int k = 0; k < 3; ++k) r.add_instances(out_mesh, out_at[k].data(), 1, nullptr, {k == 2 ? glass_mat : mat});
    const Mat4d in_at = tools::translation(-1.5, -0.5, 0.3), open_at = tools::translation(0.5, -1.5, 0.6),
                housing_at = tools::translation(2.0, 2.0, 1.5);
    r.add_instances(in_mesh, in_at.data(), 1, nullptr, {mat});
    r.add_instances(open_mesh, open_at.data(), 1, nullptr, {mixed_mat});
    r.add_instances(out_mesh, housing_at.data(), 1, nullptr, {mat});
    const tools::MeshArrays room = welded_box(15.0f, true);
    const std::uint32_t room_mesh = r.add_mesh(room.view());
    const Mat4d room_at = tools::translation(0.0, 0.0, 14.9);
    r.add_instances(room_mesh, room_at.data(), 1, nullptr, {mat}, false);

    auto aimed = [](LightType type, double x, double y, double z, double tx, double ty, float energy) {
        Light l;
        l.type = type;
        const double eye[3] = {x, y, z}, target[3] = {tx, ty, 0.0};
        l.matrix = tools::look_at(eye, target);
        l.energy = energy;
        return l;
    };
    Light sun = aimed(LightType::Sun, 3.0, -2.0, 6.0, 0.0, 0.0, 2.0f);
    sun.angle = float(4.0 * M_PI / 180.0);
    r.add_light(sun);
    Light point = aimed(LightType::Point, -1.0, 1.0, 3.0, 0.0, 0.0, 300.0f);
    point.radius = 0.2f;
    r.add_light(point);
    Light area = aimed(LightType::Area, 1.2, -1.0, 2.5, -0.5, 0.3, 300.0f);
    area.size = 0.8f;
    r.add_light(area);
    Light spot = aimed(LightType::Spot, 2.0, 2.0, 1.5, 0.5, 0.5, 300.0f);
    spot.radius = 0.05f;
    spot.spot_size = float(80.0 * M_PI / 180.0);
    r.add_light(spot);
    deferred::testing::set_world_color(r, 0.05f, 0.06f, 0.08f);

    Camera cam;
    const double eye[3] = {5.0, -6.0, 6.0}, target[3] = {0.0, 0.0, 0.8};
    cam.matrix = tools::look_at(eye, target);
    RenderSettings s;
    s.width = 96;
    s.height = 64;
    s.samples = 4;
    s.passes = {Pass::Combined, Pass::DiffDir, Pass::GlossDir, Pass::Shadow, Pass::AO,
                Pass::Depth,    Pass::Normal,  Pass::IndexOB,  Pass::UV};
    FrameResult f = r.render(cam, s);
    unsetenv("DEFERRED_DRAW_BY_VERTEX");
    unsetenv("DEFERRED_FACE_CULLING");
    return f;
}

// A low sun's long shadows across a field of posts, most of them outside
// the view, and low-poly smooth spheres whose shadow terminator offset
// (Geometry Offset 1) moves their lookups well off the surface, one of
// them at the view's side. `ortho`: an orthographic camera, else a
// perspective one looking along the field. The sun's cascades draw the
// casters that can shadow a lookup of their slice
// (DEFERRED_SHADOW_RECEIVER_CULLING, shadow_module.cpp slice_casters), or
// every one in their square ("off"). `lamp`: a sphere light behind and
// beside the camera, out of the view volume, instead of the sun, under a
// black world: its cube faces draw the casters in the cone the view
// volume fills from its point (cone_casters), or every one in the face.
FrameResult slices_frame(const char* receiver_culling, bool ortho, bool balls, bool lamp = false) {
    setenv("DEFERRED_SHADOW_RECEIVER_CULLING", receiver_culling, 1);
    Renderer r;
    const std::uint32_t mat = deferred::testing::add_plane(r, grey(), 40.0f, 4);
    const tools::MeshArrays post = welded_box(0.15f), ball = tools::make_uv_sphere(0.6f, 6, 4);
    const std::uint32_t post_mesh = r.add_mesh(post.view()), ball_mesh = r.add_mesh(ball.view());
    std::vector<double> posts;
    unsigned seed = 12345u;
    auto next = [&seed]() {
        seed = seed * 1664525u + 1013904223u;
        return double(seed >> 8) / double(1u << 24);
    };
    // Gravel floating 0.1 m above the floor, so dense that some of it
    // shadows every strip along the view's edges, and a few tall posts.
    for (int i = 0; i < 120; ++i)
        for (int j = 0; j < 120; ++j) {
            const Mat4d m = scaled(0.25, 0.25, 0.25, -18.0 + 0.3 * i + 0.2 * next(), -18.0 + 0.3 * j + 0.2 * next(),
                                   0.14);
            posts.insert(posts.end(), m.begin(), m.end());
        }
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j) {
            const double height = 1.0 + 6.0 * next();
            const Mat4d m = scaled(1.0, 1.0, height, -18.0 + 6.0 * i + next(), -18.0 + 6.0 * j + next(), 0.15 * height);
            posts.insert(posts.end(), m.begin(), m.end());
        }
    r.add_instances(post_mesh, posts.data(), posts.size() / 16, nullptr, {mat});
    const float offset = 1.0f;
    for (const Mat4d& at : {tools::translation(3.2, -6.0, 1.2), tools::translation(-2.0, 4.0, 1.0),
                            tools::translation(6.0, 10.0, 1.0)})
        if (balls) r.add_instances(ball_mesh, at.data(), 1, nullptr, {mat}, true, nullptr, nullptr, nullptr, false, 0, &offset);
    if (lamp) {
        Light point;
        point.type = LightType::Point;
        point.matrix = tools::translation(-8.0, -22.0, 5.0);
        point.energy = 20000.0f;
        point.radius = 0.3f;
        r.add_light(point);
        deferred::testing::set_world_color(r, 0.0f, 0.0f, 0.0f);
    } else {
        Light sun;
        sun.type = LightType::Sun;
        const double from[3] = {-10.0, -4.0, 7.0}, to[3] = {0.0, 0.0, 0.0};
        sun.matrix = tools::look_at(from, to);
        sun.energy = 3.0f;
        sun.angle = float(2.0 * M_PI / 180.0);
        r.add_light(sun);
        deferred::testing::set_world_color(r, 0.02f, 0.02f, 0.03f);
    }

    Camera cam;
    if (ortho) {
        const double eye[3] = {4.0, -8.0, 14.0}, target[3] = {0.0, 0.0, 0.0};
        cam.matrix = tools::look_at(eye, target);
        cam.type = CameraType::Orthographic;
        cam.ortho_scale = 12.0f;
        cam.clip_start = 8.0f;
        cam.clip_end = 30.0f;
    } else {
        const double eye[3] = {0.0, -14.0, 2.5}, target[3] = {0.0, 0.0, 0.5};
        cam.matrix = tools::look_at(eye, target);
        cam.lens = 40.0f;
        cam.clip_end = 80.0f;
    }
    RenderSettings s;
    // Coarse pixels, a wide filter and coarse maps: the strips the margins
    // keep (the filter's reach beyond the view, texels) span metres.
    s.width = 48;
    s.height = 32;
    s.filter_width = 4.0f;
    s.shadow_resolution = 128;
    s.samples = 8;
    s.passes = {Pass::Combined, Pass::Shadow, Pass::AO, Pass::Depth};
    FrameResult f = r.render(cam, s);
    unsetenv("DEFERRED_SHADOW_RECEIVER_CULLING");
    return f;
}

// Every value of each pass in `passes` of `a` equal to `b`'s, to the bit.
void expect_same_passes(const FrameResult& a, const FrameResult& b, std::initializer_list<Pass> passes,
                        const std::string& name) {
    for (Pass pass : passes) {
        const PassImage* x = a.find(pass);
        const PassImage* y = b.find(pass);
        ASSERT_TRUE(x && y) << name << ", pass " << int(pass) << " missing";
        ASSERT_EQ(x->pixels.size(), y->pixels.size());
        std::size_t differ = 0;
        double worst = 0;
        for (std::size_t i = 0; i < x->pixels.size(); ++i) {
            differ += x->pixels[i] != y->pixels[i];
            worst = std::max(worst, double(std::abs(x->pixels[i] - y->pixels[i])));
        }
        EXPECT_EQ(differ, 0u) << name << ", pass " << int(pass) << ": largest difference " << worst;
    }
}

}  // namespace

TEST(MeshTopology, ClosedMeshesAndTheSideTheyFace) {
    EXPECT_EQ(orientation(welded_box(1.0f)), 1);
    EXPECT_EQ(orientation(welded_box(1.0f, true)), -1);
    // Far from the origin: each part's volume is taken at its own vertex.
    EXPECT_EQ(orientation(welded_box(0.01f, false, 1.0e5f)), 1);
    // Two parts facing out; one out and one in (a shell seen from both
    // sides: its inner part would be met first from inside the cavity).
    EXPECT_EQ(orientation(joined(welded_box(1.0f), welded_box(0.5f, false, 3.0f))), 1);
    EXPECT_EQ(orientation(joined(welded_box(1.0f), welded_box(0.5f, true))), 0);
    // Open: a plane, a box whose faces do not share corners, a box missing
    // a triangle.
    EXPECT_EQ(orientation(tools::make_plane(1.0f, 2)), 0);
    EXPECT_EQ(orientation(tools::make_box(1.0f, 1.0f, 1.0f)), 0);
    tools::MeshArrays holed = welded_box(1.0f);
    holed.indices.resize(holed.indices.size() - 3);
    EXPECT_EQ(orientation(holed), 0);
    // Inconsistently wound: one triangle turned over.
    tools::MeshArrays turned = welded_box(1.0f);
    std::swap(turned.indices[1], turned.indices[2]);
    EXPECT_EQ(orientation(turned), 0);
    // Non-manifold: a third triangle on an edge (with its own way back).
    tools::MeshArrays fin = welded_box(1.0f);
    fin.positions.insert(fin.positions.end(), {0.0f, 0.0f, 3.0f});
    fin.indices.insert(fin.indices.end(), {0, 1, 8, 1, 0, 8});
    EXPECT_EQ(orientation(fin), 0);
    // A quad drawn both ways: every edge twice, once each way, but no volume.
    tools::MeshArrays sheet;
    sheet.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    sheet.indices = {0, 1, 2, 0, 2, 3, 0, 2, 1, 0, 3, 2};
    EXPECT_EQ(orientation(sheet), 0);
    // Degenerate: an edge from a vertex to itself; an index out of range.
    tools::MeshArrays degenerate = welded_box(1.0f);
    degenerate.indices[1] = degenerate.indices[0];
    EXPECT_EQ(orientation(degenerate), 0);
    tools::MeshArrays beyond = welded_box(1.0f);
    beyond.indices[0] = 99;
    EXPECT_EQ(orientation(beyond), 0);
}

TEST(DrawStyle, ByVertexAndFrontFacesOnlyChangeNoPixel) {
    struct EnvGuard {
        ~EnvGuard() {
            unsetenv("DEFERRED_DRAW_BY_VERTEX");
            unsetenv("DEFERRED_FACE_CULLING");
        }
    } guard;
    const FrameResult reference = casters_frame("off", "off");
    const FrameResult by_vertex = casters_frame("on", "off");
    const FrameResult one_sided = casters_frame("on", "on");
    EXPECT_EQ(reference.timings.shadow_instances_one_sided, 0u);
    EXPECT_EQ(by_vertex.timings.shadow_instances_one_sided, 0u);
    EXPECT_TRUE(by_vertex.timings.visibility_buffer);
    // The closed boxes facing out or in, mirrored or not, from every map but
    // the world's and the spot's inside its housing; never the floor or the
    // open box.
    EXPECT_GT(one_sided.timings.shadow_instances_one_sided, 0u);
    EXPECT_LT(one_sided.timings.shadow_instances_one_sided, one_sided.timings.shadow_instances_drawn);
    EXPECT_EQ(one_sided.timings.shadow_instances_drawn, reference.timings.shadow_instances_drawn);
    std::printf("%llu of %llu instances drawn into the maps without back faces\n",
                static_cast<unsigned long long>(one_sided.timings.shadow_instances_one_sided),
                static_cast<unsigned long long>(one_sided.timings.shadow_instances_drawn));
    for (const FrameResult* f : {&by_vertex, &one_sided}) {
        const char* name = f == &by_vertex ? "by vertex" : "by vertex, front faces only";
        expect_same_passes(*f, reference,
                           {Pass::Combined, Pass::DiffDir, Pass::GlossDir, Pass::Shadow, Pass::AO, Pass::Depth,
                            Pass::Normal, Pass::IndexOB, Pass::UV},
                           name);
    }
}

// With partly transparent constant materials in the scene, only their
// slots take the alpha test's program (SCENE_ALPHA: by corner, both sides);
// the opaque casters keep the plain one, by vertex and, closed, front faces
// only, in the maps and in the visibility buffer alike: the same image to
// the bit as every surface drawn through the alpha test
// (DEFERRED_ALPHA_APART=off), its alpha noise included.
TEST(DrawStyle, OnlyPartlyTransparentMaterialsTakeTheAlphaTest) {
    struct EnvGuard {
        ~EnvGuard() {
            unsetenv("DEFERRED_DRAW_BY_VERTEX");
            unsetenv("DEFERRED_FACE_CULLING");
            unsetenv("DEFERRED_ALPHA_APART");
        }
    } guard;
    setenv("DEFERRED_ALPHA_APART", "off", 1);
    const FrameResult together = casters_frame("on", "on", true);
    setenv("DEFERRED_ALPHA_APART", "on", 1);
    const FrameResult apart = casters_frame("on", "on", true);
    const FrameResult opaque = casters_frame("on", "on", false);
    EXPECT_TRUE(apart.timings.visibility_buffer);
    EXPECT_EQ(together.timings.shadow_instances_one_sided, 0u);
    EXPECT_GT(apart.timings.shadow_instances_one_sided, 0u);
    EXPECT_EQ(apart.timings.shadow_instances_drawn, together.timings.shadow_instances_drawn);
    std::printf("%llu of %llu instances drawn into the maps without back faces (none drawn so together)\n",
                static_cast<unsigned long long>(apart.timings.shadow_instances_one_sided),
                static_cast<unsigned long long>(apart.timings.shadow_instances_drawn));
    expect_same_passes(apart, together,
                       {Pass::Combined, Pass::DiffDir, Pass::GlossDir, Pass::Shadow, Pass::AO, Pass::Depth,
                        Pass::Normal, Pass::IndexOB, Pass::UV},
                       "opaque casters apart");
    // The transparency shows: the two boxes' shadows and colours are not the opaque scene's.
    const PassImage* a = apart.find(Pass::Combined);
    const PassImage* o = opaque.find(Pass::Combined);
    ASSERT_TRUE(a && o);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a->pixels.size(); ++i) differ += std::abs(a->pixels[i] - o->pixels[i]) > 1e-3f;
    EXPECT_GT(differ, a->pixels.size() / 100);
}

// A sun's cascade draws only the casters whose shadow can fall on a lookup
// of its own slice of the view (shadow_module.cpp slice_casters: over the
// part of the visible instances' boxes in the slice, receiver_points), the
// world's maps those beside the projection of the boxes in view (the
// floor's among them: a flat box), a light's cube face
// those in the cone the view fills from its point (cone_casters): the maps
// differ only in texels no lookup reads, so the image is the same to the bit.
TEST(DrawStyle, ShadowMapsLeaveOutOnlyCastersNoLookupSees) {
    struct EnvGuard {
        ~EnvGuard() { unsetenv("DEFERRED_SHADOW_RECEIVER_CULLING"); }
    } guard;
    for (int view = 0; view < 6; ++view) {
        const bool ortho = view & 1, balls = view & 2, lamp = view >= 4;
        const FrameResult every = slices_frame("off", ortho, balls, lamp);
        const FrameResult culled = slices_frame("on", ortho, balls, lamp);
        const std::string name = std::string(ortho ? "orthographic" : "perspective") + (balls ? ", spheres" : "") +
                                 (lamp ? ", a light out of view" : ", the sun");
        std::printf("%s: %llu of %llu instances drawn into the maps\n", name.c_str(),
                    static_cast<unsigned long long>(culled.timings.shadow_instances_drawn),
                    static_cast<unsigned long long>(every.timings.shadow_instances_drawn));
        // Most posts lie outside the view, beside or behind it. Under the
        // sun, the cascades and the world's map take only the instances'
        // boxes in their slice (the floor's strip, not the air above it):
        // 38-49 % drawn, 64-82 % over the whole slices.
        EXPECT_LT(double(culled.timings.shadow_instances_drawn),
                  (lamp ? 0.95 : 0.6) * double(every.timings.shadow_instances_drawn))
            << name;
        expect_same_passes(culled, every, {Pass::Combined, Pass::Shadow, Pass::AO, Pass::Depth}, name);
    }
}

// An instance's bounding sphere (FrameScene::place, the cull of every
// stage) holds its mesh under a shear: a box sheared by x += y and turned
// so its corner (1, 1) points along +x reaches 8.94 m out along x, where a
// sphere over the longest column (8 m) stops. Placed so that sphere ends
// beyond the view's left edge while the corner's tip is in view, the tip
// is drawn.
TEST(Culling, ShearedInstancesKeepTheirCornersInTheirSphere) {
    Renderer r;
    const tools::MeshArrays slab = tools::make_box(4.0f, 4.0f, 0.05f);
    const std::uint32_t mesh = r.add_mesh(slab.view());
    const std::uint32_t mat = r.add_material(grey());
    const double t = -std::atan2(1.0, 2.0), c = std::cos(t), s = std::sin(t);
    // Columns of R(t) * [[1, 1, 0], [0, 1, 0], [0, 0, 1]].
    Mat4d m = identity_matrix();
    m[0] = c;
    m[1] = s;
    m[4] = c - s;
    m[5] = s + c;
    m[12] = -11.4;
    const std::uint32_t index = 7;
    r.add_instances(mesh, m.data(), 1, &index, {mat});
    deferred::testing::set_world_color(r, 0.1f, 0.1f, 0.1f);
    RenderSettings settings;
    settings.width = settings.height = 64;
    settings.samples = 1;
    settings.passes = {Pass::Combined, Pass::IndexOB};
    // Top down over x, y in [-3, 3]: the tip reaches x = -2.46.
    const FrameResult f = r.render(deferred::testing::top_down_ortho(10.0, 6.0f), settings);
    const PassImage& ids = *f.find(Pass::IndexOB);
    int tip = 0;
    for (int y = 0; y < ids.height; ++y)
        for (int x = 0; x < ids.width; ++x) tip += ids.pixels[std::size_t(y * ids.width + x) * ids.channels] == 7.0f;
    // The tip: a triangle about 0.54 m deep (5.8 px) and twice as wide.
    EXPECT_GE(tip, 10) << "pixels of the sheared slab's tip in view";
    std::printf("%d pixels of the sheared slab's tip\n", tip);
}

// geometry_frag.glsl terminator_offset's lift h along the interpolated
// normal, for corners V, normals N, weights (u, v) and which side the
// normal faces (front: dot(v_term_dir, Ng) > 0), in double.
static double terminator_lift(const glm::dvec3 V[3], const glm::dvec3 N[3], double u, double v, bool front) {
    const double G01 = glm::dot(V[1] - V[0], N[0]), G02 = glm::dot(V[2] - V[0], N[0]);
    const double G10 = glm::dot(V[0] - V[1], N[1]), G12 = glm::dot(V[2] - V[1], N[1]);
    const double G20 = glm::dot(V[0] - V[2], N[2]), G21 = glm::dot(V[1] - V[2], N[2]);
    const double w = 1.0 - u - v;
    const double D0 = -(v * G01 + w * G02), D1 = -(u * G10 + w * G12), D2 = -(u * G20 + v * G21);
    const double a = G20 + G02, b = G21 + G12, c = -(G10 + G01);
    double h = a * u * (u - 1.0) + (a + b + c) * u * v + b * v * (v - 1.0);
    if (front) {
        const double h0 = std::max(D0 + std::max({G01, G02, 0.0}), 0.0);
        const double h1 = std::max(D1 + std::max({G10, G12, 0.0}), 0.0);
        const double h2 = std::max(D2 + std::max({G20, G21, 0.0}), 0.0);
        return std::max(std::min({h0, h1, h2}), h * 0.5);
    }
    const double h0 = std::max(-D0 + std::max({-G01, -G02, 0.0}), 0.0);
    const double h1 = std::max(-D1 + std::max({-G10, -G12, 0.0}), 0.0);
    const double h2 = std::max(-D2 + std::max({-G20, -G21, 0.0}), 0.0);
    return std::min(-std::min({h0, h1, h2}), h * 0.5);
}

// The shadow lookups' margin for the terminator (scene_store.h
// terminator_reach): every offset over every triangle, both sides, stays
// within it: a coarse smooth sphere, and triangles with random normals of
// random length.
TEST(Culling, TheTerminatorOffsetStaysWithinItsBound) {
    tools::MeshArrays ball = tools::make_uv_sphere(1.5f, 6, 4);
    tools::MeshArrays wild = tools::make_plane(1.0f, 3);
    unsigned seed = 7u;
    auto next = [&seed]() {
        seed = seed * 1664525u + 1013904223u;
        return double(seed >> 8) / double(1u << 24) * 2.0 - 1.0;
    };
    for (float& n : wild.normals) n = float(next());
    for (std::size_t i = 2; i < wild.positions.size(); i += 3) wild.positions[i] = float(0.3 * next());
    for (const tools::MeshArrays* m : {&ball, &wild}) {
        const double bound = terminator_reach(m->view());
        double worst = 0.0;
        for (std::size_t t = 0; t < m->indices.size() / 3; ++t) {
            glm::dvec3 V[3], N[3];
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t i = m->indices[3 * t + std::size_t(k)];
                V[k] = glm::dvec3(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]);
                const float* n = &m->normals[(3 * t + std::size_t(k)) * 3];
                N[k] = glm::dvec3(n[0], n[1], n[2]);
            }
            for (int iu = 0; iu <= 20; ++iu)
                for (int iv = 0; iu + iv <= 20; ++iv) {
                    const double u = iu / 20.0, v = iv / 20.0;
                    const glm::dvec3 n = u * N[0] + v * N[1] + (1.0 - u - v) * N[2];
                    for (bool front : {true, false})
                        worst = std::max(worst, std::abs(terminator_lift(V, N, u, v, front)) * glm::length(n));
                }
        }
        std::printf("largest terminator offset %.4f, bound %.4f\n", worst, bound);
        EXPECT_GT(worst, 0.0);
        EXPECT_LE(worst, bound);
    }
}

namespace {

// A carpet of small spheres touching each other and the floor under a 1
// degree sun, seen from above at a slant (`count` a side: 40 puts ~600 000
// triangles in the cascades, 3 a few hundred), lit by the sun alone.
FrameResult carpet_frame(int count, bool rays, const char* dense) {
    setenv("DEFERRED_DENSE_CASCADES", dense, 1);
    Renderer r;
    const std::uint32_t mat = deferred::testing::add_plane(r, grey(), 6.0f, 4);
    const tools::MeshArrays ball = tools::make_uv_sphere(0.1f, 16, 12);
    const std::uint32_t ball_mesh = r.add_mesh(ball.view());
    std::vector<double> at;
    for (int i = 0; i < count; ++i)
        for (int j = 0; j < count; ++j) {
            const Mat4d m = tools::translation(-0.2 * (count - 1) / 2.0 + 0.2 * i, -0.2 * (count - 1) / 2.0 + 0.2 * j, 0.1);
            at.insert(at.end(), m.begin(), m.end());
        }
    r.add_instances(ball_mesh, at.data(), at.size() / 16, nullptr, {mat});
    Light sun;
    sun.type = LightType::Sun;
    const double from[3] = {1.0, 0.6, 6.0}, to[3] = {0.0, 0.0, 0.0};
    sun.matrix = tools::look_at(from, to);
    sun.energy = 3.0f;
    sun.angle = float(1.0 * M_PI / 180.0);
    r.add_light(sun);
    deferred::testing::set_world_color(r, 0.0f, 0.0f, 0.0f);
    Camera cam;
    const double eye[3] = {0.0, -3.0, 3.0}, target[3] = {0.0, 0.0, 0.0};
    cam.matrix = tools::look_at(eye, target);
    cam.lens = 35.0f;
    RenderSettings s;
    s.width = 96;
    s.height = 64;
    s.samples = 16;
    s.shadow_resolution = 4096;
    s.shadow_rays = rays;
    FrameResult f = r.render(cam, s);
    unsetenv("DEFERRED_DENSE_CASCADES");
    return f;
}

double mean_combined(const FrameResult& f) {
    const PassImage* c = f.find(Pass::Combined);
    double sum = 0;
    for (std::size_t i = 0; i < c->pixels.size(); i += 4) sum += c->pixels[i] + c->pixels[i + 1] + c->pixels[i + 2];
    return sum / double(c->pixels.size() / 4);
}

}  // namespace

// Where a sun's casters are dense, its cascades take finer texels than the
// receivers need (ShadowModule::fit, kDenseCascades): the maps' moving grid
// blurs each lookup over a texel, which darkens the lit parts of the
// spheres beside their contacts. Against shadow rays (the exact
// visibility of the same light points), the carpet is darker with the
// receivers' need alone and closer with the finer texels; a few spheres
// keep the need's resolution.
TEST(SunCascades, DenseCastersTakeFinerTexels) {
    struct EnvGuard {
        ~EnvGuard() { unsetenv("DEFERRED_DENSE_CASCADES"); }
    } guard;
    const FrameResult exact = carpet_frame(40, true, "on");
    const FrameResult need = carpet_frame(40, false, "off");
    const FrameResult dense = carpet_frame(40, false, "on");
    ASSERT_EQ(need.timings.shadow_resolutions.size(), 1u);
    ASSERT_EQ(dense.timings.shadow_resolutions.size(), 1u);
    const int r_need = need.timings.shadow_resolutions[0], r_dense = dense.timings.shadow_resolutions[0];
    const double m_exact = mean_combined(exact), m_need = mean_combined(need), m_dense = mean_combined(dense);
    std::printf("carpet: rays %.4f; maps %d texels %.4f (%.4f of it), %d texels %.4f (%.4f)\n", m_exact, r_need, m_need,
                m_need / m_exact, r_dense, m_dense, m_dense / m_exact);
    EXPECT_GE(r_dense, int(1.5 * r_need));  // the need is rounded up to 32 texels, its double from the need itself
    EXPECT_LE(r_dense, int(ShadowModule::kDenseCascades * r_need) + 32);
    EXPECT_LT(m_need, m_exact);
    EXPECT_LT(std::abs(m_dense - m_exact), 0.7 * std::abs(m_need - m_exact));
    // Few casters: the receivers' need.
    const FrameResult few = carpet_frame(3, false, "on");
    const FrameResult few_need = carpet_frame(3, false, "off");
    EXPECT_EQ(few.timings.shadow_resolutions, few_need.timings.shadow_resolutions);
}
