#pragma once
/// Quadratic 3-node enriched-kinematics beam element (9 dofs per node: x0, g1, g2).
///
/// Placement x = x0 + xi1 g1 + xi2 g2; the energy at each of the 2 Gauss points along the
/// element is w J * 1/2 e^T C e, where e (15) are the generalized strains (dot products of
/// the five vectors x0', g1, g2, g1', g2' minus their reference values) and C the section's
/// condensed stiffness. Two-point (reduced) integration along the axis avoids shear locking.
/// Derivation: docs/theory/beam.md.
#include <Eigen/Core>
#include <array>

#include "fibra/beam/section.hpp"
#include "fibra/core/types.hpp"

namespace fibra {

using ElemVec = Eigen::Matrix<double, kElementDofs, 1>;
using ElemMat = Eigen::Matrix<double, kElementDofs, kElementDofs>;
/// The five vectors at a point of the axis, as columns: x0', g1, g2, g1', g2'.
using AxisVectors = Eigen::Matrix<double, 3, 5>;

/// Gauss points along the element axis (reduced 2-point rule on [-1, 1]).
inline constexpr int kBeamGauss = 2;


/// Reference data of one Gauss point.
struct BeamGauss {
  double weight = 0;    ///< Gauss weight times reference arc-length jacobian [m]
  double inv_jac = 0;   ///< 1 / (d s / d eta) [1/m]
  GenVec reference;     ///< reference generalized dot products
};

/// Hourglass control of the in-section strains s = (g1.g1, g2.g2, g1.g2): the 2-point rule
/// cannot see their nodal pattern (1, -2, 1); this adds back exactly the energy the rule misses
/// for that pattern, (8/45) J/2 c^T C_ss c with c = (s_0 - 2 s_1 + s_2)/2 from nodal values.
/// Always positive, so the element stays positive semi-definite. See docs/theory/beam.md.
struct SectionHourglass {
  double weight = 0;               ///< (8/45) * mean reference jacobian [m]
  Eigen::Matrix3d reference;       ///< reference nodal s (columns: nodes 0, 1, 2)
};

/// One element: its 27 contiguous dofs start at `first_dof`.
struct BeamElement {
  Index first_dof = 0;  ///< global index of dof 0 of the element's first node
  int section = 0;      ///< index into the model's sections
  int fiber = 0;        ///< index of the owning fiber
  std::array<BeamGauss, kBeamGauss> gauss;
  SectionHourglass hourglass;
};

/// Shape function values (N) and parametric derivatives (dN/deta) at parametric point eta.
void beam_shape(double eta, double n[3], double dn[3]);

/// Parametric coordinate of Gauss point `gp`.
double beam_gauss_point(int gp);

/// The five axis vectors at parametric point eta from the element's 27 dofs, with the
/// derivative scaled by inv_jac (so primes are d/ds, s = reference arc length).
AxisVectors beam_axis_vectors(const double* q, double eta, double inv_jac);

/// The 15 generalized dot products of the axis vectors (order in docs/theory/beam.md).
GenVec beam_dot_products(const AxisVectors& v);

/// Builds the Gauss data of an element (both rules) from its reference dofs (27 values).
void beam_reference(const double* q_ref, BeamElement& element);

/// Energy of the element at dofs `q` (27 values); adds nothing, writes grad/hess if non-null
/// (hess is the exact, symmetric second derivative). [J], [N or N m], [N/m ...]
double beam_element_energy(const BeamElement& element, const Section& section, const double* q,
                           ElemVec* grad, ElemMat* hess);

/// Generalized strains e = d - D at Gauss point gp (for post-processing).
GenVec beam_generalized_strains(const BeamElement& element, const double* q, int gp);

}  // namespace fibra

namespace fibra {

/// Axial state at parametric point eta of an element.
struct AxialState {
  double strain = 0;  ///< engineering axial strain of the centroid line, |x0'| - 1
  double force = 0;   ///< axial force resultant N = |x0'| * int S33 dA [N]
};

/// Axial strain and force at parametric point eta in [-1, 1] (nodes at -1, 0, 1).
AxialState beam_axial_state(const BeamElement& element, const Section& section, const double* q, double eta);

}  // namespace fibra
