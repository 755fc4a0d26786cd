// CHOLMOD back end: supernodal LL^T with METIS ordering, symbolic analysis reused.
#include <cholmod.h>
#include <omp.h>

#include <fmt/core.h>

#include <chrono>
#include <stdexcept>

#include "fibra/core/debug.hpp"
#include "fibra/solver/blas_threads.hpp"
#include "fibra/solver/cholmod_view.hpp"
#include "fibra/solver/linear_solver.hpp"
#include "fibra/solver/rounded_factor.hpp"

namespace fibra {
namespace {


class CholmodSolver final : public LinearSolver {
 public:
  explicit CholmodSolver(const std::string& ordering) {
    cholmod_start(&m_common);
    m_common.supernodal = CHOLMOD_SUPERNODAL;
    if (ordering == "auto") {
      m_common.nmethods = 0;  // CHOLMOD's default strategy
    } else {
      m_common.nmethods = 1;
      m_common.method[0].ordering = ordering == "amd" ? CHOLMOD_AMD : CHOLMOD_METIS;
    }
    m_common.postorder = 1;
    m_common.quick_return_if_not_posdef = 1;
    m_common.print = 0;
    m_common.error_handler = nullptr;
  }
  ~CholmodSolver() override {
    if (m_factor) cholmod_free_factor(&m_factor, &m_common);
    for (cholmod_dense** d : {&m_x, &m_y, &m_e})
      if (*d) cholmod_free_dense(d, &m_common);
    cholmod_finish(&m_common);
  }

  void analyze(const BlockPattern& pattern) override {
    m_pattern = &pattern;
    m_pending = true;
  }

  FactorStatus factorize(const std::vector<double>& values, double shift) override {
    if (m_pending) {
      if (m_factor) cholmod_free_factor(&m_factor, &m_common);
      m_dummy.assign(m_pattern->nonzeros(), 0.0);
      cholmod_sparse pattern = cholmod_upper(*m_pattern, m_dummy.data());
      const auto t0 = std::chrono::steady_clock::now();
      m_factor = cholmod_analyze(&pattern, &m_common);
      if (!m_factor) throw std::runtime_error("CHOLMOD analysis failed");
      if (debug_newton())
        fmt::print(stderr, "  analysis: {:.2f} s, {:.4g} factor nonzeros\n",
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), m_common.lnz);
      m_flops = m_common.fl;
      m_pending = false;
    }
    m_factored = false;
    cholmod_sparse a = cholmod_upper(*m_pattern, values.data());
    double beta[2] = {shift, 0.0};
    // CHOLMOD's supernodal factorization opens an OpenMP region per supernode copy (with a
    // team size fixed when CHOLMOD was built): on a small machine with passive waiting that is a
    // futex wake and a context switch per supernode, more than the copy. The dense supernode
    // work goes to the threaded BLAS; the copies run on this thread.
    // (The team size is fixed inside CHOLMOD, so the regions are made inactive instead.)
    const int levels = omp_get_max_active_levels();
    omp_set_max_active_levels(0);
    const ScopedBlasThreads blas(blas_threads_for_factor());
    cholmod_factorize_p(&a, beta, nullptr, 0, m_factor, &m_common);
    omp_set_max_active_levels(levels);
    if (m_common.status == CHOLMOD_NOT_POSDEF) return FactorStatus::NotPositiveDefinite;
    if (m_common.status < CHOLMOD_OK) return FactorStatus::Failed;
    m_factored = true;
    m_rounded_ready = false;
    if (m_precision == KrylovPrecision::Single || m_precision == KrylovPrecision::Half ||
        (m_precision == KrylovPrecision::Auto && m_common.lnz >= kRoundedFactorNonzeros)) {
      SupernodalView v = supernodal_view(*m_factor);
      if (storage() == FactorStorage::Half) {
        const Index n = m_pattern->rows();
        m_diagonal.assign(n, shift);
        for (Index d = 0; d < n; ++d) m_diagonal[d] += values[m_pattern->find(d, d)];
        v.diagonal = m_diagonal.data();
      }
      m_rounded.assign(v, storage());
      m_rounded_ready = true;
      if (debug_newton()) print_rounded_comparison();
    }
    return FactorStatus::Ok;
  }

  bool has_factor() const override { return m_factored; }

