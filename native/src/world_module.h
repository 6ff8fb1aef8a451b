// The world beyond a constant colour: its node tree (a MaterialGraph whose
// surface closure's emission is the background radiance) baked into an
// equirectangular map on the GPU, and the luminance distribution the
// lighting samples it by (shaders/world_lib.glsl has the mapping and the
// density). A constant world has no map, no CDF and no bake: the lighting
// integrates it analytically (only what the scene needs).
//
// Two maps when the graph reads Light Path (Is Camera Ray and friends) or
// has a Nishita sky (whose sun disc lights as a sun lamp the add-on adds,
// so the lighting map leaves it out): the world as camera rays see it
// (background, Env pass) and as light samples see it (lighting); otherwise
// one map serves both.
#pragma once

#include "gl_util.h"
#include "shader_library.h"

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace deferred {

class MaterialModule;

// The direction of a film sample's world occlusion map: light arrives from
// `dir` (unit, world space). The map answers for `dir` and `-dir`, so the
// pair is drawn with density pair_pdf = p(dir) + p(-dir) (solid angle).
struct WorldDirection {
    glm::dvec3 dir{0.0, 0.0, 1.0};
    double pair_pdf = 1.0 / (2.0 * 3.14159265358979323846);
};

class WorldModule {
public:
    // Largest baked map (width; height is half): 4096 x 2048 RGBA32F is 128 MiB.
    static constexpr int kMaxWidth = 4096;
    // A world graph without images (gradients, procedurals) is baked at this width.
    static constexpr int kDefaultWidth = 1024;

    // Bakes world graph `graph` of `materials` (or drops the maps for -1)
    // and builds the sampling distribution. The frame constants must be
    // bound (Camera texture coordinates). Returns the bake's milliseconds.
    double prepare(ShaderLibrary& shaders, MaterialModule& materials, std::int32_t graph);
    void release() { *this = WorldModule(); }

    bool has_map() const { return width_ > 0; }
    int width() const { return width_; }
    int height() const { return height_; }
    // Mean radiance of the lighting map over the sphere (what a white
    // unoccluded diffuse sphere reflects); > 0 when the world lights anything.
    const glm::dvec3& mean_radiance() const { return mean_; }
    bool lights() const { return mean_.x > 0.0 || mean_.y > 0.0 || mean_.z > 0.0; }

    // The occlusion map's direction for a film sample's point u in [0,1)^2:
    // uniform on the sphere without a map, else drawn as world_sample() does.
    WorldDirection occlusion_direction(const std::array<float, 2>& u) const;
    // Density world_pdf() of the GLSL (per solid angle) at unit direction d.
    double pdf(const glm::dvec3& d) const;

    void add_defines(ShaderVariant& variant) const;
    void bind() const;  // the maps and the CDF buffer, when there is a map

private:
    Texture bake(ShaderLibrary& shaders, MaterialModule& materials, std::uint32_t graph, bool lighting);
    void build_distribution(const std::vector<float>& rgba);

    int width_ = 0, height_ = 0;
    Texture radiance_, camera_;   // camera_ empty: camera rays see radiance_
    Buffer cdf_buffer_;
    std::vector<double> row_cdf_;  // H + 1
    std::vector<double> col_cdf_;  // H x (W + 1)
    glm::dvec3 mean_{0.0};
};

}  // namespace deferred
