#include "fibra/export/fiber_curve.hpp"

#include <algorithm>
#include <cmath>

namespace fibra {

SectionPoint element_point(const VecX& q, const BeamElement& e, double eta) {
  double n[3], dn[3];
  beam_shape(eta, n, dn);
  SectionPoint p;
  const double* node = q.data() + e.first_dof;
  for (int a = 0; a < kElementNodes; ++a, node += kNodeDofs) {
    const Eigen::Map<const Vec3> x(node), g1(node + 3), g2(node + 6);
    p.x += n[a] * x;
    p.dx += dn[a] * x;
    p.g1 += n[a] * g1;
    p.g2 += n[a] * g2;
    p.dg1 += dn[a] * g1;
    p.dg2 += dn[a] * g2;
  }
  return p;
}

SectionPoint fiber_point(const Model& model, const VecX& q, const Fiber& fiber, double t, Index* element) {
  const double clamped = std::clamp(t, 0.0, static_cast<double>(fiber.num_elements));
  const Index local = std::min<Index>(static_cast<Index>(std::floor(clamped)), fiber.num_elements - 1);
  const Index e = fiber.first_element + local;
  if (element) *element = e;
  return element_point(q, model.elements[e], 2.0 * (clamped - static_cast<double>(local)) - 1.0);
}

double section_support(const Vec3& g1, const Vec3& g2, double a, double b, const Vec3& n) {
  return std::hypot(a * g1.dot(n), b * g2.dot(n));
}

}  // namespace fibra
