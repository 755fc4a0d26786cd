#include "fibra/solver/problem.hpp"

#include <chrono>

#include "fibra/solver/nodal_load.hpp"

namespace fibra {
namespace {

StencilSet beam_stencils(const Model& model) {
  StencilSet set;
  for (const BeamElement& e : model.elements) {
    const Index n0 = e.first_dof / kNodeDofs;
    const Index g[3] = {n0, n0 + 1, n0 + 2};
    set.add(g);
  }
  set.colorize(model.num_nodes());
  return set;
}

}  // namespace

Problem::Problem(const Model& model)
    : m_model(model),
      m_beams(beam_stencils(model)),
      m_pattern(std::vector<int>(model.num_nodes(), kNodeDofs), {&m_beams}),
      m_fixed(model.num_dofs(), 0),
      m_forces(VecX::Zero(model.num_dofs())) {
  m_diagonal.resize(model.num_dofs());
  for (Index d = 0; d < model.num_dofs(); ++d) m_diagonal[d] = m_pattern.find(d, d);
}

double Problem::evaluate(const VecX& q, VecX* gradient, std::vector<double>* hessian) {
  const auto t0 = std::chrono::steady_clock::now();
  if (gradient) gradient->setZero(q.size());
  if (hessian) hessian->assign(m_pattern.nonzeros(), 0.0);
  AssemblyTarget target{&m_pattern, &m_fixed, gradient, hessian};
  const Model& model = m_model;
  double energy = assemble_set<ElemVec, ElemMat>(
      m_beams, target, gradient != nullptr, hessian != nullptr, m_energy_buffer,
      [&](Index s, ElemVec* g, ElemMat* h) {
        const BeamElement& e = model.elements[s];
        return beam_element_energy(e, model.sections[e.section], q.data() + e.first_dof, g, h);
      });

  // Dead forces: potential -f . (q - q_ref).
  energy -= m_forces.dot(q - model.reference);
  if (gradient) *gradient -= m_forces;
  // Moments on section vectors (conservative about their axis; work from the energy base).
  const VecX& base = m_energy_base.size() == q.size() ? m_energy_base : model.reference;
  for (const NodalMoment& m : m_moments) {
    const Index d = kNodeDofs * m.node;
    energy -= moment_work(m.moment, model.reference.segment<3>(d + 3), model.reference.segment<3>(d + 6),
                          base.segment<3>(d + 3), base.segment<3>(d + 6), q.segment<3>(d + 3), q.segment<3>(d + 6));
    Mat6x6 df;
    const Vec6 f = moment_generalized_force(m.moment, model.reference.segment<3>(d + 3), model.reference.segment<3>(d + 6),
                                            q.segment<3>(d + 3), q.segment<3>(d + 6), hessian ? &df : nullptr);
    if (gradient) gradient->segment<6>(d + 3) -= f;
    if (hessian) {
      Eigen::Matrix<double, 9, 9> h = Eigen::Matrix<double, 9, 9>::Zero();
      h.block<6, 6>(3, 3) = -df;
      const Index grp[1] = {m.node};
      scatter_local<Eigen::Matrix<double, 9, 1>, Eigen::Matrix<double, 9, 9>>(target, grp, nullptr, &h);
    }
  }
  if (hessian) {
    double scale = 0.0;
    Index count = 0;
    for (Index d = 0; d < q.size(); ++d)
      if (!m_fixed[d]) {
        scale += std::abs((*hessian)[m_diagonal[d]]);
        ++count;
      }
    scale = count ? scale / count : 1.0;
    for (Index d = 0; d < q.size(); ++d)
      if (m_fixed[d]) (*hessian)[m_diagonal[d]] = scale;
  }
  m_times.assembly += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ++m_times.evaluations;
  return energy;
}

}  // namespace fibra
