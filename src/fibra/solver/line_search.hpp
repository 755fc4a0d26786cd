#pragma once
/// The step length of a searched Newton step (docs/theory/solver.md, "Line search"): a
/// backtracking Armijo search on the total potential, then a bounded expansion of a shortened
/// step while the potential keeps falling.
#include <algorithm>
#include <cmath>

namespace fibra {

/// What a line search found: the step length, the potential there, and how many potentials it
/// evaluated beyond the full step's.
struct StepLength {
  double alpha = 1.0;
  double energy = 0.0;
  int trials = 0;
};

/// The length along a descent direction. `energy(alpha)` is the potential at q + alpha dq (not
/// finite where the model cannot be evaluated), `e0` the potential at q, `slope` the
/// directional derivative dq.r there (negative) and `noise` the round-off below which two
/// potentials are equal.
///
/// Backtracking: from alpha = 1, the minimum of the quadratic through e0, the slope and
/// e(alpha), kept in [0.1, 0.5] alpha, until the sufficient decrease
/// e(alpha) <= e0 + 1e-4 alpha slope holds, at most eight times (a step that has not found it
/// is taken as it is).
///
/// Expansion: a backtracked step's length comes from one interpolation through a non-smooth
/// potential (friction's stick-slip kink, a contact closing from a gap), and often lands far
/// short of the minimum along the direction. Up to three times, the search tries
/// min(2 alpha, (alpha + refused) / 2), refused being the shortest length refused so far, and
/// keeps it while the potential falls; it never reaches a refused length.
template <class Energy>
StepLength search_step_length(Energy&& energy, double e0, double slope, double noise) {
  StepLength s;
  s.energy = energy(1.0);
  auto sufficient = [&](double alpha, double e) { return std::isfinite(e) && e <= e0 + 1e-4 * alpha * slope + noise; };
  double refused = 1.0;
  for (int k = 0; k < 8 && !sufficient(s.alpha, s.energy); ++k) {
    refused = s.alpha;
    const double a_q = std::isfinite(s.energy) ? -slope * s.alpha * s.alpha / (2.0 * (s.energy - e0 - slope * s.alpha))
                                               : 0.1 * s.alpha;
    s.alpha = std::clamp(a_q, 0.1 * s.alpha, 0.5 * s.alpha);
    s.energy = energy(s.alpha);
    ++s.trials;
  }
  if (s.alpha == 1.0 || !sufficient(s.alpha, s.energy)) return s;
  for (int k = 0; k < 3; ++k) {
    const double a = std::min(2.0 * s.alpha, 0.5 * (s.alpha + refused));  // at least 1.07 alpha
    const double e = energy(a);
    ++s.trials;
    if (!(std::isfinite(e) && e < s.energy)) break;
    s.alpha = a;
    s.energy = e;
  }
  return s;
}

/// How far along a prediction Newton starts (a weave increment's, StaticSolver::search_prediction).
/// `energy(t)` is the potential at the start moved by t times the prediction, `e0` the potential
/// at the start and `slope` the directional derivative along the prediction there (of either
/// sign: a prediction is no descent direction by construction).
///
/// The minimum in [0, 1] of the parabola through e0, the slope and e(1) (1 where the parabola is
/// not convex; 0.5 where e(1) is not finite), halved up to four times until the potential there
/// is below e0; 0 (the start) where it is nowhere so.
template <class Energy>
StepLength search_prediction_length(Energy&& energy, double e0, double slope) {
  StepLength s;
  const double e1 = energy(1.0);
  const double curvature = e1 - e0 - slope;
  s.alpha = !std::isfinite(e1) ? 0.5 : curvature > 0.0 ? std::clamp(-slope / (2.0 * curvature), 0.0, 1.0) : 1.0;
  s.energy = s.alpha == 1.0 ? e1 : s.alpha > 0.0 ? energy(s.alpha) : e0;
  s.trials = s.alpha == 1.0 || s.alpha == 0.0 ? 0 : 1;
  for (int k = 0; k < 4 && s.alpha > 0.0 && !(s.energy < e0); ++k) {
    s.alpha *= 0.5;
    s.energy = energy(s.alpha);
    ++s.trials;
  }
  if (!(s.energy < e0)) {
    s.alpha = 0.0;
    s.energy = e0;
  }
  return s;
}

}  // namespace fibra
