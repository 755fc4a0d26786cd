// Rigid bodies and averaged bindings (body/bodies.hpp) on a fabric-scale model: 10 straight
// tows (5 along x, 5 along y, one layer each, no contact), each of 48 parallel glass fibers
// (radius 20 um, length 5 mm, 10 quadratic elements each) on a hexagonal grid inside an
// elliptical section of 0.8 mm x 0.2 mm. A body at each end of each tow binds the 48 fiber
// ends there (20 tow-end bodies, 48 members each, dense local Hessian of size 9*48+6 = 438),
// and 4 edge bodies each bind the 5 tow-end bodies of one edge of the fabric (hierarchy).
// 480 fibers, 4,800 elements, 10,080 nodes, 24 bodies, 24 bindings, 980 bound members.
// The model is written as a case TOML string and read by parse_case_toml.
//
//   BM_BindingEnergy/threads:T    BodySystem::evaluate, energy + gradient + Hessian, into a
//                                 pattern of the binding stencils only; items = bindings,
//                                 also member_evals_per_second (bound members per second);
//                                 T OpenMP threads (used only inside Eigen's GEMM)
//   BM_BindingEnergyGripped       the same (1 thread) with every tow end gripped across its
//                                 tow (grip = [2, 3] / [1, 3]) and its spin held (spin = true):
//                                 2 880 single-node conditions more
//   BM_BindingGradient            the same, energy + gradient only (1 thread, as the rest)
//   BM_BindingScatter             the scatter_local calls of BM_BindingEnergy alone (a dense
//                                 local matrix per binding), to split kernel and scatter
//   BM_ProblemEvaluateWithBindings/threads:T   Problem(model, &bodies).evaluate with gradient +
//                                 Hessian (beams + bindings); items = beam elements
//   BM_ProblemEvaluateNoBindings/threads:T     Problem(model).evaluate: the same beams alone
//   BM_BindingScatterByColumns    what-if: the same scatter with column-ordered loops
//   BM_FabricFactorize/bindings:B CHOLMOD factorization of the matrix with (1) / without (0)
//                                 the bindings (fill of the dense tow-end blocks)
//
// State: reference plus small random perturbations of every node and body, body rotations of
// a few 0.01 rad, random nonzero multipliers. The Problem benchmarks eliminate the 4 edge
// bodies' dofs (an edge is driven by a step in a real fabric model).
//
// Run with OMP_WAIT_POLICY=passive.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "fibra/body/bodies.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/assembly/assembler.hpp"
#include "fibra/assembly/block_pattern.hpp"
#include "fibra/solver/linear_solver.hpp"
#include "fibra/solver/problem.hpp"

