#include "fibra/export/mesh_voxelizer.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace fibra {

namespace {

using Point2 = Eigen::Vector2d;

/// (v - u) x (p - u), computed from the lexicographically smaller endpoint so that the two
/// triangles of an edge get the same value up to its sign, exactly.
double edge_function(const Point2& u, const Point2& v, const Point2& p) {
  const bool swap = std::make_pair(v.x(), v.y()) < std::make_pair(u.x(), u.y());
  const Point2& a = swap ? v : u;
  const Point2& b = swap ? u : v;
  const double e = (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
  return swap ? -e : e;
}

/// Whether the counter-clockwise triangle owns its edge u -> v when p lies on it: of an
/// edge's two directions exactly one passes.
bool owns_edge(const Point2& u, const Point2& v) {
  const Point2 d = v - u;
  return d.y() < 0 || (d.y() == 0 && d.x() > 0);
}

/// Whether p is inside the counter-clockwise triangle (a, b, c), edges owned as above.
bool covers(const Point2& a, const Point2& b, const Point2& c, const Point2& p) {
  const Point2* v[3] = {&a, &b, &c};
  for (int k = 0; k < 3; ++k) {
    const Point2& u = *v[k];
    const Point2& w = *v[(k + 1) % 3];
    const double e = edge_function(u, w, p);
    if (e < 0 || (e == 0 && !owns_edge(u, w))) return false;
  }
  return true;
}

/// The x where the line {y, z} = p meets the plane of triangle t (not parallel to x).
double crossing_x(const Vec3& a, const Vec3& b, const Vec3& c, const Point2& p) {
  const Vec3 n = (b - a).cross(c - a);
  return a.x() - (n.y() * (p.x() - a.y()) + n.z() * (p.y() - a.z())) / n.x();
}

}  // namespace

void for_each_voxel_inside(const TriangleMesh& mesh, const VoxelGrid& grid, const std::function<void(Index)>& visit) {
  const Index ny = grid.count[1], nz = grid.count[2];
  auto row_range = [&](double lo, double hi, int axis, Index n) {
    // Rows whose centre coordinate lies in [lo, hi].
    const double first = std::ceil((lo - grid.origin[axis]) / grid.spacing[axis] - 0.5);
    const double last = std::floor((hi - grid.origin[axis]) / grid.spacing[axis] - 0.5);
    return std::make_pair(static_cast<Index>(std::max(first, 0.0)),
                          static_cast<Index>(std::min(last, static_cast<double>(n - 1))));
  };
  std::vector<std::pair<Index, double>> crossings;  // (row j + ny k, x)
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
    Point2 pa(a.y(), a.z()), pb(b.y(), b.z()), pc(c.y(), c.z());
    const double area = edge_function(pa, pb, pc);
    if (area == 0) continue;  // parallel to x: its neighbours account for the crossing
    if (area < 0) std::swap(pb, pc);
    const auto [j0, j1] = row_range(std::min({a.y(), b.y(), c.y()}), std::max({a.y(), b.y(), c.y()}), 1, ny);
    const auto [k0, k1] = row_range(std::min({a.z(), b.z(), c.z()}), std::max({a.z(), b.z(), c.z()}), 2, nz);
    for (Index k = k0; k <= k1; ++k)
      for (Index j = j0; j <= j1; ++j) {
        const Vec3 centre = grid.center(0, j, k);
        const Point2 p(centre.y(), centre.z());
        if (covers(pa, pb, pc, p)) crossings.emplace_back(j + ny * k, crossing_x(a, b, c, p));
      }
  }
  std::sort(crossings.begin(), crossings.end());
  for (size_t n = 0; n < crossings.size();) {
    size_t end = n;
    while (end < crossings.size() && crossings[end].first == crossings[n].first) ++end;
    const Index row = crossings[n].first, j = row % ny, k = row / ny;
    // Inside between the first and second crossing, the third and fourth, ...
    for (size_t m = n; m + 1 < end; m += 2) {
      const double lo = crossings[m].second, hi = crossings[m + 1].second;
      const double first = std::ceil((lo - grid.origin.x()) / grid.spacing.x() - 0.5);
      const double last = std::floor((hi - grid.origin.x()) / grid.spacing.x() - 0.5);
      for (Index i = static_cast<Index>(std::max(first, 0.0));
           i <= static_cast<Index>(std::min(last, static_cast<double>(grid.count[0] - 1))); ++i)
        visit(grid.index(i, j, k));
    }
    n = end;
  }
}

}  // namespace fibra
