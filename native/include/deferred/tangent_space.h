// MikkTSpace tangents of a triangle mesh for one UV map, computed natively
// for the add-on's export (normal maps, the Tangent node's UV Map mode).
#pragma once

#include <cstddef>
#include <cstdint>

namespace deferred {

// The tangent space of every triangle corner, by Mikkelsen's MikkTSpace
// ("Simulation of Wrinkled Surfaces Revisited", 2008; the reference
// implementation Blender and Cycles ship in intern/mikktspace), over
// triangles as Cycles 3.4 feeds it (intern/cycles/blender/mesh.cpp: one
// MikkTSpace face per triangle of the mesh's loop triangulation, the
// shading normal per corner, the UV map per corner).
//
// Corner c of triangle t is element 3t + c, as everywhere in the exporter.
//   positions:      vertex_count x 3
//   indices:        triangle_count x 3 vertex indices (< vertex_count)
//   corner_normals: 3 triangle_count x 3, unit shading normals
//   corner_uvs:     3 triangle_count x 2
//   flat_triangles: triangle_count flags, or null: a flat-shaded triangle's
//                   corners read the triangle's own normal as Cycles computes
//                   it (scene/mesh.cpp Triangle::compute_normal, float32)
//                   instead of corner_normals. Its zero components carry
//                   either sign, and MikkTSpace welds corners by their bits,
//                   so the triangles of one flat polygon may keep their own
//                   tangents, as in Cycles (visible on n-gons and on UVs
//                   that are not affine across a polygon).
//   tangents (out): 3 triangle_count x 4: the unit tangent and the bitangent
//                   sign (B = sign * cross(N, T)), as Blender's
//                   Mesh.calc_tangents gives `tangent` and `bitangent_sign`.
//
// Deterministic, and the same result on any number of threads: the one
// order-dependent step (grouping) runs in MikkTSpace's order on one thread.
// Throws std::invalid_argument for an index out of range or a mesh of
// 2^31 / 3 triangles or more.
void compute_tangents(const float* positions, std::size_t vertex_count, const std::uint32_t* indices,
                      std::size_t triangle_count, const float* corner_normals, const float* corner_uvs,
                      const bool* flat_triangles, float* tangents);

}  // namespace deferred
