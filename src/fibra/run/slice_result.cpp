// Slices of a run's final state (slice_result.hpp).
#include "fibra/run/slice_result.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>

#include "fibra/core/error.hpp"
#include "fibra/export/result_state.hpp"
#include "fibra/io/slice.hpp"
#include "fibra/model/model.hpp"
#include "fibra/model/slice_cuts.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

/// A plane of a slice: p[axis] = value.
struct Plane {
  int axis = 0;
  double value = 0;
  std::string text;  ///< as given, for messages
};

/// Parses "x=0.5e-3" (axis x, y or z; the value in metres).
Plane parse_plane(const std::string& text) {
  auto fail = [&] {
    throw InputError("fibra slice", "--plane",
                     fmt::format("expected AXIS=VALUE with AXIS x, y or z and VALUE a position in metres "
                                 "(e.g. --plane x=0.5e-3), got \"{}\"",
                                 text));
  };
  const size_t eq = text.find('=');
  if (eq == std::string::npos) fail();
  auto trim = [](std::string s) {
    s.erase(0, s.find_first_not_of(" \t"));
    s.erase(s.find_last_not_of(" \t") + 1);
    return s;
  };
  const std::string axis = trim(text.substr(0, eq)), value = trim(text.substr(eq + 1));
  Plane p;
  p.text = text;
  if (axis == "x" || axis == "X")
    p.axis = 0;
  else if (axis == "y" || axis == "Y")
    p.axis = 1;
  else if (axis == "z" || axis == "Z")
    p.axis = 2;
  else
    fail();
  const char* begin = value.data();
  if (!value.empty() && value[0] == '+') ++begin;
  const auto [end, ec] = std::from_chars(begin, value.data() + value.size(), p.value);
  if (value.empty() || ec != std::errc() || end != value.data() + value.size() || !std::isfinite(p.value)) fail();
  return p;
}

/// "x from A to B, y from ..., z from ... m": where the fibers' centroid lines are.
std::string describe_bounds(const Eigen::AlignedBox3d& box) {
  return fmt::format(
      "the fibers' centroid lines span x from {:.4g} to {:.4g}, y from {:.4g} to {:.4g}, "
      "z from {:.4g} to {:.4g} m",
      box.min().x(), box.max().x(), box.min().y(), box.max().y(), box.min().z(), box.max().z());
}

/// The plane's position in a file name: 6 significant digits, no "-0".
std::string value_label(double value) { return fmt::format("{:.6g}", value == 0 ? 0.0 : value); }

/// File stem of a slice: DIR/slice_x_0.0005.
std::string slice_stem(const fs::path& dir, int axis, double value) {
  return (dir / fmt::format("slice_{}_{}", slice_axis_name(axis), value_label(value))).string();
}

/// The number of stations: an integer from 1 to 999.
int parse_stations(const std::string& text) {
  int n = 0;
  const char* end = text.data() + text.size();
  const auto [at, ec] = std::from_chars(text.data(), end, n);
  if (text.empty() || ec != std::errc() || at != end || n < 1 || n > 999)
    throw InputError("fibra slice", "--stations",
                     fmt::format("expected the number of slices across the tow, an integer from 1 to 999 "
                                 "(e.g. --stations 5), got \"{}\"",
                                 text));
  return n;
}

