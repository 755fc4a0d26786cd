#include "fibra/export/voxel_vti.hpp"

#include <cstdint>

#include <fmt/format.h>

#include "fibra/export/vtk_xml.hpp"

namespace fibra {

std::string voxel_vti(const VoxelModel& vm) {
  const VoxelGrid& g = vm.grid;
  std::vector<std::int32_t> tow(vm.tow.begin(), vm.tow.end());
  std::vector<double> direction;
  direction.reserve(3 * vm.direction.size());
  for (const Vec3& d : vm.direction) direction.insert(direction.end(), {d.x(), d.y(), d.z()});
  VtkAppendedData data;
  const std::string extent = fmt::format("0 {} 0 {} 0 {}", g.count[0], g.count[1], g.count[2]);
  std::string out = vtk_file_header("ImageData");
  out += fmt::format(
      "<ImageData WholeExtent=\"{}\" Origin=\"{:.17g} {:.17g} {:.17g}\" "
      "Spacing=\"{:.17g} {:.17g} {:.17g}\">\n",
      extent, g.origin.x(), g.origin.y(), g.origin.z(), g.spacing.x(), g.spacing.y(), g.spacing.z());
  out += fmt::format("<Piece Extent=\"{}\">\n<PointData>\n</PointData>\n", extent);
  out += "<CellData Scalars=\"tow\" Vectors=\"fiber_direction\">\n";
  out += data.data_array("Int32", "tow", 1, tow);
  out += data.data_array("Float64", "fiber_direction", 3, direction);
  out += data.data_array("Float64", "fiber_volume_fraction", 1, vm.fraction);
  out += "</CellData>\n</Piece>\n</ImageData>\n";
  return out + data.close();
}

}  // namespace fibra
