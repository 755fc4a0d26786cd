// The diagnosis of an increment that cannot converge (solver/stall_diagnosis.hpp): where a
// motion is, in the user's words, and the three kinds of tangent on whole runs that fail.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <numbers>
#include <string>

#include "fibra/solver/stall_diagnosis.hpp"
#include "verification/verification_support.hpp"

namespace fibra {
namespace {

using test::solve_toml;

const char* kTwoFibers = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "a"
material = "m"
radius = 0.001
points = [[0, 0, 0], [0.1, 0, 0]]
elements = 4
[[fiber]]
name = "b"
material = "m"
radius = 0.002
points = [[0, 0.01, 0], [0.1, 0.01, 0]]
elements = 4
[[fix]]
fiber = "a"
node = "first"
[[fix]]
fiber = "b"
node = "first"
[[step]]
name = "s"
)";

VecX weights(const Model& model) {
  VecX w = VecX::Ones(model.num_dofs());
  for (const Fiber& f : model.fibers)
    for (Index n = f.first_node; n < f.first_node + f.num_nodes; ++n)
      for (int k = 3; k < kNodeDofs; ++k) w[kNodeDofs * n + k] = model.sections[f.section].a;
  return w;
}

TEST(DescribeMotion, NamesTheFiberTheNodeRangeAndTheDirection) {
  const Case c = parse_case_toml(kTwoFibers, "two.toml");
  const Model model = build_model(c);
  const VecX w = weights(model);
  VecX v = VecX::Zero(model.num_dofs());
  // Nodes 3-5 of fiber b along -y (the sign of a mode is arbitrary: written positive), node 4 most.
  const Index b0 = model.fibers[1].first_node;
  v[kNodeDofs * (b0 + 3) + 1] = -0.6;
  v[kNodeDofs * (b0 + 4) + 1] = -1.0;
  v[kNodeDofs * (b0 + 5) + 1] = -0.5;
  v[kNodeDofs * (b0 + 6) + 1] = -0.4;  // below half of the largest: not in the range
  EXPECT_EQ(describe_motion(model, v, w), "fiber \"b\", nodes 3-5 (of 0-8): the centre line, along (0.00, 1.00, 0.00)");
  // One node alone, and another fiber moving as much is counted.
  v.setZero();
  v[kNodeDofs * (b0 + 8) + 2] = 1.0;
  v[kNodeDofs * 2 + 0] = 0.9;
  EXPECT_EQ(describe_motion(model, v, w),
            "fiber \"b\", node 8 (of 0-8) (and 1 other fiber or body): the centre line, along (0.00, 0.00, 1.00)");
  EXPECT_EQ(describe_motion(model, VecX::Zero(model.num_dofs()), w), "");
}

TEST(DescribeMotion, SectionVectorsAreWeighedByTheRadius) {
  const Case c = parse_case_toml(kTwoFibers, "two.toml");
  const Model model = build_model(c);
  const VecX w = weights(model);
  VecX v = VecX::Zero(model.num_dofs());
  // A turn of node 2's section on fiber a (|dg| = 1, radius 1e-3: a boundary motion of 1e-3 m)
  // beside a centre-line motion of 3e-3 m on fiber b: the centre line is larger.
  v[kNodeDofs * 2 + 4] = 1.0;
  const Index b0 = model.fibers[1].first_node;
  v[kNodeDofs * (b0 + 1) + 0] = 3e-3;
  EXPECT_EQ(describe_motion(model, v, w), "fiber \"b\", node 1 (of 0-8): the centre line, along (1.00, 0.00, 0.00)");
  v[kNodeDofs * (b0 + 1) + 0] = 0.4e-3;
  EXPECT_EQ(describe_motion(model, v, w), "fiber \"a\", node 2 (of 0-8): the section vectors (the sections turn or deform)");
}

// A column compressed past its Euler load stays straight: the load step follows that
// equilibrium, unstable (docs/theory/solver.md, "Unstable equilibria in load steps"), and
// reports it: a clamped-free column of circular section at twice P_cr = pi^2 E I / (4 L^2),
// below the second mode's 9 P_cr, has one unstable mode in each bending plane, two negative
// pivots. A sideways push in one increment, with too few iterations to reach it, then fails:
// the diagnosis names the last equilibrium unstable and the column's tip moving sideways.
TEST(StallDiagnosis, ColumnPastItsEulerLoadIsUnstable) {
  const double young = 1e9, radius = 0.01, length = 1.0;
  const double inertia = std::numbers::pi * std::pow(radius, 4) / 4.0;
  const double critical = std::numbers::pi * std::numbers::pi * young * inertia / (4.0 * length * length);
  const test::Solved s = solve_toml(test::straight_cantilever(length, radius, 20, young, 0.3, fmt::format(R"(
[solver]
max_iterations = 3
max_cuts = 0
[[step]]
name = "compress"
increments = 1
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [{:.17g}, 0, 0]
[[step]]
name = "push"
increments = 1
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, {:.17g}]
)", -2.0 * critical, 50.0 * critical)));
  ASSERT_FALSE(s.converged());
  ASSERT_EQ(s.step_end_info.size(), 1u) << "the compression converges";
  EXPECT_EQ(s.step_end_info[0].negative_pivots, 2);
  EXPECT_EQ(s.result.step, "push");
  const StallDiagnosis& d = s.result.diagnosis;
  EXPECT_EQ(d.tangent, StallDiagnosis::Tangent::Indefinite) << d.text();
  EXPECT_LT(d.softest_stiffness, 0.0);
  EXPECT_NE(d.softest_mode.find("fiber \"beam\""), std::string::npos) << d.softest_mode;
  EXPECT_NE(d.softest_mode.find("the centre line"), std::string::npos) << d.softest_mode;
  EXPECT_NE(d.text().find("unstable"), std::string::npos);
}

// A fiber that nothing holds, pushed: a mechanism (its rigid motions).
TEST(StallDiagnosis, LooseFiberIsAMechanism) {
  const test::Solved s = solve_toml(R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "loose"
material = "m"
radius = 0.001
points = [[0, 0, 0], [0.1, 0, 0]]
elements = 4
[[step]]
name = "push"
  [[step.load]]
  fiber = "loose"
  node = "last"
  force = [0, 1, 0]
)");
  ASSERT_FALSE(s.converged());
  const StallDiagnosis& d = s.result.diagnosis;
  EXPECT_EQ(d.tangent, StallDiagnosis::Tangent::Singular) << d.text();
  EXPECT_NE(d.softest_mode.find("fiber \"loose\", nodes 0-8"), std::string::npos) << d.softest_mode;
  EXPECT_NE(d.text().find("[[fix]]"), std::string::npos);
}

// A stable cantilever given too few iterations for a large load in one increment: the tangent
// is positive definite, the advice is more increments, and the attempt moved the tip along z.
TEST(StallDiagnosis, StableModelThatNewtonCannotReachInOneIncrement) {
  const test::Solved s = solve_toml(test::straight_cantilever(1.0, 0.01, 8, 1e9, 0.3, R"(
[solver]
max_iterations = 2
max_cuts = 0
[[step]]
name = "load"
increments = 1
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, -500]
)"));
  ASSERT_FALSE(s.converged());
  const StallDiagnosis& d = s.result.diagnosis;
  EXPECT_EQ(d.tangent, StallDiagnosis::Tangent::Definite) << d.text();
  EXPECT_GT(d.softest_stiffness, 0.0);
  EXPECT_NE(d.text().find("more increments"), std::string::npos);
  EXPECT_NE(d.largest_motion.find("fiber \"beam\""), std::string::npos) << d.largest_motion;
}

// A fiber driven through another in one increment (from 1.5 mm above it to 1.5 mm below, radii
// 0.5 mm: no contact element before, none after), no cut allowed: the swept check of the contact
// loop refuses the attempt, and the diagnosis says so, naming both fibers.
TEST(StallDiagnosis, ContactLoopRefusalIsNamed) {
  const test::Solved s = solve_toml(R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "below"
material = "m"
radius = 0.0005
points = [[-0.005, 0, 0], [0.005, 0, 0]]
elements = 4
[[fiber]]
name = "above"
material = "m"
radius = 0.0005
points = [[0, -0.005, 0.0015], [0, 0.005, 0.0015]]
elements = 4
[contact]
[solver]
max_cuts = 0
[[fix]]
fiber = "below"
node = "first"
[[fix]]
fiber = "below"
node = "last"
[[fix]]
fiber = "above"
node = "first"
[[fix]]
fiber = "above"
node = "last"
[[step]]
name = "through"
increments = 1
  [[step.displacement]]
  fiber = "above"
  node = "first"
  value = [0, 0, -0.003]
  [[step.displacement]]
  fiber = "above"
  node = "last"
  value = [0, 0, -0.003]
)");
  ASSERT_FALSE(s.converged());
  const StallDiagnosis& d = s.result.diagnosis;
  EXPECT_NE(d.refusal.find("through each other"), std::string::npos) << d.text();
  EXPECT_NE(d.refusal.find("fiber \"below\""), std::string::npos) << d.refusal;
  EXPECT_NE(d.refusal.find("fiber \"above\""), std::string::npos) << d.refusal;
  EXPECT_EQ(d.text().rfind("the contact loop refused the last attempt: ", 0), 0u) << d.text();
}

}  // namespace
}  // namespace fibra
