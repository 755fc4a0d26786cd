#include "fibra/beam/beam_element.hpp"

#include <cmath>

namespace fibra {
namespace {

// Generalized dot products d_k = v_i . v_j; vectors 0 x0', 1 g1, 2 g2, 3 g1', 4 g2'.
constexpr int kPairs[kGenStrains][2] = {{1, 1}, {2, 2}, {1, 2}, {1, 0}, {1, 3}, {1, 4}, {2, 0}, {2, 3},
                                        {2, 4}, {0, 0}, {0, 3}, {0, 4}, {3, 3}, {3, 4}, {4, 4}};

// Which vector a node field feeds and whether through N (0) or N' (1):
// field 0 (x0) -> x0' (N'); field 1 (g1) -> g1 (N), g1' (N'); field 2 (g2) -> g2 (N), g2' (N').
struct Feed {
  int count;
  int vec[2];
  int deriv[2];
};
constexpr Feed kFeeds[3] = {{1, {0, 0}, {1, 0}}, {2, {1, 3}, {0, 1}}, {2, {2, 4}, {0, 1}}};

const double kGaussEta[kBeamGauss] = {-0.57735026918962576, 0.57735026918962576};
// In-section dot products (g1.g1, g2.g2, g1.g2) of node a.
Eigen::Vector3d nodal_section(const double* q, int a) {
  const Eigen::Map<const Vec3> g1(q + 9 * a + 3), g2(q + 9 * a + 6);
  return {g1.dot(g1), g2.dot(g2), g1.dot(g2)};
}

// Hourglass energy of the in-section strains; adds gradient and upper Hessian blocks.
double hourglass_energy(const BeamElement& element, const Section& section, const double* q, ElemVec* grad,
                        ElemMat* hess) {
  const SectionHourglass& hg = element.hourglass;
  constexpr double m[3] = {0.5, -1.0, 0.5};
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int a = 0; a < 3; ++a) c += m[a] * (nodal_section(q, a) - hg.reference.col(a));
  const Eigen::Vector3d sigma = hg.weight * (section.stiffness_inplane * c);
  const double energy = 0.5 * c.dot(sigma);
  if (!grad && !hess) return energy;
  Eigen::Matrix<double, 3, 6> jac[3];
  for (int a = 0; a < 3; ++a) {
    const Eigen::Map<const Vec3> g1(q + 9 * a + 3), g2(q + 9 * a + 6);
    if (grad) {
      grad->segment<3>(9 * a + 3) += m[a] * (2.0 * sigma[0] * g1 + sigma[2] * g2);
      grad->segment<3>(9 * a + 6) += m[a] * (2.0 * sigma[1] * g2 + sigma[2] * g1);
    }
    jac[a].setZero();
    jac[a].block<1, 3>(0, 0) = 2.0 * g1.transpose();
    jac[a].block<1, 3>(1, 3) = 2.0 * g2.transpose();
    jac[a].block<1, 3>(2, 0) = g2.transpose();
    jac[a].block<1, 3>(2, 3) = g1.transpose();
  }
  if (!hess) return energy;
  const Eigen::Matrix3d k = hg.weight * section.stiffness_inplane;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Matrix<double, 3, 6> kj = k * jac[a];
    for (int b = 0; b <= a; ++b) hess->block<6, 6>(9 * b + 3, 9 * a + 3) += (m[a] * m[b]) * jac[b].transpose() * kj;
    auto h = hess->block<6, 6>(9 * a + 3, 9 * a + 3);
    h.block<3, 3>(0, 0).diagonal().array() += m[a] * 2.0 * sigma[0];
    h.block<3, 3>(3, 3).diagonal().array() += m[a] * 2.0 * sigma[1];
    h.block<3, 3>(0, 3).diagonal().array() += m[a] * sigma[2];
    h.block<3, 3>(3, 0).diagonal().array() += m[a] * sigma[2];
  }
  return energy;
}

}  // namespace

