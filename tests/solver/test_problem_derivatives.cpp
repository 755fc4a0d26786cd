// The assembled problem and the nodal moment load against finite differences.
//
// Problem::evaluate: energy, gradient (every dof) and Hessian (upper CSC, free-free block; fixed
// rows and columns decoupled with a positive diagonal) for a curved fiber (a helix, 3 elements,
// 7 nodes, 63 dofs) at random large-deformation states (rotations up to ~1 rad, stretches of
// 10 %, distortions of 5 %), with dead forces, nodal moments on three nodes and fixed dofs.
// Central differences with h = cbrt(eps) have a relative error ~1e-9..1e-8 here; the checks ask
// for 1e-6 (the beam element's own test uses the same bound), so a wrong term of relative size
// 1e-6 or more fails. Because the beam terms dominate the norms, the load terms (forces and
// moments) are also checked on their own: evaluate(with loads) - evaluate(without loads).
//
// moment_generalized_force: its derivative against FD of the force, symmetry, the force as the
// gradient of moment_work (d work / d g = f), the couple identity g1 x f1 + g2 x f2 = M for
// section vectors normal to the axis, and the work of a rotation about the axis.
#include <cstdio>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/nodal_load.hpp"
#include "fibra/solver/problem.hpp"
#include "support/assembled.hpp"
#include "support/finite_difference.hpp"

