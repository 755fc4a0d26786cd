#pragma once
/// Slices: the cut of a fiber assembly by a plane x = value, y = value (or z = value), drawn
/// as an SVG (vector) and a PNG (raster, written without external libraries). Each fiber is
/// coloured by its tow (warp tows in blues, weft tows in reds and oranges, fibers in no tow
/// grey). File format and method: docs/outputs.md, "Slices".
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

#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// One polygon of a slice: a cut of one fiber by the plane.
struct SliceCut {
  enum class Kind { Crossing, Strip };
  Kind kind = Kind::Crossing;
  int fiber = 0;                                     ///< index into Model::fibers
  std::string name;                                  ///< the fiber's name
  int tow = -1;                                      ///< index into the tows given, -1 = in no tow
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  ///< crossing: the centroid point; strip: mean of the points
  std::vector<Eigen::Vector2d> points;               ///< polygon, in the plane's coordinates [m]
};

/// The plane's 2D coordinates: axis 0 (x = value) -> (y, z); axis 1 -> (x, z); axis 2 -> (x, y).
/// Returns the two global components {u, v}.
std::array<int, 2> slice_plane_axes(int axis);

/// "x", "y" or "z".
const char* slice_axis_name(int axis);

/// All cuts of the fibers of `model` at state `q` (9 values per node, then the bodies') by the
/// plane {p : p[axis] = value}, in fiber order (crossings and strips of a fiber in order
/// along it). `tows` gives the colours (TowSpec::fibers are fiber names). axis is 0, 1 or 2.
std::vector<SliceCut> slice_cuts(const Model& model, const VecX& q, const std::vector<TowSpec>& tows, int axis,
                                 double value);

/// Number of distinct fibers among the cuts.
int slice_fiber_count(const std::vector<SliceCut>& cuts);

/// Writes `stem`.svg and `stem`.png (creating the parent directory) for precomputed cuts:
/// `title` on top, the plane and the count of cut fibers below it, the cuts in the plane's
/// coordinates in mm at equal scale, axes with ticks, a scale bar and a legend. Returns the
/// number of cut fibers. Throws RunError when a file cannot be written.
int write_slice(const std::string& stem, const std::vector<SliceCut>& cuts, const std::vector<TowSpec>& tows, int axis,
                double value, const std::string& title);

/// slice_cuts() then write_slice(); returns the number of cut fibers.
int write_slice(const std::string& stem, const Model& model, const VecX& q, const std::vector<TowSpec>& tows, int axis,
                double value, const std::string& title);

/// Smallest box holding the centroid nodes x0 of all fibers at state q [m].
Eigen::AlignedBox3d centroid_bounds(const Model& model, const VecX& q);

}  // namespace fibra
