// Shadow rays' geometry (settings.shadow_rays; shaders/ray_lib.glsl).
//
// Two levels, as a ray tracer keeps instanced geometry:
//  - a bounding volume hierarchy per mesh in object space (MeshBvh), built
//    once per mesh on the CPU (binned SAH, Wald 2007, "On fast Construction
//    of SAH-based Bounding Volume Hierarchies") from the mesh's own GPU
//    buffers and kept with the mesh (GpuMesh::bvh), so a warm renderer or
//    a viewport re-sync reuses it;
//  - a hierarchy over the shadow-casting instances (camera-relative world
//    boxes of their meshes' roots) built per frame; a ray reaching an
//    instance's box goes into its mesh's hierarchy through the instance's
//    inverse matrix.
// Everything lives in one storage buffer of uvec4 (SSBO_RAY_SCENE), whose
// layout ray_lib.glsl reads:
//   [0]                    header: x TLAS node base, y instance base, z TLAS node count
//   node (2 uvec4)         (lo.xyz bits, left child | first item), (hi.xyz bits, item count; 0: interior);
//                          interior: children at left and left + 1 (node indices of its own hierarchy)
//   mesh triangle (3 uvec4) (v0.xyz bits, slot), e1 bits, e2 bits
//   instance (4 uvec4)     rows of the camera-relative-world -> object matrix (3 x vec4 bits),
//                          (mesh node base, mesh triangle base, slot alpha base (0: opaque), 0)
//   slot alphas            float bits, four per uvec4
// A mesh's hierarchy keeps its own indices (relative), so its block is
// copied unchanged into each frame's buffer.
//
// Transparency: a constant material's alpha (a mix chain averaged, as
// material_alpha_lib.glsl) per instance slot; a shadow ray's transmittance
// is the product of 1 - alpha over the surfaces it passes (Cycles'
// transparent shadows: the Transparent closure's weight is 1 - alpha).
#pragma once

#include "gl_util.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace deferred {

class SceneStore;
struct GpuMesh;

// A mesh's hierarchy: nodes then triangles in ray_lib.glsl's layout
// (node indices and triangle indices relative to its own block).
struct MeshBvh {
    std::vector<glm::uvec4> nodes;      // 2 per node, root first
    std::vector<glm::uvec4> triangles;  // 3 per triangle
    glm::vec3 lo{0.0f}, hi{0.0f};       // the root's box (object space)
    int depth = 0;
};

// Builds the hierarchy of triangles given as 3 float3 corners each, with the
// material slot of each (may be null: slot 0). Degenerate triangles are kept
// (a ray never hits them). Depth is limited to RAY_MAX_DEPTH levels.
MeshBvh build_mesh_bvh(const float* corners, const std::uint32_t* slots, std::size_t triangle_count);

// The mesh's hierarchy, built on first use from its GPU buffers (positions,
// indices in slot order) and kept with the mesh.
std::shared_ptr<const MeshBvh> mesh_bvh(const GpuMesh& mesh);

// Any-hit transmittance of a ray against the scene buffer, on the CPU: the
// reference the GPU traversal is tested against (tests/native/test_rays.cpp).
float trace_transmittance(const std::vector<glm::uvec4>& scene, const glm::vec3& origin, const glm::vec3& dir,
                          float tmax);

// How the programs that trace shadow rays call the traversal: through a
// subroutine (RAY_SUBROUTINE, ray_lib.glsl), so a driver need not compile a
// copy of it per call site, unless DEFERRED_RAY_CALL=inline (the inlined
// calls, for comparing the two on a driver). Adds the define to `defines`.
void add_ray_traversal_define(std::vector<std::string>& defines);
// After glUseProgram of a program that may trace rays (subroutine uniforms
// are reset by every glUseProgram): selects the traversal in `stage`; does
// nothing for a program without the subroutine.
void use_ray_traversal(GLuint program, GLenum stage);

class RayScene {
public:
    // One instance of a mesh: camera-relative model matrix, its slots' alphas
    // (empty or all 1: opaque).
    struct Instance {
        std::shared_ptr<const MeshBvh> bvh;
        glm::dmat4 model;
        std::vector<float> slot_alpha;
    };
    // Builds the buffer: the meshes' blocks, the instances' hierarchy.
    void build(const std::vector<Instance>& instances);
    // The buffer's content (CPU copy, for tests and the CPU reference).
    const std::vector<glm::uvec4>& data() const { return data_; }
    void upload();
    void bind() const;
    std::size_t bytes() const { return data_.size() * sizeof(glm::uvec4); }
    std::size_t instances() const { return instance_count_; }
    std::size_t triangles() const { return triangle_count_; }
    void release();

private:
    std::vector<glm::uvec4> data_;
    std::size_t instance_count_ = 0, triangle_count_ = 0;
    Buffer buffer_;
};

}  // namespace deferred
