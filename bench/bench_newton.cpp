// One Newton iteration of a fiber bundle, piece by piece: a bundle of 480 straight parallel
// glass fibers (radius 10 um, length 10 mm, 100 quadratic elements each, hexagonal grid, no
// contact), first node of every fiber clamped, evaluated at the reference plus a small smooth
// deformation.
//
//   BM_Assembly/threads:T         Problem::evaluate with gradient + Hessian, T OpenMP threads
//   BM_AssemblyGradient/threads:T Problem::evaluate with gradient only (residual, line search)
//   BM_CholmodAnalyze             symbolic analysis (METIS ordering, supernodes), once
//   BM_CholmodFactorize/blas_threads:B  numeric supernodal LL^T with B OpenBLAS threads
//   BM_CholmodSolve               forward/back substitution for one right-hand side
//   BM_CholmodPrecondition        the same with the factor rounded to floats (CG's preconditioner;
//                                 two threads when OpenMP has them)
//   BM_CholmodPreconditionHalf    the same with the factor's rows scaled and rounded to halves
//   BM_SymmetricMultiply/threads:T  the tangent times a vector (CG's other product)
//   BM_NewtonIteration/threads:2/blas_threads:B  assembly + factorization + solve (target < 1 s)
//   BM_EigenFactorize/fibers:F    Eigen SimplicialLDLT numeric factorization (fallback)
//   BM_EigenSolve/fibers:F        Eigen solve
//
// Run with OMP_WAIT_POLICY=passive (spinning OpenMP workers starve OpenBLAS threads).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <map>
#include <memory>
#include <string>
#include <tuple>

#include "bench_common.hpp"
#include "fibra/solver/blas_threads.hpp"
#include "fibra/solver/krylov.hpp"
#include "fibra/solver/linear_solver.hpp"

namespace {

using namespace fibra;

constexpr int kFibers = 480;
constexpr int kElements = 100;

using bench::Bundle;

Bundle& bundle(int fibers = kFibers) {
  static std::map<int, std::unique_ptr<Bundle>> cache;
  auto& b = cache[fibers];
  if (!b) b = std::make_unique<Bundle>(fibers, kElements);
  return *b;
}

/// A solver of the given kind, analysed once on the bundle's pattern (outside any timing). The
/// factorization benchmarks keep CG's preconditioner in double (no single-precision copy timed
/// with them); BM_CholmodPrecondition asks for the single one, BM_CholmodPreconditionHalf for halves.
LinearSolver& analysed(const std::string& kind, int fibers = kFibers,
                       KrylovPrecision precision = KrylovPrecision::Double) {
  static std::map<std::tuple<std::string, int, KrylovPrecision>, std::unique_ptr<LinearSolver>> cache;
  auto& s = cache[{kind, fibers, precision}];
  if (!s) {
    s = make_linear_solver(kind);
    s->set_krylov_precision(precision);
    Bundle& b = bundle(fibers);
    s->analyze(b.problem->pattern());
    // Warm-up: the first factorization allocates the numeric factor (page faults on ~150 MB).
    s->factorize(b.hessian, 0.0);
  }
  return *s;
}

void add_size_counters(benchmark::State& state, const Bundle& b) {
  state.counters["elements"] = static_cast<double>(b.model.elements.size());
  state.counters["dofs"] = static_cast<double>(b.model.num_dofs());
  state.counters["nnz_A"] = static_cast<double>(b.problem->pattern().nonzeros());
}

/// Sets the OpenBLAS thread count for a scope (restores it after); ok() false without OpenBLAS.
class BlasThreads {
 public:
  explicit BlasThreads(int n) : m_scope(n) {}
  bool ok() const { return blas_threads_available(); }

 private:
  ScopedBlasThreads m_scope;
};

/// Sets the OpenMP thread count for a scope (restores the previous one after).
class OmpThreads {
 public:
  explicit OmpThreads(int n) : m_previous(omp_get_max_threads()) { omp_set_num_threads(n); }
  ~OmpThreads() { omp_set_num_threads(m_previous); }