namespace fibra {
namespace {

using test::dense;
using test::fd_gradient;
using test::fd_jacobian;
using test::fd_step;
using test::random_unit;
using test::rel_error;

const char* kCase = R"(
[[material]]
name = "carbon"
model = "transverse"
young = 230e9
poisson = 0.2
young_transverse = 15e9
shear_axial = 24e9
poisson_transverse = 0.45

[[fiber]]
name = "coil"
material = "carbon"
semi_axes = [0.05, 0.03]
helix = { center = [0, 0, 0], axis = [0.2, 0.1, 1], radius = 0.4, pitch = 0.3, turns = 0.5 }
elements = 3

[[step]]
  [[step.load]]
  fiber = "coil"
  node = "last"
  force = [1, 0, 0]
)";

// A random large-deformation state: a rotation growing along the fiber (up to ~1 rad), a
// translation, stretch of x0 and g by ~10 %, and random distortions.
VecX random_state(const Model& model, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 axis = random_unit(rng), shift(u(rng), u(rng), u(rng));
  VecX q = model.reference;
  const Index n = model.num_nodes();
  for (Index k = 0; k < n; ++k) {
    const Mat3 rot =
        Eigen::AngleAxisd(1.0 * static_cast<double>(k) / static_cast<double>(n - 1) + 0.2 * u(rng), axis).toRotationMatrix();
    q.segment<3>(9 * k) = 1.1 * (rot * model.reference.segment<3>(9 * k)) + shift;
    for (int a = 0; a < 2; ++a)
      q.segment<3>(9 * k + 3 + 3 * a) = (1.0 + 0.1 * u(rng)) * (rot * model.reference.segment<3>(9 * k + 3 + 3 * a));
  }
  for (Index d = 0; d < q.size(); ++d) q[d] += 0.05 * u(rng) * (d % 9 < 3 ? 0.1 : 1.0);
  return q;
}

struct Loaded {
  VecX forces;
  std::vector<NodalMoment> moments;
  std::vector<char> fixed;
};

Loaded random_loads(const Model& model, std::mt19937& rng, double force_scale, double moment_scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Loaded l;
  l.forces = VecX::Zero(model.num_dofs());
  for (Index k : {2, 5, 6})
    for (int c = 0; c < 3; ++c) l.forces[9 * k + c] = force_scale * u(rng);
  l.moments.push_back({6, moment_scale * random_unit(rng)});
  l.moments.push_back({3, moment_scale * random_unit(rng)});
  // A moment about the reference tangent of node 4 (a torque: both weights 1/2).
  const Vec3 t = model.reference.segment<3>(9 * 4 + 3).cross(model.reference.segment<3>(9 * 4 + 6));
  l.moments.push_back({4, moment_scale * t});
  l.fixed.assign(model.num_dofs(), 0);
  for (int d = 0; d < 9; ++d) l.fixed[d] = 1;  // node 0 clamped
  for (Index d : {9 * 3 + 1, 9 * 5 + 4, 9 * 5 + 8, 9 * 6 + 2}) l.fixed[d] = 1;  // scattered dofs
  return l;
}

void apply(Problem& p, const Loaded& l, bool with_loads) {
  p.fixed() = l.fixed;
  p.forces() = with_loads ? l.forces : VecX::Zero(l.forces.size());
  p.moments() = with_loads ? l.moments : std::vector<NodalMoment>{};
}

TEST(ProblemDerivatives, GradientAndHessianMatchFiniteDifferencesWithFixedDofs) {
  const Case c = parse_case_toml(kCase, "problem.toml");
  const Model model = build_model(c);
  Problem p(model);
  std::mt19937 rng(2024);
  // Force and moment scales comparable to the internal forces of the random states.
  const double ea = 230e9 * std::numbers::pi * 0.05 * 0.03;
  const double h = fd_step(1.0);
  for (int trial = 0; trial < 4; ++trial) {
    const VecX q = random_state(model, rng);
    const Loaded l = random_loads(model, rng, 0.05 * ea, 0.05 * ea * 0.04);
    auto energy = [&](const VecX& x) { return p.evaluate(x, nullptr, nullptr); };
    auto gradient = [&](const VecX& x) {
      VecX g;
      p.evaluate(x, &g, nullptr);
      return g;
    };
    apply(p, l, true);
    VecX g;
    std::vector<double> hv;
    const double e = p.evaluate(q, &g, &hv);
    EXPECT_EQ(e, energy(q));
    // Gradient on every dof (fixed ones too: the reactions need it).
    const VecX g_fd = fd_gradient(energy, q, h);
    EXPECT_LT(rel_error(g, g_fd), 1e-6) << "trial " << trial;
    // Hessian: free-free block against FD of the gradient.
    const Eigen::MatrixXd hd = dense(p.pattern(), hv);
    const Eigen::MatrixXd h_fd = fd_jacobian(gradient, q, h);
    std::vector<Index> free, fixed;
    for (Index d = 0; d < q.size(); ++d) (l.fixed[d] ? fixed : free).push_back(d);
    const Eigen::MatrixXd hff = hd(free, free), hff_fd = h_fd(free, free);
    EXPECT_LT(rel_error(hff, 0.5 * (hff_fd + hff_fd.transpose())), 1e-6) << "trial " << trial;
    // Fixed rows and columns: decoupled, with one positive diagonal value.
    const double diag = hd(fixed[0], fixed[0]);
    EXPECT_GT(diag, 0.0);
    for (Index d : fixed) {
      EXPECT_EQ(hd(d, d), diag);
      for (Index j = 0; j < q.size(); ++j)
        if (j != d) {
          EXPECT_EQ(hd(d, j), 0.0) << d << ", " << j;
        }
    }
    // The diagonal value is the mean |free diagonal| (the documented unit scaling).
    double mean = 0.0;
    for (Index d : free) mean += std::abs(hd(d, d)) / static_cast<double>(free.size());
    EXPECT_NEAR(diag / mean, 1.0, 1e-12);

    // Load terms on their own: (with loads) - (without loads).
    apply(p, l, false);
    VecX g0;
    std::vector<double> hv0;
    const double e0 = p.evaluate(q, &g0, &hv0);
    const Eigen::MatrixXd hd0 = dense(p.pattern(), hv0);
    auto load_energy = [&](const VecX& x) {
      apply(p, l, true);
      const double a = p.evaluate(x, nullptr, nullptr);
      apply(p, l, false);
      return a - p.evaluate(x, nullptr, nullptr);
    };
    auto load_gradient = [&](const VecX& x) {
      VecX a, b;
      apply(p, l, true);
      p.evaluate(x, &a, nullptr);
      apply(p, l, false);
      p.evaluate(x, &b, nullptr);
      return VecX(a - b);
    };
    EXPECT_NEAR(e - e0, load_energy(q), 1e-12 * std::abs(e));
    const VecX gl = g - g0;
    EXPECT_LT(rel_error(gl, fd_gradient(load_energy, q, h)), 1e-6) << "trial " << trial;
    // Only x0 of loaded nodes and g of moment nodes carry load terms.
    for (Index d = 0; d < q.size(); ++d) {
      const Index node = d / 9;
      const bool moment_node = node == 3 || node == 4 || node == 6;
      const bool force_node = node == 2 || node == 5 || node == 6;
      if (!((d % 9 < 3 && force_node) || (d % 9 >= 3 && moment_node))) {
        EXPECT_EQ(gl[d], 0.0) << d;
      }
    }
    const Eigen::MatrixXd hl = (hd - hd0)(free, free);
    const Eigen::MatrixXd hl_fd = fd_jacobian(load_gradient, q, h)(free, free);
    EXPECT_LT(rel_error(hl, hl_fd), 1e-6) << "trial " << trial;
    std::printf("trial %d: |load Hessian| / |Hessian| = %.2e, |load gradient| / |gradient| = %.2e\n", trial,
                hl.norm() / hff.norm(), gl.norm() / g.norm());
  }
}

// The drag of weave, relax and test steps (Problem::set_drag): the term on its own, (with drag)
// - (without), against finite differences, isotropic and with a weak drag along the fiber; and
// its energy for a motion along the fiber's tangent and across it, against the formula.
TEST(ProblemDerivatives, DragAlongAndAcrossTheFiberMatchesFiniteDifferences) {
  const Case c = parse_case_toml(kCase, "problem.toml");
  const Model model = build_model(c);
  Problem p(model);
  std::mt19937 rng(7);
  const double h = fd_step(1.0);
  const double stiffness = 3.0e4, director = 100.0;
  for (const double axial : {1.0, 0.01}) {
    const VecX anchor = random_state(model, rng);
    const VecX q = random_state(model, rng);
    const Loaded l = random_loads(model, rng, 0.0, 0.0);
    apply(p, l, false);
    auto drag_energy = [&](const VecX& x) {
      p.set_drag(stiffness, anchor, director, axial);
      const double a = p.evaluate(x, nullptr, nullptr);
      p.set_drag(0.0, anchor);
      return a - p.evaluate(x, nullptr, nullptr);
    };
    auto drag_gradient = [&](const VecX& x) {
      VecX a, b;
      p.set_drag(stiffness, anchor, director, axial);
      p.evaluate(x, &a, nullptr);
      p.set_drag(0.0, anchor);
      p.evaluate(x, &b, nullptr);
      return VecX(a - b);
    };
    VecX g1, g0;
    std::vector<double> h1, h0;
    p.set_drag(stiffness, anchor, director, axial);
    p.evaluate(q, &g1, &h1);
    p.set_drag(0.0, anchor);
    p.evaluate(q, &g0, &h0);
    const VecX gd = g1 - g0;
    EXPECT_LT(rel_error(gd, fd_gradient(drag_energy, q, h)), 1e-6) << "axial weight " << axial;
    std::vector<Index> free;
    for (Index d = 0; d < q.size(); ++d)
      if (!l.fixed[d]) free.push_back(d);
    const Eigen::MatrixXd hd = (dense(p.pattern(), h1) - dense(p.pattern(), h0))(free, free);
    const Eigen::MatrixXd hd_fd = fd_jacobian(drag_gradient, q, h)(free, free);
    EXPECT_LT(rel_error(hd, hd_fd), 1e-6) << "axial weight " << axial;
    // The gradient is the drag's force: zero at the anchor; drag_force_norm is its scaled norm.
    EXPECT_EQ(drag_gradient(anchor).norm(), 0.0);
    VecX scale = VecX::Ones(q.size());
    for (Index d = 0; d < q.size(); ++d)
      if (d % 9 >= 3) scale[d] = 25.0;  // e.g. 1 / r on the section vectors
    p.set_drag(stiffness, anchor, director, axial);
    EXPECT_NEAR(p.drag_force_norm(q, scale), scale.cwiseProduct(gd).norm(), 1e-9 * scale.cwiseProduct(gd).norm());

    // Node 3 moved along the anchor's tangent there (from its neighbours), then across it.
    const Index node = 3;
    const Vec3 t = (anchor.segment<3>(9 * (node + 1)) - anchor.segment<3>(9 * (node - 1))).normalized();
    const Vec3 n = t.unitOrthogonal();
    for (const auto& [dir, weight] : {std::pair{t, axial}, std::pair{n, 1.0}}) {
      VecX x = anchor;
      x.segment<3>(9 * node) += 1e-2 * dir;
      // (The energy is a difference of two evaluations with the beam's energy in both.)
      const double expected = 0.5 * stiffness * weight * 1e-4;
      EXPECT_NEAR(drag_energy(x), expected, 1e-6 * expected) << "axial weight " << axial;
      const Vec3 force = drag_gradient(x).segment<3>(9 * node);
      EXPECT_LT((force - stiffness * weight * 1e-2 * dir).norm(), 1e-6 * stiffness * weight * 1e-2);
      p.set_drag(stiffness, anchor, director, axial);
      EXPECT_LT((p.drag_projected(node, 1e-3 * dir) - weight * 1e-3 * dir).norm(), 1e-15);
    }
  }
}

TEST(MomentLoad, DerivativeMatchesFiniteDifferencesAndIsSymmetric) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 m = (1.0 + 3.0 * std::abs(u(rng))) * random_unit(rng);
    const Vec3 rg1 = random_unit(rng), rg2 = (random_unit(rng).cross(rg1)).normalized();
    VecX g(6);
    g.segment<3>(0) = 1.3 * random_unit(rng);
    g.segment<3>(3) = 0.8 * random_unit(rng);
    auto force = [&](const VecX& x) {
      return VecX(moment_generalized_force(m, rg1, rg2, x.segment<3>(0), x.segment<3>(3), nullptr));
    };
    Mat6x6 df;
    const Vec6 f = moment_generalized_force(m, rg1, rg2, g.segment<3>(0), g.segment<3>(3), &df);
    EXPECT_LT((f - force(g)).norm(), 1e-15 * f.norm());
    const Eigen::MatrixXd df_fd = fd_jacobian(force, g, fd_step(1.0));
    EXPECT_LT(rel_error(df, df_fd), 1e-7) << "trial " << trial;
    EXPECT_LT((df - df.transpose()).norm(), 1e-12 * df.norm()) << "trial " << trial;
  }
}

