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

}  // namespace
}  // namespace fibra::test
