#pragma once
/// `fibra export`: a run's final state as tow envelopes, a voxel model and an Abaqus input file
/// (docs/export.md).
#include <string>
#include <vector>

#include "fibra/export/export_options.hpp"
#include "fibra/export/export_state.hpp"
#include "fibra/export/voxel_grid.hpp"

namespace fibra {

/// What an export wrote and found.
struct ExportReport {
  std::vector<std::string> files;  ///< relative to the output directory
  std::vector<std::string> notes;  ///< what the user should know (intersecting envelopes, ...)
  Index tows = 0;
  VoxelGrid grid;
  double largest_inset = 0;          ///< the most a contour's line was moved inward [m]
  double fiber_volume_fraction = 0;  ///< over the whole box
};

/// Reads the run in `result_dir` (read_result_state), computes its export and writes it into
/// options.out. Throws InputError, before anything is computed or written, for a missing or
/// unreadable result, a case without tows, options that do not fit the fibers, and an output
/// directory that cannot be written.
ExportReport export_result(const std::string& result_dir, const ExportOptions& options);

}  // namespace fibra
