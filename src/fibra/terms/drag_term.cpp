#include "fibra/terms/drag_term.hpp"

#include <algorithm>

namespace fibra {

DragTerm::DragTerm(const Model& model, const BodySystem* bodies) : m_model(model), m_bodies(bodies) {
  m_node_r2.assign(model.num_nodes(), 0.0);
  for (const Fiber& f : model.fibers)
    for (Index k = 0; k < f.num_nodes; ++k)
      m_node_r2[f.first_node + k] = model.sections[f.section].a * model.sections[f.section].b;
}

void DragTerm::pattern_changed(const BlockPattern& pattern) {
  m_diagonal.resize(m_model.num_dofs());
  for (Index d = 0; d < m_model.num_dofs(); ++d) m_diagonal[d] = pattern.find(d, d);
  m_position_offdiagonal.resize(m_model.num_nodes());
  for (Index n = 0; n < m_model.num_nodes(); ++n) {
    const Index d = kNodeDofs * n;
    m_position_offdiagonal[n] = {pattern.find(d, d + 1), pattern.find(d, d + 2), pattern.find(d + 1, d + 2)};
  }
}

void DragTerm::set(double c, const VecX& anchor, double director_weight, double axial_weight, double position_weight) {
  m_c = c;
  m_position = position_weight;
  m_anchor = anchor;
  m_director = director_weight;
  m_axial = axial_weight;
  if (axial_weight == 1.0 || c <= 0.0) return;
  // Unit tangent at each node from its neighbours along the fiber (one-sided at the ends).
  m_axis.resize(m_model.num_nodes());
  for (const Fiber& f : m_model.fibers)
    for (Index k = 0; k < f.num_nodes; ++k) {
      const Index a = f.first_node + std::max<Index>(k - 1, 0), b = f.first_node + std::min(k + 1, f.num_nodes - 1);
      const Vec3 t = anchor.segment<3>(kNodeDofs * b) - anchor.segment<3>(kNodeDofs * a);
      const double len = t.norm();
      m_axis[f.first_node + k] = len > 0.0 ? Vec3(t / len) : Vec3::Zero();
    }
}

double DragTerm::assemble(const VecX& q, const AssemblyTarget& target) {
  if (m_c <= 0.0) return 0.0;
  return energy(q, target.gradient, target.values, target.fixed);
}

double DragTerm::force_norm(const VecX& q, const VecX& scale, DragPart part) const {
  if (m_c <= 0.0) return 0.0;
  VecX g = VecX::Zero(q.size());
  energy(q, &g, nullptr, nullptr);
  if (part == DragPart::Positions)
    for (Index n = 0; n < m_model.num_nodes(); ++n) g.segment<kNodeDofs - 3>(kNodeDofs * n + 3).setZero();
  if (part == DragPart::Sections) {
    for (Index n = 0; n < m_model.num_nodes(); ++n) g.segment<3>(kNodeDofs * n).setZero();
    g.tail(q.size() - m_model.node_dofs).setZero();
  }
  return scale.cwiseProduct(g).norm();
}

double DragTerm::energy(const VecX& q, VecX* gradient, std::vector<double>* hessian, const std::vector<char>* fixed_dofs) const {
  const Model& model = m_model;
  double energy = 0.0;
  const bool axial = m_axial != 1.0;
  const double cp = m_c * m_position;  // positions and bodies
  auto fixed = [&](Index d) { return fixed_dofs && (*fixed_dofs)[d]; };
  for (Index n = 0; n < model.num_nodes(); ++n) {
    const Index base = kNodeDofs * n;
    // Position: c/2 u^T P u, P = I - (1 - w_axial) t t^T.
    const Vec3 u = q.segment<3>(base) - m_anchor.segment<3>(base);
    const Vec3 pu = projected(n, u);
    energy += 0.5 * cp * u.dot(pu);
    if (gradient) gradient->segment<3>(base) += cp * pu;
    if (hessian) {
      Mat3 p = Mat3::Identity();
      if (axial) p -= (1.0 - m_axial) * m_axis[n] * m_axis[n].transpose();
      for (int i = 0; i < 3; ++i)
        if (!fixed(base + i)) (*hessian)[m_diagonal[base + i]] += cp * p(i, i);
      if (axial) {  // the upper off-diagonal entries (x,y), (x,z), (y,z)
        const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
        for (int k = 0; k < 3; ++k) {
          const int i = pairs[k][0], j = pairs[k][1];
          if (!fixed(base + i) && !fixed(base + j)) (*hessian)[m_position_offdiagonal[n][k]] += cp * p(i, j);
        }
      }
    }
    for (int d = 3; d < kNodeDofs; ++d) {
      const Index dof = base + d;
      const double c = m_c * m_director * m_node_r2[n];
      const double ud = q[dof] - m_anchor[dof];
      energy += 0.5 * c * ud * ud;
      if (gradient) (*gradient)[dof] += c * ud;
      if (hessian && !fixed(dof)) (*hessian)[m_diagonal[dof]] += c;
    }
  }
  // Bodies too (their rotations scaled by their size).
  for (Index b = 0; m_bodies && b < m_bodies->num_bodies(); ++b)
    for (int d = 0; d < 6; ++d) {
      const Index dof = model.bodies[b].first_dof + d;
      const double c = d < 3 ? cp : cp * m_bodies->size(b) * m_bodies->size(b);
      const double u = q[dof] - m_anchor[dof];
      energy += 0.5 * c * u * u;
      if (gradient) (*gradient)[dof] += c * u;
      if (hessian && !fixed(dof)) (*hessian)[m_diagonal[dof]] += c;
    }
  return energy;
}

}  // namespace fibra