  void solve(const VecX& b, VecX& x) override {
    if (!m_factored) throw std::logic_error("CHOLMOD solve without a factorization");
    cholmod_dense rhs;
    rhs.nrow = b.size();
    rhs.ncol = 1;
    rhs.nzmax = b.size();
    rhs.d = b.size();
    rhs.x = const_cast<double*>(b.data());
    rhs.z = nullptr;
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    // solve2 keeps its solution and work arrays between calls (repeated preconditioner solves).
    const ScopedBlasThreads blas(blas_threads_for_factor());
    if (!cholmod_solve2(CHOLMOD_A, m_factor, &rhs, nullptr, &m_x, nullptr, &m_y, &m_e, &m_common))
      throw std::runtime_error("CHOLMOD solve failed");
    x = Eigen::Map<const VecX>(static_cast<double*>(m_x->x), b.size());
  }

  void set_krylov_precision(KrylovPrecision p) override { m_precision = p; }
  bool rounded_preconditioner() const override { return m_rounded_ready; }

  void precondition(const VecX& b, VecX& x) override {
    if (!m_rounded_ready) return solve(b, x);
    m_rounded.solve(b, x);
  }

  std::string name() const override { return "cholmod"; }
  double factor_nonzeros() const override { return m_common.lnz; }
  double factor_flops() const override { return m_flops; }

 private:
  /// BLAS threads for this factor's factorization and solves (0: leave them as they are).
  /// With adaptive BLAS threads, factors of at least 5e10 flops (by default) run their BLAS on
  /// as many threads as OpenMP has. Small factors stay on one BLAS thread: there OpenBLAS's idle
  /// threads spin between the many small BLAS calls and take the cores from the OpenMP assembly
  /// (a 2 x 2 weave ran twice as fast on one BLAS thread; the bundle benchmark's factor, 4.4e8
  /// flops, factorizes in 828 ms on one and 900 ms on two). A 480-fiber woven sample's factor
  /// (3.2e11 flops) factorizes 1.4 times faster on two, and its solves 1.25 times
  /// (docs/performance.md, "BLAS and OpenMP threads").
  int blas_threads_for_factor() const {
    return m_flops >= adaptive_blas_min_flops() ? omp_get_max_threads() : 0;
  }

  /// How the rounded copy stores its values: halves when asked, floats otherwise (Auto too:
  /// docs/performance.md, "The rounded preconditioner").
  FactorStorage storage() const {
    return m_precision == KrylovPrecision::Half ? FactorStorage::Half : FactorStorage::Float;
  }

  /// Times a double and a rounded solve of one random right-hand side and prints them
  /// with their relative difference (FIBRA_DEBUG_NEWTON).
  void print_rounded_comparison() {
    const VecX b = VecX::Random(static_cast<Index>(m_factor->n));
    VecX x_double, x_rounded;
    const auto t0 = std::chrono::steady_clock::now();
    solve(b, x_double);
    const auto t1 = std::chrono::steady_clock::now();
    // The rounded solve's best of three (the first touches its work arrays).
    double rounded = 1e300;
    for (int k = 0; k < 3; ++k) {
      const auto t2 = std::chrono::steady_clock::now();
      m_rounded.solve(b, x_rounded);
      rounded = std::min(rounded, std::chrono::duration<double>(std::chrono::steady_clock::now() - t2).count());
    }
    fmt::print(stderr,
               "  rounded factor: {:.3e} {} values, {:.1f} % in the tree's top; solve {:.3f} s (best of 3; double {:.3f} s), "
               "relative difference {:.2e}\n",
               m_rounded.values(), m_rounded.storage() == FactorStorage::Half ? "half" : "single",
               100.0 * m_rounded.top_share(),
               rounded, std::chrono::duration<double>(t1 - t0).count(),
               (x_double - x_rounded).norm() / x_double.norm());
  }

  cholmod_common m_common{};
  cholmod_factor* m_factor = nullptr;
  cholmod_dense *m_x = nullptr, *m_y = nullptr, *m_e = nullptr;  // solve2's solution and work arrays
  double m_flops = 0.0;     // flops of a numeric factorization, from the last analysis
  bool m_pending = false;   // a new pattern waits for its analysis (next factorize)
  bool m_factored = false;  // m_factor holds a successful numeric factorization
  const BlockPattern* m_pattern = nullptr;
  std::vector<double> m_dummy;
  std::vector<double> m_diagonal;  // the factored matrix's diagonal (halves' row scales)
  RoundedFactor m_rounded;      // the factor rounded to floats or halves, for preconditioning
  bool m_rounded_ready = false;  // m_rounded holds the last successful factorization
  KrylovPrecision m_precision = KrylovPrecision::Auto;
};

}  // namespace

std::unique_ptr<LinearSolver> make_cholmod_solver(const std::string& ordering) {
  if (ordering != "metis" && ordering != "amd" && ordering != "auto")
    throw std::invalid_argument("unknown ordering \"" + ordering + "\" (expected \"metis\", \"amd\" or \"auto\")");
  return std::make_unique<CholmodSolver>(ordering);
}

}  // namespace fibra
