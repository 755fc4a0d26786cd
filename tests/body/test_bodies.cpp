// Rigid bodies and averaged bindings (body/rotation.hpp, body/bodies.hpp) against finite
// differences and exact identities.
//
// rotation_exp: first and second derivatives against central differences at rotation
// vectors from 1e-9 to 2.5 rad, on both sides of the series/closed-form switch (0.5 rad);
// R orthonormal; the tangent T against dR R^T; log(exp(phi)) = phi.
//
// Bindings: the energy of every binding of a two-level hierarchy (fiber ends bound to two
// "tow" bodies, the tows bound to an "edge" body, plus a binding mixing ends and a body),
// at random states (body rotations up to ~1 rad after a committed increment, so that the
// frames differ from their initial ones), with random multipliers: gradient and Hessian
// against central differences (h = cbrt(eps) scaled; relative error ~1e-9 expected, 1e-6
// asked). The conditions are zero for any rigid motion of the whole assembly (the frame
// invariance the formulation must have) and non-zero when one member moves alone.
// Grips (tow2's ends along its axes 1 and 3, which are turned from the global ones; the mixed
// binding's ends along 2) are part of every binding energy above; a gripped end moved along
// a gripped axis breaks its condition by that motion, along the free axis not at all.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "fibra/body/bodies.hpp"
#include "fibra/body/rotation.hpp"
#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "support/assembled.hpp"
#include "support/finite_difference.hpp"

namespace fibra {
namespace {

using test::dense;
using test::fd_gradient;
using test::fd_jacobian;
using test::rel_error;

Eigen::VectorXd flatten(const Mat3& m) { return Eigen::Map<const Eigen::VectorXd>(m.data(), 9); }

class RotationExp : public ::testing::TestWithParam<double> {};

TEST_P(RotationExp, DerivativesMatchFiniteDifferences) {
  const double angle = GetParam();
  const Vec3 axis = Vec3(0.3, -0.5, 0.8).normalized();
  const Eigen::VectorXd phi = angle * axis;
  Mat3 dR[3], d2R[9];
  const Mat3 r = rotation_exp(phi, dR, d2R);
  EXPECT_LT((r.transpose() * r - Mat3::Identity()).norm(), 1e-14);
  EXPECT_NEAR(r.determinant(), 1.0, 1e-14);
  // Closed form of Rodrigues for comparison.
  const Mat3 ref = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  EXPECT_LT((r - ref).norm(), 1e-14);
  const double h = 1e-5;
  auto f = [&](const Eigen::VectorXd& p) { return flatten(rotation_exp(Vec3(p))); };
  const Eigen::MatrixXd jac = fd_jacobian(f, phi, h);
  for (int j = 0; j < 3; ++j) EXPECT_LT(rel_error(flatten(dR[j]), jac.col(j), 1e-3), 1e-8) << "dR " << j;
  for (int j = 0; j < 3; ++j) {
    auto fj = [&](const Eigen::VectorXd& p) {
      Mat3 d[3];
      rotation_exp(Vec3(p), d);
      return flatten(d[j]);
    };
    const Eigen::MatrixXd jj = fd_jacobian(fj, phi, h);
    for (int l = 0; l < 3; ++l)
      EXPECT_LT(rel_error(flatten(d2R[3 * j + l]), jj.col(l), 1e-3), 1e-7) << "d2R " << j << l;
  }
  // Tangent: dR/dphi_j R^T = [T e_j]x.
  const Mat3 t = rotation_tangent(phi);
  for (int j = 0; j < 3; ++j) EXPECT_LT((dR[j] * r.transpose() - skew(t.col(j))).norm(), 1e-13);
  if (angle < 3.0) {
    EXPECT_LT((rotation_log(r) - Vec3(phi)).norm(), 1e-12);
  }
}

INSTANTIATE_TEST_SUITE_P(Angles, RotationExp, ::testing::Values(1e-9, 1e-4, 0.1, 0.4999, 0.5001, 1.3, 2.5));

TEST(RotationExp, CoefficientsContinuousAtTheSeriesSwitch) {
  Mat3 dlo[3], dhi[3], d2lo[9], d2hi[9];
  const Vec3 axis = Vec3(1, 2, 3).normalized();
  rotation_exp((0.5 - 1e-12) * axis, dlo, d2lo);
  rotation_exp((0.5 + 1e-12) * axis, dhi, d2hi);
  for (int j = 0; j < 3; ++j) EXPECT_LT((dlo[j] - dhi[j]).norm(), 1e-11);
  for (int j = 0; j < 9; ++j) EXPECT_LT((d2lo[j] - d2hi[j]).norm(), 1e-10);
}

const char* kCase = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "a"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0, 0], [1, 0.02, 0]]
[[fiber]]
name = "b"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.05, 0.01], [1.1, 0.05, 0.01]]
[[fiber]]
name = "c"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.01, 0.06], [0.9, 0.01, 0.06]]
[[fiber]]
name = "d"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.3, 0], [1, 0.3, 0]]
[[fiber]]
name = "e"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.35, 0.02], [1, 0.36, 0.02]]
[[fiber]]
name = "f"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.31, 0.05], [1, 0.32, 0.07]]
[[body]]
name = "tow1"
center = [1.0, 0.03, 0.02]
[[body]]
name = "tow2"
center = [1.0, 0.32, 0.03]
axes = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]
[[body]]
name = "edge"
center = [1.05, 0.2, 0.0]
[[body]]
name = "mixed"
center = [0.0, 0.2, 0.0]
[[binding]]
body = "tow1"
ends = [{ fiber = "a", node = "last" }, { fiber = "b", node = "last" }, { fiber = "c", node = "last" }]
[[binding]]
body = "tow2"
ends = [{ fiber = "d", node = "last" }, { fiber = "e", node = "last" }, { fiber = "f", node = "last" }]
grip = [1, 3]
spin = true
[[binding]]
body = "edge"
bodies = ["tow1", "tow2"]
[[binding]]
body = "mixed"
ends = [{ fiber = "a", node = "first" }, { fiber = "d", node = "first" }]
bodies = ["edge"]
grip = [2]
spin = true
[[step]]
name = "s"
)";

