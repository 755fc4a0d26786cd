#pragma once
/// The diagonal shift of a refused tangent (docs/theory/solver.md, "Indefinite tangents"): the
/// Newton solver factorizes H + beta I, beta from a hundredth of the last shift that passed
/// upward by factors of 100, until a factor passes.
#include <algorithm>
#include <vector>

#include "fibra/solver/linear_solver.hpp"

namespace fibra {

/// What a shift search found: the status of its last factorization, the shift it used (0 when
/// it tried none) and how many factorizations it made.
struct ShiftSearch {
  FactorStatus status = FactorStatus::NotPositiveDefinite;
  double shift = 0;
  int factorizations = 0;
};

/// The first shift tried, relative to the tangent's mean diagonal: a hundredth of `last` (the
/// last shift that passed, relative to its own tangent's mean diagonal), at least 1e-14. A
/// tangent that needed a shift needs about as much at the next iteration: started at 1e-14
/// each time, a shift of 1e-6 takes five factorizations instead of two.
inline double first_shift(double last) { return std::max(1e-14, 1e-2 * last); }

/// Factorizes `values` + beta I with beta = first_shift(last) mean_diag, then 100 times more
/// each time it is refused, until a factor passes or beta reaches `mean_diag` (within 1e-9 of
/// it: 1e-14 times 100 seven times is the mean diagonal only up to round-off, which a compiler
/// may leave on either side).
inline ShiftSearch factorize_shifted(LinearSolver& solver, const std::vector<double>& values, double mean_diag,
                                     double last) {
  ShiftSearch s;
  while (s.status == FactorStatus::NotPositiveDefinite && s.shift < (1.0 - 1e-9) * mean_diag) {
    s.shift = s.shift == 0.0 ? first_shift(last) * mean_diag : s.shift * 100.0;
    s.status = solver.factorize(values, s.shift);
    ++s.factorizations;
  }
  return s;
}

}  // namespace fibra
