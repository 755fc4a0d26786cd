// The step drivers' rules (fibra/steps/step_driver.hpp), each on its own: which driver a step
// gets, how a relax step's drag follows its increments, how a test's levels are sized and
// settled, the weave's end and the load steps' predictor. A host records what a driver asks of
// the solver. Whole runs through these rules are checked by the robustness corpus.
#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "fibra/steps/step_driver.hpp"

namespace fibra::test {
namespace {

class RecordingHost : public StepHost {
 public:
  void move_free_dofs(const VecX& motion, double scale) override {
    moved = motion;
    move_scale = scale;
  }
  void predict_test_level(double lambda) override { predicted.push_back(lambda); }
  double drag_force_residual() const override { return drag_residual; }
  void release_positions(double lambda, int& iterations) override {
    released.push_back(lambda);
    if (progress != nullptr) released_settling.push_back(progress->relax_settling);
    iterations += release_iterations;
  }
  double penetration_over_cap() const override { return depth; }
  double test_drag() const override { return last_test_drag; }
  void set_test_drag(double drag) override { last_test_drag = drag; }
  double normal_feedback() const override { return feedback; }

  VecX moved;
  double move_scale = 0;
  std::vector<double> predicted, released;
  double drag_residual = 0, depth = 0, last_test_drag = 0, feedback = 0;
  int release_iterations = 0;
  /// The run whose flags a release records (the solver reads them during the release).
  const SolverProgress* progress = nullptr;
  std::vector<bool> released_settling;  ///< whether each release was solved as a settling increment
};

constexpr double kK0 = 1000.0;  // the contact's initial stiffness the drags are multiples of

StepSpec step(StepSpec::Kind kind, int increments = 4) {
  StepSpec st;
  st.name = std::string(1, 's');  // (not from a literal: GCC 12 warns of a false -Wrestrict there)
  st.kind = kind;
  st.increments = increments;
  st.tolerance = 1e-4;
  return st;
}

SolverProgress fresh(const StepDriver& d, int increments) {
  SolverProgress run;
  run.dl = 1.0 / increments;
  run.relax_drag = 0.0;
  d.begin(run);
  return run;
}

SolvedIncrement solved(double step_dl, int iterations, double settling_moved = -1.0) {
  SolvedIncrement inc;
  inc.step_dl = step_dl;
  inc.iterations = iterations;
  inc.drag = 7.0;
  inc.settling_moved = settling_moved;
  return inc;
}

TEST(StepDrivers, EachKindOfStepGetsItsDriver) {
  const SolverSpec opt;
  EXPECT_TRUE(dynamic_cast<LoadDriver*>(StepDriver::make(step(StepSpec::Kind::Standard), opt, true, kK0).get()));
  EXPECT_TRUE(dynamic_cast<WeaveDriver*>(StepDriver::make(step(StepSpec::Kind::Weave), opt, true, kK0).get()));
  auto relax = StepDriver::make(step(StepSpec::Kind::Relax), opt, true, kK0);
  EXPECT_TRUE(dynamic_cast<RelaxDriver*>(relax.get()) && !dynamic_cast<TestDriver*>(relax.get()));
  EXPECT_TRUE(dynamic_cast<TestDriver*>(StepDriver::make(step(StepSpec::Kind::Biaxial), opt, true, kK0).get()));
  EXPECT_TRUE(dynamic_cast<TestDriver*>(StepDriver::make(step(StepSpec::Kind::Shear), opt, true, kK0).get()));
  // Without contact, or with the drag off, nothing is held by a drag: a load step's rules.
  EXPECT_TRUE(dynamic_cast<LoadDriver*>(StepDriver::make(step(StepSpec::Kind::Relax), opt, false, 0.0).get()));
  SolverSpec no_drag;
  no_drag.method.relax_drag = 0.0;
  EXPECT_TRUE(dynamic_cast<LoadDriver*>(StepDriver::make(step(StepSpec::Kind::Biaxial), no_drag, true, kK0).get()));
}

TEST(StepDrivers, ALoadStepPredictsFromTheLastIncrementsMotion) {
  const SolverSpec opt;
  const StepSpec st = step(StepSpec::Kind::Standard);
  const LoadDriver d(st, opt, false, 0.0);
  SolverProgress run = fresh(d, 4);
  EXPECT_TRUE(run.relaxed);  // ends at full load
  const IncrementMode mode = d.mode(run, 0.25);  // no drag, no weave, no test
  EXPECT_FALSE(mode.weave || mode.proximal || mode.test || mode.loading);
  EXPECT_EQ(mode.drag, 0.0);
  RecordingHost host;
  const double first = d.load_step(run, host);
  EXPECT_DOUBLE_EQ(first, 0.25);
  d.predict(run, host, first);
  EXPECT_EQ(host.moved.size(), 0);  // no motion yet to predict from
  const VecX start = VecX::Zero(3), end = VecX::Constant(3, 2.0);
  SolvedIncrement inc = solved(first, 3);
  inc.start = &start;
  inc.state = &end;
  EXPECT_EQ(d.converged(run, host, inc), 0);
  run.lambda += first;
  d.predict(run, host, 0.125);
  EXPECT_EQ(host.moved, end);
  EXPECT_DOUBLE_EQ(host.move_scale, 0.5);
  // Easy increments grow back to the step's own size, never beyond it.
  run.dl = 0.1;
  d.grow(run, 4);
  EXPECT_DOUBLE_EQ(run.dl, 0.15);
  d.grow(run, 5);
  EXPECT_DOUBLE_EQ(run.dl, 0.15);
  run.dl = 0.2;
  d.grow(run, 1);
  EXPECT_DOUBLE_EQ(run.dl, 0.25);
  // The last increment takes what is left.
  run.lambda = 0.9;
  EXPECT_NEAR(d.load_step(run, host), 0.1, 1e-15);
}

// A load step with contact is held from its first failure on: the same increment again with
// the stiffest drag, then each level repeated until the drag's force is below the held
// tolerance of the load at an increment that iterated its normals; the drag stays above the
// normals' feedback and is never released.
TEST(StepDrivers, ALoadStepWithContactIsHeldFromItsFirstFailure) {
  const SolverSpec opt;
  const StepSpec st = step(StepSpec::Kind::Standard);
  const LoadDriver d(st, opt, true, kK0);
  SolverProgress run = fresh(d, 4);
  RecordingHost host;
  EXPECT_DOUBLE_EQ(d.load_step(run, host), 0.25);
  EXPECT_EQ(d.mode(run, 0.25).drag, 0.0);  // not held before a failure
  EXPECT_TRUE(d.failed(run, 0.25));        // held: the same increment again, not cut
  EXPECT_DOUBLE_EQ(run.relax_drag, opt.method.relax_drag * kK0);
  EXPECT_DOUBLE_EQ(d.load_step(run, host), 0.25);
  IncrementMode mode = d.mode(run, 0.25);
  EXPECT_TRUE(mode.proximal && mode.held && mode.loading);
  EXPECT_FALSE(mode.test || mode.weave);
  EXPECT_DOUBLE_EQ(mode.drag, kK0);
  EXPECT_DOUBLE_EQ(mode.tolerance, opt.method.held_tolerance);  // what the solver settles its normals to
  const VecX start = VecX::Zero(3), end = VecX::Constant(3, 1.0);
  SolvedIncrement inc = solved(0.25, 6);
  inc.start = &start;
  inc.state = &end;
  host.drag_residual = 1e-2;
  host.feedback = 100.0;
  run.normals_settled = true;
  EXPECT_EQ(d.converged(run, host, inc), 0);
  run.lambda += 0.25;
  EXPECT_FALSE(run.level_settled || run.relax_settling);
  EXPECT_DOUBLE_EQ(run.relax_drag, kK0 / 4);
  EXPECT_DOUBLE_EQ(d.load_step(run, host), 0.0);  // the level repeats
  mode = d.mode(run, 0.0);
  EXPECT_TRUE(mode.held && !mode.loading);
  // Below the step's tolerance: the next increments iterate their normals.
  host.drag_residual = 0.5 * st.tolerance;
  host.feedback = 400.0;  // the contact's force grew: the drag follows it
  d.converged(run, host, solved(0.0, 3));
  EXPECT_TRUE(run.relax_settling);
  EXPECT_FALSE(run.level_settled);
  EXPECT_DOUBLE_EQ(run.relax_drag, 400.0);  // kept while settling, raised to the normals' feedback
  // Within the held tolerance, but its normals not settled, then settled.
  host.drag_residual = 0.5 * opt.method.held_tolerance;
  run.normals_settled = false;
  d.converged(run, host, solved(0.0, 2));
  EXPECT_FALSE(run.level_settled);
  run.normals_settled = true;
  d.converged(run, host, solved(0.0, 2));
  EXPECT_TRUE(run.level_settled);
  EXPECT_FALSE(run.relaxed);          // not at full load
  EXPECT_FALSE(run.relax_settling);   // the next level's loading is lagged
  EXPECT_TRUE(host.released.empty());  // nothing to release
  EXPECT_DOUBLE_EQ(d.load_step(run, host), 0.25);
  // Without contact, a failure is cut.
  const LoadDriver alone(st, opt, false, 0.0);
  SolverProgress bare = fresh(alone, 4);
  EXPECT_FALSE(alone.failed(bare, 0.25));
  EXPECT_EQ(bare.relax_drag, 0.0);
}

TEST(StepDrivers, AWeaveEndsOnceItsTowsAreApartAndStopsAtTwiceItsIncrements) {
  const SolverSpec opt;
  const StepSpec st = step(StepSpec::Kind::Weave, 3);
  const WeaveDriver d(st, opt, true, kK0);
  SolverProgress run = fresh(d, 3);
  EXPECT_FALSE(run.relaxed);
  // Solved with the weave's prescribed normals and its drag, not as a proximal step.
  const IncrementMode mode = d.mode(run, 1.0 / 3.0);
  EXPECT_TRUE(mode.weave);
  EXPECT_FALSE(mode.proximal || mode.test || mode.loading);
  EXPECT_DOUBLE_EQ(mode.drag, opt.method.weave_drag * kK0);
  RecordingHost host;
  host.depth = 1.5;
  run.lambda = 2.0 / 3.0;
  const VecX start = VecX::Zero(2), end = VecX::Ones(2);
  SolvedIncrement inc = solved(1.0 / 3.0, 5);
  inc.start = &start;
  inc.state = &end;
  d.converged(run, host, inc);
  EXPECT_FALSE(run.relaxed);  // at full load, but 1.5 times the cap deep
  run.lambda = 1.0;
  run.done = 5;
  EXPECT_TRUE(d.stop(run, host).empty());
  run.done = 6;
  const std::string why = d.stop(run, host);
  EXPECT_NE(why.find("after 6 increments"), std::string::npos) << why;
  EXPECT_NE(why.find("1.5 times"), std::string::npos) << why;
  host.depth = 1.0;
  inc.step_dl = 0.0;
  d.converged(run, host, inc);
  EXPECT_TRUE(run.relaxed);
  EXPECT_TRUE(d.stop(run, host).empty());
  // Without contact a weave ends at full load.
  const WeaveDriver alone(st, opt, false, 0.0);
  EXPECT_TRUE(fresh(alone, 3).relaxed);
}

// A weave increment with contact starts from the last one's motion scaled to its load step (the
// whole motion at full load), and is solved as the unpredicted increment is: its drag holds its
// start and its first detection is made there (IncrementMode::predicted, StaticSolver).
TEST(StepDrivers, AWeavePredictsFromTheLastIncrementsMotion) {
  const SolverSpec opt;
  const StepSpec st = step(StepSpec::Kind::Weave, 4);
  const WeaveDriver d(st, opt, true, kK0);
  SolverProgress run = fresh(d, 4);
  RecordingHost host;
  EXPECT_FALSE(d.mode(run, 0.25).predicted);
  d.predict(run, host, 0.25);
  EXPECT_EQ(host.moved.size(), 0);  // the step's first increment: no motion yet
  const VecX start = VecX::Constant(3, 1.0), end = VecX::Constant(3, 3.0);
  SolvedIncrement inc = solved(0.25, 6);
  inc.start = &start;
  inc.state = &end;
  d.converged(run, host, inc);
  run.lambda = 0.25;
  EXPECT_TRUE(d.mode(run, 0.125).predicted);
  d.predict(run, host, 0.125);
  EXPECT_EQ(host.moved, VecX::Constant(3, 2.0));
  EXPECT_DOUBLE_EQ(host.move_scale, 0.5);
  // At full load the increments have no load step: the last motion as it was.
  inc.step_dl = 0.0;
  d.converged(run, host, inc);
  run.lambda = 1.0;
  d.predict(run, host, 0.0);
  EXPECT_DOUBLE_EQ(host.move_scale, 1.0);
  // Without contact nothing is predicted (the weave is then a load step without loads).
  const WeaveDriver alone(st, opt, false, 0.0);
  SolverProgress bare = fresh(alone, 4);
  alone.converged(bare, host, inc);
  EXPECT_FALSE(alone.mode(bare, 0.25).predicted);
  RecordingHost untouched;
  alone.predict(bare, untouched, 0.25);
  EXPECT_EQ(untouched.moved.size(), 0);
}

TEST(StepDrivers, ARelaxStepsDragFallsAfterEasyIncrementsAndRisesAfterFailures) {
  const SolverSpec opt;
  const StepSpec st = step(StepSpec::Kind::Relax);
  const RelaxDriver d(st, opt, kK0);
  SolverProgress run = fresh(d, 4);
  EXPECT_DOUBLE_EQ(run.relax_drag, kK0);  // the stiffest: the weave's
  EXPECT_FALSE(run.relaxed);
  run.relax_drag = 0.5 * kK0;
  const IncrementMode mode = d.mode(run, 0.25);  // solved with the adapted drag
  EXPECT_TRUE(mode.proximal);
  EXPECT_FALSE(mode.weave || mode.test || mode.loading);
  EXPECT_DOUBLE_EQ(mode.drag, 0.5 * kK0);
  run.relax_drag = kK0;
  RecordingHost host;
  host.drag_residual = 1.0;  // far from equilibrium
  d.converged(run, host, solved(0.25, 12));
  EXPECT_DOUBLE_EQ(run.relax_drag, kK0 / 4);
  d.converged(run, host, solved(0.25, 30));
  EXPECT_DOUBLE_EQ(run.relax_drag, kK0 / 8);
  d.converged(run, host, solved(0.25, 31));
  EXPECT_DOUBLE_EQ(run.relax_drag, kK0 / 8);
  // A failure: a stiffer drag (x4, up to k0), and a floor at twice the drag that failed.
  EXPECT_TRUE(d.failed(run, 0.25));
  EXPECT_DOUBLE_EQ(run.relax_drag, kK0 / 2);
  EXPECT_DOUBLE_EQ(run.failed_floor, kK0 / 4);
  // The floor holds the drag after an easy increment; far from equilibrium it falls as the
  // drag would (x1/4).
  d.converged(run, host, solved(0.25, 5));
  EXPECT_DOUBLE_EQ(run.relax_drag, kK0 / 4);
  EXPECT_DOUBLE_EQ(run.failed_floor, kK0 / 16);
  // Close to it (drag force at most 100 times the tolerance) the floor decays by 0.7 and holds
  // the drag.
  host.drag_residual = 1e-3;
  d.converged(run, host, solved(0.25, 5));
  EXPECT_DOUBLE_EQ(run.relax_drag, kK0 / 16);
  EXPECT_DOUBLE_EQ(run.failed_floor, 0.7 * kK0 / 16);
  d.converged(run, host, solved(0.25, 5));
  EXPECT_DOUBLE_EQ(run.relax_drag, 0.7 * kK0 / 16);
  // At the stiffest drag a failure has nothing stiffer to try: the load step is cut.
  run.relax_drag = kK0;
  EXPECT_FALSE(d.failed(run, 0.25));
  EXPECT_DOUBLE_EQ(run.relax_drag, kK0);
  // The drag never falls below 1e-9 k0.
  run.relax_drag = 2e-9 * kK0;
  run.failed_floor = 0.0;
  d.converged(run, host, solved(0.25, 5));
  EXPECT_DOUBLE_EQ(run.relax_drag, 1e-9 * kK0);
  EXPECT_TRUE(host.released.empty());  // not at full load: no release
}

TEST(StepDrivers, ARelaxEndsAtFullLoadOnceItsDragForceIsNegligibleAndItsNormalsSettled) {
  const SolverSpec opt;
  const StepSpec st = step(StepSpec::Kind::Relax);
  const RelaxDriver d(st, opt, kK0);
  SolverProgress run = fresh(d, 4);
  RecordingHost host;
  host.release_iterations = 3;
  run.lambda = 1.0;
  run.relax_drag = 40.0;
  // Drag force below the tolerance, normals unsettled: settling; the drag stays.
  host.drag_residual = 5e-5;
  run.normals_settled = false;
  EXPECT_EQ(d.converged(run, host, solved(0.0, 5, 1e-2)), 0);
  EXPECT_FALSE(run.relaxed);
  EXPECT_TRUE(run.relax_settling);
  EXPECT_DOUBLE_EQ(run.relax_drag, 40.0);
  EXPECT_DOUBLE_EQ(run.settling_residual, 1e-2);
  // The next settling increment halves that residual: the creep dies out, the drag stays.
  d.converged(run, host, solved(0.0, 5, 4e-3));
  EXPECT_DOUBLE_EQ(run.relax_drag, 40.0);
  // It does not halve: the creep goes on, the drag falls as after any easy increment.
  d.converged(run, host, solved(0.0, 5, 3e-3));
  EXPECT_DOUBLE_EQ(run.relax_drag, 10.0);
  d.converged(run, host, solved(0.0, 20, 2.9e-3));
  EXPECT_DOUBLE_EQ(run.relax_drag, 5.0);
  // Nothing the drag holds still moves (its force below a tenth of the tolerance): the
  // residual with the updated normals stalls, but a weaker drag would only free what it holds.
  host.drag_residual = 0.09 * st.tolerance;
  d.converged(run, host, solved(0.0, 5, 2.8e-3));
  EXPECT_DOUBLE_EQ(run.relax_drag, 5.0);
  d.converged(run, host, solved(0.0, 5, 2.8e-3));
  EXPECT_DOUBLE_EQ(run.relax_drag, 5.0);
  // At a tenth of it, the creep goes on.
  host.drag_residual = 0.1 * st.tolerance;
  d.converged(run, host, solved(0.0, 5, 2.8e-3));
  EXPECT_DOUBLE_EQ(run.relax_drag, 1.25);
  EXPECT_TRUE(host.released.empty());
  // Settled: the step ends, solved on with the positions released (its iterations returned).
  run.normals_settled = true;
  EXPECT_EQ(d.converged(run, host, solved(0.0, 5, 5e-5)), 3);
  EXPECT_TRUE(run.relaxed);
  ASSERT_EQ(host.released.size(), 1u);
  EXPECT_DOUBLE_EQ(host.released[0], 1.0);
  // Not at full load, nothing ends whatever the drag force.
  SolverProgress early = fresh(d, 4);
  d.converged(early, host, solved(0.25, 5));
  EXPECT_FALSE(early.relaxed);
  EXPECT_FALSE(early.relax_settling);
}

TEST(StepDrivers, ATestRepeatsEachLevelUntilItSettles) {
  const SolverSpec opt;
  const StepSpec st = step(StepSpec::Kind::Biaxial, 4);
  const TestDriver d(st, opt, kK0);
  SolverProgress run = fresh(d, 4);
  RecordingHost host;
  host.last_test_drag = 300.0;
  run.relax_drag = 10.0;
  // A level's loading increment starts at the drag that applied the last level, from the
  // interior moved like the edges.
  const double first = d.load_step(run, host);
  EXPECT_DOUBLE_EQ(first, 0.25);
  EXPECT_DOUBLE_EQ(run.relax_drag, 300.0);
  const IncrementMode loading = d.mode(run, first);
  EXPECT_TRUE(loading.proximal && loading.test && loading.loading);
  EXPECT_DOUBLE_EQ(loading.drag, 300.0);
  d.predict(run, host, first);
  ASSERT_EQ(host.predicted.size(), 1u);
  EXPECT_DOUBLE_EQ(host.predicted[0], 0.25);
  // It converged with its drag force above the tolerance: the level settles at the same load
  // factor (load step 0), its drag remembered for the next level.
  host.drag_residual = 1e-2;
  d.converged(run, host, solved(first, 14));
  EXPECT_FALSE(run.level_settled);
  EXPECT_DOUBLE_EQ(host.last_test_drag, 7.0);
  EXPECT_DOUBLE_EQ(run.load_residual, 1e-2);
  run.lambda += first;
  d.grow(run, 14);
  EXPECT_DOUBLE_EQ(run.dl, 0.25);
  EXPECT_DOUBLE_EQ(d.load_step(run, host), 0.0);
  EXPECT_FALSE(d.mode(run, 0.0).loading);
  // A settling increment that fails raises the drag but sets no floor above a loading one's.
  run.failed_floor = 0.0;
  d.failed(run, 1.0);
  EXPECT_DOUBLE_EQ(run.failed_floor, 0.0);
  d.failed(run, 0.0);
  EXPECT_GT(run.failed_floor, 0.0);
  run.failed_floor = 0.0;
  // Settled: released, a point of the curves; the next level grows by half if this one was
  // loaded at the first attempt. The release is solved as a settling increment (its normals
  // and cones iterated until the residual with them is within the tolerance), and the next
  // level's loading increment is a lagged one again.
  host.drag_residual = 5e-5;
  host.progress = &run;
  run.normals_settled = true;
  run.dl = 0.125;
  d.converged(run, host, solved(0.0, 6));
  EXPECT_TRUE(run.level_settled);
  EXPECT_FALSE(run.relaxed);
  ASSERT_EQ(host.released.size(), 1u);
  ASSERT_EQ(host.released_settling.size(), 1u);
  EXPECT_TRUE(host.released_settling[0]);
  EXPECT_FALSE(run.relax_settling);
  d.grow(run, 6);
  EXPECT_DOUBLE_EQ(run.dl, 0.1875);
  run.level_failures = 1;
  d.grow(run, 6);
  EXPECT_DOUBLE_EQ(run.dl, 0.1875);
  EXPECT_EQ(run.level_failures, 0);
  // A level that would leave less than a quarter of itself takes the rest along.
  run.lambda = 0.78;
  run.dl = 0.2;
  EXPECT_NEAR(d.load_step(run, host), 0.22, 1e-15);
  // The last level settled ends the step.
  run.lambda = 1.0;
  d.converged(run, host, solved(0.0, 6));
  EXPECT_TRUE(run.relaxed);
  // No creep rule in tests: the settling residual is left alone.
  EXPECT_EQ(run.settling_residual, std::numeric_limits<double>::infinity());
  d.converged(run, host, solved(0.0, 6, 1e-3));
  EXPECT_EQ(run.settling_residual, std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace fibra::test