namespace {

using namespace fibra;

constexpr int kTowsPerDirection = 5;
constexpr int kFibersPerTow = 48;
constexpr int kElements = 10;
constexpr double kRadius = 2e-5;
constexpr double kLength = 5e-3;
constexpr double kWidth = 0.8e-3;  // tow section: ellipse of 0.8 mm x 0.2 mm (full axes)
constexpr double kThickness = 0.2e-3;
constexpr double kTowSpacing = 1e-3;  // centre-to-centre, in the plane
constexpr double kLayer = 0.15e-3;    // x tows at z = +kLayer, y tows at z = -kLayer

/// 48 points of a hexagonal grid (pitch 2.2 radii) inside the tow's ellipse shrunk by a fiber
/// radius (so every fiber lies inside the section), nearest to the centre in the ellipse's
/// norm; (u, v) = (across the tow, through the thickness), ordered row by row.
std::vector<std::pair<double, double>> tow_section() {
  const double a = 0.5 * kWidth - kRadius, b = 0.5 * kThickness - kRadius;
  const double pitch = 2.2 * kRadius, h = 0.5 * std::sqrt(3.0) * pitch;
  struct P {
    double u, v, r2;
    int i, j;
  };
  std::vector<P> pts;
  for (int j = -10; j <= 10; ++j)
    for (int i = -40; i <= 40; ++i) {
      const double u = pitch * (i + 0.5 * (j & 1)), v = h * j;
      const double r2 = (u / a) * (u / a) + (v / b) * (v / b);
      if (r2 <= 1.0) pts.push_back({u, v, r2, i, j});
    }
  if (pts.size() < static_cast<size_t>(kFibersPerTow)) throw std::logic_error("tow section: too few grid points");
  std::stable_sort(pts.begin(), pts.end(), [](const P& x, const P& y) {
    if (x.r2 != y.r2) return x.r2 < y.r2;
    return x.j != y.j ? x.j < y.j : x.i < y.i;
  });
  pts.resize(kFibersPerTow);
  std::sort(pts.begin(), pts.end(), [](const P& x, const P& y) { return x.j != y.j ? x.j < y.j : x.i < y.i; });
  std::vector<std::pair<double, double>> out;
  for (const P& p : pts) out.emplace_back(p.u, p.v);
  return out;
}

/// The fabric as a case file (see the header comment); `grip`: every tow-end binding also
/// holds each fiber end across its tow (grip = [2, 3] for x tows, [1, 3] for y tows) and
/// against spinning about its axis (spin = true).
std::string fabric_toml(bool grip) {
  std::ostringstream s;
  s.precision(17);
  s << "[[material]]\nname = \"glass\"\nyoung = 72e9\npoisson = 0.22\n";
  const auto section = tow_section();
  struct Tow {
    std::string name;
    int axis;  // 0: along x, 1: along y
    double c;  // in-plane centre across the tow
    double z;
  };
  std::vector<Tow> tows;
  for (int i = 0; i < kTowsPerDirection; ++i)
    tows.push_back({std::string("x").append(std::to_string(i)), 0, (i + 0.5) * kTowSpacing, kLayer});
  for (int i = 0; i < kTowsPerDirection; ++i)
    tows.push_back({std::string("y").append(std::to_string(i)), 1, (i + 0.5) * kTowSpacing, -kLayer});
  auto point = [](const Tow& t, double along, double u, double v) {
    std::ostringstream p;
    p.precision(17);
    if (t.axis == 0)
      p << "[" << along << ", " << t.c + u << ", " << t.z + v << "]";
    else
      p << "[" << t.c + u << ", " << along << ", " << t.z + v << "]";
    return p.str();
  };
  for (const Tow& t : tows)
    for (int f = 0; f < kFibersPerTow; ++f) {
      const auto [u, v] = section[f];
      s << "[[fiber]]\nname = \"" << t.name << "f" << f << "\"\nmaterial = \"glass\"\nradius = " << kRadius
        << "\nelements = " << kElements << "\npoints = [" << point(t, 0.0, u, v) << ", " << point(t, kLength, u, v)
        << "]\n";
    }
  // Tow-end bodies: one per tow end, at the centre of the tow's section there.
  const char* end_names[2] = {"first", "last"};
  for (const Tow& t : tows)
    for (int e = 0; e < 2; ++e) {
      s << "[[body]]\nname = \"" << t.name << end_names[e] << "\"\ncenter = " << point(t, e * kLength, 0.0, 0.0)
        << "\n";
      s << "[[binding]]\nbody = \"" << t.name << end_names[e] << "\"\nends = [";
      for (int f = 0; f < kFibersPerTow; ++f)
        s << (f ? ", " : "") << "{ fiber = \"" << t.name << "f" << f << "\", node = \"" << end_names[e] << "\" }";
      s << "]\n";
      if (grip) s << (t.axis == 0 ? "grip = [2, 3]\nspin = true\n" : "grip = [1, 3]\nspin = true\n");
    }
  // Edge bodies: the 5 tow ends of one edge (x = 0, x = L for the x tows; y = 0, y = L for the y tows).
  const double mid = 0.5 * kTowsPerDirection * kTowSpacing;
  for (int axis = 0; axis < 2; ++axis)
    for (int e = 0; e < 2; ++e) {
      const std::string name = std::string("edge_").append(axis == 0 ? "x" : "y").append(end_names[e]);
      const double along = e * kLength, z = axis == 0 ? kLayer : -kLayer;
      s << "[[body]]\nname = \"" << name << "\"\ncenter = ";
      if (axis == 0)
        s << "[" << along << ", " << mid << ", " << z << "]\n";
      else
        s << "[" << mid << ", " << along << ", " << z << "]\n";
      s << "[[binding]]\nbody = \"" << name << "\"\nbodies = [";
      for (int i = 0; i < kTowsPerDirection; ++i)
        s << (i ? ", " : "") << "\"" << (axis == 0 ? "x" : "y") << i << end_names[e] << "\"";
      s << "]\n";
    }
  s << "[[step]]\nname = \"s\"\n";
  return s.str();
}

struct Fabric {
  Case spec;
  Model model;
  BodySystem bodies;
  VecX q;  ///< perturbed state
  Index members = 0;
  Index largest_local = 0;
  std::vector<Index> local_sizes;  ///< local vector size of each binding's stencil

