#include "fibra/terms/load_term.hpp"

#include "fibra/assembly/psd_projection.hpp"
#include "fibra/solver/nodal_load.hpp"

namespace fibra {

LoadTerm::LoadTerm(const Model& model) : m_model(model), m_forces(VecX::Zero(model.num_dofs())) {}

double LoadTerm::assemble(const VecX& q, const AssemblyTarget& target) {
  const Model& model = m_model;
  // Dead forces: potential -f . (q - q_ref) (for a body's rotation dofs, the work of a moment
  // over the increment's rotation vector).
  double energy = -m_forces.dot(q - model.reference);
  if (target.gradient) *target.gradient -= m_forces;
  // Moments on section vectors (conservative about their axis; work from the energy base).
  const VecX& base = m_energy_base.size() == q.size() ? m_energy_base : model.reference;
  for (const NodalMoment& m : m_moments) {
    const Index d = kNodeDofs * m.node;
    energy -= moment_work(m.moment, model.reference.segment<3>(d + 3), model.reference.segment<3>(d + 6),
                          base.segment<3>(d + 3), base.segment<3>(d + 6), q.segment<3>(d + 3), q.segment<3>(d + 6));
    Mat6x6 df;
    const Vec6 f = moment_generalized_force(m.moment, model.reference.segment<3>(d + 3), model.reference.segment<3>(d + 6),
                                            q.segment<3>(d + 3), q.segment<3>(d + 6), target.values ? &df : nullptr);
    if (target.gradient) target.gradient->segment<6>(d + 3) -= f;
    if (target.values) {
      Eigen::Matrix<double, 9, 9> h = Eigen::Matrix<double, 9, 9>::Zero();
      h.block<6, 6>(3, 3) = -df;
      if (m_projected && project_psd(h.block<6, 6>(3, 3))) ++m_projections;
      const Index grp[1] = {m.node};
      scatter_local<Eigen::Matrix<double, 9, 1>, Eigen::Matrix<double, 9, 9>>(target, grp, nullptr, &h);
    }
  }
  return energy;
}

Eigen::MatrixXd LoadTerm::local_hessian(Index k, const VecX& q) const {
  const NodalMoment& m = m_moments[k];
  const Index d = kNodeDofs * m.node;
  Mat6x6 df;
  moment_generalized_force(m.moment, m_model.reference.segment<3>(d + 3), m_model.reference.segment<3>(d + 6),
                           q.segment<3>(d + 3), q.segment<3>(d + 6), &df);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(kNodeDofs, kNodeDofs);
  h.block<6, 6>(3, 3) = -df;
  return h;
}

}  // namespace fibra
