#include "fibra/terms/contact_term.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fibra {

bool ContactTerm::set_contacts(std::vector<ContactElement> contacts, const FrictionParams& friction) {
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
  const bool changed = pairs.groups != m_pairs.groups;
  m_contacts = std::move(contacts);
  m_pair_begin = std::move(begin);
  if (changed) {
    pairs.colorize(m_model.num_nodes());
    m_pairs = std::move(pairs);
  }
  return changed;
}

namespace {

struct ContactState final : LaggedState {
  std::vector<ContactElement> contacts;
  FrictionParams friction;
  std::vector<ContactResponse> solution;
};

}  // namespace

std::unique_ptr<LaggedState> ContactTerm::save() const {
  auto s = std::make_unique<ContactState>();
  s->contacts = m_contacts;
  s->friction = m_friction;
  s->solution = m_solution;
  return s;
}

bool ContactTerm::restore(const LaggedState& state) {
  const auto& s = dynamic_cast<const ContactState&>(state);
  m_solution = s.solution;
  return set_contacts(s.contacts, s.friction);
}

void ContactTerm::commit(VecX& q) {
  if (m_solution.size() != m_contacts.size())
    throw std::logic_error("ContactTerm::commit: no solution recorded for the current contact elements");
  for (size_t k = 0; k < m_contacts.size(); ++k) {
    ContactElement& c = m_contacts[k];
    c.friction_previous = m_solution[k].friction;
    c.separation_previous = particle_position(c.b, q.data() + m_model.elements[c.b.element].first_dof) -
                            particle_position(c.a, q.data() + m_model.elements[c.a.element].first_dof);
    c.fresh = false;
  }
}

double ContactTerm::freeze_cones(const VecX& q) {
  double change = 0.0, largest = 0.0;
  const std::vector<ContactResponse> now = responses(q);
  for (size_t e = 0; e < m_contacts.size(); ++e) {
    const double before = std::max(0.0, m_contacts[e].friction_normal);
    change = std::max(change, std::abs(now[e].normal_force - before));
    largest = std::max(largest, now[e].normal_force);
    m_contacts[e].friction_normal = now[e].normal_force;
  }
  return largest > 0.0 ? change / largest : 0.0;
}

void ContactTerm::begin_fixed_point(const VecX& q) {
  if (m_friction.mu > 0.0) freeze_cones(q);
}

FixedPointChange ContactTerm::update_fixed_point(const VecX& q) {
  FixedPointChange change;
  if (m_manager) change.turn = m_manager->update_normals(m_contacts, q, &change.idle_turn);
  if (m_friction.mu > 0.0) change.relative = freeze_cones(q);
  return change;
}

double ContactTerm::step_bound(const VecX& q, const VecX& dq) const {
  (void)q;
  if (!(m_max_move > 0.0)) return 1.0;
  double largest = 0.0;
  for (Index d = 0; d < dq.size(); ++d) largest = std::max(largest, std::abs(dq[d]) * m_length_scale[d]);
  return largest > m_max_move ? m_max_move / largest : 1.0;
}

double ContactTerm::assemble(const VecX& q, const AssemblyTarget& target) {
  if (m_contacts.empty()) return 0.0;
  const Model& model = m_model;
  return assemble_set<ContactVec, ContactMat>(
      m_pairs, target, target.gradient != nullptr, target.values != nullptr, m_energy_buffer,
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

Eigen::MatrixXd ContactTerm::local_hessian(Index k, const VecX& q) const {
  ContactMat sum = ContactMat::Zero(), h;
  ContactVec g;
  for (Index e = m_pair_begin[k]; e < m_pair_begin[k + 1]; ++e) {
    const ContactElement& c = m_contacts[e];
    contact_element_energy(c, q.data() + m_model.elements[c.a.element].first_dof,
                           q.data() + m_model.elements[c.b.element].first_dof, m_friction, &g, &h, nullptr);
    sum += h;
  }
  return sum;
}

std::vector<ContactResponse> ContactTerm::responses(const VecX& q) const {
  std::vector<ContactResponse> out(m_contacts.size());
  for (size_t k = 0; k < m_contacts.size(); ++k) {
    const ContactElement& c = m_contacts[k];
    contact_element_energy(c, q.data() + m_model.elements[c.a.element].first_dof,
                           q.data() + m_model.elements[c.b.element].first_dof, m_friction, nullptr, nullptr, &out[k]);
  }
  return out;
}

}  // namespace fibra
