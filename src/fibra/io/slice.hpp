#pragma once
/// Slices drawn: the cuts of a fiber assembly by a plane (model/slice_cuts.hpp) drawn once with
/// Cairo onto two surfaces, an SVG (vector) and a PNG (raster) of the same page. Each fiber is
/// coloured by its tow (warp tows in blues, weft tows in reds and oranges, fibers in no tow
/// grey). Page and colours: docs/outputs.md, "Slices".
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"
#include "fibra/model/slice_cuts.hpp"

namespace fibra {

/// The page of a slice: where the plane's points are drawn. SVG user units are PNG pixels.
struct SlicePage {
  int width = 1200, height = 0;   ///< [px]
  double scale = 1;               ///< [px per mm], the same along both axes
  double u0 = 0, v1 = 0;          ///< plane coordinates [mm] at the plot's left and top edges
  double left = 0, top = 0;       ///< the plot's top left corner [px]
  double plot_w = 0, plot_h = 0;  ///< the plot's size [px]
  double du = 0, dv = 0;          ///< the plot's size [mm]
  /// The page point [px] of the plane point (u, v) [m].
  Eigen::Vector2d to_page(const Eigen::Vector2d& uv) const {
    return {left + (1e3 * uv.x() - u0) * scale, top + (v1 - 1e3 * uv.y()) * scale};
  }
};

/// The page that draws `extent` (a region of the plane [m]; empty: the cuts' bounding box),
/// grown by 5 % on every side, at the largest equal scale that fits 1086 px wide and 1400 px
/// high.
SlicePage slice_page(const std::vector<SliceCut>& cuts, const Eigen::AlignedBox2d& extent = Eigen::AlignedBox2d());

/// Writes `stem`.svg and `stem`.png (creating the parent directory) for precomputed cuts by
/// `plane`: `title` on top, the plane and the count of cut fibers below it, the cuts in the
/// plane's coordinates in mm at equal scale, axes with ticks, a scale bar and a legend; the
/// page of slice_page(cuts, extent). Returns the number of cut fibers. Throws RunError when a
/// file cannot be drawn or written, std::invalid_argument when a cut names a tow beyond `tows`.
int write_slice(const std::string& stem, const std::vector<SliceCut>& cuts, const std::vector<TowSpec>& tows,
                const SlicePlane& plane, const std::string& title,
                const Eigen::AlignedBox2d& extent = Eigen::AlignedBox2d());

/// write_slice() for the plane p[axis] = value (axis 0, 1 or 2).
int write_slice(const std::string& stem, const std::vector<SliceCut>& cuts, const std::vector<TowSpec>& tows, int axis,
                double value, const std::string& title);

/// slice_cuts() by the plane p[axis] = value, then write_slice(); returns the number of cut fibers.
int write_slice(const std::string& stem, const Model& model, const VecX& q, const std::vector<TowSpec>& tows, int axis,
                double value, const std::string& title);

}  // namespace fibra
