#include "fibra/export/triangle_intersection.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "fibra/export/box_grid.hpp"

namespace fibra {

namespace {

/// Six times the signed volume of (a, b, c, d): > 0 when d is on the side of (b - a) x (c - a).
double orient(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) { return (b - a).cross(c - a).dot(d - a); }

int sign(double v) { return (v > 0) - (v < 0); }

/// Whether segment pq meets triangle t, p and q not both in t's plane.
bool segment_meets(const Vec3& p, const Vec3& q, const Triangle& t) {
  const int sp = sign(orient(t[0], t[1], t[2], p)), sq = sign(orient(t[0], t[1], t[2], q));
  if (sp == sq) return false;  // both strictly on one side (both zero is the coplanar case)
  // The line pq passes through the triangle when it turns the same way around its three edges.
  const int s0 = sign(orient(p, q, t[0], t[1])), s1 = sign(orient(p, q, t[1], t[2])),
            s2 = sign(orient(p, q, t[2], t[0]));
  return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

using Point2 = Eigen::Vector2d;

double cross2(const Point2& a, const Point2& b, const Point2& c) {
  return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

bool segments_meet_2d(const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
  const double d1 = cross2(c, d, a), d2 = cross2(c, d, b), d3 = cross2(a, b, c), d4 = cross2(a, b, d);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  auto on = [](const Point2& p, const Point2& q, const Point2& r, double o) {
    return o == 0 && std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) &&
           std::min(p.y(), q.y()) <= r.y() && r.y() <= std::max(p.y(), q.y());
  };
  return on(c, d, a, d1) || on(c, d, b, d2) || on(a, b, c, d3) || on(a, b, d, d4);
}

bool inside_2d(const std::array<Point2, 3>& t, const Point2& p) {
  const double a = cross2(t[0], t[1], p), b = cross2(t[1], t[2], p), c = cross2(t[2], t[0], p);
  return (a >= 0 && b >= 0 && c >= 0) || (a <= 0 && b <= 0 && c <= 0);
}

/// Two triangles in one plane (normal n): projected on the coordinate plane most facing n.
bool coplanar_intersect(const Triangle& t, const Triangle& u, const Vec3& n) {
  Eigen::Index drop = 0;
  n.cwiseAbs().maxCoeff(&drop);
  const int i = drop == 0 ? 1 : 0, j = drop == 2 ? 1 : 2;
  std::array<Point2, 3> a, b;
  for (int k = 0; k < 3; ++k) a[k] = {t[k][i], t[k][j]}, b[k] = {u[k][i], u[k][j]};
  for (int k = 0; k < 3; ++k)
    for (int m = 0; m < 3; ++m)
      if (segments_meet_2d(a[k], a[(k + 1) % 3], b[m], b[(m + 1) % 3])) return true;
  return inside_2d(a, b[0]) || inside_2d(b, a[0]);
}

Eigen::AlignedBox3d triangle_box(const TriangleMesh& mesh, size_t t) {
  Eigen::AlignedBox3d box;
  for (int corner : mesh.triangles[t]) box.extend(mesh.points[corner]);
  return box;
}

/// A triangle of (nearly) zero area: a contour's repeated vertex, up to rounding.
bool sliver(const TriangleMesh& mesh, size_t t) {
  const auto& tri = mesh.triangles[t];
  const Vec3 e1 = mesh.points[tri[1]] - mesh.points[tri[0]], e2 = mesh.points[tri[2]] - mesh.points[tri[0]];
  const double scale = std::max({e1.squaredNorm(), e2.squaredNorm(), (e2 - e1).squaredNorm()});
  return e1.cross(e2).norm() <= 1e-9 * scale;
}

Triangle triangle(const TriangleMesh& mesh, size_t t) {
  const auto& tri = mesh.triangles[t];
  return {mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]};
}

}  // namespace

bool triangles_intersect(const Triangle& t, const Triangle& u) {
  const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
  const bool coplanar =
      orient(t[0], t[1], t[2], u[0]) == 0 && orient(t[0], t[1], t[2], u[1]) == 0 && orient(t[0], t[1], t[2], u[2]) == 0;
  if (coplanar) return coplanar_intersect(t, u, n);
  for (int k = 0; k < 3; ++k)
    if (segment_meets(t[k], t[(k + 1) % 3], u) || segment_meets(u[k], u[(k + 1) % 3], t)) return true;
  return false;
}

std::vector<std::pair<Index, Index>> intersecting_triangles(const TriangleMesh& a, const TriangleMesh& b) {
  std::vector<Eigen::AlignedBox3d> boxes;
  for (size_t t = 0; t < b.triangles.size(); ++t) boxes.push_back(triangle_box(b, t));
  const BoxGrid grid(std::move(boxes));
  const Eigen::AlignedBox3d b_box = mesh_bounds(b);
  std::vector<Index> near;
  std::vector<std::pair<Index, Index>> pairs;
  for (size_t t = 0; t < a.triangles.size(); ++t) {
    const Eigen::AlignedBox3d box = triangle_box(a, t);
    if (!box.intersects(b_box) || sliver(a, t)) continue;
    grid.find(box, near);
    const Triangle ta = triangle(a, t);
    for (Index n : near)
      if (!sliver(b, static_cast<size_t>(n)) && triangles_intersect(ta, triangle(b, n)))
        pairs.emplace_back(static_cast<Index>(t), n);
  }
  return pairs;
}

}  // namespace fibra
