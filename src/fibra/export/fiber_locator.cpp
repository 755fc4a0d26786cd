#include "fibra/export/fiber_locator.hpp"

#include <algorithm>
#include <cmath>

#include "fibra/export/fiber_curve.hpp"

namespace fibra {

namespace {

/// Parameter of the section plane through p, or nothing when Newton does not settle in
/// [-1, 1] (the point belongs to a neighbouring element, or to none).
std::optional<double> section_parameter(const VecX& q, const BeamElement& el, const Vec3& p) {
  const SectionPoint a = element_point(q, el, -1.0), b = element_point(q, el, 1.0);
  const Vec3 chord = b.x - a.x;
  const double along = chord.squaredNorm() > 0 ? (p - a.x).dot(chord) / chord.squaredNorm() : 0.5;
  double eta = 2.0 * std::clamp(along, -0.25, 1.25) - 1.0;
  for (int iteration = 0; iteration < 12; ++iteration) {
    const SectionPoint s = element_point(q, el, eta);
    const Vec3 r = p - s.x, n = s.g1.cross(s.g2);
    const double f = r.dot(n);
    const double slope = -s.dx.dot(n) + r.dot(s.dg1.cross(s.g2) + s.g1.cross(s.dg2));
    if (slope == 0.0) return std::nullopt;
    const double step = f / slope;
    eta = std::clamp(eta - step, -2.0, 2.0);
    // A point on an end section lands on eta = +-1 up to rounding: kept, at the end.
    if (std::abs(step) < 1e-10)
      return std::abs(eta) <= 1.0 + 1e-9 ? std::optional<double>(std::clamp(eta, -1.0, 1.0)) : std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

std::optional<FiberHit> element_hit(const Model& model, const VecX& q, Index e, const Vec3& p) {
  const BeamElement& el = model.elements[e];
  const std::optional<double> eta = section_parameter(q, el, p);
  if (!eta) return std::nullopt;
  const SectionPoint s = element_point(q, el, *eta);
  // p - x lies in the plane of g1 and g2: its coordinates from the 2 x 2 normal equations.
  const Vec3 r = p - s.x;
  Eigen::Matrix2d m;
  m << s.g1.dot(s.g1), s.g1.dot(s.g2), s.g1.dot(s.g2), s.g2.dot(s.g2);
  const Eigen::Vector2d xi = m.inverse() * Eigen::Vector2d(r.dot(s.g1), r.dot(s.g2));
  const Section& section = model.sections[el.section];
  const double u = xi[0] / section.a, v = xi[1] / section.b;
  if (u * u + v * v > 1.0) return std::nullopt;
  return FiberHit{el.fiber, s.dx.normalized()};
}

FiberLocator::FiberLocator(const Model& model, const VecX& q) : m_model(model), m_q(q), m_grid(model, q) {
  m_capsules.reserve(model.elements.size());
  for (const BeamElement& el : model.elements) {
    const Section& section = model.sections[el.section];
    const double* node = q.data() + el.first_dof;
    double reach = 0;
    for (int k = 0; k < kElementNodes; ++k) {
      const Eigen::Map<const Vec3> g1(node + kNodeDofs * k + 3), g2(node + kNodeDofs * k + 6);
      reach = std::max(reach, section.a * g1.norm() + section.b * g2.norm());
    }
    const Eigen::Map<const Vec3> x0(node), x1(node + kNodeDofs), x2(node + 2 * kNodeDofs);
    // The sections between the nodes are bounded as in element_box: by the control points of g.
    const Eigen::Map<const Vec3> g1_0(node + 3), g1_1(node + kNodeDofs + 3), g1_2(node + 2 * kNodeDofs + 3);
    const Eigen::Map<const Vec3> g2_0(node + 6), g2_1(node + kNodeDofs + 6), g2_2(node + 2 * kNodeDofs + 6);
    reach = std::max(reach, section.a * (2.0 * g1_1 - 0.5 * (g1_0 + g1_2)).norm() +
                                section.b * (2.0 * g2_1 - 0.5 * (g2_0 + g2_2)).norm());
    m_capsules.push_back({Vec3(x0), Vec3(x2), (x1 - 0.5 * (x0 + x2)).norm() + reach});
  }
}

std::optional<FiberHit> FiberLocator::find(const Vec3& p, const std::vector<Index>& candidates) const {
  for (Index e : candidates) {
    const Capsule& c = m_capsules[e];
    const Vec3 ab = c.b - c.a;
    const double t = ab.squaredNorm() > 0 ? std::clamp((p - c.a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    if ((c.a + t * ab - p).squaredNorm() > c.radius * c.radius) continue;
    if (auto hit = element_hit(m_model, m_q, e, p)) return hit;
  }
  return std::nullopt;
}

}  // namespace fibra
