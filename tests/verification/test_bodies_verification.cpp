// Rigid bodies and averaged bindings, verified on whole solutions (METHOD §5).
//
//  1. Seven straight fibers of different lengths, clamped at one end (position and the
//     directions of the section vectors held, their lengths free so the section contracts
//     freely), their other ends bound to a body pulled along the fibers. Reference: each fiber is a St Venant–Kirchhoff bar,
//     F_i = E A l (l^2 - 1) / 2 with l = 1 + u_i / L_i (exact for free lateral contraction);
//     the binding applies to member i the axial force alpha + beta y_i + gamma z_i (the
//     position and rotation multipliers), and the ends satisfy mean(u_i) = delta,
//     sum u_i y_i = sum u_i z_i = 0: four nonlinear equations solved here by Newton. The
//     solver must give each end's displacement and the body's force to 1e-6, the body's
//     force must equal the sum of the clamps' reactions, and the ends must not move alike.
//     Driven by that force instead (x free), the grip and every end reach the same state.
//  2. A bound group twisted by its body: the six mean conditions, computed here from the
//     nodes (mean position in the body frame; Kabsch best-fit rotation of the group relative
//     to the body from an SVD), hold to 1e-9; then a nodal load pushes one member sideways:
//     it moves while the group's mean does not (the others move the other way). Driven by
//     the moment the twist needed instead (rotation about x free), the body turns as far.
//  3. Two-level hierarchy (fiber ends -> two tow bodies -> grip) against one level (all ends
//     -> grip), where both mean the same: two identical tows side by side along y, each of
//     unequal fibers but mirror-symmetric about its own x-z plane, the grip moved along x and
//     z. Then no force distribution across the tows (no moment arm between them) is needed
//     and both have the same solution (docs/theory/bodies.md); the ends' positions and the
//     grip's force agree to 1e-6. (Moved along y, the one-level binding would spread a
//     moment over the whole group and the two would differ, as they should.)
//  4. A rope: a core and three helical strands (contact and friction on), potted at one end
//     (each fiber clamped), their other ends bound to a body that is pulled, then twisted:
//     smooth, monotone tension-elongation (J-shaped as the strands close onto the core) and
//     torque-twist curves, the fibers press on each other, the body's force equals the
//     clamps' reactions. (Bound by averages at both ends, the strands of an unloaded rope
//     are free to wander until contact holds them: see docs/theory/bodies.md.)
//  5. A grip: three parallel fibers bound at both ends to two held bodies, each end also
//     held across the fibers (grip = [2, 3]); a force across one fiber at its middle. Each
//     gripped fiber is a beam pinned at both ends: midspan deflection
//     F L^3 / (48 E I) + F L / (4 kappa G A) (Timoshenko, kappa = 6(1+nu)/(7+6nu)), to 0.2 %;
//     the other fibers do not move (1e-3 of it), the bodies take the force. (Bound by
//     averages only, the three fibers could move across against each other at no cost:
//     that case has no unique solution, test 2 shows a member moving alone.)
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <string>
#include <vector>

#include "fibra/body/rotation.hpp"
#include "verification/verification_support.hpp"

