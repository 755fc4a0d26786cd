#include "fibra/export/export_files.hpp"

#include <cctype>
#include <filesystem>
#include <iterator>
#include <set>

#include <fmt/format.h>

#include "fibra/core/file.hpp"
#include "fibra/export/abaqus_inp.hpp"
#include "fibra/export/envelope_files.hpp"
#include "fibra/export/voxel_vti.hpp"

namespace fibra {

std::vector<std::string> tow_file_stems(const std::vector<TowSpec>& tows) {
  std::vector<std::string> stems;
  std::set<std::string> taken;
  for (const TowSpec& t : tows) {
    std::string stem;
    for (char c : t.name)
      stem += std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_' ? c : '_';
    if (stem.empty() || stem[0] == '.') stem = "tow" + stem;
    std::string unique = stem;
    for (int n = 2; taken.count(unique); ++n) unique = fmt::format("{}_{}", stem, n);
    taken.insert(unique);
    stems.push_back(unique);
  }
  return stems;
}

std::string tows_csv(const ExportedState& s, const std::vector<TowSpec>& tows) {
  const VoxelModel& vm = s.voxels;
  const double voxel_volume = vm.grid.spacing.prod();
  std::vector<Index> voxels(tows.size() + 1, 0);
  std::vector<double> fiber(tows.size() + 1, 0.0);
  for (size_t v = 0; v < vm.tow.size(); ++v) {
    const size_t slot = vm.tow[v] >= 0 ? static_cast<size_t>(vm.tow[v]) : tows.size();
    ++voxels[slot];
    fiber[slot] += vm.fraction[v];
  }
  auto mean = [&](size_t slot) { return voxels[slot] > 0 ? fiber[slot] / static_cast<double>(voxels[slot]) : 0.0; };
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out),
                 "tow,name,direction,fibers,stations,envelope_volume,voxels,voxel_volume,fiber_volume_fraction\n");
  for (const TowEnvelope& env : s.envelopes) {
    const TowSpec& t = tows[env.tow];
    fmt::format_to(std::back_inserter(out), "{},{},{},{},{},{:.9g},{},{:.9g},{:.9g}\n", env.tow, t.name,
                   t.direction == TowSpec::Direction::Warp ? "warp" : "weft", s.tows.fibers[env.tow].size(),
                   env.stations.size(), signed_volume(env.surface), voxels[env.tow],
                   static_cast<double>(voxels[env.tow]) * voxel_volume, mean(env.tow));
  }
  fmt::format_to(std::back_inserter(out), "-1,matrix,,,,,{},{:.9g},{:.9g}\n", voxels.back(),
                 static_cast<double>(voxels.back()) * voxel_volume, mean(tows.size()));
  return fmt::to_string(out);
}

std::vector<std::string> write_export(const ExportedState& s, const std::vector<TowSpec>& tows, const std::string& dir,
                                      const std::string& heading) {
  namespace fs = std::filesystem;
  std::vector<std::string> files;
  auto write = [&](const std::string& name, const std::string& bytes) {
    const fs::path path = fs::path(dir) / name;
    fs::create_directories(path.parent_path());
    write_file_atomic(path.string(), bytes);
    files.push_back(name);
  };
  const std::vector<std::string> stems = tow_file_stems(tows);
  write("envelopes.vtp", envelopes_vtp(s.envelopes));
  write("contours.vtp", contours_vtp(s.envelopes));
  for (const TowEnvelope& env : s.envelopes)
    write("envelopes/" + stems[env.tow] + ".stl",
          stl_binary(env.surface, fmt::format("fibra tow envelope {} (m)", tows[env.tow].name)));
  write("voxels.vti", voxel_vti(s.voxels));
  std::vector<std::string> names;
  for (const TowSpec& t : tows) names.push_back(t.name);
  write("voxels.inp", abaqus_inp(s.voxels, names, heading));
  write("tows.csv", tows_csv(s, tows));
  return files;
}

}  // namespace fibra
