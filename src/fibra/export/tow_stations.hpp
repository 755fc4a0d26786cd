#pragma once
/// Stations along a tow: where its section contours are taken. Station k is at the fraction
/// s_k = k / (count - 1) of its fibers' parameter (each fiber taken along its tow's
/// direction); its centre is the mean of the fibers' centroids there, its plane is normal to
/// the mean of their unit tangents, and each fiber is cut by that plane (docs/export.md).
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/export/section_contour.hpp"
#include "fibra/export/tow_fibers.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// One station of a tow.
struct TowStation {
  Vec3 center = Vec3::Zero();      ///< mean of the fibers' centroids at the station [m]
  Vec3 direction = Vec3::UnitX();  ///< unit normal of the station's plane, along the tow
  Vec3 u = Vec3::UnitY();          ///< in-plane unit vector, across the tow
  Vec3 w = Vec3::UnitZ();          ///< direction x u: through the tow's thickness in a flat fabric
  std::vector<PlaneEllipse> cuts;  ///< the fibers' cuts in (u, w) coordinates about the centre [m]
};

/// Default number of stations of a tow: two per element of its longest fiber, plus one (the
/// stations then follow the fibers' elements closely enough that the straight pieces between
/// them stay within a small part of a fiber radius of the curved tow).
int default_station_count(const Model& model, const std::vector<int>& fibers);

/// The `count` (>= 2) stations of tow `tow` at state q. A fiber's cut is found where its
/// centroid line meets the station's plane (Newton on the element interpolation, from the
/// fiber's point at the station's fraction); its section there is carried along the fiber's
/// tangent onto the plane (orthogonally when the tangent is more than 60 degrees from the
/// plane's normal). A fiber that ends before the plane is carried from its end point.
std::vector<TowStation> tow_stations(const Model& model, const VecX& q, const TowFibers& tows, int tow, int count);

}  // namespace fibra
