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
PcgResult pcg(const BlockPattern& pattern, const std::vector<double>& values, double shift, const VecX& b, VecX& x,
              const std::function<void(const VecX&, VecX&)>& precondition, const VecX& weight, double tolerance,
              int max_iterations, PcgWorkspace& ws);

}  // namespace fibra