namespace fibra {
namespace {

using test::kPi;
using test::Solved;
using test::solve_toml;

const BodyState& body_of(const IncrementInfo& info, int b) { return info.bodies.at(b); }

// ------------------------------------------------------------------------------------------
// 1. Seven fibers of different lengths pulled through one binding.

TEST(BindingBundle, EachFiberCarriesWhatItsOwnStiffnessGives) {
  const double r = 1e-3, young = 1e9, poisson = 0.3, rho = 3 * r, delta = 1e-4;
  const std::vector<double> lengths = {0.10, 0.07, 0.13, 0.09, 0.11, 0.06, 0.12};
  std::vector<double> ys = {0.0}, zs = {0.0};
  for (int k = 0; k < 6; ++k) {
    ys.push_back(rho * std::cos(k * kPi / 3));
    zs.push_back(rho * std::sin(k * kPi / 3));
  }
  std::string toml = fmt::format(R"(
[[material]]
name = "m"
young = {}
poisson = {}
[[body]]
name = "grip"
center = [0, 0, 0]
)", young, poisson);
  std::string ends;
  for (int i = 0; i < 7; ++i) {
    toml += fmt::format(R"(
[[fiber]]
name = "f{0}"
material = "m"
radius = {1}
section_direction = [0, 1, 0]
points = [[{2}, {3}, {4}], [0, {3}, {4}]]
elements = 4
[[fix]]
fiber = "f{0}"
node = "first"
dofs = ["x", "y", "z", "g1x", "g1z", "g2x", "g2y"]
)", i, r, -lengths[i], ys[i], zs[i]);
    ends += fmt::format("{}{{ fiber = \"f{}\", node = \"last\" }}", i ? ", " : "", i);
  }
  toml += fmt::format(R"(
[[binding]]
body = "grip"
ends = [{}]
[[step]]
name = "pull"
increments = 2
  [[step.body]]
  name = "grip"
  displacement = [{}, 0, 0]
  rotation = [0, 0, 0]
)", ends, delta);
  const Solved s = solve_toml(toml, "bundle.toml");
  ASSERT_TRUE(s.converged()) << s.result.message;
  const IncrementInfo& last = s.increments.back();
  const double area = kPi * r * r;

  // Reference: Newton on (alpha, beta, gamma, and the ends' displacements).
  auto force = [&](double u, double len) {
    const double l = 1 + u / len;
    return young * area * l * (l * l - 1) / 2;
  };
  auto stiffness = [&](double u, double len) {
    const double l = 1 + u / len;
    return young * area * (3 * l * l - 1) / 2 / len;
  };
  // Unknowns: u_i (7), alpha, beta, gamma. Equations: F_i(u_i) = alpha + beta y_i + gamma z_i,
  // mean u = delta, sum u y = 0, sum u z = 0.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(10);
  for (int i = 0; i < 7; ++i) x[i] = delta;
  for (int it = 0; it < 30; ++it) {
    Eigen::VectorXd f(10);
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(10, 10);
    for (int i = 0; i < 7; ++i) {
      f[i] = force(x[i], lengths[i]) - x[7] - x[8] * ys[i] - x[9] * zs[i];
      j(i, i) = stiffness(x[i], lengths[i]);
      j(i, 7) = -1;
      j(i, 8) = -ys[i];
      j(i, 9) = -zs[i];
    }
    f[7] = -delta;
    f[8] = f[9] = 0;
    for (int i = 0; i < 7; ++i) {
      f[7] += x[i] / 7;
      f[8] += x[i] * ys[i] / rho;
      f[9] += x[i] * zs[i] / rho;
      j(7, i) = 1.0 / 7;
      j(8, i) = ys[i] / rho;
      j(9, i) = zs[i] / rho;
    }
    x -= j.lu().solve(f);
  }
  double total = 0, umin = 1e300, umax = -1e300;
  for (int i = 0; i < 7; ++i) {
    const double u = s.u(-1, i).x();
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    EXPECT_NEAR(u, x[i], 1e-6 * delta) << "fiber " << i;
    // The clamp's reaction is the fiber's axial force.
    const double reaction = -last.reactions[3 * i];
    EXPECT_NEAR(reaction, force(x[i], lengths[i]), 1e-6 * force(delta, 0.1)) << "fiber " << i;
    total += reaction;
  }
  const BodyState& grip = body_of(last, 0);
  EXPECT_NEAR(grip.force.x(), total, 1e-6 * std::abs(total));
  double ref_total = 0;
  for (int i = 0; i < 7; ++i) ref_total += force(x[i], lengths[i]);
  EXPECT_NEAR(grip.force.x(), ref_total, 1e-6 * ref_total);
  // Unlike a clamp, the ends do not move alike.
  EXPECT_GT(umax - umin, 0.3 * delta);
  EXPECT_NEAR(grip.center.x(), delta, 1e-12);
  EXPECT_LT(last.binding_violation, 1e-8 * s.model.length_scale);
  // The same grip driven by the force it needed: it moves by delta (a force-driven body).
  std::string driven = toml;
  const std::string prescribed = fmt::format("  displacement = [{}, 0, 0]\n", delta);
  driven.replace(driven.find(prescribed), prescribed.size(),
                 fmt::format("  displacement = [\"free\", 0, 0]\n  force = [{:.17g}, 0, 0]\n", grip.force.x()));
  const Solved f = solve_toml(driven, "bundle_force.toml");
  ASSERT_TRUE(f.converged()) << f.result.message;
  EXPECT_NEAR(body_of(f.increments.back(), 0).center.x(), delta, 1e-6 * delta);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(f.u(-1, i).x(), x[i], 1e-6 * delta) << "fiber " << i;
  std::printf("bundle: grip force %.9g N (reference %.9g), ends move %.4g..%.4g of delta, %d binding updates\n",
              grip.force.x(), ref_total, umin / delta, umax / delta, s.stats.binding_updates);
}

// ------------------------------------------------------------------------------------------
// 2. A bound group twisted by its body, then one member pushed sideways.

struct GroupCheck {
  Vec3 mean_body_frame;  ///< mean of D^T (x - R) over the members
  double kabsch_angle;   ///< best-fit rotation of the group relative to the body [rad]
};

GroupCheck group_check(const std::vector<Vec3>& x0, const Vec3& r0, const Mat3& d0, const std::vector<Vec3>& x,
                       const Vec3& r, const Mat3& d) {
  const size_t n = x.size();
  std::vector<Vec3> a(n), b(n);
  Vec3 ma = Vec3::Zero(), mb = Vec3::Zero();
  for (size_t i = 0; i < n; ++i) {
    a[i] = d0.transpose() * (x0[i] - r0);
    b[i] = d.transpose() * (x[i] - r);
    ma += a[i] / n;
    mb += b[i] / n;
  }
  Mat3 h = Mat3::Zero();
  for (size_t i = 0; i < n; ++i) h += (b[i] - mb) * (a[i] - ma).transpose();
  const Eigen::JacobiSVD<Mat3> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 fix = Mat3::Identity();
  fix(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  const Mat3 rot = svd.matrixU() * fix * svd.matrixV().transpose();
  return {mb - ma, rotation_log(rot).norm()};
}

TEST(BindingGroup, TwistedByItsBodyThenOneMemberPushedAside) {
  const double r = 1e-3, len = 0.1;
  const std::vector<Vec3> offsets = {{0, 0, 0}, {0, 3 * r, 0}, {0, 0, 3 * r}, {0, -3 * r, -r}, {0, 2 * r, -3 * r}};
  std::string toml = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[body]]
name = "head"
center = [0.1, 0.0005, 0.0002]
)";
  std::string ends;
  for (size_t i = 0; i < offsets.size(); ++i) {
    toml += fmt::format(R"(
[[fiber]]
name = "f{0}"
material = "m"
radius = {1}
points = [[0, {2}, {3}], [{4}, {2}, {3}]]
elements = 6
[[fix]]
fiber = "f{0}"
node = "first"
dofs = "all"
)", i, r, offsets[i].y(), offsets[i].z(), len);
    ends += fmt::format("{}{{ fiber = \"f{}\", node = \"last\" }}", i ? ", " : "", i);
  }
  const double twist = 0.3, push = 0.02;
  toml += fmt::format(R"(
[[binding]]
body = "head"
ends = [{}]
[[step]]
name = "twist"
increments = 3
  [[step.body]]
  name = "head"
  displacement = [0, 0, 0]
  rotation = [{}, 0, 0]
[[step]]
name = "push"
increments = 2
  [[step.load]]
  fiber = "f1"
  node = "last"
  force = [0, {}, 0]
)", ends, twist, push);
  const Solved s = solve_toml(toml, "group.toml");
  ASSERT_TRUE(s.converged()) << s.result.message;
  ASSERT_EQ(s.step_end_states.size(), 2u);
  const Vec3 r0(0.1, 0.0005, 0.0002);
  std::vector<Vec3> x0, x1, x2;
  for (size_t i = 0; i < offsets.size(); ++i) {
    x0.push_back(s.ref_x0(-1, i));
    x1.push_back(s.step_end_states[0].segment<3>(9 * s.node(-1, i)));
    x2.push_back(s.step_end_states[1].segment<3>(9 * s.node(-1, i)));
  }
  const BodyState& b1 = body_of(s.step_end_info[0], 0);
  const BodyState& b2 = body_of(s.step_end_info[1], 0);
  const Mat3 expected = Eigen::AngleAxisd(twist, Vec3::UnitX()).toRotationMatrix();
  EXPECT_LT((b1.frame - expected).norm(), 1e-12);
  EXPECT_LT((b1.center - r0).norm(), 1e-14);
  // Bounds from the binding tolerance (1e-8 of the model size, in length): the angle's is that
  // length over the group's rms radius.
  double rms = 0;
  {
    Vec3 mean = Vec3::Zero();
    for (const Vec3& x : x0) mean += x / x0.size();
    for (const Vec3& x : x0) rms += (x - mean).squaredNorm() / x0.size();
    rms = std::sqrt(rms);
  }
  const double tol = 1e-8 * s.model.length_scale;
  const GroupCheck c1 = group_check(x0, r0, Mat3::Identity(), x1, b1.center, b1.frame);
  EXPECT_LT(c1.mean_body_frame.norm(), tol);
  EXPECT_LT(c1.kabsch_angle, tol / rms);
  // The members did turn with the body (by about the twist; each has its own rotation).
  const Vec3 turned = b1.frame * (x0[1] - r0) + r0;
  EXPECT_LT((x1[1] - turned).norm(), 0.1 * (x0[1] - r0).norm());
  // A moment was needed.
  EXPECT_GT(std::abs(b1.moment.x()), 0.0);

