#pragma once
/// fibra's data as CHOLMOD sees it, without copies: a BlockPattern's upper triangle as a
/// symmetric sparse matrix, and a supernodal factor as RoundedFactor reads it (used by the
/// CHOLMOD back end, its tests and benchmarks).
#include <cholmod.h>

#include "fibra/assembly/block_pattern.hpp"
#include "fibra/solver/rounded_factor.hpp"

namespace fibra {

/// The pattern's upper CSC storage (sorted, packed) with `values`, as CHOLMOD's symmetric
/// matrix (stype 1).
inline cholmod_sparse cholmod_upper(const BlockPattern& pattern, const double* values) {
  cholmod_sparse a{};
  a.nrow = a.ncol = pattern.rows();
  a.nzmax = pattern.nonzeros();
  a.p = const_cast<int*>(pattern.col_ptr().data());
  a.i = const_cast<int*>(pattern.row_idx().data());
  a.x = const_cast<double*>(values);
  a.stype = 1;
  a.itype = CHOLMOD_INT;
  a.xtype = CHOLMOD_REAL;
  a.dtype = CHOLMOD_DOUBLE;
  a.sorted = 1;
  a.packed = 1;
  return a;
}

/// The structure and values of a supernodal factor (`is_super`), without copying them.
inline SupernodalView supernodal_view(const cholmod_factor& f) {
  SupernodalView v;
  v.n = static_cast<Index>(f.n);
  v.nsuper = static_cast<Index>(f.nsuper);
  v.super = static_cast<const int*>(f.super);
  v.pi = static_cast<const int*>(f.pi);
  v.px = static_cast<const int*>(f.px);
  v.s_rows = static_cast<const int*>(f.s);
  v.values = static_cast<const double*>(f.x);
  v.perm = static_cast<const int*>(f.Perm);
  return v;
}

}  // namespace fibra
