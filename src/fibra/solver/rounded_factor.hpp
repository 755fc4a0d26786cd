#pragma once
/// A copy of a supernodal Cholesky factor rounded to floats or to halves, for preconditioning only.
///
/// Conjugate gradients preconditioned by the last factorization spend their time in the
/// forward and back substitutions with the factor, and those stream the factor's values from
/// memory (1.7 GB in doubles on the 480-fiber woven sample) without reusing them. Stored in
/// floats the factor streams in half the time, in halves (IEEE binary16) in a quarter; its
/// diagonal blocks are packed to their lower triangles (CHOLMOD stores them whole), 14 % fewer
/// values to stream on the 480-fiber twill. The values are rounded once per factorization; the
/// substitutions compute in double.
///
/// Halves hold 11 significant bits and span 2^-24 to 65504, so before rounding to halves each
/// row of L is scaled to unit length: L = S^-1 L^, S = diag(1 / sqrt((P A P^T)_kk)) (a row of L
/// has the length sqrt(A_kk)), which puts every value of L^ in [-1, 1] whatever the units of the
/// unknowns (positions, rotations, bodies). The pivots L^_jj are kept in double.
///
/// The preconditioner is then M = S^-1 L~ L~^T S^-1 with L~ the rounded factor, still symmetric
/// positive definite, and CG on the exact tangent corrects the difference like any other
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
  /// The factored matrix's diagonal in A's order (any shift included), for halves' row scales;
  /// null: the rows' lengths summed from L, on one thread.
  const double* diagonal = nullptr;
};

/// How the rounded factor stores its values.
enum class FactorStorage {
  Float,  ///< IEEE binary32, as they are
  Half,   ///< IEEE binary16, each row scaled to unit length first
};

/// IEEE binary16 conversions: the processor's (F16C) where the build has it, else in software,
/// with the same results for every value but NaNs (round to nearest, ties to even).
std::uint16_t float_to_half(float value);
float half_to_float(std::uint16_t bits);
/// True when the build converts halves with the processor's instructions (F16C): without them
/// the substitutions in halves are correct but slow.
bool halves_in_hardware();
/// The software conversions, whatever the build (tested against the processor's).
std::uint16_t float_to_half_in_software(float value);
float half_to_float_in_software(std::uint16_t bits);

/// L rounded to floats or halves, with forward and back substitutions in double
/// (x = P^T S L~^-T L~^-1 S P b).
class RoundedFactor {
 public:
  /// Copies (and rounds) the factor's values; the structure is copied too, so the view may be
  /// freed or refactored after. Reuses its storage when the sizes match.
  void assign(const SupernodalView& f, FactorStorage storage = FactorStorage::Float);
  /// x = P^T S L~^-T L~^-1 S P b. No allocation after the first call at a given size.
  void solve(const VecX& b, VecX& x);
  FactorStorage storage() const { return m_storage; }
  /// Number of rounded values (the packed factor).
  double values() const { return static_cast<double>(m_offset.empty() ? 0 : m_offset.back()); }
  /// Bytes held by the rounded values.
  double value_bytes() const {
    return values() * (m_storage == FactorStorage::Half ? sizeof(std::uint16_t) : sizeof(float));
  }
  /// Share of the factor's values in the top of the tree (done by one thread), in [0, 1].
  double top_share() const { return m_top_share; }

 private:
  /// A range of supernodes [first, last] forming whole subtrees, and the first column after
  /// them: rows at or beyond it belong to the top.
  struct Range {
    Index first = 0, last = 0, end_column = 0;
  };
  /// Supernode s: its first column, column and row counts, rows below its diagonal block, row
  /// indices and first packed value.
  struct Node {
    Index first_column, nscol, nsrow, below;
    const int* rows;
    std::int64_t offset;
  };
  Node node(Index s) const;
  /// Start of packed column j (rows j .. nsrow-1) within its supernode's values.
  static std::int64_t packed_column(Index j, Index nsrow) {
    return static_cast<std::int64_t>(j) * nsrow - static_cast<std::int64_t>(j) * (j - 1) / 2;
  }
  /// The packed values of columns [j0, j1) of a supernode as floats: the stored ones, or the
  /// halves converted into the thread's scratch. Column j starts at the result plus
  /// packed_column(j, nsrow) - packed_column(j0, nsrow).
  const float* columns(const Node& d, Index j0, Index j1, int thread) const;
  void split_tree();
  void forward(Index s, Index end_column, double* y, double* delta, double* w, int thread) const;
  void backward(Index s, double* y, double* w, int thread) const;

  FactorStorage m_storage = FactorStorage::Float;
  Index m_n = 0;
  std::vector<int> m_super, m_pi, m_s_rows, m_perm;
  std::vector<std::int64_t> m_px;      // CHOLMOD's value offsets (whole diagonal blocks)
  std::vector<std::int64_t> m_offset;  // each supernode's first packed value
  std::vector<float> m_values;         // Float storage
  std::vector<std::uint16_t> m_halves; // Half storage
  std::vector<double> m_pivot;         // L~_jj, in double
  std::vector<double> m_scale;         // S (Half storage; empty for Float: S = I)
  std::vector<Range> m_part[2];      // each thread's subtrees, in increasing order
  std::vector<Index> m_top;          // the supernodes of the top, in increasing order
  std::vector<Index> m_top_columns;  // their columns
  double m_top_share = 0.0;
  std::vector<double> m_work;       // S P b, then the solution in the permuted order
  std::vector<double> m_delta[2];   // each part's updates of the top's unknowns
  std::vector<double> m_scratch[2]; // a supernode's rows, per thread
  mutable std::vector<float> m_block[2];  // converted columns (Half storage), per thread
};

}  // namespace fibra
