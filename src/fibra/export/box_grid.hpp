#pragma once
/// A uniform grid of cubic cells over a set of boxes, to find the boxes that meet a query box
/// without testing them all (the elements near a voxel, the triangles near a triangle).
#include <array>
#include <vector>

#include <Eigen/Geometry>

#include "fibra/core/types.hpp"

namespace fibra {

/// Boxes binned into the cells they meet; cells about as large as the mean box.
class BoxGrid {
 public:
  explicit BoxGrid(std::vector<Eigen::AlignedBox3d> boxes);
  /// The indices of the boxes that meet `box`, in `out` (cleared first), sorted, each once.
  void find(const Eigen::AlignedBox3d& box, std::vector<Index>& out) const;
  /// Box n as given.
  const Eigen::AlignedBox3d& box(Index n) const { return m_boxes[n]; }
  Index size() const { return static_cast<Index>(m_boxes.size()); }

 private:
  std::array<Index, 3> cell_of(const Vec3& p) const;
  template <class Fn>
  void for_cells(const Eigen::AlignedBox3d& box, Fn&& fn) const;
  std::vector<Eigen::AlignedBox3d> m_boxes;
  Vec3 m_origin = Vec3::Zero();
  double m_cell = 1;
  std::array<Index, 3> m_count{1, 1, 1};
  std::vector<Index> m_start;  ///< per cell, its first entry in m_items (CSR), then the end
  std::vector<Index> m_items;
};

}  // namespace fibra