void beam_shape(double eta, double n[3], double dn[3]) {
  n[0] = 0.5 * eta * (eta - 1.0);
  n[1] = 1.0 - eta * eta;
  n[2] = 0.5 * eta * (eta + 1.0);
  dn[0] = eta - 0.5;
  dn[1] = -2.0 * eta;
  dn[2] = eta + 0.5;
}

double beam_gauss_point(int gp) { return kGaussEta[gp]; }

AxisVectors beam_axis_vectors(const double* q, double eta, double inv_jac) {
  double n[3], dn[3];
  beam_shape(eta, n, dn);
  AxisVectors v = AxisVectors::Zero();
  for (int a = 0; a < 3; ++a) {
    const Eigen::Map<const Vec3> x0(q + 9 * a), g1(q + 9 * a + 3), g2(q + 9 * a + 6);
    const double d = dn[a] * inv_jac;
    v.col(0) += d * x0;
    v.col(1) += n[a] * g1;
    v.col(2) += n[a] * g2;
    v.col(3) += d * g1;
    v.col(4) += d * g2;
  }
  return v;
}

GenVec beam_dot_products(const AxisVectors& v) {
  GenVec d;
  for (int k = 0; k < kGenStrains; ++k) d[k] = v.col(kPairs[k][0]).dot(v.col(kPairs[k][1]));
  return d;
}

void beam_reference(const double* q_ref, BeamElement& element) {
  for (int gp = 0; gp < kBeamGauss; ++gp) {
    BeamGauss& g = element.gauss[gp];
    const AxisVectors raw = beam_axis_vectors(q_ref, kGaussEta[gp], 1.0);
    const double jac = raw.col(0).norm();
    g.weight = jac;  // Gauss weights are 1 for the 2-point rule
    g.inv_jac = 1.0 / jac;
    g.reference = beam_dot_products(beam_axis_vectors(q_ref, kGaussEta[gp], g.inv_jac));
  }
  double jac_sum = 0.0;
  for (int gp = 0; gp < kBeamGauss; ++gp) jac_sum += element.gauss[gp].weight;
  element.hourglass.weight = (8.0 / 45.0) * 0.5 * jac_sum;
  for (int a = 0; a < 3; ++a) element.hourglass.reference.col(a) = nodal_section(q_ref, a);
}

GenVec beam_generalized_strains(const BeamElement& element, const double* q, int gp) {
  const BeamGauss& g = element.gauss[gp];
  return beam_dot_products(beam_axis_vectors(q, kGaussEta[gp], g.inv_jac)) - g.reference;
}

