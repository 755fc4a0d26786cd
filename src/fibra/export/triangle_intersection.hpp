#pragma once
/// Whether triangles, and triangulated surfaces, intersect: used to check that the envelopes
/// of different tows do not overlap.
#include <array>
#include <utility>
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/export/triangle_mesh.hpp"

namespace fibra {

using Triangle = std::array<Vec3, 3>;

/// Whether two triangles share a point (touching counts). Not coplanar: an edge of one crosses
/// the other (orientation tests); coplanar: their projections on the plane overlap.
bool triangles_intersect(const Triangle& t, const Triangle& u);

/// The pairs (triangle of a, triangle of b) that intersect, by their indices; the triangles of
/// b are binned by their boxes (box_grid.hpp). Triangles of (nearly) zero area (a contour's
/// repeated vertex) are left out: their points belong to their neighbours too.
std::vector<std::pair<Index, Index>> intersecting_triangles(const TriangleMesh& a, const TriangleMesh& b);

}  // namespace fibra
