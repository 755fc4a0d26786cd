#include "fibra/export/abaqus_inp.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iterator>
#include <set>

#include <fmt/format.h>

namespace fibra {

namespace {

const char* const kOrientation = "FIBRA_ORIENTATION";
const char* const kDistribution = "FIBRA_FIBER_AXES";

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

/// Writes "ids" 16 to a line (the most Abaqus reads on a data line).
void write_ids(fmt::memory_buffer& out, const std::vector<Index>& ids) {
  for (size_t n = 0; n < ids.size(); ++n)
    fmt::format_to(std::back_inserter(out), "{}{}", ids[n], (n + 1) % 16 == 0 || n + 1 == ids.size() ? "\n" : ", ");
}

void write_nodes(fmt::memory_buffer& out, const VoxelGrid& g) {
  fmt::format_to(std::back_inserter(out), "*Node\n");
  Index id = 1;
  for (Index k = 0; k <= g.count[2]; ++k)
    for (Index j = 0; j <= g.count[1]; ++j)
      for (Index i = 0; i <= g.count[0]; ++i, ++id) {
        const Vec3 p = g.origin + g.spacing.cwiseProduct(
                                      Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
        fmt::format_to(std::back_inserter(out), "{}, {:.12g}, {:.12g}, {:.12g}\n", id, p.x(), p.y(), p.z());
      }
}

Index node_id(const VoxelGrid& g, Index i, Index j, Index k) {
  return 1 + i + (g.count[0] + 1) * (j + (g.count[1] + 1) * k);
}

void write_elements(fmt::memory_buffer& out, const VoxelGrid& g) {
  fmt::format_to(std::back_inserter(out), "*Element, type=C3D8R\n");
  for (Index k = 0; k < g.count[2]; ++k)
    for (Index j = 0; j < g.count[1]; ++j)
      for (Index i = 0; i < g.count[0]; ++i)
        fmt::format_to(std::back_inserter(out), "{}, {}, {}, {}, {}, {}, {}, {}, {}\n", g.index(i, j, k) + 1,
                       node_id(g, i, j, k), node_id(g, i + 1, j, k), node_id(g, i + 1, j + 1, k),
                       node_id(g, i, j + 1, k), node_id(g, i, j, k + 1), node_id(g, i + 1, j, k + 1),
                       node_id(g, i + 1, j + 1, k + 1), node_id(g, i, j + 1, k + 1));
}

/// The node set of the face where coordinate `axis` is at its low (side 0) or high end.
void write_face(fmt::memory_buffer& out, const VoxelGrid& g, int axis, int side) {
  static const char* const kNames[3][2] = {{"XMIN", "XMAX"}, {"YMIN", "YMAX"}, {"ZMIN", "ZMAX"}};
  std::vector<Index> ids;
  for (Index k = 0; k <= g.count[2]; ++k)
    for (Index j = 0; j <= g.count[1]; ++j)
      for (Index i = 0; i <= g.count[0]; ++i) {
        const Index c[3] = {i, j, k};
        if (c[axis] == (side == 0 ? 0 : g.count[axis])) ids.push_back(node_id(g, i, j, k));
      }
  fmt::format_to(std::back_inserter(out), "*Nset, nset={}\n", kNames[axis][side]);
  write_ids(out, ids);
}

void write_orientations(fmt::memory_buffer& out, const VoxelModel& vm) {
  fmt::format_to(std::back_inserter(out),
                 "** Local axes per element: point a on axis 1 (the fiber direction), point b in the 1-2 plane\n"
                 "*Distribution Table, name={0}_TABLE\ncoord3d, coord3d\n"
                 "*Distribution, name={0}, location=element, table={0}_TABLE\n"
                 ", 1., 0., 0., 0., 1., 0.\n",
                 kDistribution);
  for (size_t v = 0; v < vm.direction.size(); ++v) {
    const auto [a, b] = local_axes(vm.direction[v]);
    fmt::format_to(std::back_inserter(out), "{}, {:.9g}, {:.9g}, {:.9g}, {:.9g}, {:.9g}, {:.9g}\n", v + 1, a.x(), a.y(),
                   a.z(), b.x(), b.y(), b.z());
  }
  fmt::format_to(std::back_inserter(out), "*Orientation, name={}, definition=coordinates\n{}\n1, 0.\n", kOrientation,
                 kDistribution);
}

}  // namespace

std::vector<std::string> abaqus_tow_sets(const std::vector<std::string>& tow_names) {
  std::vector<std::string> sets;
  std::set<std::string> taken;
  for (const std::string& name : tow_names) {
    std::string label = "TOW_";
    for (char c : name) label += std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '_';
    label = label.substr(0, 70);
    std::string unique = label;
    for (int n = 2; taken.count(upper(unique)); ++n) unique = fmt::format("{}_{}", label, n);
    taken.insert(upper(unique));
    sets.push_back(unique);
  }
  return sets;
}

std::pair<Vec3, Vec3> local_axes(const Vec3& a) {
  if (a.squaredNorm() == 0) return {Vec3::UnitX(), Vec3::UnitY()};
  const Vec3 up = std::abs(a.z()) < std::cos(0.1 * 3.14159265358979323846 / 180.0) ? Vec3::UnitZ() : Vec3::UnitX();
  const Vec3 axis3 = (up - up.dot(a) * a).normalized();
  return {a, axis3.cross(a)};
}

std::string abaqus_inp(const VoxelModel& vm, const std::vector<std::string>& tow_names, const std::string& heading) {
  const VoxelGrid& g = vm.grid;
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out),
                 "*Heading\n{}\n** Units: m, N, Pa. One C3D8R element per voxel, numbered x fastest (as the .vti).\n",
                 heading);
  write_nodes(out, g);
  write_elements(out, g);
  const std::vector<std::string> sets = abaqus_tow_sets(tow_names);
  std::vector<std::vector<Index>> members(tow_names.size() + 1);  // the last: the matrix
  for (size_t v = 0; v < vm.tow.size(); ++v)
    members[vm.tow[v] >= 0 ? vm.tow[v] : tow_names.size()].push_back(static_cast<Index>(v) + 1);
  for (size_t t = 0; t < members.size(); ++t) {
    if (members[t].empty()) continue;  // Abaqus refuses an empty set
    fmt::format_to(std::back_inserter(out), "*Elset, elset={}\n", t < sets.size() ? sets[t] : "MATRIX");
    write_ids(out, members[t]);
  }
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) write_face(out, g, axis, side);
  write_orientations(out, vm);
  std::vector<std::string> used;  // the element sets that hold elements, each with its section
  for (size_t t = 0; t < members.size(); ++t)
    if (!members[t].empty()) used.push_back(t < sets.size() ? sets[t] : "MATRIX");
  fmt::format_to(std::back_inserter(out), "** Placeholder materials, to be defined (*Material) before a run: MAT_{}\n",
                 fmt::join(used, ", MAT_"));
  for (const std::string& set : used)
    fmt::format_to(std::back_inserter(out), "*Solid Section, elset={0}, material=MAT_{0}{1}\n1.,\n", set,
                   set == "MATRIX" ? "" : fmt::format(", orientation={}", kOrientation));
  return fmt::to_string(out);
}

}  // namespace fibra
