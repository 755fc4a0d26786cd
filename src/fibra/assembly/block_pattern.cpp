#include "fibra/assembly/block_pattern.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <stdexcept>

namespace fibra {

void StencilSet::add(std::span<const Index> g) {
  if (group_begin.empty()) group_begin.push_back(0);
  groups.insert(groups.end(), g.begin(), g.end());
  group_begin.push_back(static_cast<Index>(groups.size()));
}

void StencilSet::colorize(Index num_groups, int partitions) {
  if (group_begin.empty()) group_begin.push_back(0);
  const Index n = size();
  by_partition.assign(partitions, {});
  by_color.clear();
  const Index width = std::max<Index>(1, (num_groups + partitions - 1) / partitions);
  std::vector<Index> straddling;
  for (Index s = 0; s < n; ++s) {
    Index lo = num_groups, hi = -1;
    for (Index g : stencil(s)) {
      lo = std::min(lo, g);
      hi = std::max(hi, g);
    }
    const Index p = hi < 0 ? 0 : lo / width;
    if (hi < 0 || p == hi / width)
      by_partition[p].push_back(s);
    else
      straddling.push_back(s);
  }
  // Straddling stencils: colours in rounds of 64; a stencil takes the lowest colour no group
  // of it holds yet.
  std::vector<int> color(n, 0);
  std::vector<std::uint64_t> used(num_groups, 0);
  std::vector<Index> pending = straddling;
  int base = 0, max_color = -1;
  while (!pending.empty()) {
    std::fill(used.begin(), used.end(), 0);
    std::vector<Index> rest;
    for (Index s : pending) {
      std::uint64_t mask = 0;
      for (Index g : stencil(s)) mask |= used[g];
      if (~mask == 0) {
        rest.push_back(s);
        continue;
      }
      const int c = std::countr_one(mask);
      for (Index g : stencil(s)) used[g] |= (std::uint64_t{1} << c);
      color[s] = base + c;
      max_color = std::max(max_color, base + c);
    }
    pending.swap(rest);
    base += 64;
  }
  by_color.resize(max_color + 1);
  for (Index s : straddling) by_color[color[s]].push_back(s);
}

BlockPattern::BlockPattern(std::vector<int> group_sizes, const std::vector<const StencilSet*>& sets)
    : m_size(std::move(group_sizes)) {
  const Index ng = static_cast<Index>(m_size.size());
  m_dof_begin.assign(ng + 1, 0);
  for (Index g = 0; g < ng; ++g) m_dof_begin[g + 1] = m_dof_begin[g] + m_size[g];
  m_group_of_dof.resize(m_dof_begin.back());
  for (Index g = 0; g < ng; ++g)
    for (int k = 0; k < m_size[g]; ++k) m_group_of_dof[m_dof_begin[g] + k] = g;

  m_upper.assign(ng, {});
  for (Index g = 0; g < ng; ++g) m_upper[g].push_back(g);
  for (const StencilSet* set : sets)
    for (Index s = 0; s < set->size(); ++s) {
      auto st = set->stencil(s);
      for (Index a : st)
        for (Index b : st)
          if (a < b) m_upper[b].push_back(a);
    }
  m_rel.assign(ng, {});
  m_col.assign(m_dof_begin.back() + 1, 0);
  size_t nnz = 0;
  for (Index g = 0; g < ng; ++g) {
    auto& up = m_upper[g];
    std::sort(up.begin(), up.end());
    up.erase(std::unique(up.begin(), up.end()), up.end());
    int rel = 0;
    m_rel[g].resize(up.size());
    for (size_t k = 0; k < up.size(); ++k) {
      m_rel[g][k] = rel;
      if (up[k] != g) rel += m_size[up[k]];
    }
    for (int c = 0; c < m_size[g]; ++c) {
      const Index col = m_dof_begin[g] + c;
      m_col[col] = static_cast<int>(nnz);
      nnz += static_cast<size_t>(rel + c + 1);
    }
  }
  if (nnz > static_cast<size_t>(INT32_MAX)) throw std::length_error("sparse pattern exceeds 2^31 entries");
  m_col[m_dof_begin.back()] = static_cast<int>(nnz);
  m_row.resize(nnz);
  for (Index g = 0; g < ng; ++g) {
    for (int c = 0; c < m_size[g]; ++c) {
      int pos = m_col[m_dof_begin[g] + c];
      for (Index h : m_upper[g]) {
        const int rows = (h == g) ? c + 1 : m_size[h];
        for (int r = 0; r < rows; ++r) m_row[pos++] = static_cast<int>(m_dof_begin[h] + r);
      }
    }
  }
}

int BlockPattern::relative_offset(Index h, Index g) const {
  const auto& up = m_upper[g];
  auto it = std::lower_bound(up.begin(), up.end(), h);
  if (it == up.end() || *it != h) return -1;
  return m_rel[g][it - up.begin()];
}

Index BlockPattern::find(Index row, Index col) const {
  const Index h = m_group_of_dof[row], g = m_group_of_dof[col];
  const int rel = relative_offset(h, g);
  if (rel < 0) return -1;
  return m_col[col] + rel + (row - m_dof_begin[h]);
}

}  // namespace fibra