struct Fixture {
  Case c = parse_case_toml(kCase, "bodies.toml");
  Model model = build_model(c);
  BodySystem bodies{c, model};
  BlockPattern pattern{model.group_sizes(), {&bodies.stencils()}};
  std::vector<char> fixed = std::vector<char>(model.num_dofs(), 0);
  std::vector<char> group_fixed = std::vector<char>(model.num_groups(), 0);

  double energy(const VecX& q, VecX* g, std::vector<double>* h) {
    if (g) g->setZero(q.size());
    if (h) h->assign(pattern.nonzeros(), 0.0);
    AssemblyTarget t{&pattern, &fixed, &group_fixed, g, h};
    return bodies.evaluate(q, t, g != nullptr, h != nullptr);
  }
};

TEST(Bindings, ZeroAtTheReferenceAndUnderAnyRigidMotion) {
  Fixture fx;
  const VecX& ref = fx.model.reference;
  EXPECT_LT(fx.bodies.violation(ref), 1e-15);
  EXPECT_LT(std::abs(fx.energy(ref, nullptr, nullptr)), 1e-20);
  // A rigid motion of everything: x -> Q (x - o) + o + t; bodies: R likewise, theta = log Q.
  const Mat3 rot = Eigen::AngleAxisd(2.2, Vec3(0.2, 1.0, -0.4).normalized()).toRotationMatrix();
  const Vec3 o(0.4, 0.1, -0.2), t(0.3, -0.7, 0.5);
  VecX q = ref;
  for (Index n = 0; n < fx.model.num_nodes(); ++n) {
    q.segment<3>(9 * n) = rot * (ref.segment<3>(9 * n) - o) + o + t;
    q.segment<3>(9 * n + 3) = rot * ref.segment<3>(9 * n + 3);
    q.segment<3>(9 * n + 6) = rot * ref.segment<3>(9 * n + 6);
  }
  for (const Body& b : fx.model.bodies) {
    q.segment<3>(b.first_dof) = rot * (ref.segment<3>(b.first_dof) - o) + o + t;
    q.segment<3>(b.first_dof + 3) = rotation_log(rot);
  }
  EXPECT_LT(fx.bodies.violation(q), 1e-14);
  // Committed in two increments (rotation split), the conditions stay zero.
  VecX half = ref;
  const Mat3 rh = Eigen::AngleAxisd(1.1, Vec3(0.2, 1.0, -0.4).normalized()).toRotationMatrix();
  for (const Body& b : fx.model.bodies) half.segment<3>(b.first_dof + 3) = rotation_log(rh);
  fx.bodies.commit(half);
  for (const Body& b : fx.model.bodies) q.segment<3>(b.first_dof + 3) = rotation_log(rh);
  EXPECT_LT(fx.bodies.violation(q), 1e-14);
  for (Index b = 0; b < fx.bodies.num_bodies(); ++b)
    EXPECT_LT((fx.bodies.frame(b, q) - rot * fx.model.bodies[b].axes).norm(), 1e-14);
  // One member moving alone breaks its binding's position condition by 1/N of its motion.
  q = ref;
  for (const Body& b : fx.model.bodies) q.segment<3>(b.first_dof + 3).setZero();
  Fixture fresh;
  VecX moved = fresh.model.reference;
  const Index end_a = fresh.model.fibers[0].first_node + fresh.model.fibers[0].num_nodes - 1;
  moved[9 * end_a + 1] += 0.03;
  const Vec6 g = fresh.bodies.conditions(0, moved);
  EXPECT_NEAR(g[1], 0.01, 1e-15);
  EXPECT_GT(g.tail<3>().norm(), 1e-4);
}

