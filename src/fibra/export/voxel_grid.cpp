#include "fibra/export/voxel_grid.hpp"

namespace fibra {

VoxelGrid VoxelGrid::over(const Eigen::AlignedBox3d& box, const std::array<Index, 3>& count) {
  VoxelGrid g;
  g.origin = box.min();
  g.count = count;
  for (int k = 0; k < 3; ++k) g.spacing[k] = box.sizes()[k] / static_cast<double>(count[k]);
  return g;
}

Vec3 VoxelGrid::center(Index i, Index j, Index k) const {
  return origin + spacing.cwiseProduct(
                      Vec3(static_cast<double>(i) + 0.5, static_cast<double>(j) + 0.5, static_cast<double>(k) + 0.5));
}

Eigen::AlignedBox3d VoxelGrid::voxel_box(Index i, Index j, Index k) const {
  const Vec3 lo =
      origin + spacing.cwiseProduct(Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
  return {lo, lo + spacing};
}

Eigen::AlignedBox3d VoxelGrid::box() const {
  const Vec3 hi = origin + spacing.cwiseProduct(Vec3(static_cast<double>(count[0]), static_cast<double>(count[1]),
                                                     static_cast<double>(count[2])));
  return {origin, hi};
}

}  // namespace fibra
