#include "fibra/beam/material.hpp"

#include <Eigen/LU>

namespace fibra {

Mat6 compliance_matrix(const MaterialSpec& m) {
  Mat6 s = Mat6::Zero();
  double et, el, nult, nutt, glt, gtt;
  if (m.model == MaterialSpec::Model::Isotropic) {
    et = el = m.young;
    nult = nutt = m.poisson;
    glt = gtt = m.young / (2.0 * (1.0 + m.poisson));
  } else {
    el = m.young;
    et = m.young_transverse;
    nult = m.poisson;
    nutt = m.poisson_transverse;
    glt = m.shear_axial;
    gtt = et / (2.0 * (1.0 + nutt));
  }
  s(0, 0) = s(1, 1) = 1.0 / et;
  s(2, 2) = 1.0 / el;
  s(0, 1) = s(1, 0) = -nutt / et;
  s(0, 2) = s(2, 0) = s(1, 2) = s(2, 1) = -nult / el;
  s(3, 3) = s(4, 4) = 1.0 / glt;
  s(5, 5) = 1.0 / gtt;
  return s;
}

Mat6 stiffness_matrix(const MaterialSpec& m) { return compliance_matrix(m).inverse(); }

double axial_shear_modulus(const MaterialSpec& m) {
  return m.model == MaterialSpec::Model::Isotropic ? m.young / (2.0 * (1.0 + m.poisson)) : m.shear_axial;
}

double axial_poisson(const MaterialSpec& m) { return m.poisson; }

}  // namespace fibra
