// Node materials through the native API: graph validation, code generation
// and the geometry pass (program per structure, slots, attributes, images),
// on the real GL. The per-node formulas are measured against Cycles by the
// Blender probe test (tests/blender/test_node_probes.py).
#include "material_codegen.h"
#include "test_helpers.h"

#include <deferred/renderer.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace deferred::testing {
namespace {

GraphArg const_arg(SocketType t, int offset) { return GraphArg::constant(t, offset); }
GraphArg shading_arg(const std::string& name) { return GraphArg::shading(name); }
GraphArg link_arg(SocketType type, int node, int output, SocketType from) {
    return GraphArg::link(type, node, output, from);
}

// Emission shader of `color` (an argument) and strength 1 (constant 0).
MaterialGraph emission_graph(const GraphArg& color) {
    MaterialGraph g;
    g.constants = {1.0f};
    g.nodes.push_back({"node_emission", {color, const_arg(SocketType::Float, 0)}, {SocketType::Closure}});
    g.surface_node = 0;
    return g;
}

MaterialGraph constant_emission_graph(float r, float gr, float b) {
    MaterialGraph g = emission_graph(const_arg(SocketType::Color, 1));
    g.constants = {1.0f, r, gr, b};
    return g;
}

RenderSettings small(int w = 16, int h = 16) {
    RenderSettings s;
    s.width = w;
    s.height = h;
    s.samples = 1;
    return s;
}

void expect_invalid(const MaterialGraph& g, const std::string& fragment) {
    try {
        validate_material_graph(g);
        ADD_FAILURE() << "accepted a graph that should fail with '" << fragment << "'";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
}

TEST(MaterialGraphValidation, NamesTheProblem) {
    MaterialGraph ok = constant_emission_graph(1, 0, 0);
    EXPECT_NO_THROW(validate_material_graph(ok));

    MaterialGraph later = ok;
    later.nodes[0].args[0] = link_arg(SocketType::Color, 0, 0, SocketType::Closure);
    expect_invalid(later, "not an earlier node");

    MaterialGraph name = ok;
    name.nodes[0].func = "node_x(); discard; //";
    expect_invalid(name, "identifier");

    MaterialGraph offset = ok;
    offset.nodes[0].args[0] = const_arg(SocketType::Color, 2);  // needs 3 floats from 2, only 4 exist
    expect_invalid(offset, "outside the constants");

    MaterialGraph nan = ok;
    nan.constants[1] = std::nanf("");
    expect_invalid(nan, "NaN");

    MaterialGraph shading = emission_graph(shading_arg("gl_FragCoord"));
    expect_invalid(shading, "unknown shading value");

    MaterialGraph closure_to_value = ok;
    closure_to_value.nodes.push_back({"node_emission", {link_arg(SocketType::Color, 0, 0, SocketType::Closure),
                                                        const_arg(SocketType::Float, 0)},
                                      {SocketType::Closure}});
    expect_invalid(closure_to_value, "closures connect only to closures");

    MaterialGraph surface = ok;
    surface.surface_node = 3;
    expect_invalid(surface, "surface node");
}

TEST(MaterialGraphCodegen, DependsOnStructureNotValues) {
    const std::string a = material_graph_glsl(constant_emission_graph(1, 0, 0));
    const std::string b = material_graph_glsl(constant_emission_graph(0, 0.5f, 1));
    EXPECT_EQ(a, b);  // values live in the constants buffer
    EXPECT_NE(a.find("node_emission(mat_const3(1), mat_const(0), n0_0)"), std::string::npos) << a;
    EXPECT_NE(a, material_graph_glsl(emission_graph(shading_arg("generated"))));
}

class MaterialGraphRender : public ::testing::Test {
protected:
    Renderer r;
    const Camera cam = top_down_ortho(5.0, 2.0f);  // the plane of half size 1 fills the frame

    std::uint32_t plane_with(std::uint32_t material) {
        tools::MeshArrays plane = tools::make_plane(1.0f, 1);
        const std::uint32_t mesh = r.add_mesh(plane.view());
        r.add_instances(mesh, identity_matrix().data(), 1, nullptr, {material});
        return mesh;
    }
};

TEST_F(MaterialGraphRender, GeneratedCoordinatesReachEmission) {
    set_world_color(r, 0, 0, 0);
    plane_with(r.add_graph_material(Material{}, emission_graph(shading_arg("generated"))));
    // The graph in the fragment stage, and resolved in compute from the
    // visibility buffer (visibility_module.h).
    for (const bool visibility : {false, true}) {
        RenderSettings s = small();
        s.visibility_buffer = visibility;
        FrameResult f = r.render(cam, s);
        EXPECT_EQ(f.timings.visibility_buffer, visibility);
        const PassImage& img = *f.find(Pass::Combined);
        double worst = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                // Pixel centre at P = (-1 + (x + 0.5) / 8, ...); texture space of the plane:
                // location 0, size 1, so generated = (P + 1) / 2 (z = 0.5).
                const glm::dvec3 want((x + 0.5) / img.width, (y + 0.5) / img.height, 0.5);
                worst = std::max(worst, glm::length(pixel3(img, x, y) - want));
            }
        EXPECT_LT(worst, 1e-5) << (visibility ? "visibility buffer" : "raster");
    }
}

TEST_F(MaterialGraphRender, ConstantPrincipledGraphEqualsTheConstantMaterial) {
    Material m;
    m.base_color = {0.3f, 0.5f, 0.7f};
    m.metallic = 0.2f;
    m.roughness = 0.4f;
    m.sheen = 0.3f;
    Light sun;
    sun.type = LightType::Sun;
    sun.matrix = tools::look_at(std::array<double, 3>{1, 2, 3}.data(), std::array<double, 3>{0, 0, 0}.data());
    sun.energy = 3.0f;
    r.add_light(sun);
    set_world_color(r, 0.1f, 0.1f, 0.1f);
    const std::uint32_t constant = r.add_material(m);

    // Principled with every input a constant, in node_bsdf_principled's order.
    MaterialGraph g;
    g.constants = {0.3f, 0.5f, 0.7f, m.metallic, m.specular, m.specular_tint, m.roughness, m.sheen, m.sheen_tint,
                   m.clearcoat, m.clearcoat_roughness, 0, 0, 0, 1.0f, 1.0f};
    std::vector<GraphArg> args = {const_arg(SocketType::Color, 0)};
    for (int k = 3; k <= 10; ++k) args.push_back(const_arg(SocketType::Float, k));
    args.push_back(const_arg(SocketType::Color, 11));
    args.push_back(const_arg(SocketType::Float, 14));
    args.push_back(const_arg(SocketType::Float, 15));
    args.push_back(shading_arg("N"));
    g.nodes.push_back({"node_bsdf_principled", args, {SocketType::Closure}});
    g.surface_node = 0;
    tools::MeshArrays plane = tools::make_plane(1.0f, 1);
    const std::uint32_t mesh = r.add_mesh(plane.view());
    r.add_instances(mesh, identity_matrix().data(), 1, nullptr, {constant});
    FrameResult a = r.render(cam, small());
    r.clear_scene();
    r.add_light(sun);
    set_world_color(r, 0.1f, 0.1f, 0.1f);
    plane_with(r.add_graph_material(Material{}, g));
    FrameResult b = r.render(cam, small());
    const PassImage& ia = *a.find(Pass::Combined);
    const PassImage& ib = *b.find(Pass::Combined);
    double worst = 0, level = 0;
    for (std::size_t i = 0; i < ia.pixels.size(); ++i) {
        worst = std::max(worst, double(std::abs(ia.pixels[i] - ib.pixels[i])));
        level = std::max(level, double(ia.pixels[i]));
    }
    EXPECT_GT(level, 0.05);
    EXPECT_LT(worst, 1e-5 * std::max(1.0, level));
}

TEST_F(MaterialGraphRender, MaterialsOfOneStructureShareOneProgramAndValuesNeverRecompile) {
    set_world_color(r, 0, 0, 0);
    const std::uint32_t red = r.add_graph_material(Material{}, constant_emission_graph(1, 0, 0));
    const std::uint32_t blue = r.add_graph_material(Material{}, constant_emission_graph(0, 0, 1));
    tools::MeshArrays plane = tools::make_plane(0.5f, 1);
    const std::uint32_t mesh = r.add_mesh(plane.view());
    const Mat4d left = tools::translation(-0.5, 0, 0), right = tools::translation(0.5, 0, 0);
    r.add_instances(mesh, left.data(), 1, nullptr, {red});
    r.add_instances(mesh, right.data(), 1, nullptr, {blue});
    FrameResult first = r.render(cam, small());
    EXPECT_EQ(first.timings.material_programs, 1u);
    const PassImage& img = *first.find(Pass::Combined);
    EXPECT_NEAR(pixel3(img, 2, 8).x, 1.0, 1e-6);
    EXPECT_NEAR(pixel3(img, 13, 8).z, 1.0, 1e-6);
    EXPECT_NEAR(pixel3(img, 13, 8).x, 0.0, 1e-6);

    // New values, same structure: the program is reused.
    r.clear_scene();
    set_world_color(r, 0, 0, 0);
    plane_with(r.add_graph_material(Material{}, constant_emission_graph(0.25f, 0.5f, 0.75f)));
    FrameResult second = r.render(cam, small());
    EXPECT_EQ(second.timings.programs_compiled, 0u);
    EXPECT_NEAR(pixel3(*second.find(Pass::Combined), 8, 8).y, 0.5, 1e-6);
}

TEST_F(MaterialGraphRender, SlotsOfOneMeshDrawWithTheirOwnMaterials) {
    // A 4x4-quad plane whose triangles alternate between two slots, in an
    // order that is not sorted: slot 0 a constant material, slot 1 a graph.
    set_world_color(r, 0, 0, 0);
    tools::MeshArrays plane = tools::make_plane(1.0f, 4);
    std::vector<std::int32_t> slots_of(plane.indices.size() / 3);
    for (std::size_t t = 0; t < slots_of.size(); ++t) slots_of[t] = std::int32_t((t / 2 + t / 8) % 2);
    MeshData data = plane.view();
    data.material_indices = slots_of.data();
    Material red;
    red.base_color = {0, 0, 0};
    red.specular = 0;
    red.emission = {1, 0, 0};
    const std::uint32_t constant = r.add_material(red);
    const std::uint32_t graph = r.add_graph_material(Material{}, constant_emission_graph(0, 1, 0));
    const std::uint32_t mesh = r.add_mesh(data);
    r.add_instances(mesh, identity_matrix().data(), 1, nullptr, {constant, graph});
    const PassImage img = *r.render(cam, small()).find(Pass::Combined);
    // Quad (i, j) of the 4x4 grid covers 4x4 pixels; its slot is (i + j) % 2.
    int wrong = 0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            const int slot = (x / 4 + y / 4) % 2;
            const glm::dvec3 want = slot == 0 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
            if (glm::length(pixel3(img, x, y) - want) > 1e-6) ++wrong;
        }
    EXPECT_EQ(wrong, 0);
}

