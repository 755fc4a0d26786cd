#pragma once
/// The voxels whose centres lie inside a closed triangulated surface, by the parity of its
/// crossings along lines parallel to x through the centres (one line per row of voxels).
/// A line through an edge or a vertex is counted by one triangle only: in the (y, z)
/// projection each triangle owns the edges on one side of a fixed direction (the rule of
/// rasterizers), with the edge functions computed in one order for both triangles of an edge.
#include <functional>

#include "fibra/export/triangle_mesh.hpp"
#include "fibra/export/voxel_grid.hpp"

namespace fibra {

/// Calls visit(voxel index) for every voxel of `grid` whose centre is inside `mesh` (closed),
/// rows in order of (k, j), each row in increasing x.
void for_each_voxel_inside(const TriangleMesh& mesh, const VoxelGrid& grid, const std::function<void(Index)>& visit);

}  // namespace fibra
