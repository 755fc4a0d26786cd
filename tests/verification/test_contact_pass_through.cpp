// An increment that would let fibers pass through each other is cut, not accepted.
//
// Fiber b (pinned at its ends, 40 mm span) starts 1.5 r above contact range over fiber a
// (clamped, crossing at right angles; centres 3.5 r apart) and a dead force F at its middle is
// applied in ONE requested increment. Without a, F would bend b by 8 r at mid-span, through a:
// with no contact element at the start (beyond the detection margin), Newton alone puts b's
// centre 4.5 r below a's, and a detection at that state finds nothing (apart again, beyond the
// margin). The loops (and, as the last guard, the swept check ContactManager::crossed) must
// not accept that state: the run ends with b resting on a, which carries part of F.
#include <gtest/gtest.h>

#include <cmath>

#include "fibra/contact/contact_manager.hpp"
#include "verification/verification_support.hpp"

namespace fibra::test {
namespace {

TEST(ContactPassThrough, IncrementThroughAFiberIsCut) {
  const double r = 0.5e-3, span = 40e-3, young = 210e9;
  const double inertia = kPi * std::pow(r, 4) / 4.0;
  const double force = 48.0 * young * inertia * (8.0 * r) / std::pow(span, 3);  // 8 r free deflection
  const std::string toml = fmt::format(R"(
[[material]]
name = "steel"
young = {E}
poisson = 0.3
[[fiber]]
name = "a"
material = "steel"
radius = {r}
points = [[-20e-3, 0, 0], [20e-3, 0, 0]]
elements = 20
[[fiber]]
name = "b"
material = "steel"
radius = {r}
points = [[0.3e-3, -20e-3, {z}], [0.3e-3, 20e-3, {z}]]
elements = 20
[[fix]]
fiber = "a"
node = "first"
[[fix]]
fiber = "a"
node = "last"
[[fix]]
fiber = "b"
node = "first"
dofs = ["x", "y", "z", "g1x"]
[[fix]]
fiber = "b"
node = "last"
dofs = "position"
[contact]
max_penetration = 0.02
[[step]]
increments = 1
  [[step.load]]
  fiber = "b"
  node = 20
  force = [0, 0, {F}]
)",
                                       fmt::arg("E", young), fmt::arg("r", r), fmt::arg("z", 3.5 * r),
                                       fmt::arg("F", -force));
  const Solved s = solve_toml(toml);
  ASSERT_TRUE(s.converged()) << s.result.message;
  // b stays above a where they cross: centre distance at least 2 r minus the allowed penetration.
  const Vec3 mid_a = s.x0(20, 0), mid_b = s.x0(20, 1);
  EXPECT_GT(mid_b.z() - mid_a.z(), 2.0 * r * (1.0 - 0.02) - 1e-9);
  // a carries part of F through the contact (b's pinned ends the rest).
  EXPECT_GT(s.increments.back().contact.total_normal_force, 0.05 * force);
  EXPECT_LT(s.increments.back().contact.total_normal_force, force);
  EXPECT_LE(s.increments.back().contact.max_penetration_ratio, 0.02 * (1 + 1e-9));
}

// Two straight fibers "a" and "b" (points as TOML arrays) of one material, contact on.
std::string two_fibers(const char* material, double young, double poisson, double r, const std::string& a_points,
                       const std::string& b_points, int elements) {
  return fmt::format(R"(
[[material]]
name = "{0}"
young = {1}
poisson = {2}
[[fiber]]
name = "a"
material = "{0}"
radius = {3}
points = {4}
elements = {6}
[[fiber]]
name = "b"
material = "{0}"
radius = {3}
points = {5}
elements = {6}
[contact]
[[step]]
)",
                     material, young, poisson, r, a_points, b_points, elements);
}

// q with every node of fiber f moved by shift.
VecX fiber_moved(const Model& model, VecX q, int f, const Vec3& shift) {
  const Fiber& fiber = model.fibers[f];
  for (Index k = 0; k < fiber.num_nodes; ++k) q.segment<3>(9 * (fiber.first_node + k)) += shift;
  return q;
}

// The swept check alone: two crossed chords, the second moving from above to below the first,
// through it (crossed) and around its end (not crossed).
TEST(ContactPassThrough, SweptCheckSeesLinesGoingThroughNotAround) {
  const double r = 0.5e-3;
  const Case c = parse_case_toml(
      two_fibers("steel", 210e9, 0.3, r, "[[-10e-3, 0, 0], [10e-3, 0, 0]]", "[[1e-3, -10e-3, 5e-3], [1e-3, 10e-3, 5e-3]]", 4),
      "swept.toml");
  const Model model = build_model(c);
  ContactManager contacts(model, c.contact);
  const VecX start = model.reference;
  auto moved = [&](const Vec3& shift) { return fiber_moved(model, start, 1, shift); };
  EXPECT_TRUE(contacts.crossed(start, moved(Vec3(0, 0, -10e-3))));     // straight down through a
  EXPECT_FALSE(contacts.crossed(start, moved(Vec3(0, 0, -4e-3))));     // stops 1 mm above a
  // Around the end of a (x = 10 mm): when b is level with a it is at x = 13.5 mm.
  EXPECT_FALSE(contacts.crossed(start, moved(Vec3(25e-3, 0, -10e-3))));
  EXPECT_FALSE(contacts.crossed(start, start));
}

// Two fibers side by side in one plane at 10 degrees, touching with 3 % penetration (as in a
// flattened tow): a slight motion of one across their plane changes the side of its chord along
// the common normal (their lines meet beyond the chords' ends), but they never go through each
// other. Going down through the other by the same route is still a crossing.
TEST(ContactPassThrough, SweptCheckLetsSideBySideFibersMoveAcrossTheirPlane) {
  const double r = 20e-6, angle = 10.0 * std::acos(-1.0) / 180.0, y0 = 0.97 * 2.0 * r;
  const Case c = parse_case_toml(
      two_fibers("glass", 72e9, 0.22, r, "[[-0.5e-3, 0, 0], [0.5e-3, 0, 0]]",
                 fmt::format("[[-0.5e-3, {}, 1e-6], [{}, {}, 1e-6]]", y0, -0.5e-3 + 1e-3 * std::cos(angle),
                             y0 + 1e-3 * std::sin(angle)),
                 1),
      "side_by_side.toml");
  const Model model = build_model(c);
  ContactManager contacts(model, c.contact);
  const VecX start = model.reference;
  auto moved = [&](const Vec3& shift) { return fiber_moved(model, start, 1, shift); };
  EXPECT_FALSE(contacts.crossed(start, moved(Vec3(0, 0, -2e-6))));        // 1 um above to 1 um below
  EXPECT_TRUE(contacts.crossed(start, moved(Vec3(0, -2.0 * y0, -2e-6))));  // through a to its other side
}

}  // namespace
}  // namespace fibra::test
