// Roll-up of a cantilever by an end moment: under a pure end moment M the elastica is a circle
// of curvature M/(EI), so M = pi EI/L bends the fiber into a half circle and M = 2 pi EI/L into
// a full circle with the tip back at the root and the tip section turned by 2 pi.
//
// Geometry: fiber along +x from the origin, g1 = +y, g2 = +z, clamped at node 0; moment
// [0, M, 0] at the last node. A positive moment about +y turns +x towards -z: after a total
// turn theta the fiber is an arc of radius R = L/theta with centre (0, 0, -R), the point at arc
// length s is at (R sin(s/R), 0, -R (1 - cos(s/R))), so at theta = pi the tip is at
// (0, 0, -2L/pi) with the tangent along -x, at theta = 2 pi it is back at the origin.
//
// Constraint: the library's moment is conservative about its fixed axis, not a follower moment
// out of its plane, and the rolled-up rod under it is unstable out of plane beyond about
// M = 0.4 pi EI/L (docs/theory/beam.md; measured: the smallest eigenvalue of the tangent turns
// negative between M = 0.3 and 0.4 pi EI/L, with a lateral-torsional mode). So, like
// examples/rollup, the half- and full-circle tests hold every node in the plane
// (dofs = ["y", "g1"]); a third test checks the unconstrained 3D rod below that limit.
//
// Model: L = 1 m, r = 1 mm (L/r = 1000), 20 quadratic elements. The St Venant–Kirchhoff
// moment-curvature deviation is O((r kappa)^2) = (0.001 * 2 pi)^2 ~ 4e-5 and the axial strain
// is zero under pure bending to that order; the discretization error of a circle with 20
// quadratic elements (18 degrees each) is ~1e-5 L. Measured errors (printed) are ~1e-5 L; the
// test asks for 1e-3 L in position (the brief: 0.5%) and 1e-3 rad in the rotations.
#include <gtest/gtest.h>

#include <cmath>

#include "verification/verification_support.hpp"

namespace fibra::test {
namespace {

constexpr double kLength = 1.0, kRadius = 0.001, kYoung = 210e9;
constexpr int kElements = 20;

double bending_stiffness() { return kYoung * kPi * std::pow(kRadius, 4) / 4.0; }

// Position of the arc-length point s on the rolled-up circle of total turn theta (theta > 0).
Vec3 circle_point(double theta, double s) {
  const double r = kLength / theta;
  return Vec3(r * std::sin(s / r), 0.0, -r * (1.0 - std::cos(s / r)));
}

// Largest distance of any node from its place on the circle of total turn theta.
double circle_error(const Solved& s, const VecX& q, double theta) {
  double err = 0.0;
  const Index n = s.model.fibers[0].num_nodes;
  for (Index k = 0; k < n; ++k) {
    const double arc = kLength * static_cast<double>(k) / static_cast<double>(n - 1);
    err = std::max(err, (q.segment<3>(9 * s.node(k)) - circle_point(theta, arc)).norm());
  }
  return err;
}

// Total rotation of the sections about +y from root to tip (sum of the turns of g2 between
// consecutive nodes, so it counts beyond pi).
double total_turn(const Solved& s, const VecX& q) {
  double turn = 0.0;
  for (Index k = 1; k < s.model.fibers[0].num_nodes; ++k) {
    const Vec3 a = q.segment<3>(9 * s.node(k - 1) + 6), b = q.segment<3>(9 * s.node(k) + 6);
    turn += std::atan2(a.cross(b).y(), a.dot(b));
  }
  return turn;
}

std::string planar_fixes() {
  std::string out;
  for (int k = 1; k <= 2 * kElements; ++k)
    out += fmt::format("[[fix]]\nfiber = \"beam\"\nnode = {}\ndofs = [\"y\", \"g1\"]\n", k);
  return out;
}

TEST(Rollup, PlanarEndMomentBendsTheFiberIntoAHalfThenAFullCircle) {
  const double m_half = kPi * bending_stiffness() / kLength;
  const Solved s = solve_toml(straight_cantilever(kLength, kRadius, kElements, kYoung, 0.3,
                                                  planar_fixes() + fmt::format(R"(
[[step]]
name = "half"
increments = 15
  [[step.load]]
  fiber = "beam"
  node = "last"
  moment = [0, {:.17g}, 0]

[[step]]
name = "full"
increments = 15
  [[step.load]]
  fiber = "beam"
  node = "last"
  moment = [0, {:.17g}, 0]
)",
                                                                               m_half, 2 * m_half)));
  ASSERT_TRUE(s.converged()) << s.result.message;
  ASSERT_EQ(s.step_end_states.size(), 2u);
  const Index tip = 9 * s.node(-1);