  explicit Fabric(bool grip)
      : spec(parse_case_toml(fabric_toml(grip), "<bench_bodies>")), model(build_model(spec)), bodies(spec, model) {
    std::mt19937 rng(11);
    std::normal_distribution<double> normal(0.0, 1.0);
    q = model.reference;
    // Nodes: centroids moved by ~0.05 r, section vectors by ~1e-3 of their length.
    for (Index n = 0; n < model.num_nodes(); ++n) {
      for (int d = 0; d < 3; ++d) q[9 * n + d] += 0.05 * kRadius * normal(rng);
      for (int d = 3; d < 9; ++d) q[9 * n + d] += 1e-3 * kRadius * normal(rng);
    }
    for (const Body& b : model.bodies)
      for (int d = 0; d < 3; ++d) {
        q[b.first_dof + d] += 0.05 * kRadius * normal(rng);
        q[b.first_dof + 3 + d] = 0.02 * normal(rng);
      }
    std::vector<double> lambda = bodies.multipliers();
    for (double& l : lambda) l = 1.0 + normal(rng);  // [N], nonzero
    bodies.set_multipliers(lambda);
    for (const BindingSpec& b : spec.bindings) members += static_cast<Index>(b.ends.size() + b.bodies.size());
    const StencilSet& st = bodies.stencils();
    const std::vector<int> sizes = model.group_sizes();
    for (Index k = 0; k < st.size(); ++k) {
      Index n = 0;
      for (Index g : st.stencil(k)) n += sizes[g];
      local_sizes.push_back(n);
      largest_local = std::max(largest_local, n);
    }
  }
  /// The 6 dofs of every edge body marked as eliminated.
  void fix_edges(Problem& p) const {
    for (const Body& b : model.bodies)
      if (b.name.rfind("edge_", 0) == 0)
        for (int d = 0; d < 6; ++d) p.fixed()[b.first_dof + d] = 1;
  }
};

Fabric& fabric(bool grip = false) {
  static std::unique_ptr<Fabric> f[2];
  if (!f[grip]) f[grip] = std::make_unique<Fabric>(grip);
  return *f[grip];
}

/// Target over the binding stencils alone (as tests/body/test_bodies.cpp's Fixture).
struct BindingTarget {
  BlockPattern pattern;
  std::vector<char> fixed, group_fixed;
  VecX gradient;
  std::vector<double> values;
  explicit BindingTarget(const Fabric& f)
      : pattern(f.model.group_sizes(), {&f.bodies.stencils()}),
        fixed(f.model.num_dofs(), 0),
        group_fixed(f.model.num_groups(), 0),
        gradient(VecX::Zero(f.model.num_dofs())),
        values(pattern.nonzeros(), 0.0) {}
  AssemblyTarget target(bool hessian) {
    return {&pattern, &fixed, &group_fixed, &gradient, hessian ? &values : nullptr};
  }
};

void binding_counters(benchmark::State& state, const Fabric& f) {
  const double n = static_cast<double>(state.iterations());
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * f.bodies.num_bindings());
  state.counters["bindings"] = static_cast<double>(f.bodies.num_bindings());
  state.counters["members"] = static_cast<double>(f.members);
  state.counters["largest_local"] = static_cast<double>(f.largest_local);
  state.counters["member_evals_per_second"] =
      benchmark::Counter(n * static_cast<double>(f.members), benchmark::Counter::kIsRate);
}

// The values and gradient accumulate over the iterations (no reset inside the timing: the
// reset of the values is the caller's, Problem::evaluate's, cost).
// threads: the OpenMP thread count, which BodySystem::evaluate (sequential) only reaches
// through Eigen: its GEMM k J^T J (438 x 6 x 438) is above Eigen's threshold for splitting a
// product over the OpenMP threads.
// Energy + gradient + Hessian of every binding of `f` with `threads` OpenMP threads.
void binding_energy_loop(benchmark::State& state, Fabric& f, int threads) {
  omp_set_num_threads(threads);
  BindingTarget t(f);
  const AssemblyTarget target = t.target(true);
  f.bodies.evaluate(f.q, target, true, true);  // warm-up
  for (auto _ : state) benchmark::DoNotOptimize(f.bodies.evaluate(f.q, target, true, true));
  binding_counters(state, f);
  state.counters["nnz_bindings"] = static_cast<double>(t.pattern.nonzeros());
}

