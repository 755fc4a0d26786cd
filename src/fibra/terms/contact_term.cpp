#include "fibra/terms/contact_term.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

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
    const ElementDofs d = dofs(contacts[k]);
    const Index na = d.a / kNodeDofs, nb = d.b / kNodeDofs;
    const Index g[6] = {na, na + 1, na + 2, nb, nb + 1, nb + 2};
    pairs.add(g);
    begin.push_back(static_cast<Index>(k));
  }
  begin.push_back(static_cast<Index>(contacts.size()));
  const bool changed = pairs.groups != m_pairs.groups;
  m_contacts = std::move(contacts);
  m_marked.assign(m_contacts.size(), 0);
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
  std::vector<char> marked;
};

}  // namespace

std::unique_ptr<LaggedState> ContactTerm::save() const {
  auto s = std::make_unique<ContactState>();
  s->contacts = m_contacts;
  s->friction = m_friction;
  s->solution = m_solution;
  s->marked = m_marked;
  return s;
}

bool ContactTerm::restore(const LaggedState& state) {
  const auto& s = dynamic_cast<const ContactState&>(state);
  m_solution = s.solution;
  const bool changed = set_contacts(s.contacts, s.friction);
  m_marked = s.marked;
  return changed;
}

void ContactTerm::commit(VecX& q) {
  if (m_solution.size() != m_contacts.size())
    throw std::logic_error("ContactTerm::commit: no solution recorded for the current contact elements");
  for (size_t k = 0; k < m_contacts.size(); ++k) {
    ContactElement& c = m_contacts[k];
    c.friction_previous = m_solution[k].friction;
    const auto [da, db] = dofs(c);
    c.separation_previous = particle_position(c.b, q.data() + db) - particle_position(c.a, q.data() + da);
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
  if (m_manager) change.turn = m_manager->update_normals(m_contacts, q, &change.idle_turn, &change.slide);
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
          const auto [da, db] = dofs(c);
          e += contact_element_energy(c, q.data() + da, q.data() + db, m_friction, g, h, nullptr, tangent(k), true);
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
    const auto [da, db] = dofs(c);
    contact_element_energy(c, q.data() + da, q.data() + db, m_friction, &g, &h, nullptr, tangent(e));
    sum += h;
  }
  return sum;
}

Index ContactTerm::mark_overshoots(const VecX& q, const VecX& dq) {
  if (m_tangent == ContactTangent::Majorizing) return 0;
  const VecX trial = q + dq;
  Index marked = 0;
  for (size_t k = 0; k < m_contacts.size(); ++k) {
    if (m_marked[k]) continue;
    const ContactElement& c = m_contacts[k];
    const auto [da, db] = dofs(c);
    const StepModel m =
        contact_step_model(c, q.data() + da, q.data() + db, trial.data() + da, trial.data() + db, m_friction);
    if (m.excess() > 0.1 * (std::abs(m.slope) + std::abs(m.change()))) {
      m_marked[k] = 1;
      ++marked;
    }
  }
  return marked;
}

std::string ContactTerm::explain_step(const VecX& q, const VecX& dq) const {
  if (m_contacts.empty()) return {};
  const VecX trial = q + dq;
  struct Surprise {
    size_t element = 0;
    StepModel step;
  };
  std::vector<Surprise> worst;
  double change_n = 0, model_n = 0, change_t = 0, model_t = 0;
  Index closing = 0, to_slip = 0, to_stick = 0, reversed = 0;
  for (size_t k = 0; k < m_contacts.size(); ++k) {
    const ContactElement& c = m_contacts[k];
    const auto [da, db] = dofs(c);
    const StepModel m = contact_step_model(c, q.data() + da, q.data() + db, trial.data() + da, trial.data() + db,
                                           m_friction, tangent(static_cast<Index>(k)));
    change_n += m.normal_change;
    model_n += m.normal_model;
    change_t += m.friction_change;
    model_t += m.friction_model;
    closing += m.start.gap >= 0.0 && m.end.gap < 0.0;
    to_slip += !m.start.slip && m.end.slip;
    to_stick += m.start.slip && !m.end.slip;
    reversed += m.start.friction.dot(m.end.friction) < 0.0;
    worst.push_back({k, m});
  }
  constexpr size_t kShown = 6;
  const auto larger = [](const Surprise& x, const Surprise& y) { return x.step.excess() > y.step.excess(); };
  std::partial_sort(worst.begin(), worst.begin() + static_cast<std::ptrdiff_t>(std::min(kShown, worst.size())),
                    worst.end(), larger);
  std::string out = fmt::format(
      "     normal: change {:.4e} J, model {:.4e} J; friction: change {:.4e} J, model {:.4e} J\n"
      "     of {} elements: {} close from a gap, {} stick to slip, {} slip to stick, {} friction forces reversed\n",
      change_n, model_n, change_t, model_t, m_contacts.size(), closing, to_slip, to_stick, reversed);
  for (size_t i = 0; i < std::min(kShown, worst.size()); ++i) {
    const StepModel& s = worst[i].step;
    const ContactElement& c = m_contacts[worst[i].element];
    out += fmt::format(
        "     element {} (beam elements {}, {}): beyond the model normal {:.3e} J, friction {:.3e} J; gap {:.3e} -> "
        "{:.3e} m (p_r {:.1e}); normal force {:.3e} N (cone {:.3e}); friction {:.3e} N {} -> {:.3e} N {}\n",
        worst[i].element, c.a.element, c.b.element, s.normal_change - s.normal_model,
        s.friction_change - s.friction_model, s.start.gap, s.end.gap, c.law.regularization, s.start.normal_force,
        c.friction_normal, s.start.friction.norm(), s.start.slip ? "slip" : "stick", s.end.friction.norm(),
        s.end.slip ? "slip" : "stick");
  }
  return out;
}

std::vector<ContactResponse> ContactTerm::responses(const VecX& q) const {
  std::vector<ContactResponse> out(m_contacts.size());
  for (size_t k = 0; k < m_contacts.size(); ++k) {
    const ContactElement& c = m_contacts[k];
    const auto [da, db] = dofs(c);
    contact_element_energy(c, q.data() + da, q.data() + db, m_friction, nullptr, nullptr, &out[k]);
  }
  return out;
}

}  // namespace fibra
