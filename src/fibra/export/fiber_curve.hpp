#pragma once
/// The fibers of a model at a state, evaluated anywhere along their elements: the quadratic
/// interpolation of the beam elements' nodal centroids and section vectors (model/model.hpp).
#include "fibra/beam/beam_element.hpp"
#include "fibra/core/types.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// The centroid, the section vectors and their derivatives at one point of an element.
struct SectionPoint {
  Vec3 x = Vec3::Zero();    ///< centroid [m]
  Vec3 dx = Vec3::Zero();   ///< d x / d eta, eta the element's parameter in [-1, 1] [m]
  Vec3 g1 = Vec3::Zero();   ///< section vector along the semi-axis a [-]
  Vec3 g2 = Vec3::Zero();   ///< section vector along the semi-axis b [-]
  Vec3 dg1 = Vec3::Zero();  ///< d g1 / d eta [-]
  Vec3 dg2 = Vec3::Zero();  ///< d g2 / d eta [-]
};

/// The point of element `e` at parameter eta (state q: 9 values per node, then the bodies').
SectionPoint element_point(const VecX& q, const BeamElement& e, double eta);

/// The point of a fiber at t in [0, num_elements]: element floor(t) (the last one at its
/// end), eta = 2 (t - element) - 1; `element` receives the element's global index.
SectionPoint fiber_point(const Model& model, const VecX& q, const Fiber& fiber, double t, Index* element = nullptr);

/// The extent of the section ellipse x + a cos(s) g1 + b sin(s) g2 along a unit direction n:
/// max over s of its offset along n, sqrt((a g1.n)^2 + (b g2.n)^2) [m].
double section_support(const Vec3& g1, const Vec3& g2, double a, double b, const Vec3& n);

}  // namespace fibra