TEST_F(MaterialGraphRender, AttributesAreReadByNameAndMissingOnesAreZero) {
    set_world_color(r, 0, 0, 0);
    tools::MeshArrays plane = tools::make_plane(1.0f, 1);
    const std::size_t corners = plane.indices.size();
    std::vector<float> colors(corners * 4);
    for (std::size_t c = 0; c < corners; ++c) {
        colors[c * 4] = 0.25f;
        colors[c * 4 + 1] = 0.5f;
        colors[c * 4 + 2] = 0.75f;
        colors[c * 4 + 3] = 1.0f;
    }
    MeshData data = plane.view();
    data.attributes.push_back({"color:Col", 4, colors.data()});
    const std::uint32_t mesh = r.add_mesh(data);

    // node_vertex_color(attr0) -> Emission colour.
    auto graph_reading = [](const std::string& name) {
        MaterialGraph g;
        g.constants = {1.0f};
        g.attributes = {name};
        g.nodes.push_back({"node_vertex_color", {shading_arg("attr0")}, {SocketType::Color, SocketType::Float}});
        g.nodes.push_back({"node_emission", {link_arg(SocketType::Color, 0, 0, SocketType::Color),
                                             const_arg(SocketType::Float, 0)},
                           {SocketType::Closure}});
        g.surface_node = 1;
        return g;
    };
    const std::uint32_t present = r.add_graph_material(Material{}, graph_reading("color:Col"));
    const std::uint32_t missing = r.add_graph_material(Material{}, graph_reading("color:Other"));
    const Mat4d left = tools::scale_translation(0.5, -0.5, 0, 0), right = tools::scale_translation(0.5, 0.5, 0, 0);
    r.add_instances(mesh, left.data(), 1, nullptr, {present});
    r.add_instances(mesh, right.data(), 1, nullptr, {missing});
    const PassImage img = *r.render(cam, small()).find(Pass::Combined);
    EXPECT_LT(glm::length(pixel3(img, 3, 8) - glm::dvec3(0.25, 0.5, 0.75)), 1e-6);
    EXPECT_LT(glm::length(pixel3(img, 12, 8)), 1e-6);

    std::vector<float> nan_colors = colors;
    nan_colors[5] = std::nanf("");
    MeshData bad = plane.view();
    bad.attributes.push_back({"color:Col", 4, nan_colors.data()});
    EXPECT_THROW(r.add_mesh(bad), InvalidInput);
}

