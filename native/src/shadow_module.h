// Shadow maps, rendered once per film sample from that sample's point on
// each shadow-casting light (shaders/shadow_frag.glsl, lookups in
// shaders/shadow_lib.glsl).
//
//  point, spot, area : a cube of 6 R32F layers storing the distance from the
//                      light point (90 degree faces, reversed-Z depth test);
//                      sphere lights use, per face, the point of the disk
//                      perpendicular to the face's axis
//  sun               : 4 orthographic cascades over the view frustum
//                      (practical split scheme, lambda 0.75) storing depth
//                      along the sun's direction
// All maps are layers of one 2D array texture, so the number of shadowed
// lights is not limited by texture units. Only lights that cast shadows,
// have energy, and whose influence sphere reaches the view frustum get maps.
//
// Resolution per light from its projected footprint (fit()): over the
// visible receivers the light reaches (a grid of sample 0's depth), the
// texels a face/cascade needs so that one texel covers at most 1/quality of
// a pixel there; the 90th percentile of that need, rounded up to a multiple
// of 32, between 32 and the maximum setting. A light uses the lower-left
// r x r corner of its layers (GpuShadow params.w = r / array size).
// Lights without size (point/spot radius 0, sun angle 0) cast the same
// shadow every sample: their maps are rendered once per frame.
// Spots and area lights draw their cubes only where they shine (lit_region
// in shadow_module.cpp): faces no lit direction passes through are only
// cleared, the others are scissored to the lit directions, and casters are
// clipped to the lit region (a spot's cone widened by its radius, the half
// space in front of an area light).
//
// The world (offer_world(n)): per sample n orthographic RG32F maps (layers
// of one array) along n directions of the world over the visible receivers' bounding sphere,
// storing the nearest and the farthest geometry along it (MAX blending), so
// it answers for that direction and its opposite; 4x the lights' texel
// density. Each map draws only the instances whose bounding sphere can cast
// into it (the caller's DrawCasters applies the test).
#pragma once

#include "camera.h"
#include "convex_geometry.h"
#include "draw_style.h"
#include "gl_util.h"
#include "shader_library.h"

#include "../../shaders/shader_shared.h"

#include <deferred/scene.h>

#include <array>
#include <functional>
#include <vector>
#include <string>

