#pragma once
/// Sparse symmetric linear solver interface: analyse a pattern once, factor values (optionally
/// shifted, A + beta I), solve. Implementations: CHOLMOD (supernodal, METIS) and Eigen.
#include <memory>
#include <string>
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/solver/block_pattern.hpp"

namespace fibra {

/// Outcome of a factorization.
enum class FactorStatus { Ok, NotPositiveDefinite, Failed };

/// Symmetric sparse direct solver working on a BlockPattern's upper CSC storage.
class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  /// Symbolic analysis (ordering, elimination tree) of a new pattern, reused until the pattern
  /// changes. Done at the next factorize(): until then solve() still uses the last factor (of
  /// the old pattern's matrix: the Newton solver preconditions with it).
  virtual void analyze(const BlockPattern& pattern) = 0;
  /// Numeric factorization of A + shift * I with A's upper-triangle values.
  virtual FactorStatus factorize(const std::vector<double>& values, double shift) = 0;
  /// True when the last factorization succeeded (solve() may be called).
  virtual bool has_factor() const = 0;
  /// Solves A x = b with the last successful factorization.
  virtual void solve(const VecX& b, VecX& x) = 0;
  /// Short name ("cholmod", "eigen").
  virtual std::string name() const = 0;
  /// Nonzeros in the factor after the last factorization (0 if unknown).
  virtual double factor_nonzeros() const { return 0; }
  /// Floating-point operations of one numeric factorization, from the last analysis (0 if unknown).
  virtual double factor_flops() const { return 0; }
};

/// Creates a solver by name ("cholmod" or "eigen"); throws std::invalid_argument otherwise.
/// `ordering` (CHOLMOD only): "metis" (default), "amd", or "auto" (CHOLMOD's own choice: AMD,
/// then METIS when AMD fills badly).
std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name, const std::string& ordering = "metis");

}  // namespace fibra
