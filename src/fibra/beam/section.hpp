#pragma once
/// Cross-section of a fiber and its exactly integrated, condensed stiffness.
///
/// The beam energy per unit length is 1/2 e^T C e with e the 15 generalized strains
/// (differences of dot products of x0', g1, g2, g1', g2' with their reference values, see
/// docs/theory/beam.md). C integrates the St Venant–Kirchhoff law exactly over the
/// elliptical section and statically condenses zero-mean linear and quadratic enhanced
/// modes of the in-section strains, which removes Poisson locking.
#include <Eigen/Core>

#include "fibra/model/case.hpp"

namespace fibra {

/// Number of generalized strains at a beam integration point.
inline constexpr int kGenStrains = 15;
using GenVec = Eigen::Matrix<double, kGenStrains, 1>;
using GenMat = Eigen::Matrix<double, kGenStrains, kGenStrains>;

/// Elliptical section (a circle when a == b) with its condensed stiffness.
struct Section {
  double a = 0;           ///< semi-axis along g1 [m]
  double b = 0;           ///< semi-axis along g2 [m]
  double area = 0;        ///< pi a b [m^2]
  double inertia_1 = 0;   ///< int xi2^2 dA: bending about g1 [m^4]
  double inertia_2 = 0;   ///< int xi1^2 dA: bending about g2 [m^4]
  GenMat stiffness;       ///< condensed section stiffness C (15x15, symmetric PSD) [N, N m, N m^2]
  Eigen::Matrix3d stiffness_inplane;  ///< in-section block of C (strains 0..2), for hourglass control
};

/// Builds the section of semi-axes (a, b) of the given material; `enhanced` = false skips
/// the condensation (plain 3D law, Poisson-locked; kept for tests and comparison).
Section make_section(const MaterialSpec& material, double a, double b, bool enhanced = true);

}  // namespace fibra
