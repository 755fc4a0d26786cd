#include "fibra/solver/problem.hpp"

#include <algorithm>
#include <chrono>
#include <string>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

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

Problem::Problem(const Model& model, BodySystem* bodies)
    : m_model(model),
      m_bodies(bodies),
      m_beams(beam_stencils(model)),
      m_pattern(model.group_sizes(), {}),
      m_fixed(model.num_dofs(), 0),
      m_forces(VecX::Zero(model.num_dofs())) {
  build_pattern();
  m_node_r2.assign(model.num_nodes(), 0.0);
  for (const Fiber& f : model.fibers)
    for (Index k = 0; k < f.num_nodes; ++k)
      m_node_r2[f.first_node + k] = model.sections[f.section].a * model.sections[f.section].b;
}

void Problem::build_pattern() {
  std::vector<const StencilSet*> sets = {&m_beams, &m_contact_pairs};
  if (m_bodies) sets.push_back(&m_bodies->stencils());
  m_pattern = BlockPattern(m_model.group_sizes(), sets);
  m_diagonal.resize(m_model.num_dofs());
  for (Index d = 0; d < m_model.num_dofs(); ++d) m_diagonal[d] = m_pattern.find(d, d);
  m_position_offdiagonal.resize(m_model.num_nodes());
  for (Index n = 0; n < m_model.num_nodes(); ++n) {
    const Index d = kNodeDofs * n;
    m_position_offdiagonal[n] = {m_pattern.find(d, d + 1), m_pattern.find(d, d + 2), m_pattern.find(d + 1, d + 2)};
  }
}

void Problem::set_drag(double c, const VecX& anchor, double director_weight, double axial_weight) {
  m_drag = c;
  m_drag_anchor = anchor;
  m_drag_director = director_weight;
  m_drag_axial = axial_weight;
  if (axial_weight == 1.0 || c <= 0.0) return;
  // Unit tangent at each node from its neighbours along the fiber (one-sided at the ends).
  m_drag_axis.resize(m_model.num_nodes());
  for (const Fiber& f : m_model.fibers)
    for (Index k = 0; k < f.num_nodes; ++k) {
      const Index a = f.first_node + std::max<Index>(k - 1, 0), b = f.first_node + std::min(k + 1, f.num_nodes - 1);
      const Vec3 t = anchor.segment<3>(kNodeDofs * b) - anchor.segment<3>(kNodeDofs * a);
      const double len = t.norm();
      m_drag_axis[f.first_node + k] = len > 0.0 ? Vec3(t / len) : Vec3::Zero();
    }
}

bool Problem::set_contacts(std::vector<ContactElement> contacts, const FrictionParams& friction) {
  m_friction = friction;
  for (ContactElement& c : contacts)
    if (c.a.element > c.b.element) {
      std::swap(c.a, c.b);
      c.normal = -c.normal;
      c.friction_previous = -c.friction_previous;
      c.separation_previous = -c.separation_previous;
    }
  std::stable_sort(contacts.begin(), contacts.end(), [](const ContactElement& x, const ContactElement& y) {
    return std::pair(x.a.element, x.b.element) < std::pair(y.a.element, y.b.element);
  });
  StencilSet pairs;
  std::vector<Index> begin;
  for (size_t k = 0; k < contacts.size(); ++k) {
    if (k > 0 && contacts[k].a.element == contacts[k - 1].a.element && contacts[k].b.element == contacts[k - 1].b.element)
      continue;
    const Index na = m_model.elements[contacts[k].a.element].first_dof / kNodeDofs;
    const Index nb = m_model.elements[contacts[k].b.element].first_dof / kNodeDofs;
    const Index g[6] = {na, na + 1, na + 2, nb, nb + 1, nb + 2};
    pairs.add(g);
    begin.push_back(static_cast<Index>(k));
  }
  begin.push_back(static_cast<Index>(contacts.size()));
  const bool changed = pairs.groups != m_contact_pairs.groups;
  m_contacts = std::move(contacts);
  m_pair_begin = std::move(begin);
  if (changed) {
    pairs.colorize(m_model.num_nodes());
    m_contact_pairs = std::move(pairs);
    build_pattern();
  }
  return changed;
}

std::vector<ContactResponse> Problem::contact_responses(const VecX& q) const {
  std::vector<ContactResponse> out(m_contacts.size());
  for (size_t k = 0; k < m_contacts.size(); ++k) {
    const ContactElement& c = m_contacts[k];
    contact_element_energy(c, q.data() + m_model.elements[c.a.element].first_dof,
                           q.data() + m_model.elements[c.b.element].first_dof, m_friction, nullptr, nullptr, &out[k]);
  }
  return out;
}

