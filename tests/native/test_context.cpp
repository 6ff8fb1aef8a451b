// Headless context: creation, device selection errors, repeated create/destroy,
// shader error messages.
#include "gl_test_context.h"
#include "shader_sources.h"

#include "builtin_scenes.h"

#include <deferred/renderer.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <sstream>
#include <vector>

using namespace deferred;

TEST(Context, CreatesGL45CoreAndReportsIt) {
    Renderer r;
    const GLInfo& info = r.gl_info();
    EXPECT_FALSE(info.renderer.empty());
    EXPECT_NE(info.version.find("4."), std::string::npos) << info.version;
    EXPECT_FALSE(info.display.empty());
    std::printf("GL: %s | %s | %s via %s\n", info.vendor.c_str(), info.renderer.c_str(), info.version.c_str(),
                info.display.c_str());
}

TEST(Context, MissingDeviceIndexIsAClearError) {
    ContextOptions o;
    o.device_index = 999;
    try {
        Renderer r(o);
        FAIL() << "device 999 should not exist";
    } catch (const Error& e) {
        const std::string msg = e.what();
        // Either path names the index asked for: EGL's own device list
        // ("EGL device 999 requested, but only N ...") or, with NVIDIA's
        // driver, the GPUs visible to the process ("Device 999 requested,
        // but 1 GPU(s) are visible ...", device_selection.cpp).
        EXPECT_NE(msg.find("evice 999 requested, but "), std::string::npos) << msg;
    }
    // The library still works afterwards.
    Renderer ok;
    EXPECT_FALSE(ok.gl_info().renderer.empty());
}

TEST(Context, RenderersCanBeCreatedAndDestroyedRepeatedly) {
    for (int i = 0; i < 5; ++i) {
        Renderer r;
        tools::MeshArrays plane = tools::make_plane(1.0f);
        const std::uint32_t mesh = r.add_mesh(plane.view());
        const std::uint32_t mat = r.add_material(Material{});
        Mat4d I = identity_matrix();
        r.add_instances(mesh, I.data(), 1, nullptr, {mat});
        Camera cam;
        cam.matrix = tools::translation(0, 0, 3);
        RenderSettings s;
        s.width = 16;
        s.height = 16;
        FrameResult f = r.render(cam, s);
        ASSERT_EQ(f.passes.size(), 1u);
    }
}

class ShaderErrors : public deferred::testing::GLTest {};

TEST_F(ShaderErrors, CompileErrorNamesFileAndLine) {
    ShaderVariant v;
    v.defines.push_back("PASS_ID 99");  // hits the #error in passes_comp.glsl
    try {
        shaders().compute_program("passes_comp.glsl", v);
        FAIL() << "expected a compile error";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("passes_comp.glsl:"), std::string::npos) << msg;
        EXPECT_NE(msg.find("unknown PASS_ID"), std::string::npos) << msg;
    }
}

TEST_F(ShaderErrors, ErrorsAfterASkippedIncludeNameTheirFileAndLine) {
    // light_lib.glsl includes shadow_lib.glsl under #ifdef HAS_SHADOWS. With
    // SHADOW_RAYS and no HAS_SHADOWS (a variant the renderer never makes)
    // its calls to shadow_ray fail: the log must name light_lib.glsl at
    // those calls' lines, though the skipped group took the include's #line
    // directives with it.
    std::string text;
    for (const ShaderSource& src : embedded_shader_sources())
        if (std::string(src.name) == "light_lib.glsl") text = src.text;
    ASSERT_FALSE(text.empty());
    std::vector<int> calls;
    int lines = 0;
    {
        std::istringstream in(text);
        std::string line;
        while (std::getline(in, line)) {
            ++lines;
            if (line.find("shadow_ray(s, P") != std::string::npos) calls.push_back(lines);
        }
    }
    ASSERT_FALSE(calls.empty());
    ShaderVariant v;
    v.defines = {"HAS_POINT_LIGHTS", "HAS_AREA_LIGHTS", "HAS_SUN_LIGHTS", "SHADOW_RAYS"};
    try {
        shaders().compute_program("lighting_comp.glsl", v);
        FAIL() << "expected a compile error";
    } catch (const Error& e) {
        const std::string msg = e.what();
        int named = 0, beyond = 0;
        for (std::size_t at = msg.find("light_lib.glsl:"); at != std::string::npos;
             at = msg.find("light_lib.glsl:", at + 1)) {
            const int line = std::atoi(msg.c_str() + at + 15);
            if (std::find(calls.begin(), calls.end(), line) != calls.end()) ++named;
            if (line > lines) ++beyond;
        }
        EXPECT_GT(named, 0) << msg;
        EXPECT_EQ(beyond, 0) << msg;
    }
}

