// The scene as one frame draws it: every instance placed camera-relative
// (in double, then packed), the material table, the per-instance data the
// passes read (Cryptomatte hashes, light groups), and the draw calls over
// it. Stages never walk SceneStore's batches themselves: they cull the
// instances with a test on their bounding spheres (the camera's frustum, a
// shadow map's volume) and draw the ones kept, a batch's triangles at a time
// or one material slot's range at a time, through an instance remap buffer
// (geometry_vert.glsl pulls its vertices from the mesh's storage buffers).
//
// Motion blur: the instances that move over the shutter keep their three
// steps; place_at() puts them (and their shadow-ray casters) at a sample's
// time.
#pragma once

#include "camera.h"
#include "convex_geometry.h"
#include "draw_style.h"
#include "gl_util.h"
#include "ray_scene.h"
#include "scene_store.h"

#include "../../shaders/shader_shared.h"

#include <deferred/renderer.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace deferred {

class MaterialModule;

gpu::mat4 to_gpu(const glm::dmat4& m);

// GpuMaterial.base_diffuse.w of a Holdout material (the closure model codes
// of gbuffer_lib.glsl end at 3); geometry_frag.glsl turns it into a hole.
constexpr float kClosureHoldout = 4.0f;

// What a sample's camera sees: its rotation, its position relative to the
// frame's camera (non-zero under camera motion blur) and the frustum widened
// by the pixel filter's reach and a pixel, as a test on bounding spheres.
struct ViewVolume {
    glm::dmat3 to_view{1.0};
    glm::dvec3 eye{0.0};
    double left = 0, right = 0, bottom = 0, top = 0;
    double clip_start = 0, clip_end = 0;
    bool orthographic = false;

    ViewVolume() = default;
    ViewVolume(const CameraMatrices& cam, int width, int height, std::uint32_t reach_px);
    bool contains(const glm::dvec3& center, double radius) const;
};

class FrameScene {
public:
    // Bounding sphere of an instance, camera-relative.
    struct Bound {
        glm::dvec3 center;
        double radius;
    };
    // One batch: its instances [first, first + count) and its slot map.
    struct Draw {
        std::uint32_t mesh, first, count;
        bool cast_shadow;
        std::uint32_t slot_offset, slot_count;
    };
    // The instances of one batch that passed the last cull, at [first,
    // first + count) of the remap buffer. `facing`, where the cull was given
    // a FaceCulling: +1 the triangles whose own winding faces the viewer
    // are its front faces, -1 the others (a mirrored instance, a mesh
    // facing in), 0 both sides are drawn (open mesh, viewer too near).
    struct Culled {
        const Draw* draw;
        std::uint32_t first, count;
        int facing = 0;
    };
    using Test = std::function<bool(const glm::dvec3&, double)>;

    struct Options {
        bool motion_blur = false;
        bool cryptomatte = false;  // pack each instance's object and asset hashes
        bool light_groups = false; // pack each instance's light group
    };
    // Packs the instances and materials of `scene` relative to the camera at
    // `camera_position` and uploads them (the previous frame's released).
    void build(const SceneStore& scene, const MaterialModule& materials, const glm::dvec3& camera_position,
               const Options& options, GLuint empty_vao, GLuint dummy_ssbo);
    void release();

    std::size_t instance_count() const { return instances_.size(); }
    // Every batch, in the scene's order.
    const std::vector<Draw>& draws() const { return draws_; }
    // Instance i's matrix as the vertex stage has it (camera-relative), and
    // whether it mirrors (negative determinant: its winding is reversed).
    glm::dmat4 model_matrix(std::uint32_t i) const;
    // Instance i's box: its mesh's axis-aligned bounds through that matrix
    // (camera-relative; float: callers widen for its rounding).
    Box instance_box(std::uint32_t i, const GpuMesh& mesh) const;
    bool mirrored(std::uint32_t i) const { return (instances_[i].ids.w & 1u) != 0u; }
    // Whether instance i is a holdout object (Object > Visibility > Holdout).
    bool holdout(std::uint32_t i) const { return (instances_[i].ids.w & 2u) != 0u; }
    const std::vector<Bound>& bounds() const { return bounds_; }
    // The boxes of the instances whose bounding sphere `view` contains: each
    // its mesh's axis-aligned bounds through its matrix (camera-relative).
    std::vector<Box> boxes_in_view(const ViewVolume& view) const;
    const std::vector<std::uint32_t>& crypto_hashes() const { return crypto_; }
    const gpu::GpuMaterial& material(std::uint32_t id) const { return gpu_materials_[id]; }
    // A constant material's coverage: its alpha, a stochastic mix chain's
    // averaged over the chain (material_alpha_lib.glsl's material_chain_alpha).
    float coverage(std::uint32_t id) const;
    const Material& scene_material(std::uint32_t id) const { return scene_->materials()[id]; }
    std::size_t material_count() const { return scene_->materials().size(); }
    bool any_moving() const { return !moving_.empty(); }
    // A deforming mesh under motion blur (its vertices move in the vertex stage).
    bool deforming() const { return deforming_; }
    // The most the shadow terminator offset can move a visible point of any
    // instance (metres; GpuMesh::terminator_reach through each instance's
    // matrices, with a Geometry Offset on): how far a shadow lookup can land
    // from the surface it shades.
    double terminator_lift() const { return terminator_lift_; }