double Problem::drag_energy(const VecX& q, VecX* gradient, std::vector<double>* hessian) const {
  const Model& model = m_model;
  double energy = 0.0;
  const bool axial = m_drag_axial != 1.0;
  for (Index n = 0; n < model.num_nodes(); ++n) {
    const Index base = kNodeDofs * n;
    // Position: c/2 u^T P u, P = I - (1 - w_axial) t t^T.
    const Vec3 u = q.segment<3>(base) - m_drag_anchor.segment<3>(base);
    const Vec3 pu = drag_projected(n, u);
    energy += 0.5 * m_drag * u.dot(pu);
    if (gradient) gradient->segment<3>(base) += m_drag * pu;
    if (hessian) {
      Mat3 p = Mat3::Identity();
      if (axial) p -= (1.0 - m_drag_axial) * m_drag_axis[n] * m_drag_axis[n].transpose();
      for (int i = 0; i < 3; ++i)
        if (!m_fixed[base + i]) (*hessian)[m_diagonal[base + i]] += m_drag * p(i, i);
      if (axial) {  // the upper off-diagonal entries (x,y), (x,z), (y,z)
        const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
        for (int k = 0; k < 3; ++k) {
          const int i = pairs[k][0], j = pairs[k][1];
          if (!m_fixed[base + i] && !m_fixed[base + j]) (*hessian)[m_position_offdiagonal[n][k]] += m_drag * p(i, j);
        }
      }
    }
    for (int d = 3; d < kNodeDofs; ++d) {
      const Index dof = base + d;
      const double c = m_drag * m_drag_director * m_node_r2[n];
      const double ud = q[dof] - m_drag_anchor[dof];
      energy += 0.5 * c * ud * ud;
      if (gradient) (*gradient)[dof] += c * ud;
      if (hessian && !m_fixed[dof]) (*hessian)[m_diagonal[dof]] += c;
    }
  }
  // Bodies too (their rotations scaled by their size).
  for (Index b = 0; m_bodies && b < m_bodies->num_bodies(); ++b)
    for (int d = 0; d < 6; ++d) {
      const Index dof = model.bodies[b].first_dof + d;
      const double c = d < 3 ? m_drag : m_drag * m_bodies->size(b) * m_bodies->size(b);
      const double u = q[dof] - m_drag_anchor[dof];
      energy += 0.5 * c * u * u;
      if (gradient) (*gradient)[dof] += c * u;
      if (hessian && !m_fixed[dof]) (*hessian)[m_diagonal[dof]] += c;
    }
  return energy;
}

double Problem::drag_force_norm(const VecX& q, const VecX& scale) const {
  if (m_drag <= 0.0) return 0.0;
  VecX g = VecX::Zero(q.size());
  drag_energy(q, &g, nullptr);
  return scale.cwiseProduct(g).norm();
}

