#pragma once
/// A single-precision copy of a supernodal Cholesky factor, for preconditioning only.
///
/// Conjugate gradients preconditioned by the last factorization spend their time in the
/// forward and back substitutions with the factor, and those stream the factor's values from
/// memory (1.7 GB on the 480-fiber woven sample) without reusing them. Stored in floats the
/// factor streams in half the time; its diagonal blocks are packed to their lower triangles
/// (CHOLMOD stores them whole), 14 % fewer values to stream on the 480-fiber twill. The
/// values are rounded once per factorization; the substitutions compute in double. The
/// preconditioner is then M = L~ L~^T with L~ the rounded factor, still symmetric positive
/// definite, and CG on the exact tangent corrects the difference like any other
/// (docs/theory/solver.md, "Reusing the factorization").
///
/// The substitutions run on two threads: the supernodal elimination tree is cut into a top
/// (done by one thread) and subtrees shared out in two balanced parts, which touch disjoint
/// unknowns except the top's. The cut depends on the factor only, and each part sums in a
/// fixed order, so the result is the same on one thread or two.
#include <cstdint>
#include <vector>

#include "fibra/core/types.hpp"

namespace fibra {

/// The supernodal structure and values of L in P A P^T = L L^T, as CHOLMOD stores it
/// (`cholmod_factor` with `is_super`): supernode s holds the columns super[s] .. super[s+1]-1,
/// its row indices are s_rows[pi[s] .. pi[s+1]-1] (the first ones its own columns, in order)
/// and its values the column-major block of (pi[s+1]-pi[s]) rows at values + px[s].
/// perm[k] is the row of A that is row k of P A P^T.
struct SupernodalView {
  Index n = 0;
  Index nsuper = 0;
  const int* super = nullptr;
  const int* pi = nullptr;
  const int* px = nullptr;
  const int* s_rows = nullptr;
  const double* values = nullptr;
  const int* perm = nullptr;
};

/// L rounded to floats, with forward and back substitutions in double (x = P^T L^-T L^-1 P b).
class SingleFactor {
 public:
  /// Copies (and rounds) the factor's values; the structure is copied too, so the view may be
  /// freed or refactored after. Reuses its storage when the sizes match.
  void assign(const SupernodalView& f);
  /// x = P^T L~^-T L~^-1 P b. No allocation after the first call at a given size.
  void solve(const VecX& b, VecX& x);
  /// Bytes held by the rounded values.
  double value_bytes() const { return static_cast<double>(m_values.size()) * sizeof(float); }
  /// Share of the factor's values in the top of the tree (done by one thread), in [0, 1].
  double top_share() const { return m_top_share; }

 private:
  /// A range of supernodes [first, last] forming whole subtrees, and the first column after
  /// them: rows at or beyond it belong to the top.
  struct Range {
    Index first = 0, last = 0, end_column = 0;
  };
  /// Supernode s: its first column, column and row counts, rows below its diagonal block, row
  /// indices and values.
  struct Node {
    Index first_column, nscol, nsrow, below;
    const int* rows;
    const float* l;
  };
  Node node(Index s) const;
  /// Start of packed column j (rows j .. nsrow-1) within its supernode's values.
  static std::int64_t packed_column(Index j, Index nsrow) {
    return static_cast<std::int64_t>(j) * nsrow - static_cast<std::int64_t>(j) * (j - 1) / 2;
  }
  /// Column j's rows below the diagonal block.
  static const float* below_part(const float* l, Index j, Index nscol, Index nsrow) {
    return l + packed_column(j, nsrow) + (nscol - j);
  }
  void split_tree();
  void forward(Index s, Index end_column, double* y, double* delta, double* t) const;
  void backward(Index s, double* y, double* t) const;

  Index m_n = 0;
  std::vector<int> m_super, m_pi, m_s_rows, m_perm;
  std::vector<std::int64_t> m_px;      // CHOLMOD's value offsets (whole diagonal blocks)
  std::vector<std::int64_t> m_offset;  // each supernode's first packed value
  std::vector<float> m_values;
  std::vector<Range> m_part[2];      // each thread's subtrees, in increasing order
  std::vector<Index> m_top;          // the supernodes of the top, in increasing order
  std::vector<Index> m_top_columns;  // their columns
  double m_top_share = 0.0;
  std::vector<double> m_work;       // P b, then the solution in the permuted order
  std::vector<double> m_delta[2];   // each part's updates of the top's unknowns
  std::vector<double> m_scratch[2]; // a supernode's below-diagonal rows, per thread
};

}  // namespace fibra