  // Step 2: f1's end moves sideways; the group's mean in the body frame does not.
  const GroupCheck c2 = group_check(x0, r0, Mat3::Identity(), x2, b2.center, b2.frame);
  EXPECT_LT(c2.mean_body_frame.norm(), tol);
  EXPECT_LT(c2.kabsch_angle, tol / rms);
  const double moved = (x2[1] - x1[1]).y();
  EXPECT_GT(moved, 1e-3 * r);
  double others = 0;
  for (size_t i = 0; i < offsets.size(); ++i)
    if (i != 1) others += (x2[i] - x1[i]).y();
  EXPECT_NEAR(others, -moved, 1e-6 * moved);
  // The body holds the push: its force balances the load, minus what the clamps take.
  // The twist driven by the moment it needed (rotation about x free): the body turns by the
  // same angle (a moment-driven body; the moment does the work M . theta per increment, exact
  // about a fixed axis).
  std::string driven = toml.substr(0, toml.find("[[step]]\nname = \"push\""));
  const std::string prescribed = fmt::format("  rotation = [{}, 0, 0]\n", twist);
  driven.replace(driven.find(prescribed), prescribed.size(),
                 fmt::format("  rotation = [\"free\", 0, 0]\n  moment = [{:.17g}, 0, 0]\n", b1.moment.x()));
  const Solved m = solve_toml(driven, "group_moment.toml");
  ASSERT_TRUE(m.converged()) << m.result.message;
  EXPECT_NEAR(body_of(m.increments.back(), 0).rotation.x(), twist, 1e-6 * twist);
  std::printf("moment-driven: %d Newton iterations, %d factorizations, %d with a shift, %d iterations on a shifted "
              "factor\n", m.stats.iterations, m.stats.factorizations, m.stats.regularized_factorizations,
              m.stats.shifted_iterations);
  // Its tangents are indefinite for many iterations in a row, through the bindings' second
  // derivatives (a turned body pulled by its members): in this load step Newton factorizes them
  // as they are (LDL^T) and needs no shift: 32 iterations, 29 factorizations (with those local
  // Hessians projected it took 42 iterations and 39 factorizations; with shifts alone, searched
  // from a hundredth of the last one, 61 factorizations, 33 of them shifted, for 42).
  EXPECT_EQ(m.stats.shifted_iterations, 0);
  EXPECT_EQ(m.stats.regularized_factorizations, 0);
  EXPECT_LT(m.stats.factorizations, m.stats.iterations);
  std::printf("group: member pushed by %.4g r, the others by %.4g r in total; head moment %.4g N m\n", moved / r,
              others / r, b1.moment.x());
}

// ------------------------------------------------------------------------------------------
// 3. Two levels against one.

std::string hierarchy_case(bool two_levels) {
  const double r = 1e-3;
  // Two identical tows side by side along y (translates of each other), each of four fibers
  // of two lengths, each tow mirror-symmetric about its own x-z plane.
  const std::vector<Vec3> local = {{0, -2 * r, -r}, {0, 2 * r, -r}, {0, -r, 1.5 * r}, {0, r, 1.5 * r}, {0, 0, -3 * r}};
  const std::vector<double> lengths = {0.10, 0.10, 0.07, 0.07, 0.085};
  const double tow_y[2] = {0.01, -0.01};
  std::string toml = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[body]]
name = "grip"
center = [0, 0, 0]
)";
  std::string all, tow[2];
  for (int t = 0; t < 2; ++t)
    for (size_t i = 0; i < local.size(); ++i) {
      const std::string name = fmt::format("t{}f{}", t, i);
      toml += fmt::format(R"(
[[fiber]]
name = "{0}"
material = "m"
radius = {1}
points = [[{2}, {3}, {4}], [0, {3}, {4}]]
elements = 4
[[fix]]
fiber = "{0}"
node = "first"
dofs = "all"
)", name, r, -lengths[i], tow_y[t] + local[i].y(), local[i].z());
      const std::string end = fmt::format("{{ fiber = \"{}\", node = \"last\" }}", name);
      all += (all.empty() ? "" : ", ") + end;
      tow[t] += (tow[t].empty() ? "" : ", ") + end;
    }
  if (two_levels) {
    for (int t = 0; t < 2; ++t)
      toml += fmt::format(R"(
[[body]]
name = "tow{0}"
center = [0, {1}, 0]
[[binding]]
body = "tow{0}"
ends = [{2}]
)", t, tow_y[t], tow[t]);
    toml += R"(
[[binding]]
body = "grip"
bodies = ["tow0", "tow1"]
)";
  } else {
    toml += fmt::format(R"(
[[binding]]
body = "grip"
ends = [{}]
)", all);
  }
  // A tight binding tolerance: the comparison is at the 1e-6 level.
  toml += R"(
