// What-if measurements for the CHOLMOD back end on the 480 x 100 bundle matrix (the same
// matrix as bench_newton), calling CHOLMOD directly with the settings of
// src/fibra/solver/cholmod_solver.cpp except the one varied:
//
//   ordering  metis (what fibra uses: nmethods = 1, METIS), amd, natural, and CHOLMOD's
//             default strategy (nmethods = 0: AMD, then METIS only if AMD's fill is high);
//   reuse     every cholmod_factorize allocates, fills and frees a permuted copy of A
//             (cholmod_ptranspose, ~190 MB here); glibc returns it to the kernel (munmap) and
//             the next call page-faults it back in. "reuse" installs SuiteSparse allocator
//             hooks that keep freed blocks >= 1 MB for the next request of the same size.
//
//   BM_Analyze/<ordering>             symbolic analysis, once (counters: supernodes, nnz_L, flops)
//   BM_Factorize/<ordering>           numeric factorization, analysis reused
//   BM_Factorize/<ordering>_reuse     the same with the block-reusing allocator
//   BM_Solve/<ordering>               one solve
//
// Run with OMP_WAIT_POLICY=passive. Evidence for docs/performance.md; not fibra's own code path.
#include <benchmark/benchmark.h>
#include <cholmod.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>

#include "bench_common.hpp"
#include "fibra/solver/cholmod_view.hpp"

namespace {

using namespace fibra;

bench::Bundle& bundle() {
  static bench::Bundle b(480, 100);
  return b;
}

// ------------------------------------------------------------------------------------------
// Block-reusing allocator for SuiteSparse (single-threaded use: CHOLMOD allocates from the
// calling thread only).

class BlockCache {
 public:
  static constexpr size_t kBig = size_t{1} << 20;

  static void install() {
    auto& c = SuiteSparse_config;
    s_saved = {c.malloc_func, c.calloc_func, c.realloc_func, c.free_func};
    c.malloc_func = &cache_malloc;
    c.calloc_func = &cache_calloc;
    c.realloc_func = &cache_realloc;
    c.free_func = &cache_free;
  }
  /// Restores the previous hooks; blocks still in use stay valid (they come from malloc).
  static void uninstall() {
    auto& c = SuiteSparse_config;
    c.malloc_func = s_saved.m;
    c.calloc_func = s_saved.c;
    c.realloc_func = s_saved.r;
    c.free_func = s_saved.f;
    for (auto& [size, p] : s_free) {
      s_size.erase(p);
      std::free(p);
    }
    s_free.clear();
  }

 private:
  struct Saved {
    void* (*m)(size_t);
    void* (*c)(size_t, size_t);
    void* (*r)(void*, size_t);
    void (*f)(void*);
  };
  static inline Saved s_saved{};
  static inline std::unordered_map<void*, size_t> s_size;  // tracked big blocks (live or cached)
  static inline std::multimap<size_t, void*> s_free;       // cached free blocks by size

