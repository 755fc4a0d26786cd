// Eigen back end: simplicial LDL^T on the same upper CSC storage (fallback, no BLAS needed).
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <stdexcept>

#include "fibra/solver/linear_solver.hpp"

namespace fibra {

std::unique_ptr<LinearSolver> make_cholmod_solver(const std::string& ordering);

namespace {

class EigenSolver final : public LinearSolver {
 public:
  explicit EigenSolver(bool indefinite = false) : m_indefinite(indefinite) {}
  void analyze(const BlockPattern& pattern) override {
    m_pattern = &pattern;
    m_pending = true;
  }
  FactorStatus factorize(const std::vector<double>& values, double shift) override {
    if (m_pending) {
      std::vector<double> zeros(m_pattern->nonzeros(), 0.0);
      m_ldlt.analyzePattern(map(zeros));
      m_pending = false;
    }
    m_factored = false;
    m_ldlt.setShift(shift);
    m_ldlt.factorize(map(values));
    if (m_ldlt.info() != Eigen::Success) return FactorStatus::Failed;
    const VecX pivots = m_ldlt.vectorD();  // (returned by value)
    const auto d = pivots.array();
    if (m_indefinite) {
      // A pivot within round-off of zero: singular, no step.
      const double largest = d.abs().maxCoeff();
      if (!(largest > 0.0) || (d.abs() <= 1e-13 * largest).any() || !d.allFinite()) return FactorStatus::Failed;
      m_negative = static_cast<Index>((d < 0.0).count());
    } else if ((d <= 0.0).any()) {
      // LL^T semantics: report non-positive pivots as not positive definite.
      return FactorStatus::NotPositiveDefinite;
    }
    m_factored = true;
    return FactorStatus::Ok;
  }
  bool has_factor() const override { return m_factored; }
  void solve(const VecX& b, VecX& x) override { x = m_ldlt.solve(b); }
  std::string name() const override { return m_indefinite ? "eigen-indefinite" : "eigen"; }
  Index negative_pivots() const override { return m_negative; }

 private:
  using Map = Eigen::Map<const Eigen::SparseMatrix<double, Eigen::ColMajor, int>>;
  Map map(const std::vector<double>& values) const {
    return Map(m_pattern->rows(), m_pattern->rows(), m_pattern->nonzeros(), m_pattern->col_ptr().data(),
               m_pattern->row_idx().data(), values.data());
  }
  const BlockPattern* m_pattern = nullptr;
  bool m_pending = false;   // a new pattern waits for its analysis (next factorize)
  bool m_factored = false;  // the last factorization succeeded
  bool m_indefinite = false;  // factorize() accepts negative pivots (an indefinite matrix)
  Index m_negative = 0;       // negative pivots of the last factorization
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double, Eigen::ColMajor, int>, Eigen::Upper> m_ldlt;
};

}  // namespace

KrylovPrecision krylov_precision_from(const std::string& name) {
  if (name == "auto") return KrylovPrecision::Auto;
  if (name == "single") return KrylovPrecision::Single;
  if (name == "half") return KrylovPrecision::Half;
  if (name == "double") return KrylovPrecision::Double;
  throw std::invalid_argument("unknown krylov precision \"" + name + "\" (expected \"auto\", \"single\", \"half\" or \"double\")");
}

std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name, const std::string& ordering) {
  if (name == "cholmod") return make_cholmod_solver(ordering);
  if (name == "eigen") return std::make_unique<EigenSolver>();
  throw std::invalid_argument("unknown linear solver \"" + name + "\" (expected \"cholmod\" or \"eigen\")");
}

std::unique_ptr<LinearSolver> make_indefinite_solver() { return std::make_unique<EigenSolver>(true); }

}  // namespace fibra