    // The ray scene's casters (every shadow-casting instance with its slots'
    // alphas: a constant material's mix chain averaged, as
    // material_alpha_lib.glsl), kept so place_at() can move them.
    const std::vector<RayScene::Instance>& ray_casters();
    // Puts the moving instances at shutter position r (-1 open, 1 close) and
    // uploads them; true when a shadow-ray caster moved (the ray scene must
    // be rebuilt from ray_casters()).
    bool place_at(double r);

    // The instance, slot and material tables at their storage bindings.
    void bind_buffers() const;
    // A mesh's buffers for vertex pulling (geometry_vert.glsl), and its
    // per-corner attributes (node materials).
    void bind_mesh(const GpuMesh& mesh) const;
    void bind_attributes(const GpuMesh& mesh) const;
    const GpuMesh& mesh(const Draw& d) const { return scene_->meshes()[d.mesh]; }

    // Keeps the instances whose bounding sphere passes `keep` (casters_only:
    // without the cast_shadow-off ones), fills the remap buffer and binds
    // the tables; returns how many were kept. `faces`: the projection the
    // draws will use, for which each batch's kept instances are grouped by
    // the side of their triangles that faces it (draw_style.h).
    std::uint64_t cull(const Test& keep, bool casters_only, const FaceCulling* faces = nullptr);
    const std::vector<Culled>& visible() const { return visible_; }
    // The instance index of the j-th kept instance of the last cull.
    std::uint32_t kept(std::uint32_t j) const { return remap_[j]; }
    // Triangles [first, first + count) of the kept instances of one batch,
    // with the bound program, drawn as `style` says.
    void draw_range(const Culled& c, std::uint32_t first, std::uint32_t count, const DrawStyle& style = {}) const;
    // The triangles of the shadow-casting instances whose bounding sphere
    // passes `keep` (what cull(keep, true) would keep, counted on the CPU).
    std::uint64_t caster_triangles(const Test& keep) const;
    // cull(), then every kept instance whole.
    std::uint64_t draw_culled(const Test& keep, bool casters_only, const DrawStyle& style = {},
                              const FaceCulling* faces = nullptr);
    // Instances draw_range() has drawn without their back faces since the
    // last build() (the count of each such draw's kept instances; callers
    // take differences around their draws).
    std::uint64_t one_sided_instances() const { return one_sided_; }
    // The material drawing slot s of a batch.
    std::uint32_t slot_material(const Draw& d, std::size_t s) const;
    // Entries in the slot table (every batch's slots, one after the other).
    std::size_t slot_count() const { return slots_.size(); }

    // The tables' buffers (the emission bake binds them itself).
    GLuint instance_buffer() const { return instance_buffer_.get(); }
    GLuint instance_group_buffer() const { return instance_group_buffer_.get(); }

private:
    struct Moving {
        std::size_t index;
        glm::dmat4 steps[3];  // world matrices at the shutter's open, middle, close
        std::uint32_t mesh;
    };
    void place(const glm::dmat4& world, const GpuMesh& mesh, gpu::GpuInstance& g, Bound& bound) const;
    void upload_instances() const;

    const SceneStore* scene_ = nullptr;
    glm::dvec3 camera_position_{0.0};
    GLuint empty_vao_ = 0, dummy_ssbo_ = 0;
    std::vector<gpu::GpuInstance> instances_;
    std::vector<Bound> bounds_;
    std::vector<std::uint32_t> slots_;
    std::vector<Draw> draws_;
    std::vector<Moving> moving_;
    bool deforming_ = false;
    double terminator_lift_ = 0.0;
    std::vector<gpu::GpuMaterial> gpu_materials_;
    std::vector<std::uint32_t> crypto_;  // object and asset hash per instance
    std::vector<RayScene::Instance> casters_;
    std::vector<std::int64_t> caster_of_instance_;  // -1: casts nothing
    bool casters_built_ = false;
    Buffer instance_buffer_, slot_buffer_, material_buffer_, instance_group_buffer_;
    std::vector<std::uint32_t> remap_;
    Buffer remap_buffer_;
    std::size_t remap_capacity_ = 0;
    std::vector<Culled> visible_;
    std::vector<std::uint32_t> facing_groups_[2];  // cull()'s scratch: a batch's kept instances facing -1, 0
    bool facing_ccw_ = true;                       // the last cull's FaceCulling::facing_ccw
    mutable std::uint64_t one_sided_ = 0;
};

}  // namespace deferred
