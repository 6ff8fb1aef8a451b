// The scene as the GPU sees it: validated meshes uploaded once (shared by all
// their instances), plus the CPU-side records of instances, materials,
// lights and world that are packed per frame (camera-relative) by the
// renderer's modules.
#pragma once

#include "gl_util.h"

#include <deferred/scene.h>

#include <cstdint>
#include <vector>

namespace deferred {

struct GpuMesh {
    Buffer positions, indices, normals, uvs, material_indices;
    std::uint32_t triangle_count = 0;
    std::uint32_t flags = 0;          // 1 normals, 2 uvs, 4 material indices (geometry_vert.glsl)
    std::int32_t max_material_index = 0;
};

struct InstanceBatch {
    std::uint32_t mesh_id;
    std::vector<double> matrices;             // 16 per instance, column-major
    std::vector<std::uint32_t> object_indices; // one per instance
    std::vector<std::uint32_t> material_slots; // slot -> material id
};

class SceneStore {
public:
    void clear();
    std::uint32_t add_mesh(const MeshData& mesh);  // validates, uploads
    std::uint32_t add_material(const Material& m);
    void add_instances(std::uint32_t mesh_id, const double* matrices, std::size_t count,
                       const std::uint32_t* object_indices, const std::vector<std::uint32_t>& slots);
    void add_light(const Light& light);
    void set_world(const World& world);

    const std::vector<GpuMesh>& meshes() const { return meshes_; }
    const std::vector<InstanceBatch>& batches() const { return batches_; }
    const std::vector<Material>& materials() const { return materials_; }
    const std::vector<Light>& lights() const { return lights_; }
    const World& world() const { return world_; }
    std::size_t instance_count() const { return instance_count_; }

private:
    std::vector<GpuMesh> meshes_;
    std::vector<InstanceBatch> batches_;
    std::vector<Material> materials_;
    std::vector<Light> lights_;
    World world_;
    std::size_t instance_count_ = 0;
};

}  // namespace deferred
