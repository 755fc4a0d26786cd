#pragma once
/// Contact and friction: the penalty energy of every contact element and its frozen friction
/// energy (docs/theory/contact.md), kernels on the 6-node stencil of an element pair, summed
/// pair by pair. The elements (normals, laws, friction history) are lagged: they change only
/// between minimizations (set_contacts), and an increment's end commits their friction history
/// from the responses of its solution (set_solution). Around an increment's minimizations the
/// normals and the friction cones' normal forces are iterated to their fixed point
/// (update_fixed_point). The term also bounds a Newton step: no
/// point moves further than the step limit, so that a fiber nothing holds yet does not jump
/// through its neighbours.
#include <stdexcept>
#include <vector>

#include "fibra/assembly/energy_term.hpp"
#include "fibra/contact/contact_element.hpp"
#include "fibra/contact/contact_manager.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// Contact elements and friction between fibers.
class ContactTerm final : public EnergyTerm {
 public:
  /// For the elements of `model` (kept by reference); no contact elements at first.
  explicit ContactTerm(const Model& model) : m_model(model) {}
  std::string name() const override { return "contact pairs"; }
  const StencilSet* stencils() const override { return &m_pairs; }
  double assemble(const VecX& q, const AssemblyTarget& target) override;
  Index num_local() const override { return static_cast<Index>(m_pair_begin.empty() ? 0 : m_pair_begin.size() - 1); }
  std::span<const Index> local_groups(Index k) const override { return m_pairs.stencil(k); }
  /// The sum of the pair's elements' Hessians, friction included.
  Eigen::MatrixXd local_hessian(Index k, const VecX& q) const override;
  /// The elements' Hessian in assemble() and local_hessian(): Exact (the default) or
  /// Majorizing, for every element; with Exact, the elements mark_overshoots() marked still
  /// take Majorizing.
  void set_tangent(ContactTangent tangent) { m_tangent = tangent; }
  /// Marks the elements whose energy rose above their Exact model along dq by more than a tenth
  /// of the sum of the change's and the slope's sizes (contact_step_model): a slip the step
  /// turned back, an open element pushed into penetration. They keep the Majorizing tangent
  /// until the next set_contacts.
  Index mark_overshoots(const VecX& q, const VecX& dq) override;
  /// Per element (same order as contacts()), 1 where mark_overshoots marked it.
  const std::vector<char>& marked() const { return m_marked; }
  /// Puts back what marked() returned for the same elements.
  void set_marked(std::vector<char> marked) {
    if (marked.size() != m_contacts.size()) throw std::logic_error("ContactTerm::set_marked: not one flag per element");
    m_marked = std::move(marked);
  }

  /// Replaces the contact elements (each oriented so that a.element < b.element) and the
  /// friction parameters; true when the element pairs changed (the pattern must be rebuilt).
  bool set_contacts(std::vector<ContactElement> contacts, const FrictionParams& friction);
  const std::vector<ContactElement>& contacts() const { return m_contacts; }  ///< current elements
  std::vector<ContactElement>& contacts() { return m_contacts; }              ///< (normals, laws, history)
  const FrictionParams& friction() const { return m_friction; }               ///< friction parameters
  /// Evaluated state of every contact element at q (same order as contacts()).
  std::vector<ContactResponse> responses(const VecX& q) const;

  /// Records the responses of the elements at the solution of a minimization (same order as
  /// contacts()), from which commit() takes the friction history.
  void set_solution(std::vector<ContactResponse> responses) { m_solution = std::move(responses); }
  /// The responses set_solution recorded.
  const std::vector<ContactResponse>& solution() const { return m_solution; }
  /// No dof d moves more than `max_move` / `length_scale`[d] in a Newton step (0: no bound).
  void set_step_limit(double max_move, VecX length_scale) {
    m_max_move = max_move;
    m_length_scale = std::move(length_scale);
  }

  /// The rule that updates the normals (ContactManager::update_normals; kept by reference):
  /// without one, update_fixed_point leaves them.
  void set_normal_rule(const ContactManager* manager) { m_manager = manager; }
  /// With friction (mu > 0): each element's friction cone takes its normal force at q
  /// (ContactElement::friction_normal, frozen through the next minimizations).
  void begin_fixed_point(const VecX& q) override;
  /// The normals (ContactManager::update_normals), then, with friction, the cones at q; returns
  /// the largest turn with and without force and the cones' largest change relative to the
  /// largest normal force.
  FixedPointChange update_fixed_point(const VecX& q) override;

  /// The elements, the friction parameters and the solution's responses.
  std::unique_ptr<LaggedState> save() const override;
  bool restore(const LaggedState& state) override;
  /// Each element's previous friction force (the solution's) and separation (at q); no element
  /// is fresh any more.
  void commit(VecX& q) override;
  double step_bound(const VecX& q, const VecX& dq) const override;
  /// The normal and friction parts' changes against their models, and the elements whose
  /// change exceeds their model most, with their penetration and stick or slip at both ends.
  std::string explain_step(const VecX& q, const VecX& dq) const override;

 private:
  ContactTangent tangent(Index element) const {
    return m_marked[static_cast<size_t>(element)] ? ContactTangent::Majorizing : m_tangent;
  }
  /// Where the dofs of the element's two beam elements start in a vector of all dofs.
  struct ElementDofs {
    Index a, b;
  };
  ElementDofs dofs(const ContactElement& c) const {
    return {m_model.elements[c.a.element].first_dof, m_model.elements[c.b.element].first_dof};
  }
  /// Each cone's normal force at q; returns the largest change relative to the largest force.
  double freeze_cones(const VecX& q);
  const Model& m_model;
  const ContactManager* m_manager = nullptr;
  StencilSet m_pairs;               // one stencil per element pair in contact (6 nodes)
  std::vector<Index> m_pair_begin;  // contacts of pair s: [m_pair_begin[s], m_pair_begin[s+1])
  std::vector<ContactElement> m_contacts;
  FrictionParams m_friction;
  std::vector<ContactResponse> m_solution;  // responses at the last minimization's solution
  ContactTangent m_tangent = ContactTangent::Exact;
  std::vector<char> m_marked;  // per element: Majorizing (mark_overshoots)
  double m_max_move = 0;                    // step limit [m]; 0 = none
  VecX m_length_scale;                      // per dof: length of a unit of the dof [m]
  std::vector<double> m_energy_buffer;
};

}  // namespace fibra