TEST_F(MaterialGraphRender, AGraphThatDoesNotCompileFallsBackWithAWarning) {
    set_world_color(r, 0, 0, 0);
    MaterialGraph g = constant_emission_graph(1, 1, 1);
    g.nodes[0].func = "node_not_in_the_library";
    plane_with(r.add_graph_material(Material{}, g));
    // Both G-buffer paths: the visibility buffer compiles the graph's
    // resolve instead, and warns the same way.
    for (const bool visibility : {false, true}) {
        RenderSettings s = small();
        s.visibility_buffer = visibility;
        FrameResult f;
        ASSERT_NO_THROW(f = r.render(cam, s));
        EXPECT_EQ(f.timings.visibility_buffer, visibility);
        ASSERT_EQ(f.warnings.size(), 1u);
        EXPECT_NE(f.warnings[0].find("did not compile"), std::string::npos);
        // The default surface emits nothing: black under a black world.
        EXPECT_LT(glm::length(pixel3(*f.find(Pass::Combined), 8, 8)), 1e-6);
    }
}

TEST_F(MaterialGraphRender, ImagesAreUploadedAsGivenAndRefusedWhenBroken) {
    const std::uint8_t bytes[2 * 2 * 4] = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
    ImageData image;
    image.width = 2;
    image.height = 2;
    image.bytes = bytes;
    EXPECT_EQ(r.add_image(image), 0u);
    const float nan_texels[4] = {std::nanf(""), 0, 0, 1};
    ImageData bad;
    bad.width = 1;
    bad.height = 1;
    bad.floats = nan_texels;
    EXPECT_THROW(r.add_image(bad), InvalidInput);
    ImageData empty;
    EXPECT_THROW(r.add_image(empty), InvalidInput);
    MaterialGraph g = constant_emission_graph(1, 1, 1);
    g.images = {7};
    EXPECT_THROW(r.add_graph_material(Material{}, g), InvalidInput);
}

