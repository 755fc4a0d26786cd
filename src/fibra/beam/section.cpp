#include "fibra/beam/section.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <numbers>

#include "fibra/beam/material.hpp"

namespace fibra {
namespace {

constexpr int kEnhanced = 15;  // 5 zero-mean modes for each of E11, E22, 2E12
constexpr int kAll = kGenStrains + kEnhanced;
using BMat = Eigen::Matrix<double, 6, kAll>;

// Voigt rows: 0 E11, 1 E22, 2 E33, 3 2E23, 4 2E13, 5 2E12.
BMat strain_map(double x1, double x2, double m11, double m22) {
  BMat bm = BMat::Zero();
  bm(0, 0) = 0.5;
  bm(1, 1) = 0.5;
  bm(5, 2) = 1.0;
  bm(4, 3) = 1.0;
  bm(4, 4) = x1;
  bm(4, 5) = x2;
  bm(3, 6) = 1.0;
  bm(3, 7) = x1;
  bm(3, 8) = x2;
  bm(2, 9) = 0.5;
  bm(2, 10) = x1;
  bm(2, 11) = x2;
  bm(2, 12) = 0.5 * x1 * x1;
  bm(2, 13) = x1 * x2;
  bm(2, 14) = 0.5 * x2 * x2;
  const double modes[5] = {x1, x2, x1 * x1 - m11, x1 * x2, x2 * x2 - m22};
  const int rows[3] = {0, 1, 5};
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 5; ++k) bm(rows[r], kGenStrains + 5 * r + k) = modes[k];
  return bm;
}

}  // namespace

Section make_section(const MaterialSpec& material, double a, double b, bool enhanced) {
  Section s;
  const double pi = std::numbers::pi;
  s.a = a;
  s.b = b;
  s.area = pi * a * b;
  s.inertia_1 = pi * a * b * b * b / 4.0;
  s.inertia_2 = pi * a * a * a * b / 4.0;
  const double m11 = a * a / 4.0, m22 = b * b / 4.0;  // section means of xi1^2, xi2^2
  const Mat6 d = stiffness_matrix(material);

  // Polar product rule on the ellipse: exact for the degree-4 polynomial integrand
  // (4-point Gauss–Legendre in rho with weight rho, 16 equal angles).
  const double gx[4] = {0.0694318442029737, 0.3300094782075719, 0.6699905217924281, 0.9305681557970263};
  const double gw[4] = {0.1739274225687269, 0.3260725774312731, 0.3260725774312731, 0.1739274225687269};
  constexpr int n_theta = 16;
  Eigen::Matrix<double, kAll, kAll> k = Eigen::Matrix<double, kAll, kAll>::Zero();
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < n_theta; ++j) {
      const double th = 2.0 * pi * j / n_theta;
      const double x1 = a * gx[i] * std::cos(th), x2 = b * gx[i] * std::sin(th);
      const double w = gw[i] * gx[i] * (2.0 * pi / n_theta) * a * b;
      const BMat bm = strain_map(x1, x2, m11, m22);
      k.noalias() += w * bm.transpose() * d * bm;
    }
  }
  const GenMat kee = k.topLeftCorner<kGenStrains, kGenStrains>();
  auto split = [](Section& out) {
    out.stiffness_inplane = out.stiffness.topLeftCorner<3, 3>();
  };
  if (!enhanced) {
    s.stiffness = kee;
    split(s);
    return s;
  }
  const auto kea = k.topRightCorner<kGenStrains, kEnhanced>();
  const Eigen::Matrix<double, kEnhanced, kEnhanced> kaa = k.bottomRightCorner<kEnhanced, kEnhanced>();
  const GenMat c = kee - kea * kaa.ldlt().solve(kea.transpose());
  s.stiffness = 0.5 * (c + c.transpose());
  split(s);
  return s;
}

}  // namespace fibra
