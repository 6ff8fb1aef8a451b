// Emissive meshes as lights (Cycles' mesh lights): every mesh instance whose
// material slots emit becomes one light (LIGHT_MESH) over its emitting
// triangles, in world space (camera-relative), with a CDF that picks a
// triangle by its power (area x luminance of its radiance) and a point
// uniform on it (the sample's shared point; the lighting's own points take a
// direction uniform in the triangle's solid angle where it is near, and
// glossy lobes trace their directions against the triangles of small
// lights). The lighting (shaders/light_lib.glsl) integrates it like
// the world: per pixel, points of its own (unoccluded light), minus the
// light blocked at the sample's shared point, whose cube shadow map the
// shadow module draws (a control variate: unbiased, no noise where nothing
// occludes).
//
// Emission is two-sided (Cycles' emissive_simple_eval: |N.I|). A constant
// material's is colour x strength x alpha, averaged over its stochastic mix
// chain; a node material gives a constant found by the add-on, or, when its
// emission varies over the surface (textures, attributes, procedurals), it
// is baked: every emitting triangle of such a material is drawn with the
// graph's own program (EMISSION_BAKE, geometry_vert/frag.glsl) into a tile
// of T(T + 1)/2 texels in barycentric coordinates, read back once per
// render; lights then pick triangles by their baked power and take the
// radiance at a point from the texel that holds it (piecewise constant at
// T texels along an edge, T from a texel budget shared by all such
// triangles). The bake sees the surface from its front along its normal as
// a light sample does (Light Path outputs 0, as PATH_RAY_EMISSION).
#pragma once

#include "gl_util.h"
#include "material_module.h"
#include "scene_store.h"
#include "shader_library.h"

#include "../../shaders/shader_shared.h"

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace deferred {

struct MeshLight {
    std::uint32_t first = 0, count = 0;  // its triangles in the emitter buffer
    glm::dvec3 center{0.0};              // bounding sphere (camera-relative)
    double radius = 0.0;
    double area = 0.0;                   // total emitting area, m^2 (one side)
    double power = 0.0;                  // sum of area x luminance of the radiance
    double max_radiance = 0.0;           // largest radiance channel
    bool cast_shadow = true;
    std::uint32_t light_group = 0;       // the instance's light group
    // Which side emits: 0 both (an open mesh, as Cycles' emission); +1 or -1
    // the side the triangles' winding normal points to, for a closed mesh,
    // whose other side faces its own inside (lighting nothing but adding
    // noise: half of its points would be drawn to be blocked).
    int side = 0;
};

// The sample's shared point of a mesh light: where its cube map looks from,
// the radiance there, the triangle's unit normal and the point's density
// (area measure) under the light's CDF.
struct MeshLightPoint {
    glm::dvec3 position{0.0};
    glm::dvec3 normal{0.0, 0.0, 1.0};
    glm::dvec3 radiance{0.0};
    double pdf = 0.0;
};

// One draw of the emission bake: triangles [first, first + count) of mesh
// `mesh` as instance `instance` (the frame's instance index) draws them with
// material `material` (node graph `graph`); their tiles start at `first_tile`.
struct EmissionBakeRun {
    std::uint32_t instance = 0, mesh = 0, material = 0, graph = 0;
    std::uint32_t first = 0, count = 0;
    std::uint32_t first_tile = 0;
};

class EmitterModule {
public:
    // Finds the emitting triangles of the scene's instances (reading back
    // only the meshes that emit). Textured emitters then need bake(); every
    // scene needs finish() before lights() is read.
    void sync(const SceneStore& scene, const glm::dvec3& camera_position);
    void release() { *this = EmitterModule(); }

    // The bake: the runs to draw, the tile size, and the draw itself. The
    // caller binds the frame's instances, materials and a frame block, and
    // `draw` binds the run's mesh and its material's images and attribute
    // layout and draws the run's triangles with the bound program (instance
    // offset uniform 0 = the run's index in the bake's instance remap, which
    // bake() binds). Returns milliseconds. A graph whose bake program does
    // not compile adds a warning and its triangles emit nothing; a GL
    // failure throws Error (the caller warns; no baked triangle emits).
    bool needs_bake() const { return !bake_runs_.empty(); }
    double bake(ShaderLibrary& shaders, MaterialModule& materials,
                const std::function<void(const EmissionBakeRun& run, GLuint program)>& draw,
                std::vector<std::string>& warnings);
    // Powers, CDFs and upload; drops lights that emit nothing. Returns the
    // emitting triangles.
    std::size_t finish();
    // Triangles per chunk of a large light (MESH_LIGHT_CHUNK): a light of
    // more has its chunks' bounding spheres after its triangles.
    static constexpr std::uint32_t kChunk = 64;

    const std::vector<MeshLight>& lights() const { return lights_; }
    // The point of light `k` for a film sample's point u in [0, 1)^2.
    MeshLightPoint sample_point(std::size_t k, const std::array<float, 2>& u) const;
    // Textured emitters exist: the lighting reads the baked texels (HAS_EMISSION_TEXELS).
    bool has_texels() const { return bool(texel_buffer_); }
    int tile_size() const { return tile_size_; }
    std::size_t baked_triangles() const { return tile_count_; }
    void bind() const;

    // Budget of baked texels shared by all textured emitting triangles, and
    // the largest tile edge (a panel of two triangles gets 128 texels along
    // each edge; 5000 triangles get 28).
    static constexpr std::size_t kTexelBudget = std::size_t(1) << 21;
    static constexpr int kMaxTileSize = 128;

private:
    // The radiance of triangle t at barycentric weights (b1, b2) of its
    // vertices 1 and 2 (light_lib.glsl's emitter_radiance).
    glm::dvec3 radiance_at(const gpu::GpuEmitterTriangle& t, double b1, double b2) const;

    std::vector<MeshLight> lights_;
    std::vector<gpu::GpuEmitterTriangle> triangles_;
    Buffer buffer_;
    // Textured emitters: the draws, the tile edge T, the triangles baked.
    std::vector<EmissionBakeRun> bake_runs_;
    int tile_size_ = 0;
    std::size_t tile_count_ = 0;
    std::vector<float> texels_;  // rgb per texel, T(T + 1)/2 per tile
    Buffer texel_buffer_;
};

}  // namespace deferred