// Emission of a 1x1 image read through image slot 0 (Closest, Extend, flat, no flags).
MaterialGraph image_emission_graph(std::uint32_t image_id) {
    auto int_arg = [](int v) { return GraphArg::literal(v); };
    const GraphArg image = GraphArg::image(0);
    MaterialGraph g;
    g.constants = {1.0f};
    g.nodes.push_back({"node_tex_image",
                       {int_arg(1), int_arg(1), int_arg(0), int_arg(0), int_arg(0), int_arg(0), image,
                        shading_arg("generated")},
                       {SocketType::Color, SocketType::Float}});
    g.nodes.push_back({"node_emission",
                       {link_arg(SocketType::Color, 0, 0, SocketType::Color), const_arg(SocketType::Float, 0)},
                       {SocketType::Closure}});
    g.surface_node = 1;
    g.images = {image_id};
    return g;
}

TEST_F(MaterialGraphRender, TransparencyCoversAsAlphaSays) {
    // Stochastic transparency: an emitting plane of coverage 0.25 over a
    // black world averages 0.25 of its emission, as a node material (Mix of
    // Emission and a white Transparent BSDF at 0.75; MATERIAL_ALPHA) and as
    // a constant material of alpha 0.25 (SCENE_ALPHA). Per pixel, 256
    // Bernoulli(0.25) samples: the image mean's standard deviation is 0.0017.
    // Both G-buffer paths (the visibility buffer tests alpha in its own
    // raster programs, visibility_module.h).
    for (const bool visibility : {false, true}) {
    r.clear_scene();
    set_world_color(r, 0, 0, 0);
    MaterialGraph g;
    g.constants = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 0.75f};
    g.nodes.push_back({"node_emission", {const_arg(SocketType::Color, 1), const_arg(SocketType::Float, 0)},
                       {SocketType::Closure}});
    g.nodes.push_back({"node_bsdf_transparent", {const_arg(SocketType::Color, 4)}, {SocketType::Closure}});
    g.nodes.push_back({"node_mix_shader",
                       {const_arg(SocketType::Float, 7), link_arg(SocketType::Closure, 0, 0, SocketType::Closure),
                        link_arg(SocketType::Closure, 1, 0, SocketType::Closure)},
                       {SocketType::Closure}});
    g.surface_node = 2;
    g.alpha = true;
    plane_with(r.add_graph_material(Material{}, g));
    RenderSettings s = small();
    s.samples = 256;
    s.filter_width = 0.01f;  // every sample inside the plane, which fills the frame
    s.visibility_buffer = visibility;
    auto mean_of = [](const FrameResult& f) {
        const PassImage& img = *f.find(Pass::Combined);
        double sum = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) sum += pixel3(img, x, y).y;
        return sum / (img.width * img.height);
    };
    const double graph_mean = mean_of(r.render(cam, s));

    r.clear_scene();
    set_world_color(r, 0, 0, 0);
    Material m;
    m.base_color = {0, 0, 0};
    m.emission = {1, 1, 1};
    m.alpha = 0.25f;
    plane_with(r.add_material(m));
    const double constant_mean = mean_of(r.render(cam, s));
    std::printf("coverage 0.25 (%s): node material %.4f, constant material %.4f\n",
                visibility ? "visibility buffer" : "raster", graph_mean, constant_mean);
    EXPECT_NEAR(graph_mean, 0.25, 0.006);
    EXPECT_NEAR(constant_mean, 0.25, 0.006);
    }
}