[solver]
binding_tolerance = 1e-12
[[step]]
name = "move"
increments = 2
  [[step.body]]
  name = "grip"
  displacement = [1e-4, 0, -3e-4]
  rotation = [0, 0, 0]
)";
  return toml;
}

TEST(BindingHierarchy, TwoLevelsGiveTheOneLevelResponse) {
  const Solved one = solve_toml(hierarchy_case(false), "one.toml");
  const Solved two = solve_toml(hierarchy_case(true), "two.toml");
  ASSERT_TRUE(one.converged()) << one.result.message;
  ASSERT_TRUE(two.converged()) << two.result.message;
  const BodyState& g1 = body_of(one.increments.back(), 0);
  const BodyState& g2 = body_of(two.increments.back(), 0);
  EXPECT_LT((g1.force - g2.force).norm(), 1e-6 * g1.force.norm());
  double spread = 0;
  for (size_t f = 0; f < one.model.fibers.size(); ++f) {
    EXPECT_LT((one.u(-1, f) - two.u(-1, f)).norm(), 1e-6 * 3e-4) << one.model.fibers[f].name << " "
        << one.u(-1, f).transpose() << " vs " << two.u(-1, f).transpose();
    spread = std::max(spread, std::abs(one.u(-1, f).x() - 1e-4));
  }
  // The ends do not all move like the grip (the tows are not clamps).
  EXPECT_GT(spread, 1e-6);
  // The tows' force adds up to the grip's.
  const Vec3 tows = body_of(two.increments.back(), 1).force + body_of(two.increments.back(), 2).force;
  EXPECT_LT((tows - g2.force).norm(), 1e-6 * g2.force.norm());
  std::printf("hierarchy: grip force %.6g %.6g %.6g (one level) vs %.6g %.6g %.6g (two levels)\n", g1.force.x(),
              g1.force.y(), g1.force.z(), g2.force.x(), g2.force.y(), g2.force.z());
}