/// The slices of one tow at successive stations along it: RESULT/slices/tow_NAME_01 ... (or
/// STEM_01 ...), only that tow's fibers, all at the same scale and frame.
void slice_tow(const std::string& dir, const Case& c, const Model& model, const VecX& q, const std::string& tow_name,
               int count, const std::string& out, SliceOutcome& outcome) {
  const auto tow = std::find_if(c.tows.begin(), c.tows.end(), [&](const TowSpec& t) { return t.name == tow_name; });
  if (tow == c.tows.end()) {
    std::vector<std::string> names;
    for (const TowSpec& t : c.tows) names.push_back(t.name);
    throw InputError("fibra slice", "--tow",
                     names.empty() ? fmt::format("no tow named \"{}\": the case has no tows", tow_name)
                                   : fmt::format("no tow named \"{}\"; the case's tows: {}", tow_name,
                                                 fmt::format("{}", fmt::join(names, ", "))));
  }
  const int index = static_cast<int>(tow - c.tows.begin());
  TowStations stations;
  try {
    stations = tow_stations(model, q, *tow, count);
  } catch (const std::invalid_argument& e) {
    throw InputError("fibra slice", "--tow " + tow_name, e.what());
  }
  std::vector<std::vector<SliceCut>> cuts;
  Eigen::AlignedBox2d frame;  // one frame for all, so that the slices compare
  for (const SlicePlane& plane : stations.planes) {
    std::vector<SliceCut> all = slice_cuts(model, q, c.tows, plane), own;
    for (SliceCut& cut : all)
      if (cut.tow == index) own.push_back(std::move(cut));
    frame.extend(slice_extent(own));
    cuts.push_back(std::move(own));
  }
  const std::string title = c.title.empty() ? fs::path(dir).filename().string() : c.title;
  const int width = std::max(2, static_cast<int>(std::to_string(count).size()));
  const std::string base =
      out.empty() ? (fs::path(dir) / "slices" / ("tow_" + step_file_stem(tow_name))).string() : out;
  auto component = [](double x) { return std::abs(x) < 5e-5 ? 0.0 : x; };  // no "-0.0000"
  outcome.lines.push_back(
      fmt::format("tow {}: {} stations from {:.6g} to {:.6g} mm along its direction ({:.4f}, {:.4f}, {:.4f})\n",
                  tow_name, count, 1e3 * stations.start, 1e3 * stations.end, component(stations.direction.x()),
                  component(stations.direction.y()), component(stations.direction.z())));
  for (int k = 0; k < count; ++k) {
    const SlicePlane& plane = stations.planes[k];
    const std::string stem = fmt::format("{}_{:0{}d}", base, k + 1, width);
    const int fibers = write_slice(stem, cuts[k], c.tows, plane, title, frame);
    outcome.lines.push_back(fmt::format("station {} at {:.6g} mm: {} of {} fibers cut ({} polygons): {}.svg, {}.png",
                                        k + 1, 1e3 * (plane.offset - stations.start), fibers, tow->fibers.size(),
                                        cuts[k].size(), stem, stem));
    outcome.files.push_back(stem + ".svg");
    outcome.files.push_back(stem + ".png");
  }
}

}  // namespace

SliceOutcome slice_result(const std::string& dir, const SliceRequest& request) {
  SliceOutcome outcome;
  // The options are checked before anything is read.
  if (!request.planes.empty() && request.has_tow)
    throw InputError("fibra slice", "--tow", "give either --plane or --tow with --stations, not both");
  if (request.planes.empty() && !request.has_tow && !request.has_stations)
    throw InputError("fibra slice", "--plane",
                     "expected --plane AXIS=VALUE (e.g. --plane x=0.5e-3) or --tow NAME --stations N");
  if (request.has_tow && !request.has_stations)
    throw InputError("fibra slice", "--stations",
                     "--tow needs --stations N, the number of slices across the tow (e.g. --stations 5)");
  if (!request.has_tow && request.has_stations)
    throw InputError("fibra slice", "--stations", "--stations counts the slices of a tow: give --tow NAME too");
  const int count = request.has_tow ? parse_stations(request.stations) : 0;
  std::vector<Plane> planes;
  for (const std::string& t : request.planes) planes.push_back(parse_plane(t));
  const ResultState result = read_result_state(dir, "fibra slice");
  const Case& c = result.c;
  const Model& model = result.model;
  const VecX& q = result.q;
  if (request.has_tow) {
    slice_tow(dir, c, model, q, request.tow, count, request.out, outcome);
    return outcome;
  }

  // Every plane is checked before anything is written.
  const Eigen::AlignedBox3d box = centroid_bounds(model, q);
  std::vector<std::vector<SliceCut>> cuts;
  for (const Plane& p : planes) {
    cuts.push_back(slice_cuts(model, q, c.tows, p.axis, p.value));
    if (cuts.back().empty())
      throw InputError("fibra slice", "--plane " + p.text, "the plane cuts no fiber: " + describe_bounds(box));
  }
  const std::string title = c.title.empty() ? fs::path(dir).filename().string() : c.title;
  for (size_t k = 0; k < planes.size(); ++k) {
    const Plane& p = planes[k];
    std::string stem;
    if (request.out.empty())
      stem = slice_stem(fs::path(dir) / "slices", p.axis, p.value);
    else if (planes.size() == 1)
      stem = request.out;
    else
      stem = fmt::format("{}_{}_{}", request.out, slice_axis_name(p.axis), value_label(p.value));
    const int fibers = write_slice(stem, cuts[k], c.tows, p.axis, p.value, title);
    outcome.lines.push_back(fmt::format("slice {} = {:g}: {} fibers cut ({} polygons): {}.svg, {}.png",
                                        slice_axis_name(p.axis), p.value, fibers, cuts[k].size(), stem, stem));
    outcome.files.push_back(stem + ".svg");
    outcome.files.push_back(stem + ".png");
  }
  return outcome;
}

}  // namespace fibra
