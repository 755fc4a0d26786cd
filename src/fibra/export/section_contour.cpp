#include "fibra/export/section_contour.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace fibra {

namespace {

Eigen::Vector2d normal(int j, int m) {
  const double angle = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(m);
  return {std::cos(angle), std::sin(angle)};
}

/// The point where the lines {n1 . v = h1} and {n2 . v = h2} meet (n1, n2 not parallel).
Eigen::Vector2d meet(const Eigen::Vector2d& n1, double h1, const Eigen::Vector2d& n2, double h2) {
  const double det = n1.x() * n2.y() - n1.y() * n2.x();
  return {(h1 * n2.y() - h2 * n1.y()) / det, (n1.x() * h2 - n2.x() * h1) / det};
}

/// The supports of the polygon {x : n_j . x <= h_j for all j} itself: h_j lowered to the
/// largest n_j . x over its corners (the square of half-side `reach` clipped by every
/// half-plane), so that a line moved inward less than its neighbours, which no longer bounds
/// the polygon, passes through a corner instead of crossing the polygon.
std::vector<double> polygon_supports(const std::vector<double>& h, double reach) {
  const int m = static_cast<int>(h.size());
  std::vector<Eigen::Vector2d> poly = {{-reach, -reach}, {reach, -reach}, {reach, reach}, {-reach, reach}};
  for (int j = 0; j < m && !poly.empty(); ++j) {
    const Eigen::Vector2d n = normal(j, m);
    std::vector<Eigen::Vector2d> kept;  // Sutherland-Hodgman against n . x <= h_j
    for (size_t i = 0; i < poly.size(); ++i) {
      const Eigen::Vector2d& p = poly[i];
      const Eigen::Vector2d& q = poly[(i + 1) % poly.size()];
      const double dp = n.dot(p) - h[j], dq = n.dot(q) - h[j];
      if (dp <= 0) kept.push_back(p);
      if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) kept.push_back(p + (q - p) * (dp / (dp - dq)));
    }
    poly = std::move(kept);
  }
  std::vector<double> support(h);
  for (int j = 0; j < m && !poly.empty(); ++j) {
    double best = -std::numeric_limits<double>::infinity();
    for (const Eigen::Vector2d& p : poly) best = std::max(best, normal(j, m).dot(p));
    support[j] = std::min(h[j], best);
  }
  return support;
}

}  // namespace

double hull_support(const std::vector<PlaneEllipse>& ellipses, const Eigen::Vector2d& n) {
  double h = -std::numeric_limits<double>::infinity();
  for (const PlaneEllipse& e : ellipses)
    h = std::max(h, e.center.dot(n) + std::hypot(e.axis_a.dot(n), e.axis_b.dot(n)));
  return h;
}

std::vector<Eigen::Vector2d> circumscribed_contour(const std::vector<PlaneEllipse>& ellipses,
                                                   const std::vector<double>& insets) {
  const int m = static_cast<int>(insets.size());
  std::vector<double> h(m);
  bool inset = false;
  double reach = 0;
  for (int j = 0; j < m; ++j) {
    h[j] = hull_support(ellipses, normal(j, m)) - insets[j];
    inset = inset || insets[j] != 0;
    reach = std::max(reach, std::abs(h[j]));
  }
  if (inset) h = polygon_supports(h, 4.0 * reach + 1e-300);
  std::vector<Eigen::Vector2d> vertices(m);
  for (int j = 0; j < m; ++j) vertices[j] = meet(normal(j, m), h[j], normal(j + 1, m), h[(j + 1) % m]);
  return vertices;
}

double smallest_width(const std::vector<PlaneEllipse>& ellipses, int m) {
  double width = std::numeric_limits<double>::infinity();
  for (int j = 0; j < m; ++j) {
    const Eigen::Vector2d n = normal(j, m);
    width = std::min(width, hull_support(ellipses, n) + hull_support(ellipses, -n));
  }
  return width;
}

}  // namespace fibra
