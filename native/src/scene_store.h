// The scene as the GPU sees it: validated meshes uploaded once (shared by all
// their instances), plus the CPU-side records of instances, materials,
// lights and world that are packed per frame (camera-relative) by the
// renderer's modules.
#pragma once

#include "gl_util.h"

#include <deferred/scene.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <unordered_map>
#include <vector>

namespace deferred {

struct MeshBvh;

// Where a named per-corner attribute lives in GpuMesh::attributes.
struct MeshAttributeLayout {
    std::string name;
    std::uint32_t offset = 0;  // first float
    int components = 0;
};

struct GpuMesh {
    Buffer positions, indices, normals, uvs, material_indices;
    Buffer attributes;                                  // every CornerAttribute, one after the other
    Buffer motion_positions;                            // a deforming mesh's previous and next vertices (flag 8)
    std::vector<MeshAttributeLayout> attribute_layout;
    float texspace_location[3] = {0.0f, 0.0f, 0.0f};
    float texspace_size[3] = {1.0f, 1.0f, 1.0f};
    // Triangles are stored sorted by material slot: slot s covers triangles
    // [slot_ranges[s].first, + .second), so one slot draws as one range.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> slot_ranges;
    std::uint32_t triangle_count = 0;
    std::uint32_t flags = 0;          // 1 normals, 2 uvs, 4 material indices, 8 vertex motion (geometry_vert.glsl)
    std::int32_t max_material_index = 0;
    // Bounding sphere of the vertices (object space), for culling instances
    // out of shadow maps.
    double bound_center[3] = {0.0, 0.0, 0.0};
    double bound_radius = 0.0;
    // Half the extent of the vertices' axis-aligned box around bound_center
    // (object space): with the instance's matrix, a box that holds it
    // (FrameScene::receiver_boxes).
    double bound_half[3] = {0.0, 0.0, 0.0};
    // closed_orientation() of its triangles (mesh_topology.h): +1/-1 closed
    // and facing out/in, whose back faces a draw may leave out; 0 both sides.
    int closed = 0;
    // planar_mesh() (mesh_topology.h): every triangle in the plane
    // dot(plane_normal, p) = plane_offset (object space). False for a
    // deforming mesh (its rest shape is all that is known).
    bool planar = false;
    double plane_normal[3] = {0.0, 0.0, 1.0};
    double plane_offset = 0.0;
    // convex_mesh() (mesh_topology.h): closed and bounding a convex solid.
    bool convex = false;
    // The most any point of it is lifted by the shadow terminator offset,
    // before its instance's matrix stretches it (object units;
    // terminator_reach() below). 0 without normals.
    double terminator_reach = 0.0;
    // Its ray hierarchy (ray_scene.h), built on first use by shadow rays.
    mutable std::shared_ptr<const MeshBvh> bvh;
};

// Input contract of the scene API (README, "Hard cases and bad input").
// Everything outside it is refused with InvalidInput naming the field; the
// few documented fallbacks are applied by SceneStore when it stores a light.
// The bounds keep every float32 product of the G-buffer and the lighting
// finite (squared camera-relative distances stay below ~1e31, radiances of
// the smallest lights below ~1e36).
struct InputLimits {
    static constexpr double kMaxCoordinate = 1e15;   // |position| and |matrix entry|, m
    static constexpr float kMaxHalf = 65504.0f;      // base colour (RGBA16F G-buffer)
    static constexpr float kMaxSpecular = 12.0f;     // F0 = 0.08 specular <= 0.96 (12.5: infinite IOR)
    static constexpr float kMaxLightPower = 1e12f;   // |energy| x colour, W (sun: W/m^2)
    static constexpr float kMaxLightSize = 1e6f;     // radius, size, size_y, m
    static constexpr float kMinLightExtent = 1e-6f;  // smaller point/spot radius: 0; smaller area extent: raised
    static constexpr float kMaxWorld = 1e12f;        // world colour
    static constexpr std::uint32_t kMaxPassIndex = 1u << 24;  // exact in the float32 index passes
    static constexpr std::int32_t kMaxMaterialSlot = 32766;   // Blender's MAXMAT (32767 slots)
};

// Validation only (plain CPU, no GL: usable by tests and sanitizer builds).
// Each throws InvalidInput("<field>: <problem>"); validate_mesh returns the
// largest material index used (0 without material indices).
// A bound on the shadow terminator offset's length over the mesh, before
// its instance's matrix (geometry_frag.glsl terminator_offset: Cycles 3.4's
// shadow_ray_smooth_surface_offset). With G = max |Gij| = |dot(V_j - V_i,
// N_i)| over the triangles' corners: |D_i| <= (1 - b_i) G (b_i corner i's
// weight), so h_i <= (2 - b_i) G, and the corner with the largest weight
// (>= 1/3) gives min(h0, h1, h2) <= 5/3 G; with |a|, |b|, |c| <= 2 G and
// u(1 - u), v(1 - v), uv <= 1/4 inside the triangle, the parabola is at
// most 2.5 G, halved 1.25 G; so |h| <= 5/3 G. The offset is h along the
// interpolated normal through the instance's matrix, at most max |N_i|
// times its largest stretch (FrameScene::terminator_lift). 1.8 instead of
// 5/3: slack for barycentrics a hair outside the triangle
// (Culling.TheTerminatorOffsetStaysWithinItsBound checks it).
double terminator_reach(const MeshData& mesh);

std::int32_t validate_mesh(const MeshData& mesh);
void validate_material(const Material& material);
void validate_instances(const double* matrices, std::size_t count);
void validate_light(const Light& light);
void validate_world(const World& world);
// The light as the renderer stores it: validate_light, then the documented
// fallbacks (a point/spot radius below kMinLightExtent becomes 0, a delta
// light; an area extent (size x axis scale) below kMinLightExtent is raised
// to it, which looks the same from any distance above a few micrometres).
Light sanitized_light(const Light& light);

struct InstanceBatch {
    std::uint32_t mesh_id;
    std::vector<double> matrices;             // 16 per instance, column-major
    std::vector<std::uint32_t> object_indices; // one per instance
    std::vector<std::uint32_t> material_slots; // slot -> material id
    bool cast_shadow = true;                   // drawn into shadow and world occlusion maps
    bool holdout = false;                      // a hole in the image: black, alpha 0 (Cycles' holdout)
    std::uint32_t light_group = 0;             // its emission's light group, 0 none
    std::vector<float> colors;                 // RGBA per instance (Object Info)
    std::vector<float> randoms;                // one per instance (Object Info Random)
    std::vector<float> terminator_offsets;     // one per instance: Shadow Terminator Geometry Offset
    std::vector<std::uint32_t> crypto;         // two per instance: Cryptomatte object and asset hashes
    std::vector<double> motion;                // 32 per instance (previous, next matrix) or empty: static
    bool shadow_catcher = false;               // Object > Visibility > Shadow Catcher
};

class SceneStore {
public:
    // Drops the scene. Meshes added with a key that the scene just dropped
    // used stay uploaded for the next one (find_mesh), as keyed images do
    // (MaterialModule): the viewport re-syncs the whole scene after a
    // transform or material edit without exporting a mesh again.
    void clear();
    // Every mesh, kept ones too (the renderer's end).
    void release_all();
    // Validates, uploads. With a key (the caller's name for this mesh's
    // content), it outlives clear() while each scene uses it.
    std::uint32_t add_mesh(const MeshData& mesh, const std::string& key = {});
    // The id of a mesh kept under `key`, now used by this scene; -1: none.
    std::int64_t find_mesh(const std::string& key);
    std::size_t meshes_uploaded() const { return meshes_uploaded_; }  // since clear()
    std::size_t meshes_reused() const { return meshes_reused_; }
    std::uint32_t add_material(const Material& m);
    void add_instances(std::uint32_t mesh_id, const double* matrices, std::size_t count,
                       const std::uint32_t* object_indices, const std::vector<std::uint32_t>& slots,
                       bool cast_shadow = true, const float* colors = nullptr, const float* randoms = nullptr,
                       const std::uint32_t* crypto = nullptr, bool holdout = false,
                       std::uint32_t light_group = 0, const float* terminator_offsets = nullptr,
                       const double* motion = nullptr, bool shadow_catcher = false);
    void add_light(const Light& light);
    void set_world(const World& world);

    const std::vector<GpuMesh>& meshes() const { return meshes_; }
    const std::vector<InstanceBatch>& batches() const { return batches_; }
    const std::vector<Material>& materials() const { return materials_; }
    const std::vector<Light>& lights() const { return lights_; }
    const World& world() const { return world_; }
    std::size_t instance_count() const { return instance_count_; }

private:
    struct MeshSlot {
        std::string key;
        bool alive = false;  // holds a mesh (a dropped slot is reused by add_mesh)
        bool used = false;   // used by the scene being built
    };
    std::vector<GpuMesh> meshes_;
    std::vector<MeshSlot> mesh_slots_;  // parallel to meshes_
    std::unordered_map<std::string, std::uint32_t> mesh_by_key_;  // alive keyed slots
    bool scene_started_ = false;        // something was added or found since clear()
    std::size_t meshes_uploaded_ = 0, meshes_reused_ = 0;
    std::vector<InstanceBatch> batches_;
    std::vector<Material> materials_;
    std::vector<Light> lights_;
    World world_;
    std::size_t instance_count_ = 0;
};

}  // namespace deferred