TEST(Bindings, ManyTurnsInIncrementsStayExactAndSatisfied) {
  // Ten increments of 0.9 rad about a fixed axis (more than a full turn), each committed:
  // the frames are exp of the total, the accumulated rotation is the total angle, and a
  // rigid rotation of the whole assembly keeps every condition at zero.
  Fixture fx;
  const Vec3 axis = Vec3(0.3, -0.2, 0.9).normalized();
  const Vec3 o(0.5, 0.2, 0.0);
  const VecX& ref = fx.model.reference;
  VecX q = ref;
  for (int inc = 1; inc <= 10; ++inc) {
    const Mat3 total = Eigen::AngleAxisd(0.9 * inc, axis).toRotationMatrix();
    for (Index n = 0; n < fx.model.num_nodes(); ++n) {
      q.segment<3>(9 * n) = total * (ref.segment<3>(9 * n) - o) + o;
      q.segment<3>(9 * n + 3) = total * ref.segment<3>(9 * n + 3);
      q.segment<3>(9 * n + 6) = total * ref.segment<3>(9 * n + 6);
    }
    for (const Body& b : fx.model.bodies) {
      q.segment<3>(b.first_dof) = total * (ref.segment<3>(b.first_dof) - o) + o;
      q.segment<3>(b.first_dof + 3) = 0.9 * axis;
    }
    EXPECT_LT(fx.bodies.violation(q), 1e-13) << "increment " << inc;
    for (Index b = 0; b < fx.bodies.num_bodies(); ++b)
      EXPECT_LT((fx.bodies.frame(b, q) - total * fx.model.bodies[b].axes).norm(), 1e-13) << "increment " << inc;
    fx.bodies.commit(q);
    EXPECT_LT((fx.bodies.committed_rotation(0) - 0.9 * inc * axis).norm(), 1e-13);
  }
}