TEST_F(ShaderErrors, PrefetchedProgramsAreTheRequestedOnesAndReportTheirOwnErrors) {
    // A batch prefetched (compiling on the driver's threads where it has
    // them), then requested: the good program is the one a request returns
    // again, the failing one throws its own error at its request, as without
    // a prefetch, and again at a second request.
    ShaderLibrary library;
    ShaderVariant bad, good;
    bad.defines.push_back("PASS_ID 99");  // hits the #error in passes_comp.glsl
    good.defines.push_back("PASS_ID 1");
    library.prefetch_compute("passes_comp.glsl", bad);  // never throws
    library.prefetch_compute("passes_comp.glsl", good);
    const GLuint program = library.compute_program("passes_comp.glsl", good);
    EXPECT_NE(program, 0u);
    EXPECT_EQ(library.compute_program("passes_comp.glsl", good), program);
    for (int attempt = 0; attempt < 2; ++attempt) {
        try {
            library.compute_program("passes_comp.glsl", bad);
            ADD_FAILURE() << "expected a compile error, attempt " << attempt;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("unknown PASS_ID"), std::string::npos) << e.what();
        }
    }
    check_gl("prefetched programs");
    // The user's own setting, kept and put back.
    const char* user = std::getenv("DEFERRED_PARALLEL_COMPILE");
    const std::string user_value = user ? user : "";
    // Mesa's llvmpipe and NVIDIA's driver both offer the extension.
    if (!user) {
        EXPECT_EQ(library.parallel_compile(), epoxy_has_gl_extension("GL_KHR_parallel_shader_compile") ||
                                                  epoxy_has_gl_extension("GL_ARB_parallel_shader_compile"));
    }
    // DEFERRED_PARALLEL_COMPILE=0: no compiler threads asked for, prefetch a no-op.
    setenv("DEFERRED_PARALLEL_COMPILE", "0", 1);
    ShaderLibrary serial;
    EXPECT_FALSE(serial.parallel_compile());
    if (user) setenv("DEFERRED_PARALLEL_COMPILE", user_value.c_str(), 1);
    else unsetenv("DEFERRED_PARALLEL_COMPILE");
    serial.prefetch_compute("passes_comp.glsl", good);
    EXPECT_EQ(serial.compile_count() + serial.disk_loads(), 0u);
    EXPECT_NE(serial.compute_program("passes_comp.glsl", good), 0u);
}

TEST_F(ShaderErrors, EveryShipedVariantFamilyCompiles) {
    // Geometry with every optional target, lighting with every light type and
    // the light split, and every pass.
    ShaderVariant full;
    full.defines = {"GBUF_PARAMS1", "GBUF_IDS", "GBUF_UV", "GBUF_GEOMETRY", "GBUF_EMIT"};
    EXPECT_NE(shaders().graphics_program("geometry_vert.glsl", "geometry_frag.glsl", full), 0u);
    ShaderVariant lighting = full;
    lighting.defines.insert(lighting.defines.end(), {"HAS_POINT_LIGHTS", "HAS_SPOT_LIGHTS", "HAS_SUN_LIGHTS",
                                                     "HAS_AREA_LIGHTS", "HAS_MESH_LIGHTS", "HAS_EMISSION_TEXELS",
                                                     "HAS_SHADOWS", "OUT_LIGHT_SPLIT"});
    EXPECT_NE(shaders().compute_program("lighting_comp.glsl", lighting), 0u);
    for (int p = 1; p < int(kPassCount); ++p) {
        ShaderVariant v = full;
        v.defines.push_back("OUT_LIGHT_SPLIT");
        v.defines.push_back("PASS_ID " + std::to_string(p));
        EXPECT_NE(shaders().compute_program("passes_comp.glsl", v), 0u) << pass_info(Pass(p)).name;
    }
    // Each optional G-buffer target alone (a target's declaration must not
    // hide inside another's block), with every light type.
    for (const char* target : {"GBUF_PARAMS1", "GBUF_IDS", "GBUF_UV", "GBUF_GEOMETRY"}) {
        ShaderVariant one;
        one.defines = {target, "HAS_POINT_LIGHTS", "HAS_SPOT_LIGHTS", "HAS_SUN_LIGHTS", "HAS_AREA_LIGHTS",
                       "HAS_SHADOWS", "OUT_LIGHT_SPLIT"};
        EXPECT_NE(shaders().compute_program("lighting_comp.glsl", one), 0u) << target;
        one.defines.resize(1);
        EXPECT_NE(shaders().graphics_program("geometry_vert.glsl", "geometry_frag.glsl", one), 0u) << target;
    }
    // Stochastic transparency of constant materials: geometry and casters.
    ShaderVariant alpha = full;
    alpha.defines.push_back("SCENE_ALPHA");
    EXPECT_NE(shaders().graphics_program("geometry_vert.glsl", "geometry_frag.glsl", alpha), 0u);
    ShaderVariant casters;
    casters.defines = {"SCENE_ALPHA", "SHADOW_PASS"};
    EXPECT_NE(shaders().graphics_program("geometry_vert.glsl", "shadow_frag.glsl", casters), 0u);
    casters.defines.push_back("WORLD_MAP");
    EXPECT_NE(shaders().graphics_program("geometry_vert.glsl", "shadow_frag.glsl", casters), 0u);
}

