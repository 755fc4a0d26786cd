#pragma once
/// Preconditioned conjugate gradients on a BlockPattern's symmetric upper-CSC matrix, used by
/// the Newton solver to reuse a factorization over several iterations: the factor of an
/// earlier tangent preconditions the current one (docs/theory/solver.md, "Reusing the
/// factorization").
#include <functional>
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/assembly/block_pattern.hpp"

namespace fibra {

/// y = (A + shift I) x for the symmetric matrix whose upper triangle `values` has `pattern`.
/// `scratch` holds one accumulation vector per OpenMP thread (resized on first use).
void symmetric_multiply(const BlockPattern& pattern, const std::vector<double>& values, double shift, const VecX& x,
                        VecX& y, std::vector<VecX>& scratch);

/// Outcome of pcg().
struct PcgResult {
  bool converged = false;  ///< weighted residual below tolerance x weighted |b|
  bool breakdown = false;  ///< a search direction of non-positive curvature (matrix not SPD)
  bool abandoned = false;  ///< stopped early: at its rate, the tolerance was beyond `abandon_beyond`
  int iterations = 0;      ///< preconditioner applications after the first
  double relative_residual = 0;  ///< |W (b - A x)| / |W b| at the end
};

/// Work vectors of pcg(), kept between calls (no allocation once sized).
struct PcgWorkspace {
  VecX r, z, p, ap;
  std::vector<VecX> scratch;
  /// The relative weighted residual after each iteration of the last call (entry 0: at the
  /// start), for diagnostics.
  std::vector<double> history;
};

/// Solves (A + shift I) x = b by conjugate gradients preconditioned by `precondition`
/// (z = M^-1 r, M symmetric positive definite), starting from x = M^-1 b. Stops when
/// |W (b - A x)| <= tolerance |W b| (W = diag(weight), the dofs' force scales) or after
/// `max_iterations` further iterations; x holds the last iterate either way.
/// With `abandon_beyond` > 0 it also stops, unconverged and `abandoned`, once the residual,
/// falling at its geometric rate over the last 10 iterations, would reach the tolerance only
/// after more than `abandon_beyond` iterations in all (judged every 5 iterations from the 15th,
/// on the least of three successive residuals, since CG's residual is not monotone).
/// The CG iterations preconditioned by an older factorization that a new one is worth: the
/// budget of a solve before it gives up, and of the solves since the last factorization beyond
/// the first one's iterations. Automatic (setting < 0): a factorization's flops over 16 times
/// its factor's nonzeros, between 20 and 100. A CG iteration's substitutions do about 4 flops
/// per factor nonzero at memory speed, the factorization its flops at BLAS-3 speed, some 4 times
/// faster per flop on these machines: a factorization of the 480-fiber woven samples (3.2e11
/// flop, 1.9e8 nonzeros) is worth ~100 iterations (docs/theory/solver.md, "Reusing the
/// factorization"); a small model's factor, cheap anyway, gets 20. From flop counts, not timings,
/// so that the solver's path is the same from run to run.
int krylov_budget(int setting, double flops, double nonzeros);

PcgResult pcg(const BlockPattern& pattern, const std::vector<double>& values, double shift, const VecX& b, VecX& x,
              const std::function<void(const VecX&, VecX&)>& precondition, const VecX& weight, double tolerance,
              int max_iterations, PcgWorkspace& ws, int abandon_beyond = 0);

}  // namespace fibra