TEST(MomentLoad, ForceIsTheGradientOfTheWork) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 m = 2.5 * random_unit(rng);
    const Vec3 rg1 = random_unit(rng), rg2 = (random_unit(rng).cross(rg1)).normalized();
    // Base (h) and current (g) section vectors a moderate turn apart (the work is the swept
    // angle, valid below pi).
    const Mat3 turn = Eigen::AngleAxisd(0.9, random_unit(rng)).toRotationMatrix();
    const Vec3 h1 = rg1 + 0.1 * random_unit(rng), h2 = rg2 + 0.1 * random_unit(rng);
    VecX g(6);
    g.segment<3>(0) = 1.2 * (turn * h1);
    g.segment<3>(3) = 0.9 * (turn * h2);
    auto work = [&](const VecX& x) { return moment_work(m, rg1, rg2, h1, h2, x.segment<3>(0), x.segment<3>(3)); };
    const Vec6 f = moment_generalized_force(m, rg1, rg2, g.segment<3>(0), g.segment<3>(3), nullptr);
    EXPECT_LT(rel_error(f, fd_gradient(work, g, fd_step(1.0))), 1e-8) << "trial " << trial;
    // The work starts at zero and is additive along a path.
    const Mat3 about_m = Eigen::AngleAxisd(0.4, m.normalized()).toRotationMatrix();
    const Vec3 k1 = about_m * h1, k2 = about_m * h2;
    EXPECT_NEAR(moment_work(m, rg1, rg2, h1, h2, h1, h2), 0.0, 1e-15);
    EXPECT_NEAR(moment_work(m, rg1, rg2, h1, h2, k1, k2) + moment_work(m, rg1, rg2, k1, k2, g.segment<3>(0), g.segment<3>(3)),
                work(g), 1e-12);
    // A rigid turn of both section vectors by theta about the moment axis does work |M| theta.
    EXPECT_NEAR(moment_work(m, rg1, rg2, h1, h2, k1, k2), m.norm() * 0.4, 1e-12);
  }
}

