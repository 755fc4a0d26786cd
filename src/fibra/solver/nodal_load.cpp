#include "fibra/solver/nodal_load.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace fibra {
namespace {

// Weight of a section vector whose reference projection on the moment plane has squared
// length p (the other's q); a vector along the axis up to rounding gets exactly 0, so it
// adds no (spurious, indefinite) stiffness.
double moment_weight(double p, double q) {
  if (p < 1e-24 * (p + q)) return 0.0;
  if (q < 1e-24 * (p + q)) return 1.0;
  return p / (p + q);
}

}  // namespace

Vec6 moment_generalized_force(const Vec3& moment, const Vec3& rg1, const Vec3& rg2, const Vec3& g1,
                              const Vec3& g2, Mat6x6* dforce) {
  Vec6 f = Vec6::Zero();
  if (dforce) dforce->setZero();
  const double mag = moment.norm();
  if (mag == 0.0) return f;
  const Vec3 n = moment / mag;
  const Mat3 proj = Mat3::Identity() - n * n.transpose();
  const double p1 = (proj * rg1).squaredNorm(), p2 = (proj * rg2).squaredNorm();
  const double w[2] = {moment_weight(p1, p2), moment_weight(p2, p1)};
  Mat3 skew;
  skew << 0, -n.z(), n.y(), n.z(), 0, -n.x(), -n.y(), n.x(), 0;
  const Vec3* gs[2] = {&g1, &g2};
  for (int a = 0; a < 2; ++a) {
    if (w[a] == 0.0) continue;
    const Vec3 p = proj * (*gs[a]);
    const double rho2 = p.squaredNorm();
    const Vec3 np = n.cross(p);
    f.segment<3>(3 * a) = mag * w[a] * np / rho2;
    if (dforce) dforce->block<3, 3>(3 * a, 3 * a) = mag * w[a] * (skew / rho2 - 2.0 * np * p.transpose() / (rho2 * rho2));
  }
  return f;
}

double moment_work(const Vec3& moment, const Vec3& rg1, const Vec3& rg2, const Vec3& h1, const Vec3& h2,
                   const Vec3& g1, const Vec3& g2) {
  const double mag = moment.norm();
  if (mag == 0.0) return 0.0;
  const Vec3 n = moment / mag;
  const Mat3 proj = Mat3::Identity() - n * n.transpose();
  const double p1 = (proj * rg1).squaredNorm(), p2 = (proj * rg2).squaredNorm();
  const double w[2] = {moment_weight(p1, p2), moment_weight(p2, p1)};
  const Vec3* from[2] = {&h1, &h2};
  const Vec3* to[2] = {&g1, &g2};
  double work = 0.0;
  for (int a = 0; a < 2; ++a) {
    if (w[a] == 0.0) continue;
    const Vec3 u = proj * (*from[a]), v = proj * (*to[a]);
    work += mag * w[a] * std::atan2(n.dot(u.cross(v)), u.dot(v));
  }
  return work;
}

}  // namespace fibra
