#pragma once
/// Writes an exported state into a directory (docs/export.md, "Files"):
///   envelopes.vtp, contours.vtp, envelopes/TOW.stl, voxels.vti, voxels.inp, tows.csv.
#include <string>
#include <vector>

#include "fibra/export/export_state.hpp"
#include "fibra/model/case.hpp"

namespace fibra {

/// The file stem of each tow: its name with every character other than a letter, a digit,
/// ".", "-" or "_" made "_", and "_2", "_3", ... after a stem already taken.
std::vector<std::string> tow_file_stems(const std::vector<TowSpec>& tows);

/// tows.csv: one row per tow (tow, name, direction, fibers, stations, envelope_volume,
/// voxels, fiber_volume_fraction) and one for the matrix (tow -1).
std::string tows_csv(const ExportedState& s, const std::vector<TowSpec>& tows);

/// Writes every file into `dir` (made when missing; RunError when a write fails) and returns
/// their paths relative to it.
std::vector<std::string> write_export(const ExportedState& s, const std::vector<TowSpec>& tows, const std::string& dir,
                                      const std::string& heading);

}  // namespace fibra
