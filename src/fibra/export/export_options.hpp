#pragma once
/// The options of `fibra export` and the voxel grid they give (docs/export.md). Every bad
/// value is an InputError naming the option and what was expected.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fibra/core/types.hpp"
#include "fibra/export/voxel_grid.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// The most voxels an export holds: each takes about 350 bytes of memory while the files are
/// made (the voxel model, then the .inp text, about 250 bytes per voxel, before it is written).
inline constexpr Index kMaxExportVoxels = Index{1} << 23;
/// Voxels along the longest side of the box when neither --voxels nor --voxel-size is given.
inline constexpr Index kDefaultVoxelsAlongLongestSide = 100;
/// Sub-sampling points per voxel edge (k: k^3 points per voxel): default and largest.
inline constexpr int kDefaultSamples = 4;
inline constexpr int kMaxSamples = 16;

/// What `fibra export` was asked for.
struct ExportOptions {
  std::string out;                             ///< output directory
  std::optional<std::array<Index, 3>> voxels;  ///< --voxels NX NY NZ
  std::optional<double> voxel_size;            ///< --voxel-size H [m]
  std::optional<Eigen::AlignedBox3d> box;      ///< --box XMIN YMIN ZMIN XMAX YMAX ZMAX [m]
  int samples = kDefaultSamples;               ///< --samples K: K^3 points per voxel
};

/// The options from the command line's words (each list empty when the option is absent):
/// checks the counts of values, that they are numbers, counts > 0, a size > 0, a box with
/// min < max on every axis, 1 <= samples <= kMaxSamples, and not both --voxels and --voxel-size.
ExportOptions parse_export_options(const std::string& out, const std::vector<std::string>& voxels,
                                   const std::vector<std::string>& voxel_size, const std::vector<std::string>& box,
                                   const std::vector<std::string>& samples);

/// The box of the fibers' material at state q: their sections sampled at 8 points per element
/// (each section's extent along x, y and z is exact) [m].
Eigen::AlignedBox3d fibers_bounds(const Model& model, const VecX& q);

/// The voxel grid of the options over the box (the fibers' bounds by default): --voxels as
/// given; --voxel-size H (or the longest side / kDefaultVoxelsAlongLongestSide) as
/// ceil(side / H) voxels per axis, of edges side / count <= H. Throws InputError for a box that
/// meets no fiber, or more than kMaxExportVoxels voxels.
VoxelGrid export_grid(const ExportOptions& options, const Eigen::AlignedBox3d& fibers);

/// "x from A to B, y from C to D, z from E to F m".
std::string describe_box(const Eigen::AlignedBox3d& box);

}  // namespace fibra