TEST_F(MaterialGraphRender, KeyedImagesOutliveTheSceneThatUsesThem) {
    // A persistent renderer (the add-on's Persistent Data) keeps an image
    // with a key across clear_scene() while each scene uses it: the next
    // scene finds it by key and uploads nothing. Images no scene used since
    // the previous clear, and images without a key, are released.
    const std::uint8_t red[4] = {255, 0, 0, 255}, green[4] = {0, 255, 0, 255}, blue[4] = {0, 0, 255, 255};
    auto one_texel = [](const std::uint8_t* texel) {
        ImageData im;
        im.width = im.height = 1;
        im.bytes = texel;
        return im;
    };
    set_world_color(r, 0, 0, 0);
    const std::uint32_t a = r.add_image(one_texel(red), "file:a");
    r.add_image(one_texel(green), "file:b");
    const std::uint32_t unkeyed = r.add_image(one_texel(blue));
    plane_with(r.add_graph_material(Material{}, image_emission_graph(a)));
    FrameResult first = r.render(cam, small());
    EXPECT_EQ(first.timings.images_uploaded, 3u);
    EXPECT_EQ(first.timings.images_reused, 0u);

    r.clear_scene();
    set_world_color(r, 0, 0, 0);
    EXPECT_EQ(r.find_image("file:a"), std::int64_t(a));
    EXPECT_EQ(r.find_image("file:c"), -1);
    EXPECT_EQ(r.find_image(""), -1);
    MaterialGraph stale = image_emission_graph(unkeyed);  // released by the clear
    EXPECT_THROW(r.add_graph_material(Material{}, stale), InvalidInput);
    plane_with(r.add_graph_material(Material{}, image_emission_graph(a)));
    FrameResult second = r.render(cam, small());
    EXPECT_EQ(second.timings.images_uploaded, 0u);
    EXPECT_EQ(second.timings.images_reused, 1u);
    EXPECT_EQ(second.timings.programs_compiled, 0u);
    EXPECT_EQ(second.timings.programs_loaded, 0u);
    const glm::dvec3 c = pixel3(*second.find(Pass::Combined), 8, 8);
    EXPECT_NEAR(c.x, 1.0, 1e-6);
    EXPECT_NEAR(c.y, 0.0, 1e-6);

    // "b" was not used by the second scene: gone after the next clear; "a"
    // stays, also through a second clear with nothing in between.
    r.clear_scene();
    r.clear_scene();
    EXPECT_EQ(r.find_image("file:b"), -1);
    EXPECT_EQ(r.find_image("file:a"), std::int64_t(a));
}

