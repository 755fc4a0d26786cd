#pragma once
/// Sparse symmetric linear solver interface: analyse a pattern once, factor values (optionally
/// shifted, A + beta I), solve. Implementations: CHOLMOD (supernodal, METIS) and Eigen.
#include <memory>
#include <string>
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/assembly/block_pattern.hpp"

namespace fibra {

/// Outcome of a factorization.
enum class FactorStatus { Ok, NotPositiveDefinite, Failed };

/// Precision of the factor precondition() uses.
enum class KrylovPrecision {
  Auto,    ///< floats for factors of at least kRoundedFactorNonzeros nonzeros, double below
  Single,  ///< the factor rounded to floats (RoundedFactor)
  Half,    ///< the factor's rows scaled to unit length and rounded to halves (RoundedFactor)
  Double,  ///< the factor itself
};

/// Factors of at least this many nonzeros precondition with a rounded copy under Auto: there
/// the substitutions stream hundreds of MB per CG iteration (docs/performance.md, "The
/// rounded preconditioner").
constexpr double kRoundedFactorNonzeros = 1e7;

/// Parses "auto", "single", "half" or "double"; throws std::invalid_argument otherwise.
KrylovPrecision krylov_precision_from(const std::string& name);

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
  /// x ~ A^-1 b with the last successful factorization, as a preconditioner: by default the
  /// exact solve; CHOLMOD with a rounded preconditioner uses the factor rounded to
  /// floats or halves (RoundedFactor).
  virtual void precondition(const VecX& b, VecX& x) { solve(b, x); }
  /// Chooses the precision precondition() uses from the next factorization on (back ends
  /// without a rounded copy ignore it).
  virtual void set_krylov_precision(KrylovPrecision) {}
  /// True when the last factorization made a rounded copy (floats or halves) for precondition().
  virtual bool rounded_preconditioner() const { return false; }
  /// Short name ("cholmod", "eigen").
  virtual std::string name() const = 0;
  /// Nonzeros in the factor after the last factorization (0 if unknown).
  virtual double factor_nonzeros() const { return 0; }
  /// Floating-point operations of one numeric factorization, from the last analysis (0 if unknown).
  virtual double factor_flops() const { return 0; }
  /// Negative pivots of the last factorization (an indefinite solver's; 0 otherwise).
  virtual Index negative_pivots() const { return 0; }
};

/// Creates a solver by name ("cholmod" or "eigen"); throws std::invalid_argument otherwise.
/// `ordering` (CHOLMOD only): "metis" (default), "amd", or "auto" (CHOLMOD's own choice: AMD,
/// then METIS when AMD fills badly).
std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name, const std::string& ordering = "metis");

/// A solver of symmetric indefinite systems: LDL^T without pivoting (Eigen's simplicial), whose
/// factorize() accepts negative pivots and fails on a pivot within round-off (1e-13) of zero
/// relative to the largest (a singular matrix); negative_pivots() counts the negative ones.
std::unique_ptr<LinearSolver> make_indefinite_solver();

}  // namespace fibra
