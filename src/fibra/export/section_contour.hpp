#pragma once
/// The contour of a tow's section: the convex polygon circumscribing its fibers' cut ellipses,
/// made of support lines at fixed normal directions (docs/export.md, "Tow envelopes").
///
/// Line j has the normal n_j = (cos 2 pi j / m, sin 2 pi j / m) and touches the convex hull of
/// the ellipses (its offset is the largest support of the ellipses along n_j, exact for an
/// ellipse); vertex j is where lines j and j + 1 meet. The polygon holds every ellipse whole,
/// not only points sampled on them, and every contour has the same m vertices in the same
/// angular order, so that the contours of successive stations join vertex to vertex.
#include <Eigen/Core>
#include <vector>

namespace fibra {

/// An ellipse in a plane's 2D coordinates: center + cos(s) axis_a + sin(s) axis_b.
struct PlaneEllipse {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  Eigen::Vector2d axis_a = Eigen::Vector2d::Zero();  ///< semi-axis vector (a g1 carried into the plane) [m]
  Eigen::Vector2d axis_b = Eigen::Vector2d::Zero();  ///< semi-axis vector (b g2 carried into the plane) [m]
};

/// Largest offset along the unit vector n of a point of the ellipses: the support function
/// of their convex hull [m]. The ellipses must not be empty.
double hull_support(const std::vector<PlaneEllipse>& ellipses, const Eigen::Vector2d& n);

/// The m vertices (counter-clockwise, vertex j between the normals j and j + 1) of the polygon
/// bounded by the m support lines, line j moved inward by insets[j] [m] (all 0: the polygon
/// holds the ellipses). m = insets.size() >= 3; the ellipses must not be empty.
std::vector<Eigen::Vector2d> circumscribed_contour(const std::vector<PlaneEllipse>& ellipses,
                                                   const std::vector<double>& insets);

/// The smallest width of the ellipses' hull over the m normal directions (support along n_j
/// plus support along -n_j) [m]: an inset must stay below half of it.
double smallest_width(const std::vector<PlaneEllipse>& ellipses, int m);

}  // namespace fibra
