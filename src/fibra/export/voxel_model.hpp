#pragma once
/// The voxel model of a woven state (docs/export.md, "Voxel model"): per voxel the tow it lies
/// in, the local fiber direction and the local fiber volume fraction.
///
/// - Tow: the tow whose envelope holds the voxel's centre, -1 (matrix) for none; a centre in
///   several envelopes goes to the tow with the most fiber material in the voxel (the lower
///   tow index on a tie).
/// - Fiber volume fraction: the share of k^3 points (the centres of a regular subdivision of
///   the voxel) that lie in a fiber (fiber_locator.hpp); a point in several fibers counts
///   once.
/// - Fiber direction: the normalized sum of the unit tangents of the fibers at those points,
///   each taken along its fiber's reference direction (tow_fibers.hpp). In a voxel of a tow,
///   the points in that tow's fibers only, when there are any; else all the points in fibers;
///   in a voxel of a tow that holds none, the direction of the tow's nearest station; zero in
///   a matrix voxel without fiber.
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/export/tow_envelope.hpp"
#include "fibra/export/tow_fibers.hpp"
#include "fibra/export/voxel_grid.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// Per voxel (x fastest) values.
struct VoxelModel {
  VoxelGrid grid;
  std::vector<int> tow;          ///< index into the case's tows, -1 for matrix
  std::vector<Vec3> direction;   ///< unit fiber direction, or zero
  std::vector<double> fraction;  ///< fiber volume fraction in [0, 1]
};

/// Computes the voxel model of `grid` at state q with k^3 points per voxel (k >= 1); the
/// envelopes are those of the tows (any order, at most one per tow).
VoxelModel voxel_model(const Model& model, const VecX& q, const TowFibers& tows,
                       const std::vector<TowEnvelope>& envelopes, const VoxelGrid& grid, int k);

}  // namespace fibra