TEST(Bindings, SpinHoldMeasuresTheTurnAboutTheFiberAxisOnly) {
  // Fiber d's last node is bound to tow2 with a spin hold (tow2's axes are turned): turning
  // its section vectors about the fiber's axis by psi breaks the hold by r sin(psi); tilting
  // them about either section direction, or stretching them, does not.
  Fixture fx;
  const VecX& ref = fx.model.reference;
  const Index node = fx.model.fibers[3].first_node + fx.model.fibers[3].num_nodes - 1;
  const Vec3 g1 = ref.segment<3>(9 * node + 3), g2 = ref.segment<3>(9 * node + 6);
  const Vec3 axis = g1.cross(g2).normalized();
  const double r = 0.01;
  for (double psi : {0.01, 0.3, -0.7}) {
    VecX q = ref;
    const Mat3 turn = Eigen::AngleAxisd(psi, axis).toRotationMatrix();
    q.segment<3>(9 * node + 3) = turn * g1;
    q.segment<3>(9 * node + 6) = turn * g2;
    EXPECT_NEAR(fx.bodies.violation(q), r * std::abs(std::sin(psi)), 1e-15) << psi;
    for (const Vec3& about : {g1.normalized(), g2.normalized()}) {
      const Mat3 tilt = Eigen::AngleAxisd(psi, about).toRotationMatrix();
      q = ref;
      q.segment<3>(9 * node + 3) = 1.1 * (tilt * g1);
      q.segment<3>(9 * node + 6) = 0.9 * (tilt * g2);
      EXPECT_LT(fx.bodies.violation(q), 1e-15) << psi;
    }
  }
  // Without multipliers the hold's energy is k/2 s^2 with s = r sin(psi): the moment of the
  // section vectors' forces about the axis is dE/dpsi = k r^2 sin(psi) cos(psi), k the grip
  // penalty (the binding's penalty over its 3 nodes: both are 100 k_ref per node).
  std::vector<double> lambda = fx.bodies.multipliers();
  std::fill(lambda.begin(), lambda.end(), 0.0);
  fx.bodies.set_multipliers(lambda);
  const double psi = 0.2;
  VecX q = ref;
  const Mat3 turn = Eigen::AngleAxisd(psi, axis).toRotationMatrix();
  q.segment<3>(9 * node + 3) = turn * g1;
  q.segment<3>(9 * node + 6) = turn * g2;
  VecX g;
  fx.energy(q, &g, nullptr);
  const double moment = axis.dot(q.segment<3>(9 * node + 3).cross(g.segment<3>(9 * node + 3)) +
                                 q.segment<3>(9 * node + 6).cross(g.segment<3>(9 * node + 6)));
  const double k = fx.bodies.stiffness(1) / 3.0;
  EXPECT_NEAR(moment, k * r * r * std::sin(psi) * std::cos(psi), 1e-6 * std::abs(moment));
}

// A random state near q: every node and body centre moved by about 0.05, every body turned
// by about 0.6 rad, and multipliers of about 1e6 (the bindings' Hessians then indefinite).
void perturb(Fixture& fx, VecX& q, std::mt19937& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  for (Index d = 0; d < fx.model.node_dofs; ++d) q[d] += 0.05 * normal(rng);
  for (const Body& b : fx.model.bodies)
    for (int k = 0; k < 3; ++k) {
      q[b.first_dof + k] += 0.05 * normal(rng);
      q[b.first_dof + 3 + k] = 0.6 * normal(rng);
    }
  std::vector<double> lambda = fx.bodies.multipliers();
  for (double& l : lambda) l = 1e6 * normal(rng);
  fx.bodies.set_multipliers(lambda);
}