// ------------------------------------------------------------------------------------------
// 4. A rope (a core and three helical strands) pulled, then twisted, through a bound body.

std::string rope_case(double r, double pitch, double turns, double twist, double pull) {
  const double length = pitch * turns;
  std::string toml = fmt::format(R"(
[[material]]
name = "steel"
young = 210e9
poisson = 0.3
[contact]
friction = 0.1
[[fiber]]
name = "core"
material = "steel"
radius = {0}
points = [[0, 0, 0], [0, 0, {1}]]
elements = 8
[[fix]]
fiber = "core"
node = "first"
dofs = "all"
)", r, length);
  std::string last = R"({ fiber = "core", node = "last" })";
  for (int k = 0; k < 3; ++k) {
    toml += fmt::format(R"(
[[fiber]]
name = "s{0}"
material = "steel"
radius = {1}
helix = {{ center = [0, 0, 0], axis = [0, 0, 1], radius = {2}, pitch = {3}, turns = {4}, start_angle = {5} }}
elements = 8
[[fix]]
fiber = "s{0}"
node = "first"
dofs = "all"
)", k, r, 2.05 * r, pitch, turns, 120.0 * k);
    last += fmt::format(R"(, {{ fiber = "s{}", node = "last" }})", k);
  }
  toml += fmt::format(R"(
[[body]]
name = "top"
center = [0, 0, {0}]
[[binding]]
body = "top"
ends = [{1}]
[[step]]
name = "pull"
increments = 6
  [[step.body]]
  name = "top"
  displacement = [0, 0, {2}]
  rotation = [0, 0, 0]
[[step]]
name = "twist"
increments = 6
  [[step.body]]
  name = "top"
  rotation = [0, 0, {3}]
)", length, last, pull, twist);
  return toml;
}

