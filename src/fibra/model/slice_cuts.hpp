#pragma once
/// The cut of a fiber assembly by a plane: one polygon per place where a fiber meets the plane,
/// in the plane's own coordinates. Drawn by io/slice.hpp; method: docs/outputs.md, "Slices".
///
/// Two kinds of cut:
///  * a crossing: where a fiber's centroid curve crosses the plane (solved exactly on the
///    element's quadratic interpolation) at less than 60 degrees from the plane's normal, the
///    cut is the section ellipse {x0 + a cos t g1 + b sin t g2} carried along the fiber's
///    tangent onto the plane: exact for a locally straight fiber, the section ellipse itself
///    when the fiber crosses at right angle, elongated by 1/cos(angle) when it crosses
///    obliquely;
///  * a strip: where a fiber runs within 30 degrees of the plane (lying in it, or grazing
///    it), the plane cuts its sections along chords; the chords of sections sampled along the
///    fiber are joined into a band, closed at the ends where the chord vanishes.
#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// A cutting plane {p : normal . p = offset} and its drawing coordinates (u . p, v . p) [m].
/// normal, u and v are orthonormal.
struct SlicePlane {
  Vec3 normal = Vec3::UnitX();
  Vec3 u = Vec3::UnitY();       ///< drawn to the right
  Vec3 v = Vec3::UnitZ();       ///< drawn upwards
  double offset = 0;            ///< [m]
  int axis = 0;                 ///< 0, 1, 2: the plane x, y or z = offset; -1: another plane
  std::string u_name = "y";     ///< the axis titles of a drawing (without the unit)
  std::string v_name = "z";
  std::string caption;          ///< axis = -1: what the drawing says the plane is ("tow warp0, station 1 of 4, ...")
};

/// The plane p[axis] = value (axis 0, 1 or 2) with the coordinates of slice_plane_axes().
SlicePlane axis_plane(int axis, double value);

/// One polygon of a slice: a cut of one fiber by the plane.
struct SliceCut {
  enum class Kind { Crossing, Strip };
  Kind kind = Kind::Crossing;
  int fiber = 0;                                     ///< index into Model::fibers
  std::string name;                                  ///< the fiber's name
  int tow = -1;                                      ///< index into the tows given, -1 = in no tow
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  ///< crossing: the centroid point; strip: mean of the points
  std::vector<Eigen::Vector2d> points;               ///< polygon, in the plane's coordinates (u, v) [m]
};

/// The plane's 2D coordinates: axis 0 (x = value) -> (y, z); axis 1 -> (x, z); axis 2 -> (x, y).
/// Returns the two global components {u, v}. Throws std::invalid_argument for another axis.
std::array<int, 2> slice_plane_axes(int axis);

/// "x", "y" or "z".
const char* slice_axis_name(int axis);

/// All cuts of the fibers of `model` at state `q` (9 values per node, then the bodies') by
/// `plane`, in fiber order (crossings and strips of a fiber in order along it). `tows` gives
/// SliceCut::tow (TowSpec::fibers are fiber names).
std::vector<SliceCut> slice_cuts(const Model& model, const VecX& q, const std::vector<TowSpec>& tows,
                                 const SlicePlane& plane);

/// slice_cuts() by the plane p[axis] = value (axis 0, 1 or 2).
std::vector<SliceCut> slice_cuts(const Model& model, const VecX& q, const std::vector<TowSpec>& tows, int axis,
                                 double value);

/// Number of distinct fibers among the cuts.
int slice_fiber_count(const std::vector<SliceCut>& cuts);

/// The bounding box of the cuts' polygons in the plane's coordinates [m] (empty without cuts).
Eigen::AlignedBox2d slice_extent(const std::vector<SliceCut>& cuts);

/// Smallest box holding the centroid nodes x0 of all fibers at state q [m].
Eigen::AlignedBox3d centroid_bounds(const Model& model, const VecX& q);

/// Planes across one tow at successive stations along it (the slices of one tow, `fibra slice
/// --tow`).
struct TowStations {
  /// The tow's mean direction: the mean of its fibers' end-to-end directions (unit; turned to
  /// +x for a warp, +y for a weft).
  Vec3 direction = Vec3::UnitX();
  /// The span along `direction` that every fiber of the tow covers: from the last fiber's start
  /// to the first fiber's end, of direction . x0 over each fiber's nodes [m].
  double start = 0, end = 0;
  /// `count` planes normal to `direction` at start + (end - start) k / (count + 1), k = 1 ..
  /// count (the ends excluded); u across the tow (horizontal; towards +y for a warp, +x for a
  /// weft), v = the upward direction (+z) made normal to the tow.
  std::vector<SlicePlane> planes;
};

/// The stations of `tow` (its fibers meshed in `model`) at state `q`. Throws
/// std::invalid_argument when count < 1, the tow has no fiber in the model, or its fibers
/// cover no common span.
TowStations tow_stations(const Model& model, const VecX& q, const TowSpec& tow, int count);

}  // namespace fibra