namespace deferred {

class ShadowModule {
public:
    // Per frame: forget last frame's selection.
    // `max_resolution`: texels per face/cascade side at most; `quality`:
    // texels per pixel of the receivers' footprint.
    // `rays`: shadow rays (ray_scene.h) answer visibility instead of maps:
    // every offered light is kept (no layers, no budget), and the module only
    // packs each sample's light points and world directions (GpuShadow),
    // allocating and drawing no map.
    // `count_fragments`: a fragment query around each layer's draws
    // (collect_fragments), where the driver has pipeline statistics.
    void begin_frame(const CameraMatrices& camera, int max_resolution, float quality, std::size_t memory_budget,
                     bool rays = false, bool count_fragments = false);
    bool rays() const { return rays_; }
    // Offers a light; returns false if it cannot shadow anything visible.
    bool offer(std::size_t light_index, const Light& light, const gpu::GpuLight& packed);
    // Offers an emissive mesh's light (LIGHT_MESH, emitting `power` W): a
    // cube map from its shared point (axis_x), which moves every sample.
    bool offer_mesh(std::size_t light_index, const gpu::GpuLight& packed, double power);
    // A kept light's new data for the coming sample (a mesh light's point).
    void update_light(std::size_t light_index, const gpu::GpuLight& packed);
    // Asks for the world's occlusion maps: each sample, `maps` orthographic
    // maps along new directions of the world, fitted to the visible receivers.
    void offer_world(int maps = 1);
    // Keeps as many offered lights as the array layers and the memory budget
    // allow (the world and suns first, then by power over squared distance
    // to the camera) and returns light_index -> shadow index (-1: none); the
    // maps are allocated by fit().
    std::vector<int> allocate(std::size_t light_count);
    std::size_t dropped() const { return dropped_; }  // offered but over the limits
    // A visible surface point: camera-relative position, view depth, and the
    // width of a pixel there (metres).
    struct Receiver {
        glm::dvec3 position;
        double depth, footprint;
    };
    // Chooses each kept light's resolution from the receivers it reaches and
    // (re)allocates the array; call before the first render_sample().
    // `visible_depths` (near, far): the view depths of every visible pixel
    // at sample 0; the sun's cascades are split over them (with a margin)
    // rather than over the whole clip range, which in a scene with a far
    // clip end (Blender's default 100 m, an orthographic view's +-clip_end/2)
    // would put everything visible in one coarse cascade. (0, 0): the clip
    // range.
    //
    // `lookups`: where the visible surfaces' shadow lookups can land, when
    // that is known (not under camera motion blur): inside the frame's view
    // volume with its sides at `viewplane` (the camera's, widened by the
    // pixel filter's reach: FrameScene's ViewVolume), each lookup point
    // moved by at most `lift` metres (the shadow terminator offset,
    // FrameScene::terminator_lift), between `depths`: the view depths any
    // visible surface can have (the bounding spheres in view of every
    // instance), within the clip range. The maps then draw only the casters
    // whose shadow a lookup can read (shadow_module.cpp): a sun's cascade
    // those over its own slice of the volume (slice_casters), the world's
    // maps those over the whole volume, a light's cube face those in the
    // cone the volume fills from its point (cone_casters); no texel any
    // lookup reads changes. Without it, every caster of the map's own test.
    //
    // `boxes`, where known (empty: not): boxes that hold every visible
    // surface (each instance in view: its mesh's bounds through its matrix;
    // not where something moves or deforms over the shutter). The cascades
    // and the world's maps then take the part of these boxes inside their
    // slice or volume (receiver_points) instead of the whole of it: the sky
    // above a field, the air in front of a wall hold no lookup. (A cube
    // face's cone is not narrowed so: its plane-depth comparison reaches up
    // to 1 / SHADOW_PLANE_MIN_COS texels beyond a lookup, the cone's margin
    // grows with that, and on the instancing capture it left out 2 % more.)
    struct LookupVolume {
        glm::dvec4 viewplane{0.0};  // left, right, bottom, top (tan units, or metres for orthographic)
        glm::dvec2 depths{0.0};     // nearest, farthest
        double lift = 0.0;
        std::vector<Box> boxes;  // camera-relative
    };
    //
    // `caster_triangles` (where given): the triangles of the casters that
    // pass a test (FrameScene::caster_triangles). A sun's cascades then take
    // up to kDenseCascades times the texels per side the receivers need,
    // as many as one per triangle the fullest cascade can draw: the maps'
    // grid moves every sample, so a lookup reads its texel's centre
    // anywhere within a texel of its own point, and where the casters are
    // dense (a carpet of rocks) that blur darkens the lit surfaces beside
    // their contacts with other surfaces, by what lies under the contact
    // (the instancing sample's rocks 0.984 of Cycles' mean with the
    // receivers' need, 512 texels a side, 0.990 with this rule's 896: the
    // report's per-object table, README Speed against error). The fill of
    // one texel per triangle costs little next to the triangles themselves
    // (on llvmpipe 3-5 % of that frame); where the casters are few,
    // nothing changes.
    using CasterTest = std::function<bool(const glm::dvec3&, double)>;
    using CasterTriangles = std::function<std::uint64_t(const CasterTest&)>;
    static constexpr double kDenseCascades = 2.0;
    void fit(const std::vector<Receiver>& receivers, std::pair<double, double> visible_depths = {0.0, 0.0},
             const LookupVolume* lookups = nullptr, const CasterTriangles& caster_triangles = {});
    // Whether an instance's bounding sphere (camera-relative centre, radius)
    // can cast into the map being drawn: CasterTest.
    // Draws the scene's shadow casters that pass the test, with the
    // currently bound program (world_map: it draws a world occlusion map,
    // else a light's map), as `style` says (by vertex where the program is
    // an INDEXED_DRAW one; closed casters' back faces left out, for the
    // map's projection `faces`, where style.cull_faces).
    // `alpha_program` (0: none): the map's program for the slots of partly
    // transparent constant materials (SCENE_ALPHA), where the bound one
    // draws the opaque casters (GeometryStage::draw_casters).
    using DrawCasters = std::function<void(const CasterTest&, bool world_map, const DrawStyle& style,
                                           const FaceCulling* faces, GLuint alpha_program)>;
    // Renders every kept light's maps (and the world's) for one film sample.
    // `u`: the sample's point on the light shapes; `world_dirs`: its
    // directions of the world, one per world map (xyz unit, towards the
    // world; w the density its pair was drawn with: WorldModule's
    // occlusion_direction). `caster_defines` go into the
    // casters' program (SCENE_ALPHA: partly transparent constant materials).
    // `casters_vary`: some caster is drawn stochastically (transparency), so
    // even the maps of lights without size are drawn again every sample.
    // `grid`: this sample's point in [0, 1)^2 for the orthographic maps' texel
    // grid offset (maps drawn again every sample).
    void render_sample(ShaderLibrary& shaders, const std::array<float, 2>& u, const std::array<float, 2>& grid,
                       const std::vector<glm::dvec4>& world_dirs,
                       const DrawCasters& draw_casters, const std::vector<std::string>& caster_defines = {},
                       bool casters_vary = false);
    int world_index() const { return world_index_; }  // shadow index of the world's first map, -1: none
    int world_count() const { return world_count_; }  // the world's maps (consecutive shadow indices)
    void bind() const;
    bool empty() const { return entries_.empty(); }
    std::size_t count() const { return entries_.size() - std::size_t(world_count_); }  // lights only
    std::size_t map_bytes() const { return bytes_; }
    int resolution() const { return resolution_; }  // the array's layer size after fit()
    // Texels per side of each kept light's maps, in shadow index order (the
    // world's map left out).
    std::vector<int> resolutions() const;
    std::size_t layers_rendered() const { return layers_rendered_; }  // since fit()
    // Texels inside the scissor of each layer drawn since fit(): the fill a
    // light's lit region leaves (a spot's cone, an area light's front).
    std::uint64_t texels_rendered() const { return texels_rendered_; }
    // Fragments the maps' draws shaded since fit() (the fill itself:
    // GL_FRAGMENT_SHADER_INVOCATIONS around each layer's draws, not its
    // clears; read once the frame is done, and reset; 0 where the driver has
    // no pipeline statistics).
    std::uint64_t collect_fragments();
    // After a frame that threw inside render_sample: the fragment query
    // ended and forgotten, the clip distances off (the next frame's
    // programs do not write them).
    void abandon_frame();

private:
    struct Entry {
        gpu::GpuLight light;
        bool sun = false;
        bool world = false;
        int first_layer = 0;
        std::size_t light_index = 0;
        double priority = 0;
        int resolution = 0;
        bool fixed_point = false;  // no size: the same maps every sample
        bool rendered = false;
    };
    // The sun's cascades: split depths and bounding spheres (camera-relative)
    // of the view frustum's slices.
    struct Cascades {
        double split[SHADOW_CASCADE_COUNT + 1];
        glm::dvec3 center[SHADOW_CASCADE_COUNT];
        double radius[SHADOW_CASCADE_COUNT];
    };
    // The corners of the part of the lookup volume whose view depths select
    // cascade k (shadow_lib.glsl shadow_visibility_kind: up to the first
    // split for cascade 0, beyond the last but one for cascade 3, so those
    // two reach the lookup volume's ends), camera-relative.
    std::array<glm::dvec3, 8> slice_corners(const Cascades& cs, int k) const;
    std::pair<double, double> slice_depths(const Cascades& cs, int k) const;  // slice_corners' near, far
    // A lower bound of camera-relative point p's distance to the lookup
    // volume (<= 0: inside it).
    double lookup_distance(const glm::dvec3& p) const;
    // The lookup volume's corners between two view depths.
    std::array<glm::dvec3, 8> lookup_corners(double near, double far) const;
    // The vertices of each receiver box's part between two view depths of
    // the lookup volume (camera-relative): every visible surface point there
    // lies in their convex hull.
    std::vector<glm::dvec3> receiver_points(double near, double far) const;