  static void* cache_malloc(size_t n) {
    if (n < kBig) return std::malloc(n);
    auto it = s_free.find(n);
    if (it != s_free.end()) {
      void* p = it->second;
      s_free.erase(it);
      return p;
    }
    void* p = std::malloc(n);
    if (p) s_size[p] = n;
    return p;
  }
  static void* cache_calloc(size_t n, size_t size) {
    if (n * size < kBig) return std::calloc(n, size);
    void* p = cache_malloc(n * size);
    if (p) std::memset(p, 0, n * size);
    return p;
  }
  static void cache_free(void* p) {
    auto it = s_size.find(p);
    if (it == s_size.end()) return std::free(p);
    s_free.emplace(it->second, p);
  }
  static void* cache_realloc(void* p, size_t n) {
    auto it = p ? s_size.find(p) : s_size.end();
    if (it == s_size.end()) return std::realloc(p, n);  // untracked: plain realloc (result untracked)
    const size_t old = it->second;
    void* q = cache_malloc(n);
    if (q) {
      std::memcpy(q, p, std::min(old, n));
      cache_free(p);
    }
    return q;
  }
};

// ------------------------------------------------------------------------------------------

enum Ordering { Metis, Amd, Natural, Default };

/// CHOLMOD set up like fibra's CholmodSolver, with a chosen ordering strategy.
class Direct {
 public:
  explicit Direct(Ordering o) : m_ordering(o) {
    cholmod_start(&m_c);
    m_c.supernodal = CHOLMOD_SUPERNODAL;
    m_c.postorder = 1;
    m_c.quick_return_if_not_posdef = 1;
    m_c.print = 0;
    m_c.error_handler = nullptr;
    switch (o) {
      case Metis: m_c.nmethods = 1; m_c.method[0].ordering = CHOLMOD_METIS; break;
      case Amd: m_c.nmethods = 1; m_c.method[0].ordering = CHOLMOD_AMD; break;
      case Natural: m_c.nmethods = 1; m_c.method[0].ordering = CHOLMOD_NATURAL; break;
      case Default: m_c.nmethods = 0; break;
    }
  }
  ~Direct() {
    if (m_l) cholmod_free_factor(&m_l, &m_c);
    cholmod_finish(&m_c);
  }
  void analyze() {
    if (m_l) cholmod_free_factor(&m_l, &m_c);
    cholmod_sparse a = wrap();
    m_l = cholmod_analyze(&a, &m_c);
    m_flops = m_c.fl;
    m_lnz = m_c.lnz;
  }
  bool factorize() {
    cholmod_sparse a = wrap();
    cholmod_factorize(&a, m_l, &m_c);
    return m_c.status == CHOLMOD_OK;
  }
  void solve(const VecX& b, VecX& x) {
    cholmod_dense rhs{};
    rhs.nrow = rhs.nzmax = rhs.d = b.size();
    rhs.ncol = 1;
    rhs.x = const_cast<double*>(b.data());
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* sol = cholmod_solve(CHOLMOD_A, m_l, &rhs, &m_c);
    x = Eigen::Map<const VecX>(static_cast<double*>(sol->x), b.size());
    cholmod_free_dense(&sol, &m_c);
  }
  void counters(benchmark::State& state) const {
    state.counters["supernodes"] = static_cast<double>(m_l->nsuper);
    state.counters["nnz_L"] = m_lnz;
    state.counters["flops"] = m_flops;
    const char* names[] = {"METIS", "AMD", "natural", "default"};
    const char* chosen = m_l->ordering == CHOLMOD_METIS ? "METIS" : m_l->ordering == CHOLMOD_AMD ? "AMD" : "";
    state.SetLabel(m_ordering == Default ? std::string("default, chose ") + chosen : std::string(names[m_ordering]));
  }

 private:
  cholmod_sparse wrap() {
    const bench::Bundle& b = bundle();
    return cholmod_upper(b.problem->pattern(), b.hessian.data());
  }
  Ordering m_ordering;
  cholmod_common m_c{};
  cholmod_factor* m_l = nullptr;
  double m_flops = 0, m_lnz = 0;
};

Direct& analysed(Ordering o) {
  static std::map<Ordering, std::unique_ptr<Direct>> cache;
  auto& d = cache[o];
  if (!d) {
    d = std::make_unique<Direct>(o);
    d->analyze();
    d->factorize();  // warm-up: allocates the numeric factor
  }
  return *d;
}

void BM_Analyze(benchmark::State& state, Ordering o) {
  bundle();
  Direct d(o);
  for (auto _ : state) d.analyze();
  d.counters(state);
}

void BM_Factorize(benchmark::State& state, Ordering o, bool reuse) {
  Direct& d = analysed(o);
  if (reuse) BlockCache::install();
  for (auto _ : state)
    if (!d.factorize()) {
      state.SkipWithError("factorization failed");
      break;
    }
  if (reuse) BlockCache::uninstall();
  d.counters(state);
}

void BM_Solve(benchmark::State& state, Ordering o) {
  Direct& d = analysed(o);
  const VecX rhs = -bundle().residual;
  VecX x;
  for (auto _ : state) {
    d.solve(rhs, x);
    benchmark::DoNotOptimize(x.data());
  }
  d.counters(state);
}

}  // namespace

#define FIBRA_ORDERING(name, o)                                                                                  \
  BENCHMARK_CAPTURE(BM_Analyze, name, o)->Iterations(1)->UseRealTime()->Unit(benchmark::kMillisecond);          \
  BENCHMARK_CAPTURE(BM_Factorize, name, o, false)->MinTime(2.0)->UseRealTime()->Unit(benchmark::kMillisecond);   \
  BENCHMARK_CAPTURE(BM_Factorize, name##_reuse, o, true)->MinTime(2.0)->UseRealTime()->Unit(benchmark::kMillisecond); \
  BENCHMARK_CAPTURE(BM_Solve, name, o)->UseRealTime()->Unit(benchmark::kMillisecond)

FIBRA_ORDERING(metis, Metis);
FIBRA_ORDERING(amd, Amd);
FIBRA_ORDERING(natural, Natural);
FIBRA_ORDERING(default, Default);