double beam_element_energy(const BeamElement& element, const Section& section, const double* q,
                           ElemVec* grad, ElemMat* hess) {
  double energy = 0.0;
  if (grad) grad->setZero();
  if (hess) hess->setZero();
  for (int gp = 0; gp < kBeamGauss; ++gp) {
    const BeamGauss& g = element.gauss[gp];
    double n[3], dn[3];
    beam_shape(kGaussEta[gp], n, dn);
    const AxisVectors v = beam_axis_vectors(q, kGaussEta[gp], g.inv_jac);
    const GenVec e = beam_dot_products(v) - g.reference;
    const GenVec sigma = g.weight * (section.stiffness * e);
    energy += 0.5 * e.dot(sigma);
    if (!grad && !hess) continue;

    // Shape factor of node a for vector m (0 when node a does not feed vector m).
    double shape[5][3];
    for (int a = 0; a < 3; ++a) {
      const double d = dn[a] * g.inv_jac;
      shape[0][a] = d;
      shape[1][a] = n[a];
      shape[2][a] = n[a];
      shape[3][a] = d;
      shape[4][a] = d;
    }

    // Gradient with respect to the five vectors (3 x 5).
    AxisVectors gv = AxisVectors::Zero();
    for (int k = 0; k < kGenStrains; ++k) {
      const int i = kPairs[k][0], j = kPairs[k][1];
      gv.col(i) += sigma[k] * v.col(j);
      gv.col(j) += sigma[k] * v.col(i);
    }
    if (grad) {
      for (int a = 0; a < 3; ++a)
        for (int f = 0; f < 3; ++f) {
          Vec3 acc = Vec3::Zero();
          for (int t = 0; t < kFeeds[f].count; ++t) acc += shape[kFeeds[f].vec[t]][a] * gv.col(kFeeds[f].vec[t]);
          grad->segment<3>(9 * a + 3 * f) += acc;
        }
    }
    if (!hess) continue;

    // Hessian with respect to the five vectors (15 x 15): material part J^T (wC) J plus the
    // geometric part sum_k sigma_k d2(d_k).
    Eigen::Matrix<double, kGenStrains, kGenStrains> jac = Eigen::Matrix<double, kGenStrains, kGenStrains>::Zero();
    for (int k = 0; k < kGenStrains; ++k) {
      const int i = kPairs[k][0], j = kPairs[k][1];
      jac.block<1, 3>(k, 3 * i) += v.col(j).transpose();
      jac.block<1, 3>(k, 3 * j) += v.col(i).transpose();
    }
    const Eigen::Matrix<double, kGenStrains, kGenStrains> cj = g.weight * (section.stiffness * jac);
    Eigen::Matrix<double, kGenStrains, kGenStrains> hv = jac.transpose() * cj;
    for (int k = 0; k < kGenStrains; ++k) {
      const int i = kPairs[k][0], j = kPairs[k][1];
      for (int c = 0; c < 3; ++c) {
        hv(3 * i + c, 3 * j + c) += sigma[k];
        hv(3 * j + c, 3 * i + c) += sigma[k];
      }
    }
    // Scatter to element dofs: block (a,f),(b,h) += sum over feeds of shape * shape * hv block.
    for (int a = 0; a < 3; ++a)
      for (int f = 0; f < 3; ++f) {
        const int row = 9 * a + 3 * f;
        for (int b = 0; b < 3; ++b)
          for (int h = 0; h < 3; ++h) {
            const int col = 9 * b + 3 * h;
            if (col < row) continue;
            Mat3 acc = Mat3::Zero();
            for (int t = 0; t < kFeeds[f].count; ++t) {
              const int m = kFeeds[f].vec[t];
              const double sa = shape[m][a];
              for (int u = 0; u < kFeeds[h].count; ++u) {
                const int p = kFeeds[h].vec[u];
                acc += (sa * shape[p][b]) * hv.block<3, 3>(3 * m, 3 * p);
              }
            }
            hess->block<3, 3>(row, col) += acc;
          }
      }
  }
  energy += hourglass_energy(element, section, q, grad, hess);
  if (hess)
    for (int c = 0; c < kElementDofs; ++c)
      for (int r = c + 1; r < kElementDofs; ++r) (*hess)(r, c) = (*hess)(c, r);
  return energy;
}

}  // namespace fibra

namespace fibra {

AxialState beam_axial_state(const BeamElement& element, const Section& section, const double* q, double eta) {
  // Reference data at eta: interpolate the Gauss-point references linearly in eta (they are
  // smooth along the element); the jacobian likewise.
  const double t = (eta - beam_gauss_point(0)) / (beam_gauss_point(1) - beam_gauss_point(0));
  const double inv_jac = (1 - t) * element.gauss[0].inv_jac + t * element.gauss[1].inv_jac;
  const GenVec ref = (1 - t) * element.gauss[0].reference + t * element.gauss[1].reference;
  const AxisVectors v = beam_axis_vectors(q, eta, inv_jac);
  const GenVec e = beam_dot_products(v) - ref;
  const GenVec sigma = section.stiffness * e;
  AxialState s;
  const double stretch = v.col(0).norm() / std::sqrt(std::max(ref[9], 1e-300));
  s.strain = stretch - 1.0;
  s.force = 2.0 * sigma[9] * stretch;
  return s;
}

}  // namespace fibra