void BM_BindingEnergy(benchmark::State& state) {
  binding_energy_loop(state, fabric(), static_cast<int>(state.range(0)));
}
BENCHMARK(BM_BindingEnergy)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();

// The same with every fiber end gripped across its tow (2 x 960 grip conditions more).
void BM_BindingEnergyGripped(benchmark::State& state) {
  Fabric& f = fabric(true);
  binding_energy_loop(state, f, 1);
  state.counters["grip_conditions"] = static_cast<double>(f.bodies.num_grip_conditions());
}
BENCHMARK(BM_BindingEnergyGripped)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_BindingGradient(benchmark::State& state) {
  Fabric& f = fabric();
  omp_set_num_threads(1);
  BindingTarget t(f);
  const AssemblyTarget target = t.target(false);
  f.bodies.evaluate(f.q, target, true, false);
  for (auto _ : state) benchmark::DoNotOptimize(f.bodies.evaluate(f.q, target, true, false));
  binding_counters(state, f);
}
BENCHMARK(BM_BindingGradient)->Unit(benchmark::kMicrosecond);

/// What BodySystem::evaluate's scatter_local calls cost alone: one dense local gradient and
/// Hessian per binding (random values) scattered over the binding's stencil.
void BM_BindingScatter(benchmark::State& state) {
  Fabric& f = fabric();
  omp_set_num_threads(1);
  BindingTarget t(f);
  const AssemblyTarget target = t.target(true);
  const StencilSet& st = f.bodies.stencils();
  const Index ns = f.largest_local;
  VecX g = VecX::Random(ns);
  Eigen::MatrixXd h = Eigen::MatrixXd::Random(ns, ns);
  h = (h + h.transpose()).eval();
  const std::vector<Index>& sizes = f.local_sizes;
  for (auto _ : state) {
    for (Index k = 0; k < st.size(); ++k) {
      const auto gv = g.head(sizes[k]);
      const auto hv = h.topLeftCorner(sizes[k], sizes[k]);
      scatter_local(target, st.stencil(k), &gv, &hv);
    }
    benchmark::DoNotOptimize(t.values.data());
  }
  binding_counters(state, f);
}
BENCHMARK(BM_BindingScatter)->Unit(benchmark::kMillisecond);

/// What-if (not fibra's code path): scatter_local's fast path (no eliminated dof) with the
/// loops turned round, column group outside and row group inside, so that the local matrix
/// is read and the CSC values are written column by column, each column in one sweep.
/// scatter_local runs row group outside: for a 438 x 438 local matrix (1.5 MB, beyond L2)
/// that reads it across its columns and revisits every CSC column 49 times.
template <class LocalVec, class LocalMat>
void scatter_by_columns(const AssemblyTarget& t, std::span<const Index> groups, const LocalVec& g, const LocalMat& h,
                        std::vector<int>& rel) {
  const BlockPattern& p = *t.pattern;
  const int* col_ptr = p.col_ptr().data();
  double* values = t.values->data();
  const size_t n = groups.size();
  int off_j = 0;
  for (size_t j = 0; j < n; ++j) {
    const Index gj = groups[j];
    const int sj = p.group_size(gj);
    const Index dj = p.group_dof(gj);
    for (int r = 0; r < sj; ++r) (*t.gradient)[dj + r] += g[off_j + r];
    rel.resize(n);
    for (size_t i = 0; i < n; ++i) rel[i] = groups[i] <= gj ? p.relative_offset(groups[i], gj) : -1;
    for (int c = 0; c < sj; ++c) {
      double* column = values + col_ptr[dj + c];
      const double* hc = &h(0, off_j + c);
      int off_i = 0;
      for (size_t i = 0; i < n; ++i) {
        const int si = p.group_size(groups[i]);
        if (rel[i] >= 0) {
          double* dst = column + rel[i];
          const int rmax = groups[i] == gj ? c + 1 : si;
          for (int r = 0; r < rmax; ++r) dst[r] += hc[off_i + r];
        }
        off_i += si;
      }
    }
    off_j += sj;
  }
}

