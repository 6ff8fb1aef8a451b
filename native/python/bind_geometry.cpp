// Mesh computations the add-on's export hands to native code: MikkTSpace
// tangents (deferred/tangent_space.h), where Blender's Mesh.calc_tangents
// needs a temporary mesh copy and refuses n-gons; the Geometry node's
// Pointiness and Random Per Island (deferred/mesh_attributes.h), which
// Blender does not expose and which loop over every vertex and edge.
#include "bindings.h"

#include <deferred/mesh_attributes.h>
#include <deferred/tangent_space.h>

#include <stdexcept>

namespace deferred::python {

void declare_geometry(py::module_& m) {
    m.def(
        "compute_tangents",
        [](const py::handle& positions, const py::handle& indices, const py::handle& corner_normals,
           const py::handle& corner_uvs, const py::handle& flat_triangles) {
            py::ssize_t vertex_count = 0, triangle_count = 0, normal_count = 0, uv_count = 0;
            const float* p = borrow<float>(positions, "positions", {-1, 3}, &vertex_count);
            const std::uint32_t* idx = borrow<std::uint32_t>(indices, "indices", {-1, 3}, &triangle_count);
            const float* n = borrow<float>(corner_normals, "corner_normals", {-1, 3}, &normal_count);
            const float* uv = borrow<float>(corner_uvs, "corner_uvs", {-1, 2}, &uv_count);
            if (normal_count != 3 * triangle_count || uv_count != 3 * triangle_count)
                throw py::value_error("compute_tangents: corner_normals and corner_uvs need 3 rows per triangle (" +
                                      std::to_string(3 * triangle_count) + "), got " + std::to_string(normal_count) +
                                      " and " + std::to_string(uv_count));
            const bool* flat = nullptr;
            if (!flat_triangles.is_none()) {
                py::ssize_t flat_count = 0;
                flat = borrow<bool>(flat_triangles, "flat_triangles", {-1}, &flat_count);
                if (flat_count != triangle_count)
                    throw py::value_error("compute_tangents: flat_triangles needs one entry per triangle (" +
                                          std::to_string(triangle_count) + "), got " + std::to_string(flat_count));
            }
            py::array_t<float> out({py::ssize_t(3 * triangle_count), py::ssize_t(4)});
            float* o = out.mutable_data();
            try {
                py::gil_scoped_release release;  // the arrays stay referenced by the caller's frame
                compute_tangents(p, std::size_t(vertex_count), idx, std::size_t(triangle_count), n, uv, flat, o);
            } catch (const std::invalid_argument& ex) {
                throw py::value_error(ex.what());
            }
            return out;
        },
        py::arg("positions"), py::arg("indices"), py::arg("corner_normals"), py::arg("corner_uvs"),
        py::arg("flat_triangles") = py::none(),
        "MikkTSpace tangents over triangles, as Cycles computes them for a UV map: float32 (V,3) "
        "positions, uint32 (T,3) indices, float32 (3T,3) unit corner normals and (3T,2) corner UVs, optional bool (T,) "
        "flat-shaded triangles (MikkTSpace reads their own normal, as in Cycles) -> "
        "float32 (3T,4): tangent xyz and bitangent sign per corner (Blender's Mesh.calc_tangents layout).");

    m.def(
        "compute_pointiness",
        [](const py::handle& positions, const py::handle& vertex_normals, const py::handle& edges) {
            py::ssize_t vertex_count = 0, normal_count = 0, edge_count = 0;
            const float* p = borrow<float>(positions, "positions", {-1, 3}, &vertex_count);
            const float* n = borrow<float>(vertex_normals, "vertex_normals", {-1, 3}, &normal_count);
            const std::uint32_t* e = borrow<std::uint32_t>(edges, "edges", {-1, 2}, &edge_count);
            if (normal_count != vertex_count)
                throw py::value_error("compute_pointiness: one vertex normal per vertex (" +
                                      std::to_string(vertex_count) + "), got " + std::to_string(normal_count));
            py::array_t<float> out(vertex_count);
            float* o = out.mutable_data();
            try {
                py::gil_scoped_release release;
                compute_pointiness(p, n, std::size_t(vertex_count), e, std::size_t(edge_count), o);
            } catch (const std::invalid_argument& ex) {
                throw py::value_error(ex.what());
            }
            return out;
        },
        py::arg("positions"), py::arg("vertex_normals"), py::arg("edges"),
        "Cycles' Pointiness per vertex: float32 (V,3) positions and vertex normals, uint32 (E,2) edges -> "
        "float32 (V,).");
    m.def(
        "compute_random_per_island",
        [](py::ssize_t vertex_count, const py::handle& edges, const py::handle& first_vertices) {
            py::ssize_t edge_count = 0, triangle_count = 0;
            const std::uint32_t* e = borrow<std::uint32_t>(edges, "edges", {-1, 2}, &edge_count);
            const std::uint32_t* f = borrow<std::uint32_t>(first_vertices, "first_vertices", {-1}, &triangle_count);
            if (vertex_count < 0) throw py::value_error("compute_random_per_island: negative vertex count");
            py::array_t<float> out(triangle_count);
            float* o = out.mutable_data();
            try {
                py::gil_scoped_release release;
                compute_random_per_island(std::size_t(vertex_count), e, std::size_t(edge_count), f,
                                          std::size_t(triangle_count), o);
            } catch (const std::invalid_argument& ex) {
                throw py::value_error(ex.what());
            }
            return out;
        },
        py::arg("vertex_count"), py::arg("edges"), py::arg("first_vertices"),
        "Cycles' Random Per Island per triangle: the vertex count, uint32 (E,2) edges and (T,) the vertex of "
        "each triangle's first corner -> float32 (T,).");
}

}  // namespace deferred::python
