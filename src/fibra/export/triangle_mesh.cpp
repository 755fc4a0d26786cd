#include "fibra/export/triangle_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace fibra {

double signed_volume(const TriangleMesh& mesh) {
  // About the first point rather than the origin: the same volume, without the cancellation of
  // large terms for a mesh far from the origin.
  if (mesh.points.empty()) return 0.0;
  const Vec3 o = mesh.points.front();
  double six_v = 0.0;
  for (const auto& t : mesh.triangles)
    six_v += (mesh.points[t[0]] - o).dot((mesh.points[t[1]] - o).cross(mesh.points[t[2]] - o));
  return six_v / 6.0;
}

Index unpaired_edges(const TriangleMesh& mesh) {
  // Each directed edge (a, b) must appear once and its reverse (b, a) once: sorting the
  // directed edges makes both checks a scan.
  std::vector<std::pair<int, int>> directed;
  directed.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) directed.emplace_back(t[k], t[(k + 1) % 3]);
  std::sort(directed.begin(), directed.end());
  Index unpaired = 0;
  for (size_t i = 0; i < directed.size(); ++i) {
    const bool repeated = (i > 0 && directed[i] == directed[i - 1]);
    const auto reverse = std::make_pair(directed[i].second, directed[i].first);
    const auto range = std::equal_range(directed.begin(), directed.end(), reverse);
    if (repeated || range.second - range.first != 1) ++unpaired;
  }
  return unpaired;
}

double winding_number(const TriangleMesh& mesh, const Vec3& p) {
  // Solid angle of each triangle seen from p (Van Oosterom and Strackee, 1983).
  double total = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3 a = mesh.points[t[0]] - p, b = mesh.points[t[1]] - p, c = mesh.points[t[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2.0 * std::atan2(numerator, denominator);
  }
  return total / (4.0 * std::numbers::pi);
}

namespace {

/// The point of triangle (a, b, c) nearest to p, by the region of p (Ericson, Real-Time
/// Collision Detection, 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

}  // namespace

double distance_to_surface(const TriangleMesh& mesh, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.triangles)
    best = std::min(best, (closest_on_triangle(p, mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]]) - p).norm());
  return best;
}

Eigen::AlignedBox3d mesh_bounds(const TriangleMesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const Vec3& p : mesh.points) box.extend(p);
  return box;
}

Vec3 triangle_normal(const TriangleMesh& mesh, size_t t) {
  const auto& tri = mesh.triangles[t];
  const Vec3 n = (mesh.points[tri[1]] - mesh.points[tri[0]]).cross(mesh.points[tri[2]] - mesh.points[tri[0]]);
  const double norm = n.norm();
  return norm > 0 ? Vec3(n / norm) : Vec3::Zero();
}

}  // namespace fibra