double Problem::evaluate(const VecX& q, VecX* gradient, std::vector<double>* hessian) {
  const auto t0 = std::chrono::steady_clock::now();
  if (gradient) gradient->setZero(q.size());
  if (hessian) hessian->assign(m_pattern.nonzeros(), 0.0);
  m_group_fixed.assign(m_model.num_groups(), 0);
  for (Index d = 0; d < q.size(); ++d)
    if (m_fixed[d]) m_group_fixed[m_pattern.group_of_dof(d)] = 1;
  AssemblyTarget target{&m_pattern, &m_fixed, &m_group_fixed, gradient, hessian};
  const Model& model = m_model;
  double energy = assemble_set<ElemVec, ElemMat>(
      m_beams, target, gradient != nullptr, hessian != nullptr, m_energy_buffer,
      [&](Index s, ElemVec* g, ElemMat* h) {
        const BeamElement& e = model.elements[s];
        return beam_element_energy(e, model.sections[e.section], q.data() + e.first_dof, g, h);
      });

  if (!m_contacts.empty()) {
    energy += assemble_set<ContactVec, ContactMat>(
        m_contact_pairs, target, gradient != nullptr, hessian != nullptr, m_contact_energy_buffer,
        [&](Index s, ContactVec* g, ContactMat* h, bool& scatter) {
          // Element a < element b, so the stencil's groups ascend and the scatter reads only
          // upper blocks: the kernel accumulates just those.
          double e = 0.0;
          if (g) g->setZero();
          if (h) h->setZero();
          for (Index k = m_pair_begin[s]; k < m_pair_begin[s + 1]; ++k) {
            const ContactElement& c = m_contacts[k];
            e += contact_element_energy(c, q.data() + model.elements[c.a.element].first_dof,
                                        q.data() + model.elements[c.b.element].first_dof, m_friction, g, h, nullptr,
                                        false, true);
          }
          // Pairs within the detection distance that do not touch (and carry no friction) add
          // nothing: most of them in a tow, where every neighbour is a candidate.
          scatter = (g && !g->isZero(0.0)) || (h && !h->isZero(0.0));
          return e;
        });
  }

  // Averaged bindings of rigid bodies (augmented Lagrangian), sequential.
  if (m_bodies) energy += m_bodies->evaluate(q, target, gradient != nullptr, hessian != nullptr);

  // Drag towards the anchor (weave, relax and test steps).
  if (m_drag > 0.0) energy += drag_energy(q, gradient, hessian);

  // Dead forces: potential -f . (q - q_ref) (for a body's rotation dofs, the work of a moment
  // over the increment's rotation vector).
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

namespace fibra {

namespace {

// Smallest eigenvalue of a symmetric matrix relative to its largest magnitude, and the
// position of the eigenvector's largest component.
struct LocalSpectrum {
  double min = 0, relative = 0;
  Index at = 0;
};

// Of the rows and columns `keep` of h only (the free dofs).
LocalSpectrum local_spectrum(const Eigen::MatrixXd& full, const std::vector<Index>& keep) {
  LocalSpectrum s;
  Eigen::MatrixXd h(keep.size(), keep.size());
  for (size_t i = 0; i < keep.size(); ++i)
    for (size_t j = 0; j < keep.size(); ++j) h(i, j) = full(keep[i], keep[j]);
  if (h.rows() == 0 || h.isZero(0.0)) return s;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(h);
  const VecX& v = eig.eigenvalues();
  const double scale = std::max(std::abs(v[0]), std::abs(v[v.size() - 1]));
  s.min = v[0];
  s.relative = v[0] / scale;
  eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&s.at);
  s.at = keep[s.at];
  return s;
}

}  // namespace

std::string Problem::local_spectra(const VecX& q) const {
  // Negative beyond rounding: below -1e-10 of the local matrix's largest eigenvalue.
  constexpr double kRounding = -1e-10;
  // The free local dofs of a stencil (its groups' dofs in order, eliminated ones left out).
  std::vector<Index> keep;
  auto free_dofs = [&](std::span<const Index> groups) -> const std::vector<Index>& {
    keep.clear();
    Index local = 0;
    for (Index g : groups)
      for (int i = 0; i < m_pattern.group_size(g); ++i, ++local)
        if (!m_fixed[m_pattern.group_dof(g) + i]) keep.push_back(local);
    return keep;
  };
  std::string out;
  // One kind of local matrix: `spectrum(s)` of each of its `count` stencils in `set`.
  auto survey = [&](const char* what, const StencilSet& set, Index count, auto&& spectrum) {
    Index negative = 0, worst_index = 0;
    LocalSpectrum worst;
    for (Index s = 0; s < count; ++s) {
      const LocalSpectrum ls = spectrum(s);
      if (ls.relative >= kRounding) continue;
      ++negative;
      if (ls.min < worst.min) worst = ls, worst_index = s;
    }
    out += fmt::format("  {}: {} of {} local Hessians indefinite", what, negative, count);
    if (negative > 0) {
      // The local dof of the eigenvector's largest component, as a group and a component.
      Index group = 0, local = worst.at;
      for (Index g : set.stencil(worst_index)) {
        group = g;
        if (local < m_pattern.group_size(g)) break;
        local -= m_pattern.group_size(g);
      }
      out += fmt::format("; most negative {:.3e} ({:.2e} of its largest) in #{} at group {} component {}",
                         worst.min, worst.relative, worst_index, group, local);
    }
    out += "\n";
  };
  ElemVec ge;
  ElemMat he;
  survey("beam elements", m_beams, static_cast<Index>(m_model.elements.size()), [&](Index s) {
    const BeamElement& e = m_model.elements[s];
    beam_element_energy(e, m_model.sections[e.section], q.data() + e.first_dof, &ge, &he);
    return local_spectrum(he, free_dofs(m_beams.stencil(s)));
  });
  for (const bool with_friction : {false, true}) {
    const FrictionParams friction = with_friction ? m_friction : FrictionParams{};
    ContactVec gc;
    ContactMat hc;
    survey(with_friction ? "contact pairs, normal and friction" : "contact pairs, normal only", m_contact_pairs,
           m_contact_pairs.size(), [&](Index s) {
             ContactMat sum = ContactMat::Zero();
             for (Index k = m_pair_begin[s]; k < m_pair_begin[s + 1]; ++k) {
               const ContactElement& c = m_contacts[k];
               contact_element_energy(c, q.data() + m_model.elements[c.a.element].first_dof,
                                      q.data() + m_model.elements[c.b.element].first_dof, friction, &gc, &hc, nullptr);
               sum += hc;
             }
             return local_spectrum(sum, free_dofs(m_contact_pairs.stencil(s)));
           });
  }
  if (m_bodies)
    survey("bindings", m_bodies->stencils(), m_bodies->num_bindings(), [&](Index k) {
      return local_spectrum(m_bodies->local_hessian(k, q), free_dofs(m_bodies->stencils().stencil(k)));
    });
  return out;
}

}  // namespace fibra
