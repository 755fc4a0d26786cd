#pragma once
/// Slices of a run's final state, as `fibra slice` and the Python module draw them: the fibers
/// cut by planes x, y or z = value, or the cuts of one tow at successive stations along it
/// (io/slice.hpp draws each as SVG and PNG).
#include <string>
#include <vector>

namespace fibra {

/// What to draw: planes, or the stations of one tow. The words are as the user gave them, so
/// that the messages quote them.
struct SliceRequest {
  std::vector<std::string> planes;  ///< "AXIS=VALUE", e.g. "x=0.5e-3" (metres)
  std::string tow;                  ///< a tow's name (with has_tow)
  std::string stations;             ///< the number of slices across the tow (with has_stations)
  bool has_tow = false, has_stations = false;
  /// File stem; empty: RESULT/slices/slice_<axis>_<value>, or RESULT/slices/tow_<name>_01 ...
  std::string out;
};

/// What was drawn.
struct SliceOutcome {
  std::vector<std::string> lines;  ///< one line per slice (and one per tow), for the user
  std::vector<std::string> files;  ///< every file written (.svg and .png), in order
};

/// Draws the slices `request` asks for of the result in `dir` (its case.toml and nodes.csv).
/// Every option and plane is checked before anything is written: InputError naming the option
/// ("--plane", "--tow", "--stations") or the missing file.
SliceOutcome slice_result(const std::string& dir, const SliceRequest& request);

}  // namespace fibra