 private:
  int m_previous;
};

// ---------------------------------------------------------------------------------------------

void BM_Assembly(benchmark::State& state) {
  Bundle& b = bundle();
  const int threads = static_cast<int>(state.range(0));
  OmpThreads omp(threads);
  VecX g;
  std::vector<double> h;
  b.problem->evaluate(b.q, &g, &h);  // warm-up: allocates the value array, as in a Newton loop
  for (auto _ : state) {
    double e = b.problem->evaluate(b.q, &g, &h);
    benchmark::DoNotOptimize(e);
    benchmark::ClobberMemory();
  }
  const double elements = static_cast<double>(b.model.elements.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(elements));
  state.counters["elements_per_s_per_core"] =
      benchmark::Counter(elements * static_cast<double>(state.iterations()) / threads, benchmark::Counter::kIsRate);
  add_size_counters(state, b);
}
BENCHMARK(BM_Assembly)->ArgName("threads")->Arg(1)->Arg(2)->MinTime(2.0)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_AssemblyGradient(benchmark::State& state) {
  Bundle& b = bundle();
  const int threads = static_cast<int>(state.range(0));
  OmpThreads omp(threads);
  VecX g;
  b.problem->evaluate(b.q, &g, nullptr);
  for (auto _ : state) {
    double e = b.problem->evaluate(b.q, &g, nullptr);
    benchmark::DoNotOptimize(e);
    benchmark::ClobberMemory();
  }
  const double elements = static_cast<double>(b.model.elements.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(elements));
  state.counters["elements_per_s_per_core"] =
      benchmark::Counter(elements * static_cast<double>(state.iterations()) / threads, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_AssemblyGradient)->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

// The drag of weave, relax and test steps on its own (Problem::drag_force_norm evaluates its
// gradient alone, as the solver does once per relax increment) and in the assembly of E + g + H
// with it, one thread: isotropic (axial weight 1) and weak along the fibers (0.01, the default
// of weave, relax and test steps). Its cost beside BM_Assembly/threads:1 is the drag's per-node loop.
void BM_AssemblyWithDrag(benchmark::State& state) {
  Bundle& b = bundle();
  OmpThreads omp(1);
  const double axial = static_cast<double>(state.range(0)) / 100.0;
  VecX anchor = b.model.reference;
  for (Index d = 0; d < anchor.size(); ++d) anchor[d] -= 1e-6 * static_cast<double>(d % 7);
  b.problem->set_drag(1e4, anchor, 100.0, axial);
  VecX g;
  std::vector<double> h;
  b.problem->evaluate(b.q, &g, &h);
  for (auto _ : state) {
    double e = b.problem->evaluate(b.q, &g, &h);
    benchmark::DoNotOptimize(e);
    benchmark::ClobberMemory();
  }
  b.problem->set_drag(0.0, anchor);
  state.counters["nodes"] = static_cast<double>(b.model.num_nodes());
}
BENCHMARK(BM_AssemblyWithDrag)->ArgName("axial_percent")->Arg(100)->Arg(1)->MinTime(2.0)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_DragForceNorm(benchmark::State& state) {
  Bundle& b = bundle();
  const double axial = static_cast<double>(state.range(0)) / 100.0;
  b.problem->set_drag(1e4, b.model.reference, 100.0, axial);
  const VecX scale = VecX::Ones(b.q.size());
  for (auto _ : state) {
    double n = b.problem->drag_force_norm(b.q, scale);
    benchmark::DoNotOptimize(n);
  }
  b.problem->set_drag(0.0, b.model.reference);
  state.counters["nodes"] = static_cast<double>(b.model.num_nodes());
}
BENCHMARK(BM_DragForceNorm)->ArgName("axial_percent")->Arg(100)->Arg(1)->UseRealTime()->Unit(benchmark::kMillisecond);

// The symbolic analysis runs at the first factorization after analyze() (the last factor stays
// usable until then): timed together, a fresh solver's analysis and first factorization.
void BM_CholmodAnalyzeFactorize(benchmark::State& state) {
  Bundle& b = bundle();
  for (auto _ : state) {
    std::unique_ptr<LinearSolver> s = make_linear_solver("cholmod");
    s->analyze(b.problem->pattern());
    if (s->factorize(b.hessian, 0.0) != FactorStatus::Ok) {
      state.SkipWithError("factorization failed");
      break;
    }
    benchmark::DoNotOptimize(s.get());
  }
  add_size_counters(state, b);
}
BENCHMARK(BM_CholmodAnalyzeFactorize)->Iterations(1)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_CholmodFactorize(benchmark::State& state) {
  Bundle& b = bundle();
  LinearSolver& s = analysed("cholmod");
  BlasThreads blas(static_cast<int>(state.range(0)));
  if (!blas.ok()) {
    state.SkipWithError("openblas_set_num_threads not found: CHOLMOD is not running on OpenBLAS");
    return;
  }
  OmpThreads omp(2);
  for (auto _ : state) {
    FactorStatus st = s.factorize(b.hessian, 0.0);
    if (st != FactorStatus::Ok) {
      state.SkipWithError("factorization failed (matrix not positive definite?)");
      break;
    }
  }
  add_size_counters(state, b);
  state.counters["nnz_L"] = s.factor_nonzeros();
  state.counters["flops"] = s.factor_flops();
  state.SetLabel(blas_info());
}
BENCHMARK(BM_CholmodFactorize)
    ->ArgName("blas_threads")
    ->Arg(1)
    ->Arg(2)
    ->MinTime(3.0)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

/// Times one substitution with the bundle's factor: solve() (Double) or precondition() with the
/// factor rounded to floats (Single) or halves (Half), which also report their distance to solve().
void time_substitution(benchmark::State& state, KrylovPrecision precision) {
  Bundle& b = bundle();
  const bool single = precision != KrylovPrecision::Double;
  LinearSolver& s = analysed("cholmod", kFibers, precision);
  if (s.factorize(b.hessian, 0.0) != FactorStatus::Ok) {
    state.SkipWithError("factorization failed");
    return;
  }
  const VecX rhs = -b.residual;
  VecX x;
  for (auto _ : state) {
    if (single)
      s.precondition(rhs, x);
    else
      s.solve(rhs, x);
    benchmark::DoNotOptimize(x.data());
  }
  if (single) {
    VecX exact;
    s.solve(rhs, exact);
    state.counters["relative_difference"] = (x - exact).norm() / exact.norm();
  }
  add_size_counters(state, b);
}

/// The tangent times a vector, as conjugate gradients do once per iteration (upper triangle
/// stored, T OpenMP threads, each scattering into its own vector).
void BM_SymmetricMultiply(benchmark::State& state) {
  Bundle& b = bundle();
  const OmpThreads threads(static_cast<int>(state.range(0)));
  const VecX x = b.residual;
  VecX y;
  std::vector<VecX> scratch;
  symmetric_multiply(b.problem->pattern(), b.hessian, 0.0, x, y, scratch);  // sizes the scratch
  for (auto _ : state) {
    symmetric_multiply(b.problem->pattern(), b.hessian, 0.0, x, y, scratch);
    benchmark::DoNotOptimize(y.data());
  }
  add_size_counters(state, b);
}
BENCHMARK(BM_SymmetricMultiply)->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_CholmodSolve(benchmark::State& state) { time_substitution(state, KrylovPrecision::Double); }
BENCHMARK(BM_CholmodSolve)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_CholmodPrecondition(benchmark::State& state) { time_substitution(state, KrylovPrecision::Single); }
BENCHMARK(BM_CholmodPrecondition)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_CholmodPreconditionHalf(benchmark::State& state) { time_substitution(state, KrylovPrecision::Half); }
BENCHMARK(BM_CholmodPreconditionHalf)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_NewtonIteration(benchmark::State& state) {
  Bundle& b = bundle();
  LinearSolver& s = analysed("cholmod");
  const int threads = static_cast<int>(state.range(0));
  BlasThreads blas(static_cast<int>(state.range(1)));
  OmpThreads omp(threads);
  VecX g, r, dq;
  std::vector<double> h;
  const std::vector<char>& fixed = b.problem->fixed();
  b.problem->evaluate(b.q, &g, &h);  // warm-up: the solver keeps its Hessian storage between iterations
  for (auto _ : state) {
    b.problem->evaluate(b.q, &g, &h);
    r = g;
    for (Index d = 0; d < r.size(); ++d)
      if (fixed[d]) r[d] = 0.0;
    if (s.factorize(h, 0.0) != FactorStatus::Ok) {
      state.SkipWithError("factorization failed");
      break;
    }
    s.solve(-r, dq);
    for (Index d = 0; d < dq.size(); ++d)
      if (fixed[d]) dq[d] = 0.0;
    benchmark::DoNotOptimize(dq.data());
  }
  add_size_counters(state, b);
  state.counters["nnz_L"] = s.factor_nonzeros();
}
BENCHMARK(BM_NewtonIteration)
    ->ArgNames({"threads", "blas_threads"})
    ->Args({2, 2})
    ->Args({2, 1})
    ->MinTime(5.0)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_EigenFactorize(benchmark::State& state) {
  const int fibers = static_cast<int>(state.range(0));
  Bundle& b = bundle(fibers);
  LinearSolver& s = analysed("eigen", fibers);
  for (auto _ : state) {
    if (s.factorize(b.hessian, 0.0) != FactorStatus::Ok) {
      state.SkipWithError("factorization failed");
      break;
    }
  }
  add_size_counters(state, b);
}
BENCHMARK(BM_EigenFactorize)->ArgName("fibers")->Arg(kFibers)->MinTime(3.0)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_EigenSolve(benchmark::State& state) {
  const int fibers = static_cast<int>(state.range(0));
  Bundle& b = bundle(fibers);
  LinearSolver& s = analysed("eigen", fibers);
  if (s.factorize(b.hessian, 0.0) != FactorStatus::Ok) {
    state.SkipWithError("factorization failed");
    return;
  }
  const VecX rhs = -b.residual;
  VecX x;
  for (auto _ : state) {
    s.solve(rhs, x);
    benchmark::DoNotOptimize(x.data());
  }
  add_size_counters(state, b);
}
BENCHMARK(BM_EigenSolve)->ArgName("fibers")->Arg(kFibers)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
