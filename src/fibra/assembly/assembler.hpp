#pragma once
/// Threaded, deterministic assembly of local stencil contributions (energy, gradient,
/// Hessian) into a global gradient and a BlockPattern matrix, following the StencilSet's
/// schedule (partitions of the matrix in parallel, then colours of straddling stencils), so
/// sums are reproducible whatever the thread count.
#include <Eigen/Core>
#include <span>
#include <type_traits>
#include <vector>

#include "fibra/assembly/block_pattern.hpp"

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

/// Scatters one local contribution over the groups `groups` (sizes from the pattern). The
/// Hessian goes column by column of the global matrix (for each column, the row blocks of
/// every group at or above it), so both the local matrix (column-major) and the global CSC
/// values are read and written in order; for a binding of 48 fiber ends this is 3-4 times
/// faster than row-block order (bench/bench_bodies.cpp), with identical sums.
template <class LocalVec, class LocalMat>
void scatter_local(const AssemblyTarget& t, std::span<const Index> groups, const LocalVec* g, const LocalMat* h) {
  const BlockPattern& p = *t.pattern;
  const std::vector<char>& fixed = *t.fixed;
  const int* col_ptr = p.col_ptr().data();
  const size_t ng = groups.size();
  if (g && t.gradient) {
    int off = 0;
    for (size_t i = 0; i < ng; ++i) {
      const int si = p.group_size(groups[i]);
      const Index di = p.group_dof(groups[i]);
      for (int r = 0; r < si; ++r) (*t.gradient)[di + r] += (*g)[off + r];
      off += si;
    }
  }
  if (!(h && t.values)) return;
  // Per stencil group: local offset, size, first dof, relative offset in the current column
  // group (-1: below it), no fixed dof.
  struct Slot {
    int off, size;
    Index dof;
    int rel;
    bool free;
  };
  thread_local std::vector<Slot> slots;
  slots.resize(ng);
  int off = 0;
  for (size_t i = 0; i < ng; ++i) {
    const Index gi = groups[i];
    slots[i] = {off, p.group_size(gi), p.group_dof(gi), 0, !t.group_fixed || !(*t.group_fixed)[gi]};
    if (!t.group_fixed) slots[i].free = false;  // unknown: check every dof
    off += slots[i].size;
  }
  double* values = t.values->data();
  for (size_t j = 0; j < ng; ++j) {
    const Index gj = groups[j];
    const Slot& sj = slots[j];
    for (size_t i = 0; i < ng; ++i) slots[i].rel = groups[i] <= gj ? p.relative_offset(groups[i], gj) : -1;
    for (int c = 0; c < sj.size; ++c) {
      const Index col = sj.dof + c;
      if (!sj.free && fixed[col]) continue;
      double* column = values + col_ptr[col];
      for (size_t i = 0; i < ng; ++i) {
        const Slot& si = slots[i];
        if (si.rel < 0) continue;
        const int rmax = groups[i] == gj ? c + 1 : si.size;
        double* dst = column + si.rel;
        if (si.free && sj.free) {
          for (int r = 0; r < rmax; ++r) dst[r] += (*h)(si.off + r, sj.off + c);
        } else {
          for (int r = 0; r < rmax; ++r)
            if (!fixed[si.dof + r]) dst[r] += (*h)(si.off + r, sj.off + c);
        }
      }
    }
  }
}

/// Assembles every stencil of `set`: kernel(s, LocalVec* g, LocalMat* h) returns the energy
/// of stencil s and fills g, h when non-null. A kernel taking a fourth argument `bool& scatter`
/// may set it to false when its g and h are exactly zero (nothing to add: the scatter is
/// skipped). Returns the total energy (summed in order).
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
      bool scatter = true;
      if constexpr (std::is_invocable_v<Kernel&, Index, LocalVec*, LocalMat*, bool&>)
        energy_buffer[s] = kernel(s, want_gradient ? &g : nullptr, want_hessian ? &h : nullptr, scatter);
      else
        energy_buffer[s] = kernel(s, want_gradient ? &g : nullptr, want_hessian ? &h : nullptr);
      if (scatter) scatter_local(t, set.stencil(s), want_gradient ? &g : nullptr, want_hessian ? &h : nullptr);
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