/// Consecutive secant slopes of a sampled curve: all positive, none changing by more than
/// `factor` from one interval to the next (a jump or a kink would).
void expect_smooth_monotone(const std::vector<double>& x, const std::vector<double>& y, double factor,
                            const char* what) {
  ASSERT_GE(x.size(), 4u) << what;
  std::vector<double> slope;
  for (size_t k = 1; k < x.size(); ++k) slope.push_back((y[k] - y[k - 1]) / (x[k] - x[k - 1]));
  for (size_t k = 0; k < slope.size(); ++k) {
    EXPECT_GT(slope[k], 0.0) << what << " interval " << k;
    if (k > 0) {
      EXPECT_LT(slope[k] / slope[k - 1], factor) << what << " interval " << k;
      EXPECT_GT(slope[k] / slope[k - 1], 1.0 / factor) << what << " interval " << k;
    }
  }
}

TEST(BindingRope, PullAndTwistGiveSmoothCurvesAndTheFibersPress) {
  const double r = 0.25e-3, pitch = 40 * r, turns = 0.5, twist = 0.1, pull = 5e-3 * pitch * turns;
  const Solved s = solve_toml(rope_case(r, pitch, turns, twist, pull), "rope.toml");
  ASSERT_TRUE(s.converged()) << s.result.message;
  // Tension-elongation over the first step, torque-twist (elongation held) over the second:
  // the settled increments, as the curves take them (a load step held by its drag after a
  // failure repeats a level until it settles; its increments before are no equilibria).
  std::vector<double> stretch = {0}, tension = {0}, angle = {0}, torque;
  for (const IncrementInfo& info : s.increments) {
    if (!info.settled) continue;
    const BodyState& top = body_of(info, 0);
    if (info.step_index == 0) {
      stretch.push_back(top.center.z() - pitch * turns);
      tension.push_back(top.force.z());
    } else {
      if (torque.empty()) torque.push_back(s.step_end_info[0].bodies[0].moment.z());
      angle.push_back(top.rotation.z());
      torque.push_back(top.moment.z());
    }
  }
  for (size_t k = 0; k < stretch.size(); ++k)
    std::printf("rope stretch %.6g m  tension %.6g N\n", stretch[k], tension[k]);
  for (size_t k = 0; k < angle.size(); ++k) std::printf("rope twist %.5f rad  torque %.6g N m\n", angle[k], torque[k]);
  // The tension curve stiffens (J shape) as the strands close onto the core: up to a factor
  // 3 between successive slopes.
  expect_smooth_monotone(stretch, tension, 3.0, "tension-elongation");
  expect_smooth_monotone(angle, torque, 3.0, "torque-twist");
  EXPECT_GT(tension[2] / stretch[2], 1.5 * tension[1] / stretch[1]);  // the J: stiffer once pressed
  // The fibers press on each other, within the allowed penetration.
  const IncrementInfo& last = s.increments.back();
  EXPECT_GT(last.contact.total_normal_force, 0.1 * tension.back());
  EXPECT_LE(last.contact.max_penetration_ratio, 1.0 + 1e-9);
  // Global equilibrium: the body's force is what the clamps hold.
  double clamps = 0;
  for (int f = 0; f < 4; ++f) clamps += last.reactions[3 * f + 2];
  EXPECT_NEAR(body_of(last, 0).force.z(), -clamps, 1e-6 * body_of(last, 0).force.z());
  std::printf("rope: %d increments, %d iterations, %d binding updates, contact force %.4g N over %d elements\n",
              s.stats.increments, s.stats.iterations, s.stats.binding_updates, last.contact.total_normal_force,
              last.contact.elements);
}

