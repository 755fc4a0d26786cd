#pragma once
/// Sparsity of a symmetric matrix built from dof groups (a node's 9 dofs, later a rigid
/// body's 6) coupled by stencils (the groups one energy term touches). Stored as the upper
/// triangle in compressed columns (CHOLMOD stype = 1). Inside every column the rows come in
/// whole groups, so a stencil scatters with one precomputed offset per group pair.
#include <span>
#include <vector>

#include "fibra/core/types.hpp"

namespace fibra {

/// A set of stencils and a conflict-free, cache-friendly assembly schedule: the groups are
/// split into a fixed number of contiguous ranges (partitions); stencils inside one range are
/// assembled in order by one thread (ranges in parallel), then the stencils that straddle
/// ranges, coloured so that one colour shares no group, colour by colour. The schedule does
/// not depend on the thread count, so neither do the sums.
struct StencilSet {
  std::vector<Index> groups;         ///< flattened group lists
  std::vector<Index> group_begin;    ///< stencil s uses groups[group_begin[s] .. group_begin[s+1])
  std::vector<std::vector<Index>> by_partition;  ///< stencils inside each group range, ascending
  std::vector<std::vector<Index>> by_color;      ///< straddling stencils per colour, ascending

  Index size() const { return static_cast<Index>(group_begin.size()) - 1; }  ///< stencil count
  std::span<const Index> stencil(Index s) const {  ///< groups of stencil s
    return {groups.data() + group_begin[s], static_cast<size_t>(group_begin[s + 1] - group_begin[s])};
  }
  /// Appends a stencil.
  void add(std::span<const Index> g);
  /// Builds the schedule (partitions of the group range, then greedy colouring of the
  /// straddling stencils; deterministic, linear time).
  void colorize(Index num_groups, int partitions = 16);
};

/// Block-structured upper-triangular CSC pattern.
class BlockPattern {
 public:
  /// Builds from group sizes and every stencil set that will be assembled.
  BlockPattern(std::vector<int> group_sizes, const std::vector<const StencilSet*>& sets);

  Index rows() const { return m_dof_begin.back(); }                       ///< matrix dimension
  Index nonzeros() const { return static_cast<Index>(m_row.size()); }     ///< stored entries
  Index group_dof(Index g) const { return m_dof_begin[g]; }               ///< first dof of group g
  int group_size(Index g) const { return m_size[g]; }                     ///< dofs of group g
  Index group_of_dof(Index dof) const { return m_group_of_dof[dof]; }     ///< owning group
  const std::vector<int>& col_ptr() const { return m_col; }               ///< CSC column starts
  const std::vector<int>& row_idx() const { return m_row; }               ///< CSC row indices
  /// Offset of the value of (first row of group h, column c) relative to col_ptr[c], for any
  /// column c of group g >= h; -1 if the pair is not in the pattern.
  int relative_offset(Index h, Index g) const;
  /// Value index of entry (row, col) with row <= col, or -1.
  Index find(Index row, Index col) const;

 private:
  std::vector<int> m_size;
  std::vector<Index> m_dof_begin;
  std::vector<Index> m_group_of_dof;
  std::vector<std::vector<Index>> m_upper;   // per group g: neighbour groups h <= g, sorted
  std::vector<std::vector<int>> m_rel;       // matching relative offsets
  std::vector<int> m_col;
  std::vector<int> m_row;
};

}  // namespace fibra
