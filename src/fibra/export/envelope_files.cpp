#include "fibra/export/envelope_files.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

#include <fmt/format.h>

#include "fibra/export/vtk_xml.hpp"

namespace fibra {

namespace {

template <class T>
void append_raw(std::string& out, const T& value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

void append_floats(std::string& out, const Vec3& v) {
  for (int k = 0; k < 3; ++k) append_raw(out, static_cast<float>(v[k]));
}

/// One PolyData piece of `points` with cells of kind `cells` ("Polys" or "Lines").
std::string poly_data(const std::vector<double>& points, const char* cells,
                      const std::vector<std::int64_t>& connectivity, const std::vector<std::int64_t>& offsets,
                      const std::vector<std::pair<std::string, std::vector<std::int32_t>>>& cell_arrays) {
  VtkAppendedData data;
  const size_t n_points = points.size() / 3, n_cells = offsets.size();
  std::string out = vtk_file_header("PolyData");
  out += "<PolyData>\n";
  out += fmt::format(
      "<Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" "
      "NumberOfPolys=\"{}\">\n",
      n_points, std::string(cells) == "Lines" ? n_cells : 0, std::string(cells) == "Polys" ? n_cells : 0);
  out += "<Points>\n" + data.data_array("Float64", "Points", 3, points) + "</Points>\n";
  out += fmt::format("<{}>\n", cells);
  out += data.data_array("Int64", "connectivity", 1, connectivity);
  out += data.data_array("Int64", "offsets", 1, offsets);
  out += fmt::format("</{}>\n<CellData Scalars=\"tow\">\n", cells);
  for (const auto& [name, values] : cell_arrays) out += data.data_array("Int32", name, 1, values);
  out += "</CellData>\n</Piece>\n</PolyData>\n";
  return out + data.close();
}

}  // namespace

std::string stl_binary(const TriangleMesh& mesh, const std::string& title) {
  std::string out(80, ' ');
  std::memcpy(out.data(), title.data(), std::min<size_t>(title.size(), 80));
  append_raw(out, static_cast<std::uint32_t>(mesh.triangles.size()));
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    append_floats(out, triangle_normal(mesh, t));
    for (int corner : mesh.triangles[t]) append_floats(out, mesh.points[corner]);
    append_raw(out, std::uint16_t{0});
  }
  return out;
}

std::string envelopes_vtp(const std::vector<TowEnvelope>& envelopes) {
  std::vector<double> points;
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::int32_t> tow;
  for (const TowEnvelope& env : envelopes) {
    const auto base = static_cast<std::int64_t>(points.size() / 3);
    for (const Vec3& p : env.surface.points) points.insert(points.end(), {p.x(), p.y(), p.z()});
    for (const auto& t : env.surface.triangles) {
      for (int corner : t) connectivity.push_back(base + corner);
      offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
      tow.push_back(env.tow);
    }
  }
  return poly_data(points, "Polys", connectivity, offsets, {{"tow", tow}});
}

std::string contours_vtp(const std::vector<TowEnvelope>& envelopes) {
  std::vector<double> points;
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::int32_t> tow, station;
  for (const TowEnvelope& env : envelopes)
    for (size_t k = 0; k < env.contours.size(); ++k) {
      const auto base = static_cast<std::int64_t>(points.size() / 3);
      const auto& contour = env.contours[k];
      for (const Vec3& p : contour) points.insert(points.end(), {p.x(), p.y(), p.z()});
      for (size_t j = 0; j <= contour.size(); ++j)
        connectivity.push_back(base + static_cast<std::int64_t>(j % contour.size()));
      offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
      tow.push_back(env.tow);
      station.push_back(static_cast<std::int32_t>(k));
    }
  return poly_data(points, "Lines", connectivity, offsets, {{"tow", tow}, {"station", station}});
}

}  // namespace fibra