TEST(MomentLoad, CoupleOfTheGeneralizedForcesIsTheMoment) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 m = 3.0 * random_unit(rng);
    const Vec3 n = m.normalized();
    // Reference vectors in general position (weights strictly between 0 and 1) ...
    Vec3 rg1 = random_unit(rng), rg2 = (random_unit(rng).cross(rg1)).normalized();
    // ... and, every other trial, the moment along rg1 (weight w1 = 0: a bending moment
    // carried by g2 alone) or along the tangent (a torque: w1 = w2 = 1/2).
    if (trial % 4 == 1) rg1 = n, rg2 = random_unit(rng).cross(n).normalized();
    if (trial % 4 == 3) rg1 = random_unit(rng).cross(n).normalized(), rg2 = n.cross(rg1);
    // Current section vectors normal to n, of any length and angle between them.
    auto in_plane = [&](double len) {
      const Vec3 v = random_unit(rng);
      return Vec3(len * (v - v.dot(n) * n).normalized());
    };
    const Vec3 g1 = in_plane(u(rng)), g2 = in_plane(u(rng));
    const Vec6 f = moment_generalized_force(m, rg1, rg2, g1, g2, nullptr);
    const Vec3 couple = g1.cross(f.segment<3>(0)) + g2.cross(f.segment<3>(3));
    EXPECT_LT((couple - m).norm(), 1e-13 * m.norm()) << "trial " << trial;
    if (trial % 4 == 1) {
      EXPECT_LT(f.segment<3>(0).norm(), 1e-14 * m.norm());  // w1 = 0 up to rounding
    }
    // The generalized forces do no work along the section vectors (no stretching).
    EXPECT_NEAR(f.segment<3>(0).dot(g1), 0.0, 1e-13 * m.norm());
    EXPECT_NEAR(f.segment<3>(3).dot(g2), 0.0, 1e-13 * m.norm());
  }
}

