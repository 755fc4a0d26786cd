#pragma once
/// The envelope of a tow: its section contours at its stations joined into one closed,
/// outward-facing triangulated surface, capped at both ends (docs/export.md, "Tow envelopes").
#include <vector>

#include "fibra/export/tow_fibers.hpp"
#include "fibra/export/tow_stations.hpp"
#include "fibra/export/triangle_mesh.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// How envelopes are made.
struct EnvelopeOptions {
  int contour_points = 64;  ///< vertices of each section contour (support lines), >= 3
  int stations = 0;         ///< stations per tow (>= 2); 0: default_station_count()
};

/// One tow's envelope. Its surface's points are the contours' vertices, station after
/// station (contour_points each), then the centres of the first and last stations.
struct TowEnvelope {
  int tow = 0;  ///< index into the case's tows
  std::vector<TowStation> stations;
  std::vector<std::vector<double>> insets;  ///< per station, how far each support line is moved inward [m]
  std::vector<double> largest_inset;        ///< per station, the most a line may be moved inward [m]
  std::vector<std::vector<Vec3>> contours;  ///< per station, its contour's vertices [m]
  TriangleMesh surface;                     ///< the closed surface through the contours
};

/// The envelope of tow `tow` at state q, no line moved inward. Contour vertex j of station k
/// is joined to vertex j of station k + 1 (two triangles per quad), and each end contour is
/// closed by a fan from its station's centre.
TowEnvelope tow_envelope(const Model& model, const VecX& q, const TowFibers& tows, int tow,
                         const EnvelopeOptions& options);

/// Recomputes the contour of station k from its insets (each kept within largest_inset[k])
/// and moves its vertices in the surface.
void update_contour(TowEnvelope& envelope, int k);

/// The closed surface through contours of equal vertex counts (>= 3, counter-clockwise about
/// the directions from the first contour to the last), capped by fans from `first_center` and
/// `last_center`.
TriangleMesh loft(const std::vector<std::vector<Vec3>>& contours, const Vec3& first_center, const Vec3& last_center);

}  // namespace fibra