    // The corners of the camera's frustum with sides at `viewplane` (left,
    // right, bottom, top) between two view depths, camera-relative.
    std::array<glm::dvec3, 8> frustum_corners(const glm::dvec4& viewplane, double near, double far) const;
    // How far across an orthographic map's axis a lookup lands from the
    // surface it shades: the terminator's lift, 1.5 texels of normal offset
    // (shadow_lib.glsl's Pb) and the 0.71 to the texel's centre, rounded up
    // to 3 texels, and `slack` for the float error of camera-relative
    // positions.
    double lookup_reach(double texel, double slack) const { return lookups_.lift + 3.0 * texel + slack; }
    Cascades cascades() const;
    void begin_fragment_count();
    void end_fragment_count();
    float quality_ = 1.0f;
    bool rays_ = false;
    int world_index_ = -1;
    int world_count_ = 0;
    glm::dvec3 receivers_center_{0.0};  // bounding sphere of the visible receivers
    double receivers_radius_ = 0.0;
    std::size_t layers_rendered_ = 0;
    std::uint64_t texels_rendered_ = 0;
    bool count_fragments_ = false;
    bool query_active_ = false;
    std::vector<GLuint> fragment_queries_, free_queries_;  // this frame's, and ended ones to reuse
    bool lit_region_enabled_ = true;
    bool receiver_culling_enabled_ = true;
    bool dense_cascades_enabled_ = true;
    bool by_vertex_enabled_ = true, face_culling_enabled_ = true;
    std::size_t dropped_ = 0;
    CameraMatrices camera_{};
    double split_near_ = 0.0, split_far_ = 0.0;  // the cascades' depth range (fit)
    bool lookups_known_ = false;                   // fit() was given a LookupVolume
    LookupVolume lookups_{};
    // Where lookups_ has boxes: receiver_points() of each cascade's slice
    // (slice_corners' depths) and of the whole volume, from fit().
    bool receiver_points_known_ = false;
    std::array<std::vector<glm::dvec3>, SHADOW_CASCADE_COUNT> slice_points_;
    std::vector<glm::dvec3> volume_points_;
    int resolution_ = 1024;
    std::size_t budget_ = 0, bytes_ = 0;
    std::vector<Entry> entries_;
    int layers_ = 0;
    Texture maps_, depth_;
    Framebuffer fbo_;
    Texture world_map_;  // RG32F array, world_count_ layers of its own size (the world entries' resolution)
    Framebuffer world_fbo_;
    int world_allocated_ = 0, world_layers_ = 0;
    Buffer shadow_buffer_;
    int allocated_layers_ = 0, allocated_resolution_ = 0;
};

}  // namespace deferred