void BM_BindingScatterByColumns(benchmark::State& state) {
  Fabric& f = fabric();
  omp_set_num_threads(1);
  BindingTarget t(f), check(f);
  const AssemblyTarget target = t.target(true);
  const StencilSet& st = f.bodies.stencils();
  const Index ns = f.largest_local;
  VecX g = VecX::Random(ns);
  Eigen::MatrixXd h = Eigen::MatrixXd::Random(ns, ns);
  h = (h + h.transpose()).eval();
  const std::vector<Index>& sizes = f.local_sizes;
  std::vector<int> rel;
  // Same sums as scatter_local (the order of the additions per entry is the same).
  const AssemblyTarget reference = check.target(true);
  for (Index k = 0; k < st.size(); ++k) {
    const auto gv = g.head(sizes[k]);
    const auto hv = h.topLeftCorner(sizes[k], sizes[k]);
    scatter_local(reference, st.stencil(k), &gv, &hv);
    scatter_by_columns(target, st.stencil(k), gv, hv, rel);
  }
  if (t.values != check.values || t.gradient != check.gradient) {
    state.SkipWithError("column-ordered scatter differs from scatter_local");
    return;
  }
  for (auto _ : state) {
    for (Index k = 0; k < st.size(); ++k) {
      const auto gv = g.head(sizes[k]);
      const auto hv = h.topLeftCorner(sizes[k], sizes[k]);
      scatter_by_columns(target, st.stencil(k), gv, hv, rel);
    }
    benchmark::DoNotOptimize(t.values.data());
  }
  binding_counters(state, f);
}
BENCHMARK(BM_BindingScatterByColumns)->Unit(benchmark::kMillisecond);

void problem_counters(benchmark::State& state, const Fabric& f, const Problem& p) {
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(f.model.elements.size()));
  state.counters["elements"] = static_cast<double>(f.model.elements.size());
  state.counters["dofs"] = static_cast<double>(f.model.num_dofs());
  state.counters["nnz_A"] = static_cast<double>(p.pattern().nonzeros());
}

void BM_ProblemEvaluateWithBindings(benchmark::State& state) {
  Fabric& f = fabric();
  omp_set_num_threads(static_cast<int>(state.range(0)));
  Problem p(f.model, &f.bodies);
  f.fix_edges(p);
  VecX g;
  std::vector<double> h;
  p.evaluate(f.q, &g, &h);  // warm-up: buffers sized
  for (auto _ : state) benchmark::DoNotOptimize(p.evaluate(f.q, &g, &h));
  problem_counters(state, f, p);
}
BENCHMARK(BM_ProblemEvaluateWithBindings)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_ProblemEvaluateNoBindings(benchmark::State& state) {
  Fabric& f = fabric();
  omp_set_num_threads(static_cast<int>(state.range(0)));
  Problem p(f.model);
  f.fix_edges(p);
  VecX g;
  std::vector<double> h;
  p.evaluate(f.q, &g, &h);
  for (auto _ : state) benchmark::DoNotOptimize(p.evaluate(f.q, &g, &h));
  problem_counters(state, f, p);
}
BENCHMARK(BM_ProblemEvaluateNoBindings)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// CHOLMOD numeric factorization (fibra's settings, METIS, analysis outside the timing) of the
/// Problem's matrix with (bindings:1) and without (bindings:0) the bindings, shifted by 1e-2 of
/// the mean diagonal so that both are positive definite (without bindings the fibers are free;
/// the cost does not depend on the values once the factorization runs to the end).
void BM_FabricFactorize(benchmark::State& state) {
  Fabric& f = fabric();
  omp_set_num_threads(1);
  const bool with = state.range(0) != 0;
  Problem p(f.model, with ? &f.bodies : nullptr);
  f.fix_edges(p);
  VecX g;
  std::vector<double> h;
  p.evaluate(f.q, &g, &h);
  double diag = 0.0;
  for (Index d = 0; d < f.model.num_dofs(); ++d) diag += std::abs(h[p.pattern().find(d, d)]);
  const double shift = 1e-2 * diag / static_cast<double>(f.model.num_dofs());
  std::unique_ptr<LinearSolver> solver = make_linear_solver("cholmod");
  solver->analyze(p.pattern());
  if (solver->factorize(h, shift) != FactorStatus::Ok) {  // warm-up: factor allocated
    state.SkipWithError("factorization failed");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(solver->factorize(h, shift));
  state.counters["nnz_A"] = static_cast<double>(p.pattern().nonzeros());
  state.counters["nnz_L"] = solver->factor_nonzeros();
}
BENCHMARK(BM_FabricFactorize)->Arg(0)->Arg(1)->ArgName("bindings")->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
