// The searched Newton step's length (solver/line_search.hpp): backtracking to the sufficient
// decrease, then an expansion that recovers the length one interpolation through a kinked
// potential throws away, without ever reaching a length the backtracking refused.
#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "fibra/solver/line_search.hpp"

namespace fibra::test {
namespace {

// Records the lengths at which the search evaluated the potential.
template <class F>
struct Recorded {
  F f;
  std::vector<double> lengths;
  double operator()(double a) {
    lengths.push_back(a);
    return f(a);
  }
};
template <class F>
Recorded<F> recorded(F f) {
  return Recorded<F>{f, {}};
}

TEST(LineSearch, TakesTheFullStepOnAQuadraticWhoseMinimumItIs) {
  // e(a) = (a - 1)^2 - 1: slope -2 at 0, minimum at the full step.
  auto e = recorded([](double a) { return (a - 1.0) * (a - 1.0) - 1.0; });
  const StepLength s = search_step_length(e, 0.0, -2.0, 0.0);
  EXPECT_EQ(s.alpha, 1.0);
  EXPECT_EQ(s.trials, 0);
  EXPECT_EQ(e.lengths, std::vector<double>{1.0});
}

TEST(LineSearch, BacktracksToTheQuadraticsMinimumOnAQuadraticOvershotTwice) {
  // Minimum at 0.5: the interpolation through e(1) finds it exactly, and the expansion's first
  // try (0.75, halfway to the refused full step) raises the potential.
  auto e = recorded([](double a) { return (a - 0.5) * (a - 0.5) - 0.25; });
  const StepLength s = search_step_length(e, 0.0, -1.0, 0.0);
  EXPECT_DOUBLE_EQ(s.alpha, 0.5);
  EXPECT_DOUBLE_EQ(s.energy, -0.25);
  EXPECT_EQ(s.trials, 2);
  ASSERT_EQ(e.lengths.size(), 3u);
  EXPECT_DOUBLE_EQ(e.lengths[2], 0.75);
}

TEST(LineSearch, ExpandsAStepTheInterpolationThrewTooFarBack) {
  // A kink at 0.75 (a friction slip turning to stick, a contact closing): the quadratic through
  // e(1) puts the minimum at 0.039, clamped to 0.1. Doubling while the potential falls, and
  // halfway to the refused full step at the end, brings the step to 0.7 instead of 0.1.
  auto e = recorded([](double a) { return a <= 0.75 ? -a : -0.75 + 50.0 * (a - 0.75); });
  const StepLength s = search_step_length(e, 0.0, -1.0, 0.0);
  EXPECT_DOUBLE_EQ(s.alpha, 0.7);
  EXPECT_DOUBLE_EQ(s.energy, -0.7);
  EXPECT_EQ(s.trials, 4);
  const std::vector<double> expected{1.0, 0.1, 0.2, 0.4, 0.7};
  ASSERT_EQ(e.lengths.size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k) EXPECT_DOUBLE_EQ(e.lengths[k], expected[k]) << k;
}

TEST(LineSearch, StopsExpandingWhereTheModelCannotBeEvaluated) {
  // Beyond 0.3 the potential is not finite (fibers through each other): the backtracking takes
  // a tenth, the expansion keeps 0.2 (lower) and stops at 0.4.
  auto e = recorded([](double a) {
    return a > 0.3 ? std::numeric_limits<double>::infinity() : (a - 0.25) * (a - 0.25) - 0.0625;
  });
  const StepLength s = search_step_length(e, 0.0, -0.5, 0.0);
  EXPECT_DOUBLE_EQ(s.alpha, 0.2);
  EXPECT_DOUBLE_EQ(s.energy, 0.0025 - 0.0625);
  EXPECT_EQ(s.trials, 3);
}

TEST(LineSearch, NeverExpandsToALengthItRefused) {
  // e(1) and e(0.5) give no decrease: the backtracking refuses both and accepts 0.25. The
  // expansion tries at most halfway to 0.5 (0.375, kept; 0.4375, refused at the kink at 0.4),
  // never 0.5 itself.
  auto e = recorded([](double a) { return a <= 0.4 ? -a : 0.0; });
  const StepLength s = search_step_length(e, 0.0, -1.0, 0.0);
  EXPECT_DOUBLE_EQ(s.alpha, 0.375);
  EXPECT_EQ(s.trials, 4);
  const std::vector<double> expected{1.0, 0.5, 0.25, 0.375, 0.4375};
  ASSERT_EQ(e.lengths.size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k) EXPECT_DOUBLE_EQ(e.lengths[k], expected[k]) << k;
}

TEST(LineSearch, TakesTheLastTrialWhenNoLengthDecreasesEnough) {
  // An ascent direction mislabelled as descent: eight backtracks, no expansion, the last trial.
  auto e = recorded([](double a) { return a; });
  const StepLength s = search_step_length(e, 0.0, -1.0, 0.0);
  EXPECT_EQ(s.trials, 8);
  EXPECT_EQ(e.lengths.size(), 9u);
  EXPECT_GT(s.alpha, 0.0);
  EXPECT_LT(s.alpha, 0.5 * 0.5 * 0.5);
}

// Where Newton starts along a weave increment's prediction (search_prediction_length).
TEST(PredictionSearch, StartsAtTheParabolasMinimumOnAQuadratic) {
  // e(t) = (t - 0.3)^2: the parabola through e(0), its slope and e(1) is e itself.
  auto e = recorded([](double t) { return (t - 0.3) * (t - 0.3); });
  const StepLength s = search_prediction_length(e, 0.09, -0.6);
  EXPECT_NEAR(s.alpha, 0.3, 1e-15);
  EXPECT_NEAR(s.energy, 0.0, 1e-15);
  EXPECT_EQ(s.trials, 1);
  EXPECT_EQ(e.lengths.size(), 2u);
}

TEST(PredictionSearch, TakesTheWholePredictionWhereThePotentialFallsBeyondIt) {
  // Minimum at 1.5, beyond the prediction: the whole of it, no evaluation but e(1).
  auto e = recorded([](double t) { return (t - 1.5) * (t - 1.5); });
  const StepLength s = search_prediction_length(e, 2.25, -3.0);
  EXPECT_EQ(s.alpha, 1.0);
  EXPECT_DOUBLE_EQ(s.energy, 0.25);
  EXPECT_EQ(e.lengths, std::vector<double>{1.0});
  // Not convex along it (a concave potential): the whole of it too.
  auto c = recorded([](double t) { return -t * t - t; });
  EXPECT_EQ(search_prediction_length(c, 0.0, -1.0).alpha, 1.0);
}

TEST(PredictionSearch, HalvesUntilThePotentialIsBelowTheStarts) {
  // A kink at 0.1 (a contact closing): the parabola through e(0) = 0, the slope -1 and
  // e(1) = 1.7 has its minimum at 1 / 5.4, where the potential is 0.07, above the start's;
  // halved, 1 / 10.8, it is below.
  auto e = recorded([](double t) { return t <= 0.1 ? -t : -0.1 + 2.0 * (t - 0.1); });
  const StepLength s = search_prediction_length(e, 0.0, -1.0);
  EXPECT_NEAR(s.alpha, 1.0 / 10.8, 1e-15);
  EXPECT_NEAR(s.energy, -1.0 / 10.8, 1e-15);
  EXPECT_EQ(s.trials, 2);
  ASSERT_EQ(e.lengths.size(), 3u);
  EXPECT_NEAR(e.lengths[1], 1.0 / 5.4, 1e-15);
  // A potential that rises along the whole prediction: the start.
  auto up = recorded([](double t) { return t * t + t; });
  const StepLength none = search_prediction_length(up, 0.0, 1.0);
  EXPECT_EQ(none.alpha, 0.0);
  EXPECT_EQ(none.energy, 0.0);
  // Descending at the start, but only within 1e-3 of it: four halvings from the parabola's
  // minimum (0.25) do not get there, and Newton starts at the start.
  auto narrow = recorded([](double t) { return t < 1e-3 ? -t : 1.0; });
  const StepLength back = search_prediction_length(narrow, 0.0, -1.0);
  EXPECT_EQ(back.alpha, 0.0);
  EXPECT_EQ(back.energy, 0.0);
  EXPECT_EQ(back.trials, 5);
  EXPECT_DOUBLE_EQ(narrow.lengths.back(), 0.015625);
}

TEST(PredictionSearch, StartsHalfwayWhereThePredictionCannotBeEvaluated) {
  auto e = recorded([](double t) { return t > 0.6 ? std::numeric_limits<double>::quiet_NaN() : (t - 0.4) * (t - 0.4); });
  const StepLength s = search_prediction_length(e, 0.16, -0.8);
  EXPECT_DOUBLE_EQ(s.alpha, 0.5);
  EXPECT_DOUBLE_EQ(s.energy, 0.01);
  // Halved while the potential is not finite or not below the start's.
  auto far = recorded([](double t) { return t > 0.1 ? std::numeric_limits<double>::infinity() : -t; });
  const StepLength f = search_prediction_length(far, 0.0, -1.0);
  EXPECT_DOUBLE_EQ(f.alpha, 0.0625);
  const std::vector<double> expected{1.0, 0.5, 0.25, 0.125, 0.0625};
  EXPECT_EQ(far.lengths, expected);
}

}  // namespace
}  // namespace fibra::test