// A moment whose axis is a reference section vector, G1 = n, but only up to rounding (a
// general direction, so that P G1 = G1 - n (n . G1) is ~1e-16 instead of exactly zero): the
// weight w1 = |P G1|^2 / sum is ~1e-32 and should act as zero. While g1 stays along n (it does
// under bending about n), the exact load stiffness on g1 is zero, as for w1 = 0 exactly
// (checked first). The test asks for the g1 block of the derivative to stay below 1e-6 |M|.
TEST(MomentLoad, AxisAlongAReferenceVectorUpToRoundingAddsNoStiffnessOnIt) {
  const Vec3 dir = Vec3(1.0, 1.0, 0.3).normalized();
  const Vec3 m = 10.0 * dir;
  const Vec3 rg1 = dir, rg2 = dir.cross(Vec3(0.2, -0.7, 1.0)).normalized();
  // Exactly along the axis: no force and no stiffness on g1.
  {
    const Vec3 e = Vec3::UnitY();
    Mat6x6 df;
    const Vec6 f = moment_generalized_force(10.0 * e, e, Vec3::UnitZ(), e, Vec3::UnitZ(), &df);
    EXPECT_EQ(f.head<3>().norm(), 0.0);
    EXPECT_EQ((df.topLeftCorner<3, 3>().norm()), 0.0);
  }
  const double tiny = (rg1 - dir * dir.dot(rg1)).norm();
  ASSERT_GT(tiny, 0.0) << "this direction happens to round exactly; pick another";
  for (double dev : {0.0, 1e-16, 1e-15}) {
    const Vec3 g1 = rg1 + dev * Vec3(0.3, -0.2, 0.5);
    Mat6x6 df;
    const Vec6 f = moment_generalized_force(m, rg1, rg2, g1, rg2, &df);
    ASSERT_TRUE(f.allFinite() && df.allFinite());
    EXPECT_LT(f.head<3>().norm(), 1e-12 * m.norm()) << "deviation " << dev;
    EXPECT_LT((df.topLeftCorner<3, 3>().norm()), 1e-6 * m.norm())
        << "deviation " << dev << ": spurious g1 stiffness from the rounding-sized weight w1 = |P G1|^2 / sum = "
        << tiny * tiny;
    // The g2 part is the full moment's.
    EXPECT_LT((g1.cross(f.head<3>()) + rg2.cross(f.segment<3>(3)) - m).norm(), 1e-12 * m.norm());
  }
}

}  // namespace
}  // namespace fibra