TEST(Bindings, GradientAndHessianMatchFiniteDifferences) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    Fixture fx;
    // A committed increment first: frames differ from the initial ones.
    VecX q = fx.model.reference;
    for (const Body& b : fx.model.bodies)
      for (int k = 0; k < 3; ++k) q[b.first_dof + 3 + k] = 0.5 * normal(rng);
    fx.bodies.commit(q);
    perturb(fx, q, rng);

    VecX g;
    std::vector<double> hv;
    fx.energy(q, &g, &hv);
    const Eigen::MatrixXd hess = dense(fx.pattern, hv);
    const double h = 1e-6;
    const VecX gfd = fd_gradient([&](const VecX& x) { return fx.energy(x, nullptr, nullptr); }, q, h);
    EXPECT_LT(rel_error(g, gfd), 1e-6) << "trial " << trial;
    const Eigen::MatrixXd hfd = fd_jacobian(
        [&](const VecX& x) {
          VecX gx;
          fx.energy(x, &gx, nullptr);
          return gx;
        },
        q, h);
    EXPECT_LT(rel_error(hess, hfd), 1e-6) << "trial " << trial;
    // Blocks of the bodies' rotations on their own (small next to the position terms).
    for (const Body& b : fx.model.bodies) {
      const Index d = b.first_dof + 3;
      EXPECT_LT(rel_error(hess.block(d, d, 3, 3), hfd.block(d, d, 3, 3), 1e-3), 1e-6) << b.name;
      EXPECT_LT(rel_error(g.segment<3>(d), gfd.segment<3>(d), 1e-3), 1e-6) << b.name;
    }
  }
}

// The solver's fallback when the exact tangent is not positive definite: each binding's local
// Hessian projected onto the positive semi-definite matrices (its negative eigenvalues set to
// zero). At a turned state with large multipliers several are indefinite: the projection adds
// to each exactly its negative part (the added matrix is positive semi-definite and its trace is
// the sum of their magnitudes), and the sum of the projected ones is positive semi-definite.
// Where every local Hessian is positive definite nothing changes.
TEST(Bindings, ProjectedHessiansArePositiveSemiDefiniteAndExactWhereTheyWere) {
  std::mt19937 rng(11);
  Fixture fx;
  VecX q = fx.model.reference;
  {
    // The reference state, no multipliers: positive definite, kept as it is.
    std::vector<double> exact, projected;
    fx.energy(q, nullptr, &exact);
    fx.bodies.set_projected(true);
    fx.energy(q, nullptr, &projected);
    fx.bodies.set_projected(false);
    EXPECT_EQ(fx.bodies.take_projections(), 0);
    EXPECT_EQ(exact, projected);
  }
  perturb(fx, q, rng);
  double negative = 0.0;  // sum of the local Hessians' negative eigenvalues' magnitudes
  int indefinite = 0;
  for (Index k = 0; k < fx.bodies.num_bindings(); ++k) {
    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(fx.bodies.local_hessian(k, q)).eigenvalues();
    if (ev.minCoeff() >= -1e-10 * ev.cwiseAbs().maxCoeff()) continue;  // within round-off: kept
    for (Index i = 0; i < ev.size(); ++i) negative += std::max(0.0, -ev[i]);
    ++indefinite;
  }
  ASSERT_GE(indefinite, 2);
  std::vector<double> exact, projected;
  fx.energy(q, nullptr, &exact);
  fx.bodies.set_projected(true);
  fx.energy(q, nullptr, &projected);
  fx.bodies.set_projected(false);
  EXPECT_EQ(fx.bodies.take_projections(), indefinite);
  const Eigen::MatrixXd he = dense(fx.pattern, exact), hp = dense(fx.pattern, projected);
  const double scale = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(he).eigenvalues().cwiseAbs().maxCoeff();
  const Eigen::MatrixXd added = hp - he;
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(added).eigenvalues().minCoeff(), -1e-12 * scale);
  EXPECT_NEAR(added.trace(), negative, 1e-9 * scale);
  EXPECT_GT(added.trace(), 1e-9 * scale);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(hp).eigenvalues().minCoeff(), -1e-12 * scale);
  EXPECT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(he).eigenvalues().minCoeff(), -1e-9 * scale);
}

