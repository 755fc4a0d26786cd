#include "fibra/body/rotation.hpp"

#include <algorithm>
#include <cmath>

namespace fibra {
namespace {

/// Coefficients of R = I + a K + b K^2 (K = [phi]x, t = |phi|) and of their derivatives:
/// c = a'/t, d = b'/t, e = c'/t, f = d'/t. Taylor series below t = 0.5 (the closed forms
/// cancel catastrophically near 0: f loses 6 digits at t = 0.1), closed forms above.
struct Coefficients {
  double a, b, c, d, e, f;
};

// Taylor coefficients (in powers of t^2, up to t^20) of a, b, c, d, e, f and (1 - a) / t^2;
// below t = 0.5 the truncation error is under 1e-25.
constexpr double kSeries[7][11] = {
    {1.0 / 1.0, -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0, -1.0 / 39916800.0, 1.0 / 6227020800.0, -1.0 / 1307674368000.0, 1.0 / 355687428096000.0, -1.0 / 121645100408832000.0, 1.0 / 51090942171709440000.0},  // a
    {1.0 / 2.0, -1.0 / 24.0, 1.0 / 720.0, -1.0 / 40320.0, 1.0 / 3628800.0, -1.0 / 479001600.0, 1.0 / 87178291200.0, -1.0 / 20922789888000.0, 1.0 / 6402373705728000.0, -1.0 / 2432902008176640000.0, 1.0 / 1124000727777607680000.0},  // b
    {-1.0 / 3.0, 1.0 / 30.0, -1.0 / 840.0, 1.0 / 45360.0, -1.0 / 3991680.0, 1.0 / 518918400.0, -1.0 / 93405312000.0, 1.0 / 22230464256000.0, -1.0 / 6758061133824000.0, 1.0 / 2554547108585472000.0, -1.0 / 1175091669949317120000.0},  // c
    {-1.0 / 12.0, 1.0 / 180.0, -1.0 / 6720.0, 1.0 / 453600.0, -1.0 / 47900160.0, 1.0 / 7264857600.0, -1.0 / 1494484992000.0, 1.0 / 400148356608000.0, -1.0 / 135161222676480000.0, 1.0 / 56200036388880384000.0, -1.0 / 28202200078783610880000.0},  // d
    {1.0 / 15.0, -1.0 / 210.0, 1.0 / 7560.0, -1.0 / 498960.0, 1.0 / 51891840.0, -1.0 / 7783776000.0, 1.0 / 1587890304000.0, -1.0 / 422378820864000.0, 1.0 / 141919283810304000.0, -1.0 / 58754583497465856000.0, 1.0 / 29377291748732928000000.0},  // e
    {1.0 / 90.0, -1.0 / 1680.0, 1.0 / 75600.0, -1.0 / 5987520.0, 1.0 / 726485760.0, -1.0 / 124540416000.0, 1.0 / 28582025472000.0, -1.0 / 8447576417280000.0, 1.0 / 3122224243826688000.0, -1.0 / 1410110003939180544000.0, 1.0 / 763809585467056128000000.0},  // f
    {1.0 / 6.0, -1.0 / 120.0, 1.0 / 5040.0, -1.0 / 362880.0, 1.0 / 39916800.0, -1.0 / 6227020800.0, 1.0 / 1307674368000.0, -1.0 / 355687428096000.0, 1.0 / 121645100408832000.0, -1.0 / 51090942171709440000.0, 1.0 / 25852016738884976640000.0},  // g
};

double series(int which, double t2) {
  double v = 0.0;
  for (int k = 10; k >= 0; --k) v = v * t2 + kSeries[which][k];
  return v;
}

constexpr double kSwitch = 0.5;

Coefficients coefficients(double t) {
  const double t2 = t * t;
  if (t < kSwitch) return {series(0, t2), series(1, t2), series(2, t2), series(3, t2), series(4, t2), series(5, t2)};
  const double s = std::sin(t), co = std::cos(t);
  const double t3 = t2 * t, t4 = t2 * t2, t5 = t4 * t, t6 = t4 * t2;
  return {s / t,
          (1 - co) / t2,
          (t * co - s) / t3,
          (t * s + 2 * co - 2) / t4,
          (-t2 * s - 3 * t * co + 3 * s) / t5,
          (t2 * co - 5 * t * s - 8 * co + 8) / t6};
}

}  // namespace

Mat3 rotation_exp(const Vec3& phi, Mat3* dR, Mat3* d2R) {
  const Coefficients k = coefficients(phi.norm());
  const Mat3 K = skew(phi);
  const Mat3 K2 = K * K;
  const Mat3 R = Mat3::Identity() + k.a * K + k.b * K2;
  if (!dR && !d2R) return R;
  Mat3 G[3], GK[3];  // G_j = [e_j]x, GK_j = G_j K + K G_j
  for (int j = 0; j < 3; ++j) {
    G[j] = skew(Vec3::Unit(j));
    GK[j] = G[j] * K + K * G[j];
  }
  if (dR)
    for (int j = 0; j < 3; ++j) dR[j] = k.c * phi[j] * K + k.a * G[j] + k.d * phi[j] * K2 + k.b * GK[j];
  if (d2R)
    for (int j = 0; j < 3; ++j)
      for (int l = j; l < 3; ++l) {
        const double djl = j == l ? 1.0 : 0.0;
        Mat3 m = (k.e * phi[j] * phi[l] + k.c * djl) * K + k.c * (phi[j] * G[l] + phi[l] * G[j]) +
                 (k.f * phi[j] * phi[l] + k.d * djl) * K2 + k.d * (phi[j] * GK[l] + phi[l] * GK[j]) +
                 k.b * (G[j] * G[l] + G[l] * G[j]);
        d2R[3 * j + l] = m;
        d2R[3 * l + j] = m;
      }
  return R;
}

Vec3 rotation_log(const Mat3& r) {
  const double c = std::clamp(0.5 * (r.trace() - 1.0), -1.0, 1.0);
  const double angle = std::acos(c);
  const Vec3 w = 0.5 * vee_antisymmetric(r);  // sin(angle) * axis
  if (angle < 1e-6) return w;
  if (angle < 3.14159265358979 - 1e-6) return angle / std::sin(angle) * w;
  // Near pi: the axis from the symmetric part, sign from w.
  const Mat3 s = 0.5 * (r + r.transpose()) - c * Mat3::Identity();
  int i = 0;
  s.diagonal().maxCoeff(&i);
  Vec3 axis = s.col(i) / std::sqrt(std::max(s(i, i), 1e-300));
  if (axis.dot(w) < 0) axis = -axis;
  return angle * axis.normalized();
}

Mat3 rotation_tangent(const Vec3& phi) {
  // Spatial angular velocity of R(phi): [w]x = dR R^T with w = T dphi, the left Jacobian
  // T = I + b K + ((1 - a) / t^2) K^2 (series of (1 - a) / t^2 near 0).
  const double t = phi.norm();
  const Coefficients k = coefficients(t);
  const Mat3 K = skew(phi);
  const double g = t < kSwitch ? series(6, t * t) : (1.0 - k.a) / (t * t);
  return Mat3::Identity() + k.b * K + g * K * K;
}

}  // namespace fibra