TEST_F(ShaderErrors, EveryNodeFileCompilesInEveryGraphVariant) {
    // A graph program includes the node library files its nodes call; the
    // forward pass adds the lighting library to the same program. Every
    // node file together, in every variant a graph is compiled in, so that
    // no name of one library collides with the other's (a Math node's local
    // M_PI_F once did with bsdf_lib.glsl's macro, in the forward pass only).
    std::string source = "#include \"material_lib.glsl\"\n";
    for (const ShaderSource& s : embedded_shader_sources()) {
        const std::string name = s.name;
        if (name.rfind("nodes/", 0) == 0 && name.size() > 5 && name.substr(name.size() - 5) == ".glsl")
            source += "#include \"" + name + "\"\n";
    }
    source += "void material_graph_eval(out Closure surface) { surface = closure_none(); }\n";
    const std::vector<std::vector<std::string>> variants = {
        {},
        {"GBUF_GEOMETRY"},
        {"FORWARD_PASS", "FORWARD_MAX_LIGHTS 512", "HAS_POINT_LIGHTS", "HAS_SUN_LIGHTS", "HAS_AREA_LIGHTS",
         "HAS_SPOT_LIGHTS", "HAS_SHADOWS", "HAS_WORLD_OCCLUSION"},
        // Emissive meshes lighting a Blend-mode surface (the forward pass is
        // a fragment shader: no compute built-ins in the mesh lights' code).
        {"FORWARD_PASS", "FORWARD_MAX_LIGHTS 512", "HAS_MESH_LIGHTS", "HAS_EMISSION_TEXELS", "HAS_SHADOWS"},
        // With shadow rays: the traversal behind its subroutine (ray_lib.glsl).
        // (The renderer traces rays only where some light casts shadows.)
        {"FORWARD_PASS", "FORWARD_MAX_LIGHTS 512", "HAS_POINT_LIGHTS", "HAS_AREA_LIGHTS", "HAS_MESH_LIGHTS",
         "HAS_SHADOWS", "SHADOW_RAYS", "RAY_SUBROUTINE"},
        {"AOV_PASS", "GBUF_GEOMETRY"},
        {"SHADOW_PASS", "GBUF_GEOMETRY"},
        {"SHADOW_PASS", "WORLD_MAP"},
        {"EMISSION_BAKE"},
    };
    auto variant_of = [](const std::vector<std::string>& extra) {
        ShaderVariant v;
        v.defines = {"MATERIAL_GRAPH", "MATERIAL_ALPHA", "MATERIAL_BUMP", "MATERIAL_ATTRIBUTE_COUNT 0",
                     "MATERIAL_IMAGE_COUNT 0"};
        v.defines.insert(v.defines.end(), extra.begin(), extra.end());
        return v;
    };
    // All compiling at once on the driver's threads (NVIDIA: seconds each).
    for (const std::vector<std::string>& extra : variants)
        shaders().prefetch_graphics("geometry_vert.glsl", "geometry_frag.glsl", variant_of(extra),
                                    {{kMaterialGraphFile, source}});
    for (const std::vector<std::string>& extra : variants)
        EXPECT_NE(shaders().graphics_program("geometry_vert.glsl", "geometry_frag.glsl", variant_of(extra),
                                             {{kMaterialGraphFile, source}}),
                  0u)
            << (extra.empty() ? std::string("G-buffer") : extra[0]);
}
