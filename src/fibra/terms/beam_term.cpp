#include "fibra/terms/beam_term.hpp"

#include "fibra/assembly/psd_projection.hpp"
#include "fibra/beam/beam_element.hpp"

namespace fibra {

BeamTerm::BeamTerm(const Model& model) : m_model(model) {
  for (const BeamElement& e : model.elements) {
    const Index n0 = e.first_dof / kNodeDofs;
    const Index g[3] = {n0, n0 + 1, n0 + 2};
    m_stencils.add(g);
  }
  m_stencils.colorize(model.num_nodes());
}

double BeamTerm::assemble(const VecX& q, const AssemblyTarget& target) {
  const Model& model = m_model;
  return assemble_set<ElemVec, ElemMat>(m_stencils, target, target.gradient != nullptr, target.values != nullptr,
                                        m_energy_buffer, [&](Index s, ElemVec* g, ElemMat* h) {
                                          const BeamElement& e = model.elements[s];
                                          const double energy = beam_element_energy(
                                              e, model.sections[e.section], q.data() + e.first_dof, g, h);
                                          if (h && m_projected && project_psd(*h)) ++m_projections;
                                          return energy;
                                        });
}

Eigen::MatrixXd BeamTerm::local_hessian(Index k, const VecX& q) const {
  const BeamElement& e = m_model.elements[k];
  ElemVec g;
  ElemMat h;
  beam_element_energy(e, m_model.sections[e.section], q.data() + e.first_dof, &g, &h);
  return h;
}

}  // namespace fibra