TEST(MaterialGraphDiskCache, ASecondRendererLoadsInsteadOfCompiling) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                      ("deferred_cache_test_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    setenv("DEFERRED_SHADER_CACHE", dir.c_str(), 1);
    auto render_once = [](FrameTimings& t) {
        Renderer r;
        set_world_color(r, 0, 0, 0);
        tools::MeshArrays plane = tools::make_plane(1.0f, 1);
        const std::uint32_t mesh = r.add_mesh(plane.view());
        r.add_instances(mesh, identity_matrix().data(), 1, nullptr,
                        {r.add_graph_material(Material{}, constant_emission_graph(1, 0.5f, 0))});
        t = r.render(top_down_ortho(5.0, 2.0f), small()).timings;
    };
    FrameTimings cold, warm;
    render_once(cold);
    render_once(warm);
    unsetenv("DEFERRED_SHADER_CACHE");
    const bool stored = std::filesystem::exists(dir) && !std::filesystem::is_empty(dir);
    std::filesystem::remove_all(dir);
    if (!stored) GTEST_SKIP() << "this driver offers no program binary formats";
    EXPECT_GT(cold.programs_compiled, 0u);
    EXPECT_EQ(warm.programs_compiled, 0u);
    EXPECT_EQ(warm.programs_loaded, cold.programs_compiled);
    std::printf("programs: cold %zu compiled in %.0f ms; warm %zu loaded in %.0f ms\n", cold.programs_compiled,
                cold.compile_ms, warm.programs_loaded, warm.load_ms);
}

// A sphere of `base` (through `graph` where given) under a point light and
// a grey `world`, seen from above at 32x32, 2 samples; `also` (where given)
// is added as a constant material that nothing uses.
FrameResult lit_sphere(const Material& base, const MaterialGraph* graph, float world, const Material* also = nullptr) {
    const tools::MeshArrays sphere = tools::make_uv_sphere(0.8f, 32, 16);
    Renderer r;
    const std::uint32_t mat = graph ? r.add_graph_material(base, *graph) : r.add_material(base);
    if (also) r.add_material(*also);
    const std::uint32_t mesh = r.add_mesh(sphere.view());
    r.add_instances(mesh, identity_matrix().data(), 1, nullptr, {mat});
    Light l;
    l.type = LightType::Point;
    l.matrix = tools::translation(1.5, -1.0, 3.0);
    l.energy = 200.0f;
    r.add_light(l);
    set_world_color(r, world, world, world);
    RenderSettings s = small(32, 32);
    s.samples = 2;
    return r.render(top_down_ortho(5.0, 1.0f), s);
}

// The programs leave out the closure models no surface of the scene has
// (renderer.cpp plan_frame: CLOSURES_NO_OREN_NAYAR, CLOSURES_NO_BECKMANN),
// and keep each one a surface has, from a constant material or a node
// graph: a Glossy BSDF's Beckmann lobe shades otherwise than its GGX one, a
// Diffuse BSDF's Oren-Nayar lobe (sigma 0.9) otherwise than sigma 0, on a
// sphere under a light. Were a model left out, the two would be the same.
TEST(ClosureModels, StayWhereASurfaceHasThem) {
    auto render_with = [](const Material& base, const MaterialGraph* graph) {
        return lit_sphere(base, graph, 0.0f).find(Pass::Combined)->pixels;
    };
    auto largest_difference = [](const std::vector<float>& a, const std::vector<float>& b) {
        float d = 0.0f;
        for (std::size_t i = 0; i < a.size(); ++i) d = std::max(d, std::abs(a[i] - b[i]));
        return d;
    };
    Material glossy;
    glossy.base_color = {0.8f, 0.8f, 0.8f};
    glossy.roughness = 0.6f;
    glossy.metallic = 1.0f;
    glossy.glossy_model = 1;
    Material beckmann = glossy;
    beckmann.glossy_model = 2;
    Material lambert;
    lambert.base_color = {0.8f, 0.8f, 0.8f};
    lambert.specular = 0.0f;
    lambert.diffuse_roughness = 0.0f;
    Material oren_nayar = lambert;
    oren_nayar.diffuse_roughness = 0.9f;
    const float constant_glossy = largest_difference(render_with(glossy, nullptr), render_with(beckmann, nullptr));
    const float constant_diffuse = largest_difference(render_with(lambert, nullptr), render_with(oren_nayar, nullptr));
    // The same through node graphs: Glossy BSDF (model, colour, roughness,
    // normal) and Diffuse BSDF (colour, roughness, normal).
    auto glossy_graph = [](int model) {
        MaterialGraph g;
        g.constants = {0.8f, 0.8f, 0.8f, 0.6f};
        g.nodes.push_back({"node_bsdf_glossy",
                           {GraphArg::literal(model), const_arg(SocketType::Color, 0), const_arg(SocketType::Float, 3),
                            shading_arg("N")},
                           {SocketType::Closure}});
        g.surface_node = 0;
        return g;
    };
    auto diffuse_graph = [](float sigma) {
        MaterialGraph g;
        g.constants = {0.8f, 0.8f, 0.8f, sigma};
        g.nodes.push_back({"node_bsdf_diffuse",
                           {const_arg(SocketType::Color, 0), const_arg(SocketType::Float, 3), shading_arg("N")},
                           {SocketType::Closure}});
        g.surface_node = 0;
        return g;
    };
    const MaterialGraph ggx_g = glossy_graph(1), beckmann_g = glossy_graph(2), lambert_g = diffuse_graph(0.0f),
                        oren_nayar_g = diffuse_graph(0.9f);
    const float graph_glossy = largest_difference(render_with(Material{}, &ggx_g), render_with(Material{}, &beckmann_g));
    const float graph_diffuse =
        largest_difference(render_with(Material{}, &lambert_g), render_with(Material{}, &oren_nayar_g));
    std::printf("largest differences: constant Beckmann/GGX %.4f, Oren-Nayar/Lambert %.4f; graphs %.4f, %.4f\n",
                constant_glossy, constant_diffuse, graph_glossy, graph_diffuse);
    EXPECT_GT(constant_glossy, 0.01f);
    EXPECT_GT(constant_diffuse, 0.01f);
    EXPECT_GT(graph_glossy, 0.01f);
    EXPECT_GT(graph_diffuse, 0.01f);
}

