#include "fibra/export/tow_envelope.hpp"

#include <algorithm>

namespace fibra {

TriangleMesh loft(const std::vector<std::vector<Vec3>>& contours, const Vec3& first_center, const Vec3& last_center) {
  TriangleMesh mesh;
  const int stations = static_cast<int>(contours.size());
  const int m = static_cast<int>(contours.front().size());
  for (const auto& contour : contours) mesh.points.insert(mesh.points.end(), contour.begin(), contour.end());
  const int first = static_cast<int>(mesh.points.size()), last = first + 1;
  mesh.points.push_back(first_center);
  mesh.points.push_back(last_center);
  auto vertex = [m](int k, int j) { return k * m + (j % m); };
  // With the contours counter-clockwise about the tow's direction d, (P_kj, P_k(j+1),
  // P_(k+1)(j+1)) turns about e_phi x d = e_r: outward.
  for (int k = 0; k + 1 < stations; ++k)
    for (int j = 0; j < m; ++j) {
      mesh.triangles.push_back({vertex(k, j), vertex(k, j + 1), vertex(k + 1, j + 1)});
      mesh.triangles.push_back({vertex(k, j), vertex(k + 1, j + 1), vertex(k + 1, j)});
    }
  // The caps face -d at the first station and +d at the last.
  for (int j = 0; j < m; ++j) {
    mesh.triangles.push_back({first, vertex(0, j + 1), vertex(0, j)});
    mesh.triangles.push_back({last, vertex(stations - 1, j), vertex(stations - 1, j + 1)});
  }
  return mesh;
}

namespace {

std::vector<Vec3> station_contour(const TowStation& st, const std::vector<double>& insets) {
  std::vector<Vec3> contour;
  for (const Eigen::Vector2d& v : circumscribed_contour(st.cuts, insets))
    contour.push_back(st.center + v.x() * st.u + v.y() * st.w);
  return contour;
}

}  // namespace

TowEnvelope tow_envelope(const Model& model, const VecX& q, const TowFibers& tows, int tow,
                         const EnvelopeOptions& options) {
  TowEnvelope env;
  env.tow = tow;
  const int count = options.stations > 0 ? options.stations : default_station_count(model, tows.fibers[tow]);
  const int m = options.contour_points;
  env.stations = tow_stations(model, q, tows, tow, std::max(count, 2));
  for (const TowStation& st : env.stations) {
    env.insets.emplace_back(m, 0.0);
    // Moved inward by at most a quarter of its thinnest width, a contour never turns inside out.
    env.largest_inset.push_back(0.25 * smallest_width(st.cuts, m));
    env.contours.push_back(station_contour(st, env.insets.back()));
  }
  env.surface = loft(env.contours, env.stations.front().center, env.stations.back().center);
  return env;
}

void update_contour(TowEnvelope& env, int k) {
  for (double& inset : env.insets[k]) inset = std::clamp(inset, 0.0, env.largest_inset[k]);
  env.contours[k] = station_contour(env.stations[k], env.insets[k]);
  std::copy(env.contours[k].begin(), env.contours[k].end(), env.surface.points.begin() + k * env.contours[k].size());
}

}  // namespace fibra
