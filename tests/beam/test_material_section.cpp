// Material laws and the condensed section stiffness against closed-form section values.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <numbers>

#include "fibra/beam/material.hpp"
#include "fibra/beam/section.hpp"

namespace fibra {
namespace {

MaterialSpec iso(double nu) {
  MaterialSpec m;
  m.young = 70e9;
  m.poisson = nu;
  return m;
}

// Axial stiffness per (1/2 eps9)^2 after the in-section strains (eps0, eps1, eps2) relax.
double relaxed(const GenMat& c, int k) {
  const int idx[4] = {0, 1, 2, k};
  Eigen::Matrix4d m;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m(i, j) = c(idx[i], idx[j]);
  return m(3, 3) - m.block<1, 3>(3, 0) * m.block<3, 3>(0, 0).inverse() * m.block<3, 1>(0, 3);
}

TEST(Material, IsotropicStiffnessIsLame) {
  const MaterialSpec m = iso(0.3);
  const Mat6 d = stiffness_matrix(m);
  const double lambda = m.young * m.poisson / ((1 + m.poisson) * (1 - 2 * m.poisson));
  const double mu = m.young / (2 * (1 + m.poisson));
  EXPECT_NEAR(d(0, 0), lambda + 2 * mu, 1e-6 * mu);
  EXPECT_NEAR(d(0, 1), lambda, 1e-6 * mu);
  EXPECT_NEAR(d(3, 3), mu, 1e-6 * mu);
}

TEST(Material, TransverseComplianceMatchesEngineeringConstants) {
  MaterialSpec m;
  m.model = MaterialSpec::Model::Transverse;
  m.young = 230e9;
  m.poisson = 0.2;
  m.young_transverse = 15e9;
  m.shear_axial = 24e9;
  m.poisson_transverse = 0.4;
  const Mat6 s = stiffness_matrix(m).inverse();
  EXPECT_NEAR(1 / s(2, 2), 230e9, 1e-3 * 230e9);
  EXPECT_NEAR(1 / s(0, 0), 15e9, 1e-3 * 15e9);
  EXPECT_NEAR(-s(0, 2) / s(2, 2), 0.2, 1e-9);  // transverse contraction under axial stress
  EXPECT_NEAR(1 / s(4, 4), 24e9, 1e-3 * 24e9);
}

class SectionPoisson : public ::testing::TestWithParam<double> {};

TEST_P(SectionPoisson, BendingTensionTorsionStiffnessesAreExact) {
  const double nu = GetParam();
  const MaterialSpec m = iso(nu);
  const double a = 0.02, b = 0.013;
  const Section s = make_section(m, a, b);
  const double pi = std::numbers::pi;
  const double area = pi * a * b, i1 = pi * a * b * b * b / 4, i2 = pi * a * a * a * b / 4;
  const double g = m.young / (2 * (1 + nu));
  // Tension: E A for the relaxed section (Poisson contraction free).
  EXPECT_NEAR(relaxed(s.stiffness, 9), m.young * area / 4, 1e-9 * m.young * area);
  // Bending about g2 (curvature eps10) and g1 (eps11): E I, for any Poisson ratio.
  EXPECT_NEAR(s.stiffness(10, 10), m.young * i2, 1e-9 * m.young * i2);
  EXPECT_NEAR(s.stiffness(11, 11), m.young * i1, 1e-9 * m.young * i1);
  // Torsion terms: G int xi2^2 and G int xi1^2 (sum G J for a circle).
  EXPECT_NEAR(s.stiffness(5, 5), g * i1, 1e-9 * g * i1);
  EXPECT_NEAR(s.stiffness(7, 7), g * i2, 1e-9 * g * i2);
  // Without the enhanced modes, bending is locked by (1-nu)/((1+nu)(1-2nu)).
  const Section locked = make_section(m, a, b, false);
  const double factor = (1 - nu) / ((1 + nu) * (1 - 2 * nu));
  EXPECT_NEAR(locked.stiffness(10, 10), factor * m.young * i2, 1e-9 * m.young * i2);
  // Symmetric positive semi-definite.
  EXPECT_LT((s.stiffness - s.stiffness.transpose()).norm(), 1e-12 * s.stiffness.norm());
}

INSTANTIATE_TEST_SUITE_P(PoissonRatios, SectionPoisson, ::testing::Values(0.0, 0.2, 0.3, 0.45, 0.49));

}  // namespace
}  // namespace fibra
