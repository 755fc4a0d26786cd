#pragma once
/// The beam elements of a model at a state binned by their bounding boxes (box_grid.hpp).
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/export/box_grid.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// A box that holds the whole material of element e at state q: its centroid curve lies in
/// the hull of its Bezier control points (the two end nodes and 2 x_mid - (x_0 + x_2) / 2),
/// its sections within a |g1| + b |g2| of it, with |g| bounded by the same control points [m].
Eigen::AlignedBox3d element_box(const Model& model, const VecX& q, Index e);

/// Elements found by their boxes.
class ElementGrid {
 public:
  /// Bins the given elements (all of the model's when `elements` is empty).
  ElementGrid(const Model& model, const VecX& q, std::vector<Index> elements = {});
  /// The elements whose boxes meet `box`, in `out` (cleared first), sorted, each once.
  void find(const Eigen::AlignedBox3d& box, std::vector<Index>& out) const;
  /// The box of element e (one of those binned).
  const Eigen::AlignedBox3d& box(Index e) const { return m_grid.box(m_slot[e]); }

 private:
  static std::vector<Index> all_if_empty(const Model& model, std::vector<Index> elements);
  std::vector<Index> m_elements;  ///< the binned elements, by slot
  std::vector<Index> m_slot;      ///< per element of the model, its slot (-1 if not binned)
  BoxGrid m_grid;
};

}  // namespace fibra
