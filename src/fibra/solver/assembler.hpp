#pragma once
/// Threaded, deterministic assembly of local stencil contributions (energy, gradient,
/// Hessian) into a global gradient and a BlockPattern matrix, following the StencilSet's
/// schedule (partitions of the matrix in parallel, then colours of straddling stencils), so
/// sums are reproducible whatever the thread count.
#include <Eigen/Core>
#include <vector>

#include "fibra/solver/block_pattern.hpp"

namespace fibra {

/// Global targets of an assembly; `fixed` dofs get no matrix coupling (their rows and
/// columns are left out); the gradient is assembled on every dof (reactions need it).
struct AssemblyTarget {
  const BlockPattern* pattern = nullptr;
  const std::vector<char>* fixed = nullptr;        ///< per dof, 1 = eliminated
  const std::vector<char>* group_fixed = nullptr;  ///< per group, 1 = some dof eliminated (optional)
  VecX* gradient = nullptr;                        ///< may be null
  std::vector<double>* values = nullptr;           ///< upper CSC values; may be null
};

/// Scatters one local contribution over the groups `groups` (sizes from the pattern).
template <class LocalVec, class LocalMat>
void scatter_local(const AssemblyTarget& t, std::span<const Index> groups, const LocalVec* g, const LocalMat* h) {
  const BlockPattern& p = *t.pattern;
  const std::vector<char>& fixed = *t.fixed;
  const int* col_ptr = p.col_ptr().data();
  int off_i = 0;
  for (size_t i = 0; i < groups.size(); ++i) {
    const Index gi = groups[i];
    const int si = p.group_size(gi);
    const Index di = p.group_dof(gi);
    if (g && t.gradient)
      for (int r = 0; r < si; ++r) (*t.gradient)[di + r] += (*g)[off_i + r];
    if (h && t.values) {
      double* values = t.values->data();
      const bool free_i = t.group_fixed && !(*t.group_fixed)[gi];
      int off_j = 0;
      for (size_t j = 0; j < groups.size(); ++j) {
        const Index gj = groups[j];
        const int sj = p.group_size(gj);
        if (gi <= gj) {
          const Index dj = p.group_dof(gj);
          const int rel = p.relative_offset(gi, gj);
          if (free_i && !(*t.group_fixed)[gj]) {
            // No eliminated dof in either group: contiguous columns, no checks.
            for (int c = 0; c < sj; ++c) {
              double* dst = values + col_ptr[dj + c] + rel;
              const int rmax = (gi == gj) ? c + 1 : si;
              for (int r = 0; r < rmax; ++r) dst[r] += (*h)(off_i + r, off_j + c);
            }
          } else {
            for (int c = 0; c < sj; ++c) {
              if (fixed[dj + c]) continue;
              double* dst = values + col_ptr[dj + c] + rel;
              const int rmax = (gi == gj) ? c + 1 : si;
              for (int r = 0; r < rmax; ++r)
                if (!fixed[di + r]) dst[r] += (*h)(off_i + r, off_j + c);
            }
          }
        }
        off_j += sj;
      }
    }
    off_i += si;
  }
}

/// Assembles every stencil of `set`: kernel(s, LocalVec* g, LocalMat* h) returns the energy
/// of stencil s and fills g, h when non-null. Returns the total energy (summed in order).
template <class LocalVec, class LocalMat, class Kernel>
double assemble_set(const StencilSet& set, const AssemblyTarget& t, bool want_gradient, bool want_hessian,
                    std::vector<double>& energy_buffer, Kernel&& kernel) {
  energy_buffer.assign(set.size(), 0.0);
  const Index parts = static_cast<Index>(set.by_partition.size());
#pragma omp parallel
  {
    LocalVec g;
    LocalMat h;
    auto one = [&](Index s) {
      energy_buffer[s] = kernel(s, want_gradient ? &g : nullptr, want_hessian ? &h : nullptr);
      scatter_local(t, set.stencil(s), want_gradient ? &g : nullptr, want_hessian ? &h : nullptr);
    };
    // Partitions: one thread sweeps one contiguous range of the matrix.
#pragma omp for schedule(dynamic, 1)
    for (Index p = 0; p < parts; ++p)
      for (Index s : set.by_partition[p]) one(s);
    // Straddling stencils, colour by colour.
    for (const std::vector<Index>& stencils : set.by_color) {
      const Index n = static_cast<Index>(stencils.size());
#pragma omp for schedule(static)
      for (Index k = 0; k < n; ++k) one(stencils[k]);
    }
  }
  double total = 0.0;
  for (double e : energy_buffer) total += e;
  return total;
}

}  // namespace fibra
