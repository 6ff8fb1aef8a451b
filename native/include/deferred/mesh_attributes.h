// Per-mesh values the Geometry node reads, computed as Cycles 3.4 does in
// its Blender sync (intern/cycles/blender/mesh.cpp), for the add-on's export.
#pragma once

#include <cstddef>
#include <cstdint>

namespace deferred {

// Pointiness per vertex (attr_create_pointiness): a vertex welds to a later
// one in Cycles' order by coordinate sum whose sum is within 3 FLT_EPSILON
// and whose squared distance is below FLT_EPSILON; the welded vertex normal
// is the normalised sum of theirs, and a vertex's raw value is
// acos(N . mean of its unit edge directions) / pi over its distinct edges;
// then each value is averaged with its neighbours' (one blur step over the
// edges). positions, vertex_normals: vertex_count x 3; edges: edge_count x 2
// vertex indices; out: vertex_count. An edge whose two ends weld into one
// vertex gives that vertex 1, as in Cycles (a zero vector normalised is
// NaN, which Cycles' clamp turns into -1).
void compute_pointiness(const float* positions, const float* vertex_normals, std::size_t vertex_count,
                        const std::uint32_t* edges, std::size_t edge_count, float* out);

// Random Per Island per triangle (attr_create_random_per_island): Cycles'
// DisjointSet (union by rank, path compression) joins the two ends of every
// edge in order, and a triangle gets hash_uint_to_float(root of the set of
// its first corner's vertex). first_vertices: triangle_count vertex indices.
void compute_random_per_island(std::size_t vertex_count, const std::uint32_t* edges, std::size_t edge_count,
                               const std::uint32_t* first_vertices, std::size_t triangle_count, float* out);

}  // namespace deferred