TEST(Bindings, ForceAndMomentAreTheWorkConjugatesOnTheBody) {
  Fixture fx;
  VecX q = fx.model.reference;
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (Index d = 0; d < q.size(); ++d) q[d] += 0.02 * normal(rng);
  std::vector<double> lambda = fx.bodies.multipliers();
  for (double& l : lambda) l = 1e5 * normal(rng);
  fx.bodies.set_multipliers(lambda);
  // "mixed" is the body of binding 3 and a member of none: all the energy's dependence on its
  // dofs is what it transmits.
  const Index b = fx.model.body_index("mixed");
  const Body& body = fx.model.bodies[b];
  const BodyState s = fx.bodies.state(b, q);
  const double eps = 1e-6;
  // Force: the energy's change under a translation of the body.
  const Vec3 v(0.3, -0.6, 0.2);
  VecX qp = q, qm = q;
  qp.segment<3>(body.first_dof) += eps * v;
  qm.segment<3>(body.first_dof) -= eps * v;
  const double df = (fx.energy(qp, nullptr, nullptr) - fx.energy(qm, nullptr, nullptr)) / (2 * eps);
  EXPECT_NEAR(df, s.force.dot(v), 1e-7 * s.force.norm() * v.norm());
  // Moment: the change under a small spatial rotation w of the body about its centre.
  const Vec3 w(0.3, -0.2, 0.5);
  const Vec3 theta = q.segment<3>(body.first_dof + 3);
  qp = q;
  qm = q;
  qp.segment<3>(body.first_dof + 3) = rotation_log(rotation_exp(eps * w) * rotation_exp(theta));
  qm.segment<3>(body.first_dof + 3) = rotation_log(rotation_exp(-eps * w) * rotation_exp(theta));
  const double dm = (fx.energy(qp, nullptr, nullptr) - fx.energy(qm, nullptr, nullptr)) / (2 * eps);
  EXPECT_NEAR(dm, s.moment.dot(w), 1e-7 * s.moment.norm() * w.norm());
  EXPECT_GT(s.moment.norm(), 0.0);
  EXPECT_LT((s.frame - rotation_exp(theta) * body.axes).norm(), 1e-14);
}

TEST(Bindings, InputErrors) {
  auto expect_error = [](const std::string& text, const std::string& key, const std::string& words) {
    const Case c = parse_case_toml(text, "x.toml");
    const Model m = build_model(c);
    try {
      BodySystem b(c, m);
      FAIL() << "expected an error for " << key;
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), key) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("x.toml"), std::string::npos) << e.what();
    }
  };
  const std::string base = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "a"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0, 0], [1, 0, 0]]
[[fiber]]
name = "b"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.1, 0], [1, 0.1, 0]]
[[fiber]]
name = "c"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.2, 0], [1, 0.2, 0]]
[[fiber]]
name = "d"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.1, 0.1], [1, 0.1, 0.1]]
[[step]]
name = "s"
)";
  expect_error(base + R"(
[[body]]
name = "g"
center = [1, 0, 0]
[[binding]]
body = "g"
ends = [{ fiber = "a", node = "last" }, { fiber = "b", node = "last" }]
)", "binding[0]", "are only 2");
  expect_error(base + R"(
[[body]]
name = "g"
center = [1, 0, 0]
[[binding]]
body = "g"
ends = [{ fiber = "a", node = "last" }, { fiber = "b", node = "last" }, { fiber = "c", node = "last" }]
)", "binding[0]", "lie on one line");
  expect_error(base + R"(
[[body]]
name = "g"
center = [1, 0, 0]
[[body]]
name = "lonely"
center = [0, 0, 0]
[[binding]]
body = "g"
ends = [{ fiber = "a", node = "last" }, { fiber = "b", node = "last" }, { fiber = "d", node = "last" }]
)", "body[1]", "has no members");
}

}  // namespace
}  // namespace fibra
