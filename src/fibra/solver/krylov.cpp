#include "fibra/solver/krylov.hpp"

#include <algorithm>
#include <cmath>

#include <omp.h>

#include <cmath>

namespace fibra {

void symmetric_multiply(const BlockPattern& pattern, const std::vector<double>& values, double shift, const VecX& x,
                        VecX& y, std::vector<VecX>& scratch) {
  const Index n = pattern.rows();
  const int* col = pattern.col_ptr().data();
  const int* row = pattern.row_idx().data();
  const int threads = omp_get_max_threads();
  if (static_cast<int>(scratch.size()) != threads || (threads > 0 && scratch[0].size() != n))
    scratch.assign(threads, VecX::Zero(n));
  y.resize(n);
  // Column j holds rows i <= j: y_j gathers a_ij x_i (no conflict), y_i receives a_ij x_j
  // (scattered: into the thread's own vector, summed afterwards).
#pragma omp parallel
  {
    // The team may be smaller than the largest: only its vectors are zeroed and summed.
    const int team = omp_get_num_threads();
    VecX& acc = scratch[omp_get_thread_num()];
    acc.setZero();
#pragma omp for schedule(static)
    for (Index j = 0; j < n; ++j) {
      const double xj = x[j];
      double gather = 0.0;
      const int end = col[j + 1];
      for (int k = col[j]; k < end; ++k) {
        const Index i = row[k];
        const double a = values[k];
        if (i == j) {
          gather += (a + shift) * xj;
        } else {
          gather += a * x[i];
          acc[i] += a * xj;
        }
      }
      acc[j] += gather;
    }
#pragma omp for schedule(static)
    for (Index i = 0; i < n; ++i) {
      double s = 0.0;
      for (int t = 0; t < team; ++t) s += scratch[t][i];
      y[i] = s;
    }
  }
}

namespace {

// True when the residuals so far (history[k] after k iterations), falling at their rate over
// the last kWindow iterations, reach `tolerance` only after more than `limit` iterations.
bool hopeless(const std::vector<double>& history, double tolerance, int limit) {
  constexpr int kFirst = 15, kEvery = 5, kWindow = 10;
  const int k = static_cast<int>(history.size()) - 1;
  if (k < kFirst || k % kEvery != 0) return false;
  auto least = [&](int end) { return std::min({history[end - 2], history[end - 1], history[end]}); };
  const double now = least(k), before = least(k - kWindow);
  if (!(now > 0.0 && before > 0.0)) return false;
  if (now >= before) return true;
  const double rate = std::log(now / before) / kWindow;  // per iteration, < 0
  return k + std::log(tolerance / now) / rate > limit;
}

}  // namespace

PcgResult pcg(const BlockPattern& pattern, const std::vector<double>& values, double shift, const VecX& b, VecX& x,
              const std::function<void(const VecX&, VecX&)>& precondition, const VecX& weight, double tolerance,
              int max_iterations, PcgWorkspace& ws, int abandon_beyond) {
  PcgResult out;
  ws.history.clear();
  if (ws.history.capacity() < static_cast<size_t>(max_iterations) + 1) ws.history.reserve(max_iterations + 1);
  const double bnorm = b.cwiseProduct(weight).norm();
  precondition(b, x);
  if (!(bnorm > 0.0)) {
    x.setZero();
    out.converged = true;
    return out;
  }
  // Records the weighted residual of ws.r; true when CG stops (converged or not finite).
  auto done = [&]() {
    out.relative_residual = ws.r.cwiseProduct(weight).norm() / bnorm;
    ws.history.push_back(out.relative_residual);
    out.converged = out.relative_residual <= tolerance;
    return out.converged || !std::isfinite(out.relative_residual);
  };
  symmetric_multiply(pattern, values, shift, x, ws.ap, ws.scratch);
  ws.r = b - ws.ap;
  if (done()) return out;
  precondition(ws.r, ws.z);
  ws.p = ws.z;
  double rz = ws.r.dot(ws.z);
  for (int k = 0; k < max_iterations; ++k) {
    symmetric_multiply(pattern, values, shift, ws.p, ws.ap, ws.scratch);
    const double curvature = ws.p.dot(ws.ap);
    if (!(curvature > 0.0) || !(rz > 0.0)) {
      out.breakdown = true;
      return out;
    }
    const double alpha = rz / curvature;
    x += alpha * ws.p;
    ws.r -= alpha * ws.ap;
    out.iterations = k + 1;
    if (done()) return out;
    if (abandon_beyond > 0 && hopeless(ws.history, tolerance, abandon_beyond)) {
      out.abandoned = true;
      return out;
    }
    precondition(ws.r, ws.z);
    const double rz_next = ws.r.dot(ws.z);
    ws.p = ws.z + (rz_next / rz) * ws.p;
    rz = rz_next;
  }
  return out;
}

int krylov_budget(int setting, double flops, double nonzeros) {
  if (setting >= 0) return setting;
  if (!(flops > 0.0 && nonzeros > 0.0)) return 20;
  return static_cast<int>(std::clamp(std::round(flops / (16.0 * nonzeros)), 20.0, 100.0));
}

}  // namespace fibra