// ------------------------------------------------------------------------------------------
// 5. Gripped ends: each fiber pinned across at both ends.

std::string grip_case() {
  std::string toml = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[body]]
name = "left"
center = [0, 0, 0]
[[body]]
name = "right"
center = [0.1, 0, 0]
)";
  const double r = 1e-3;
  const std::vector<Vec3> offsets = {{0, 0, 0}, {0, 3 * r, 0}, {0, 0, 3 * r}};
  std::string first, last;
  for (size_t i = 0; i < offsets.size(); ++i) {
    toml += fmt::format(R"(
[[fiber]]
name = "f{0}"
material = "m"
radius = {1}
points = [[0, {2}, {3}], [0.1, {2}, {3}]]
elements = 8
)", i, r, offsets[i].y(), offsets[i].z());
    first += fmt::format("{}{{ fiber = \"f{}\", node = \"first\" }}", i ? ", " : "", i);
    last += fmt::format("{}{{ fiber = \"f{}\", node = \"last\" }}", i ? ", " : "", i);
  }
  const std::string grip_line = "grip = [2, 3]\n";
  toml += fmt::format(R"(
[[binding]]
body = "left"
ends = [{0}]
{2}[[binding]]
body = "right"
ends = [{1}]
{2}[[step]]
name = "push"
increments = 1
  [[step.body]]
  name = "left"
  displacement = [0, 0, 0]
  rotation = [0, 0, 0]
  [[step.body]]
  name = "right"
  displacement = [0, 0, 0]
  rotation = [0, 0, 0]
  [[step.load]]
  fiber = "f1"
  at = 0.5
  force = [0, 0, 4e-5]
)", first, last, grip_line);
  return toml;
}

TEST(BindingGrip, EachGrippedFiberIsPinnedAtBothEnds) {
  const double r = 1e-3, len = 0.1, young = 1e9, nu = 0.3, force = 4e-5;
  const double inertia = kPi * r * r * r * r / 4, area = kPi * r * r;
  const double kappa = 6 * (1 + nu) / (7 + 6 * nu), shear = young / (2 * (1 + nu));
  const double pinned = force * len * len * len / (48 * young * inertia) + force * len / (4 * kappa * shear * area);
  const Solved gripped = solve_toml(grip_case(), "grip.toml");
  ASSERT_TRUE(gripped.converged()) << gripped.result.message;
  const Index mid = 8;  // 8 elements of 3 nodes: node 8 is the middle
  const double d = gripped.u(mid, 1).z();
  EXPECT_NEAR(d, pinned, 0.002 * pinned) << "pinned-pinned beam";
  for (int f : {0, 2}) EXPECT_LT(gripped.u(mid, f).norm(), 1e-3 * d) << "fiber " << f;
  for (int f = 0; f < 3; ++f)
    for (Index end : {Index(0), Index(-1)}) EXPECT_LT(gripped.u(end, f).norm(), 1e-3 * d) << "fiber " << f;
  // The bodies hold the push, half each (symmetric): they apply -F to their members.
  const Vec3 total = body_of(gripped.increments.back(), 0).force + body_of(gripped.increments.back(), 1).force;
  EXPECT_NEAR(total.z(), -force, 1e-5 * force);
  EXPECT_NEAR(body_of(gripped.increments.back(), 0).force.z(), -0.5 * force, 1e-3 * force);
  std::printf("pinned beam: midspan %.6e m, analytic %.6e m\n", d, pinned);
}

}  // namespace
}  // namespace fibra