  // Half circle: tip at (0, 0, -2L/pi), tip tangent -x (g2 turned by pi to -z).
  {
    const VecX& q = s.step_end_states[0];
    const Vec3 x_tip = q.segment<3>(tip), g2 = q.segment<3>(tip + 6);
    const double err_tip = (x_tip - Vec3(0, 0, -2 * kLength / kPi)).norm();
    const double err_all = circle_error(s, q, kPi);
    const double turn = total_turn(s, q);
    std::printf("half circle: tip error %.2e L, largest nodal error %.2e L, total turn - pi = %.2e, |g2| - 1 = %.2e\n",
                err_tip / kLength, err_all / kLength, turn - kPi, g2.norm() - 1);
    EXPECT_LT(err_tip, 1e-3 * kLength);
    EXPECT_LT(err_all, 1e-3 * kLength);
    EXPECT_NEAR(turn, kPi, 1e-3);
    EXPECT_NEAR((g2.normalized() + Vec3::UnitZ()).norm(), 0.0, 1e-3);
  }
  // Full circle: tip back at the root (the brief: within 0.5% of L), tip section turned by 2 pi
  // (g2 back to +z).
  {
    const VecX& q = s.step_end_states[1];
    const Vec3 x_tip = q.segment<3>(tip), g2 = q.segment<3>(tip + 6);
    const double err_tip = x_tip.norm();
    const double err_all = circle_error(s, q, 2 * kPi);
    const double turn = total_turn(s, q);
    std::printf("full circle: tip distance from the root %.2e L, largest nodal error %.2e L, total turn - 2 pi = %.2e\n",
                err_tip / kLength, err_all / kLength, turn - 2 * kPi);
    EXPECT_LT(err_tip, 1e-3 * kLength);
    EXPECT_LT(err_all, 1e-3 * kLength);
    EXPECT_NEAR(turn, 2 * kPi, 1e-3);
    EXPECT_NEAR((g2.normalized() - Vec3::UnitZ()).norm(), 0.0, 1e-3);
  }
}

// Without the in-plane constraint the 3D rod follows the same circles while the in-plane state
// is stable: M = 0.3 pi EI/L (total turn 0.3 pi = 54 degrees).
TEST(Rollup, Unconstrained3DRodFollowsTheCircleBelowTheOutOfPlaneLimit) {
  const double factor = 0.3;
  const double m = factor * kPi * bending_stiffness() / kLength;
  const Solved s = solve_toml(straight_cantilever(kLength, kRadius, kElements, kYoung, 0.3, fmt::format(R"(
[[step]]
increments = 6
  [[step.load]]
  fiber = "beam"
  node = "last"
  moment = [0, {:.17g}, 0]
)",
                                                                                                     m)));
  ASSERT_TRUE(s.converged()) << s.result.message;
  const double err_all = circle_error(s, s.q, factor * kPi);
  const double turn = total_turn(s, s.q);
  std::printf("3D, M = 0.3 pi EI/L: largest nodal error %.2e L, total turn error %.2e\n", err_all / kLength,
              turn - factor * kPi);
  EXPECT_LT(err_all, 1e-3 * kLength);
  EXPECT_NEAR(turn, factor * kPi, 1e-3);
  double out_of_plane = 0.0;
  for (Index k = 0; k < s.model.fibers[0].num_nodes; ++k) out_of_plane = std::max(out_of_plane, std::abs(s.x0(k).y()));
  EXPECT_LT(out_of_plane, 1e-9 * kLength);
}

}  // namespace
}  // namespace fibra::test
