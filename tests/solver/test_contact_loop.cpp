// The contact loops of an increment (solver/contact_loop.hpp) on their own, with the
// minimization and the residual with the updated normals played by the test: what ends a
// proximal increment whose normals stop settling, and what refuses a release.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fibra/contact/contact_manager.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/contact_loop.hpp"
#include "fibra/solver/problem.hpp"

namespace fibra {
namespace {

// Fiber "b" crosses fiber "a" at right angles, pressed onto it by 1e-5 m (radii 1e-3 m: a
// fifth of the cap, 0.05 r).
const char* kPressedCrossing = R"(
material = [{ name = "m", young = 1e9, poisson = 0.3 }]
fiber = [
  { name = "a", material = "m", radius = 0.001, points = [[-0.01, 0, 0], [0.01, 0, 0]], elements = 4 },
  { name = "b", material = "m", radius = 0.001, points = [[0, -0.01, 0.00199], [0, 0.01, 0.00199]], elements = 4 },
]
contact = {}
step = [{ name = "s" }]
)";

struct Outcome {
  bool accepted = false;
  std::string refusal;
  bool normals_settled = true;
  int minimizations = 0;
};

// One increment's loops with the rules of a test level's settling increment (normals iterated,
// the level's tolerance 1e-3); `release` as StaticSolver::release_positions sets it. Each
// "minimization" moves fiber b along x by `slide` (2e-5 m: the normals between the section
// centres turn by 1e-2 rad, beyond the 1e-3 rad of their tolerance, at every update), and the
// residual with the updated normals is read from `moved` in turn.
Outcome run_loop(bool release, const std::vector<double>& moved, double slide = 2e-5) {
  const Case c = parse_case_toml(kPressedCrossing, "crossing.toml");
  const Model model = build_model(c);
  ContactManager manager(model, c.contact);
  Problem problem(model);
  problem.set_normal_rule(&manager);
  ContactLoop loop(model, manager, problem);
  VecX q = model.reference;
  const VecX q_start = q;
  const Fiber& b = model.fibers[1];
  Outcome out;
  ContactLoopRules rules;
  rules.relax = true;
  rules.lagged = false;
  rules.test_settling = true;
  rules.penetration_slack = 0.05;
  rules.release = release;
  rules.tolerance = 1e-3;
  rules.lambda = 1.0;
  ContactLoopHost host;
  host.minimize = [&](std::vector<double>& history, int& iterations, double& residual) {
    for (Index n = b.first_node; n < b.first_node + b.num_nodes; ++n) q[kNodeDofs * n] += slide;
    ++out.minimizations;
    iterations = 1;
    residual = 0.0;
    history.push_back(0.0);
    return true;
  };
  host.pattern_changed = []() {};
  size_t next = 0;
  host.moved_residual = [&]() { return moved[std::min(next++, moved.size() - 1)]; };
  std::vector<double> history;
  int iterations = 0;
  double residual = 0.0;
  ContactStats stats;
  SolverProgress run;
  out.accepted = loop.solve(rules, host, q, q_start, history, iterations, residual, stats, run, out.refusal);
  out.normals_settled = run.normals_settled;
  EXPECT_FALSE(problem.contacts().empty());
  return out;
}

// The residual with the updated normals 1e-2, then 2e-2 (not halved): a settling increment
// ends there (the level goes on with another, detected afresh); a release, whose state would
// be the level's point, is refused, and the level keeps its dragged state.
TEST(ContactLoop, AReleaseIsRefusedWhereItsNormalsStopSettling) {
  const Outcome settling = run_loop(false, {1e-2, 2e-2});
  EXPECT_TRUE(settling.accepted) << settling.refusal;
  EXPECT_FALSE(settling.normals_settled);
  EXPECT_EQ(settling.minimizations, 2);
  const Outcome release = run_loop(true, {1e-2, 2e-2});
  EXPECT_FALSE(release.accepted);
  EXPECT_EQ(release.minimizations, 2);
  EXPECT_NE(release.refusal.find("stopped settling"), std::string::npos) << release.refusal;
  EXPECT_NE(release.refusal.find("1.000e-02, then 2.000e-02"), std::string::npos) << release.refusal;
}

// Halving towards the tolerance, the normals settle: the release is accepted at the update
// whose residual is within it (1e-2, 4e-3, 1.5e-3, 8e-4).
TEST(ContactLoop, AReleaseWhoseNormalsSettleIsAccepted) {
  const Outcome release = run_loop(true, {1e-2, 4e-3, 1.5e-3, 8e-4});
  EXPECT_TRUE(release.accepted) << release.refusal;
  EXPECT_TRUE(release.normals_settled);
  EXPECT_EQ(release.minimizations, 4);
}

// Fiber b slides 3e-4 m along fiber a per minimization: after the first, the particles of the
// pressed pair lie 0.15 of their radii' sum apart across its normal, and the pair no longer
// describes the contact. A settling increment ends at that update, however its residual with
// the updated normals falls, and the next one detects afresh; a release, with no next
// increment, iterates on (here until fiber b has slid off the pair, which then carries no force
// and has settled).
TEST(ContactLoop, ASettlingIncrementEndsWhereItsPairsNoLongerFaceEachOther) {
  const std::vector<double> halving = {1e-2, 4e-3, 1.5e-3, 8e-4};
  const Outcome slid = run_loop(false, halving, 3e-4);
  EXPECT_TRUE(slid.accepted) << slid.refusal;
  EXPECT_FALSE(slid.normals_settled);
  EXPECT_EQ(slid.minimizations, 1);
  const Outcome near = run_loop(false, halving);  // 0.01 of the radii per minimization: settles
  EXPECT_TRUE(near.accepted) << near.refusal;
  EXPECT_TRUE(near.normals_settled);
  EXPECT_EQ(near.minimizations, 4);
  const Outcome release = run_loop(true, halving, 3e-4);
  EXPECT_TRUE(release.accepted) << release.refusal;
  EXPECT_TRUE(release.normals_settled);
  EXPECT_EQ(release.minimizations, 2);
}

}  // namespace
}  // namespace fibra
