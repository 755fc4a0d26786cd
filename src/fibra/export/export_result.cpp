#include "fibra/export/export_result.hpp"

#include <numeric>

#include <fmt/format.h>

#include "fibra/core/error.hpp"
#include "fibra/export/export_files.hpp"
#include "fibra/export/result_state.hpp"
#include "fibra/io/output_writer.hpp"

namespace fibra {

ExportReport export_result(const std::string& result_dir, const ExportOptions& options) {
  const ResultState r = read_result_state(result_dir, "fibra export");
  if (r.c.tows.empty())
    throw InputError(result_dir + "/case.toml", "tow",
                     "the case has no tows: `fibra export` exports the tows of a fabric (a [fabric] or [[tow]] "
                     "entries)");
  // Every option is checked, and the output directory made, before anything is computed.
  const VoxelGrid grid = export_grid(options, fibers_bounds(r.model, r.q));
  prepare_output_dir(options.out, {"envelopes"});
  const ExportedState s = export_state(r.model, r.q, r.c.tows, grid, options.samples);
  const VoxelGrid& g = s.voxels.grid;
  const std::string heading = fmt::format("fibra export of {}: {} x {} x {} voxels over {}", result_dir, g.count[0],
                                          g.count[1], g.count[2], describe_box(g.box()));
  ExportReport report;
  report.files = write_export(s, r.c.tows, options.out, heading);
  report.tows = static_cast<Index>(s.envelopes.size());
  report.grid = g;
  report.largest_inset = s.separation.largest_inset;
  report.fiber_volume_fraction = std::accumulate(s.voxels.fraction.begin(), s.voxels.fraction.end(), 0.0) /
                                 static_cast<double>(std::max<Index>(g.size(), 1));
  for (const EnvelopeClash& c : s.separation.remaining)
    report.notes.push_back(
        fmt::format("the envelopes of {} and {} still intersect ({} pairs of triangles): a voxel "
                    "in both goes to the tow with more fiber material in it",
                    r.c.tows[c.tow_a].name, r.c.tows[c.tow_b].name, c.triangle_pairs));
  return report;
}

}  // namespace fibra
