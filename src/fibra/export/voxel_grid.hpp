#pragma once
/// A regular grid of voxels over a box: nx x ny x nz equal boxes, numbered with x fastest
/// (the order of VTK image data and of the Abaqus elements the export writes).
#include <array>

#include <Eigen/Geometry>

#include "fibra/core/types.hpp"

namespace fibra {

/// The voxels of a box.
struct VoxelGrid {
  Vec3 origin = Vec3::Zero();   ///< the box's lowest corner [m]
  Vec3 spacing = Vec3::Ones();  ///< a voxel's edges [m]
  std::array<Index, 3> count{1, 1, 1};

  /// The grid of nx x ny x nz voxels filling `box`.
  static VoxelGrid over(const Eigen::AlignedBox3d& box, const std::array<Index, 3>& count);
  Index size() const { return count[0] * count[1] * count[2]; }  ///< number of voxels
  Index index(Index i, Index j, Index k) const { return i + count[0] * (j + count[1] * k); }
  /// The centre of voxel (i, j, k) [m].
  Vec3 center(Index i, Index j, Index k) const;
  /// The box of voxel (i, j, k) [m].
  Eigen::AlignedBox3d voxel_box(Index i, Index j, Index k) const;
  /// The whole box [m].
  Eigen::AlignedBox3d box() const;
};

}  // namespace fibra
