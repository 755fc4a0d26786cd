#include "fibra/export/box_grid.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace fibra {

BoxGrid::BoxGrid(std::vector<Eigen::AlignedBox3d> boxes) : m_boxes(std::move(boxes)) {
  if (m_boxes.empty()) return;
  Eigen::AlignedBox3d all;
  double size_sum = 0;
  for (const auto& b : m_boxes) {
    all.extend(b);
    size_sum += b.sizes().maxCoeff();
  }
  // Cells about as large as a box: each box in a few cells, each cell holding a few boxes; at
  // most about 8 cells per box overall.
  const double floor_size = 1e-9 * all.sizes().maxCoeff() + 1e-300;
  m_cell = std::max(size_sum / static_cast<double>(m_boxes.size()), floor_size);
  const double cells_allowed = 8.0 * static_cast<double>(m_boxes.size()) + 64.0;
  while (((all.sizes() / m_cell).array().floor() + 1.0).prod() > cells_allowed) m_cell *= 1.5;
  m_origin = all.min();
  for (int k = 0; k < 3; ++k) m_count[k] = static_cast<Index>(std::floor(all.sizes()[k] / m_cell)) + 1;
  std::vector<Index> counts(m_count[0] * m_count[1] * m_count[2] + 1, 0);
  for (const auto& b : m_boxes) for_cells(b, [&](Index c) { ++counts[c + 1]; });
  std::partial_sum(counts.begin(), counts.end(), counts.begin());
  m_start = counts;
  m_items.resize(counts.back());
  for (Index n = 0; n < size(); ++n) for_cells(m_boxes[n], [&](Index c) { m_items[counts[c]++] = n; });
}

std::array<Index, 3> BoxGrid::cell_of(const Vec3& p) const {
  std::array<Index, 3> c;
  for (int k = 0; k < 3; ++k) {
    const double v = std::floor((p[k] - m_origin[k]) / m_cell);
    c[k] = static_cast<Index>(std::clamp(v, 0.0, static_cast<double>(m_count[k] - 1)));
  }
  return c;
}

template <class Fn>
void BoxGrid::for_cells(const Eigen::AlignedBox3d& box, Fn&& fn) const {
  const auto lo = cell_of(box.min()), hi = cell_of(box.max());
  for (Index k = lo[2]; k <= hi[2]; ++k)
    for (Index j = lo[1]; j <= hi[1]; ++j)
      for (Index i = lo[0]; i <= hi[0]; ++i) fn(i + m_count[0] * (j + m_count[1] * k));
}

void BoxGrid::find(const Eigen::AlignedBox3d& box, std::vector<Index>& out) const {
  out.clear();
  if (m_start.empty()) return;
  for_cells(box, [&](Index c) {
    for (Index n = m_start[c]; n < m_start[c + 1]; ++n)
      if (m_boxes[m_items[n]].intersects(box)) out.push_back(m_items[n]);
  });
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

}  // namespace fibra
