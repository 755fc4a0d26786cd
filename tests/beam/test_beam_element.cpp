// Beam element: exact gradient and Hessian against finite differences over random large
// deformations, zero force under rigid motions, symmetric tangent, six zero-energy modes.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <random>

#include "fibra/beam/beam_element.hpp"
#include "fibra/beam/section.hpp"
#include "fibra/model/fiber_path.hpp"
#include "support/finite_difference.hpp"

namespace fibra {
namespace {

MaterialSpec steel() {
  MaterialSpec m;
  m.name = "steel";
  m.young = 2.0e11;
  m.poisson = 0.3;
  return m;
}

MaterialSpec carbon() {
  MaterialSpec m;
  m.name = "carbon";
  m.model = MaterialSpec::Model::Transverse;
  m.young = 230e9;
  m.poisson = 0.2;
  m.young_transverse = 15e9;
  m.shear_axial = 24e9;
  m.poisson_transverse = 0.45;
  return m;
}

// An element on a curved (arc) or straight reference path.
struct Sample {
  BeamElement element;
  Section section;
  ElemVec ref;
};

Sample make_sample(const MaterialSpec& mat, bool curved, double radius = 0.05) {
  PathSpec p;
  if (curved) {
    p.kind = PathSpec::Kind::Arc;
    p.radius = 2.0;
    p.angle = 0.6;
    p.axis = Vec3(0.2, 0.3, 1.0).normalized();
  } else {
    p.points = {Vec3(0, 0, 0), Vec3(0.7, 0.2, -0.1)};
  }
  const auto frames = sample_path(p, 3, std::nullopt);
  Sample s;
  for (int a = 0; a < 3; ++a) {
    s.ref.segment<3>(9 * a) = frames[a].position;
    s.ref.segment<3>(9 * a + 3) = frames[a].g1;
    s.ref.segment<3>(9 * a + 6) = frames[a].g2;
  }
  s.section = make_section(mat, radius, radius * (curved ? 0.7 : 1.0));
  beam_reference(s.ref.data(), s.element);
  return s;
}

ElemVec random_state(const ElemVec& ref, std::mt19937& rng, double amplitude) {
  std::uniform_real_distribution<double> u(-1, 1);
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(3.0 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
  const Vec3 shift(u(rng), u(rng), u(rng));
  ElemVec q;
  for (int a = 0; a < 3; ++a) {
    q.segment<3>(9 * a) = rot * ref.segment<3>(9 * a) + shift;
    q.segment<3>(9 * a + 3) = rot * ref.segment<3>(9 * a + 3);
    q.segment<3>(9 * a + 6) = rot * ref.segment<3>(9 * a + 6);
  }
  for (int i = 0; i < kElementDofs; ++i) q[i] += amplitude * u(rng);
  return q;
}

double energy_of(const Sample& s, const Eigen::VectorXd& q) {
  return beam_element_energy(s.element, s.section, q.data(), nullptr, nullptr);
}

Eigen::VectorXd grad_of(const Sample& s, const Eigen::VectorXd& q) {
  ElemVec g;
  beam_element_energy(s.element, s.section, q.data(), &g, nullptr);
  return g;
}

class BeamDerivatives : public ::testing::TestWithParam<std::tuple<bool, bool>> {};

TEST_P(BeamDerivatives, GradientAndHessianMatchFiniteDifferences) {
  const auto [curved, transverse] = GetParam();
  const Sample s = make_sample(transverse ? carbon() : steel(), curved);
  std::mt19937 rng(1234 + curved * 7 + transverse * 13);
  for (int trial = 0; trial < 25; ++trial) {
    // Amplitudes from small perturbations to large stretches and distortions.
    const double amp = (trial % 5 == 0) ? 0.3 : 0.05;
    const ElemVec q = random_state(s.ref, rng, amp);
    ElemVec g;
    ElemMat h;
    beam_element_energy(s.element, s.section, q.data(), &g, &h);
    const double step = test::fd_step(1.0);
    const Eigen::VectorXd gfd = test::fd_gradient([&](const Eigen::VectorXd& x) { return energy_of(s, x); }, q, step);
    EXPECT_LT(test::rel_error(g, gfd), 1e-6) << "trial " << trial;
    const Eigen::MatrixXd hfd = test::fd_jacobian([&](const Eigen::VectorXd& x) { return grad_of(s, x); }, q, step);
    EXPECT_LT(test::rel_error(h, hfd), 1e-6) << "trial " << trial;
    EXPECT_LT((h - h.transpose()).norm(), 1e-12 * h.norm());
  }
}

INSTANTIATE_TEST_SUITE_P(StraightCurvedIsoTransverse, BeamDerivatives,
                         ::testing::Combine(::testing::Bool(), ::testing::Bool()));

TEST(BeamElement, RigidMotionsGiveZeroEnergyAndForce) {
  for (bool curved : {false, true}) {
    const Sample s = make_sample(steel(), curved);
    std::mt19937 rng(99);
    for (int trial = 0; trial < 10; ++trial) {
      const ElemVec q = random_state(s.ref, rng, 0.0);  // large rotation + translation only
      ElemVec g;
      const double e = beam_element_energy(s.element, s.section, q.data(), &g, nullptr);
      // Scale: the force a unit strain would produce.
      const double fscale = s.section.stiffness.norm();
      EXPECT_LT(std::abs(e), 1e-12 * fscale);
      EXPECT_LT(g.norm(), 1e-10 * fscale);
    }
  }
}

TEST(BeamElement, ReferenceTangentHasExactlySixZeroModes) {
  for (bool curved : {false, true}) {
    const Sample s = make_sample(steel(), curved);
    ElemVec g;
    ElemMat h;
    beam_element_energy(s.element, s.section, s.ref.data(), &g, &h);
    Eigen::SelfAdjointEigenSolver<ElemMat> eig(h);
    const auto ev = eig.eigenvalues();
    const double top = ev.maxCoeff();
    int zero = 0;
    for (int i = 0; i < kElementDofs; ++i) {
      EXPECT_GT(ev[i], -1e-12 * top);
      if (ev[i] < 1e-10 * top) ++zero;
    }
    EXPECT_EQ(zero, 6) << "curved " << curved << " eigenvalues " << ev.transpose();
  }
}

}  // namespace
}  // namespace fibra
