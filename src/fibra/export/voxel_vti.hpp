#pragma once
/// The voxel model as VTK XML ImageData (.vti), cell arrays "tow" (Int32, -1 for matrix),
/// "fiber_direction" (Float64, 3 components) and "fiber_volume_fraction" (Float64), stored raw
/// in an appended block; origin and spacing in metres (docs/export.md).
#include <string>

#include "fibra/export/voxel_model.hpp"

namespace fibra {

/// The .vti file of a voxel model.
std::string voxel_vti(const VoxelModel& vm);

}  // namespace fibra
