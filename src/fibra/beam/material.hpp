#pragma once
/// St Venant–Kirchhoff elasticity tensors in Voigt form, axis 3 = fiber axis.
/// Voigt order: [E11, E22, E33, 2E23, 2E13, 2E12] (engineering shears).
#include <Eigen/Core>

#include "fibra/model/case.hpp"

namespace fibra {

using Mat6 = Eigen::Matrix<double, 6, 6>;

/// Stiffness D with S = D E (second Piola–Kirchhoff from Green–Lagrange), 6x6 [Pa].
Mat6 stiffness_matrix(const MaterialSpec& material);

/// Compliance D^-1 (Voigt, engineering shears), 6x6 [1/Pa].
Mat6 compliance_matrix(const MaterialSpec& material);

/// Shear modulus for torsion about the fiber axis (G or G_LT) [Pa].
double axial_shear_modulus(const MaterialSpec& material);

/// Poisson ratio of transverse contraction under axial stress (nu or nu_LT).
double axial_poisson(const MaterialSpec& material);

}  // namespace fibra