// A Principled BSDF node whose Sheen and Clearcoat are constants of 0 (the
// usual node material) needs no params1 target (MaterialModule::
// uses_params1): the G-buffer is 8 bytes a pixel smaller and the image the
// same as with the target; a clearcoat of 0.8 takes it, and shows.
TEST(ClosureModels, PrincipledNodesWithoutSheenOrClearcoatNeedNoParams1) {
    auto principled = [](float clearcoat) {
        MaterialGraph g;
        // base colour, metallic, specular, specular tint, roughness, sheen,
        // sheen tint, clearcoat, clearcoat roughness, emission, its
        // strength, alpha
        g.constants = {0.6f, 0.3f, 0.2f, 0.0f, 0.5f, 0.0f, 0.4f, 0.0f, 0.5f, clearcoat, 0.05f, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f};
        auto f = [](int k) { return const_arg(SocketType::Float, k); };
        g.nodes.push_back({"node_bsdf_principled",
                           {const_arg(SocketType::Color, 0), f(3), f(4), f(5), f(6), f(7), f(8), f(9), f(10),
                            const_arg(SocketType::Color, 11), f(14), f(15), shading_arg("N")},
                           {SocketType::Closure}});
        g.surface_node = 0;
        return g;
    };
    // `also`: an unseen constant material with clearcoat, params1 for the scene.
    auto render_with = [](const MaterialGraph& graph, const Material* also) {
        return lit_sphere(Material{}, &graph, 0.1f, also);
    };
    Material coated;
    coated.clearcoat = 1.0f;
    const FrameResult plain = render_with(principled(0.0f), nullptr);
    const FrameResult with_target = render_with(principled(0.0f), &coated);
    const FrameResult clear = render_with(principled(0.8f), nullptr);
    EXPECT_EQ(with_target.timings.gbuffer_bytes, plain.timings.gbuffer_bytes + 8u * 32u * 32u);
    EXPECT_EQ(clear.timings.gbuffer_bytes, with_target.timings.gbuffer_bytes);
    const std::vector<float>& a = plain.find(Pass::Combined)->pixels;
    const std::vector<float>& b = with_target.find(Pass::Combined)->pixels;
    const std::vector<float>& c = clear.find(Pass::Combined)->pixels;
    float same = 0.0f, coat = 0.0f;
    for (std::size_t i = 0; i < a.size(); ++i) {
        same = std::max(same, std::abs(a[i] - b[i]));
        coat = std::max(coat, std::abs(a[i] - c[i]));
    }
    std::printf("without params1 against with it: %.2e; clearcoat 0.8 against none: %.4f\n", same, coat);
    EXPECT_LT(same, 1e-5f);
    EXPECT_GT(coat, 0.01f);
}

}  // namespace
}  // namespace deferred::testing