namespace fibra {
namespace {

// A straight fiber of 4 elements along x, 1 m long: the diagnostics' model.
constexpr const char* kStraightFiber = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "a"
material = "m"
radius = 0.01
elements = 4
points = [[0, 0, 0], [1, 0, 0]]
[[step]]
name = "s"
)";

// The developers' diagnostic of indefinite tangents (Problem::local_spectra): a straight fiber
// at rest has positive semi-definite element Hessians; squeezed to half its length (St
// Venant-Kirchhoff softens and turns unstable below a stretch of 1/sqrt(3)) every element's
// Hessian has a negative eigenvalue, and the report names the elements and counts them.
TEST(ProblemDiagnostics, LocalSpectraFindTheIndefiniteElements) {
  const Case c = parse_case_toml(kStraightFiber, "straight.toml");
  const Model model = build_model(c);
  Problem p(model);
  const std::string rest = p.local_spectra(model.reference);
  EXPECT_NE(rest.find("beam elements: 0 of 4 local Hessians indefinite"), std::string::npos) << rest;
  VecX q = model.reference;
  for (Index n = 0; n < model.num_nodes(); ++n) q[9 * n] *= 0.5;
  const std::string squeezed = p.local_spectra(q);
  EXPECT_NE(squeezed.find("beam elements: 4 of 4 local Hessians indefinite; most negative -"), std::string::npos)
      << squeezed;
  // Stretched by 20 %: stable again.
  for (Index n = 0; n < model.num_nodes(); ++n) q[9 * n] = 1.2 * model.reference[9 * n];
  EXPECT_NE(p.local_spectra(q).find("beam elements: 0 of 4"), std::string::npos) << p.local_spectra(q);
}

// The developers' diagnostic of a shortened Newton step (Problem::step_energies): each term's
// energy change along dq against its quadratic model at q. A fiber stretched by 1 %, its free
// end moved on along the axis: the beam's energy is quartic in the stretch (St Venant-Kirchhoff:
// (lambda^2 - 1)^2), so its change matches the model for a small step and falls short of it by
// the quartic's higher terms for a large one.
TEST(ProblemDiagnostics, StepEnergiesCompareEachTermWithItsQuadraticModel) {
  const Case c = parse_case_toml(kStraightFiber, "stretched.toml");
  const Model model = build_model(c);
  Problem p(model);
  VecX q = model.reference;
  for (Index n = 0; n < model.num_nodes(); ++n) q[9 * n] *= 1.01;
  auto beam = [&](double size) {
    VecX dq = VecX::Zero(q.size());
    for (Index n = 0; n < model.num_nodes(); ++n) dq[9 * n] = size * model.reference[9 * n];
    const std::string report = p.step_energies(q, dq);
    const size_t at = report.find("beam elements: change ");
    EXPECT_NE(at, std::string::npos) << report;
    double change = 0.0, model_change = 0.0;
    EXPECT_EQ(std::sscanf(report.c_str() + at, "beam elements: change %lf J, model %lf J", &change, &model_change), 2)
        << report;
    EXPECT_NE(report.find("drag: change 0.0000e+00 J, model 0.0000e+00 J"), std::string::npos) << report;
    return std::pair{change, model_change};
  };
  const auto [small, small_model] = beam(1e-5);
  EXPECT_GT(small, 0.0);
  EXPECT_NEAR(small_model / small, 1.0, 1e-3);
  // Stretched on to 1.21: (1.21^2 - 1)^2 against its quadratic model from 1.01, 16 % below.
  const auto [large, large_model] = beam(0.2);
  EXPECT_NEAR(large_model / large, 0.842, 0.01) << large << " " << large_model;
}

}  // namespace
}  // namespace fibra
