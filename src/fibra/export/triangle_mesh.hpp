#pragma once
/// Triangulated surfaces (the tows' envelopes) and the checks that make them solids: closed
/// (every edge shared by exactly two triangles, in opposite directions) and outward (positive
/// enclosed volume).
#include <array>
#include <vector>

#include <Eigen/Geometry>

#include "fibra/core/types.hpp"

namespace fibra {

/// Points and triangles (indices into points; counter-clockwise seen from outside).
struct TriangleMesh {
  std::vector<Vec3> points;  ///< [m]
  std::vector<std::array<int, 3>> triangles;
};

/// Signed volume enclosed by a closed mesh, sum of the tetrahedra (0, a, b, c) / 6: positive
/// when the triangles face outward [m^3].
double signed_volume(const TriangleMesh& mesh);

/// Number of edges not shared by exactly two triangles that run through them in opposite
/// directions: 0 for a closed, consistently oriented surface.
Index unpaired_edges(const TriangleMesh& mesh);

/// Winding number of a closed mesh around p (sum of the triangles' solid angles over 4 pi): 1
/// inside an outward surface, 0 outside, undefined on it.
double winding_number(const TriangleMesh& mesh, const Vec3& p);

/// Distance from p to the nearest point of the mesh's triangles (all of them tested) [m].
double distance_to_surface(const TriangleMesh& mesh, const Vec3& p);

/// Bounding box of the points [m].
Eigen::AlignedBox3d mesh_bounds(const TriangleMesh& mesh);

/// Unit normal of triangle t (zero for a degenerate one).
Vec3 triangle_normal(const TriangleMesh& mesh, size_t t);

}  // namespace fibra
