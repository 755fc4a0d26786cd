#pragma once
/// The discrete problem at one load level: total potential Pi(q) = W_beams(q) - loads, its
/// gradient (f_int - f_ext) and Hessian, with eliminated (fixed or prescribed) dofs.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "fibra/assembly/assembler.hpp"
#include "fibra/assembly/block_pattern.hpp"
#include "fibra/assembly/energy_term.hpp"
#include "fibra/body/bodies.hpp"
#include "fibra/contact/contact_element.hpp"
#include "fibra/model/model.hpp"
#include "fibra/terms/beam_term.hpp"
#include "fibra/terms/binding_term.hpp"
#include "fibra/terms/contact_term.hpp"
#include "fibra/terms/drag_term.hpp"
#include "fibra/terms/load_term.hpp"

namespace fibra {

/// The lagged state of each term of a Problem (EnergyTerm::save), in the order of its terms.
struct LaggedStates {
  std::vector<std::unique_ptr<LaggedState>> terms;
};

/// Accumulated wall times of the assembly [s].
struct AssemblyTimes {
  double assembly = 0;  ///< element and load evaluation + scatter
  int evaluations = 0;  ///< calls to evaluate()
};

/// The total potential of the model: the sum of its energy terms (beam elasticity, contact
/// and friction, bindings, drag, external work; assembly/energy_term.hpp), assembled.
class Problem {
 public:
  /// Builds stencils, colouring and the sparsity pattern of `model` (kept by reference) and
  /// of the bindings of `bodies` (optional, kept by reference).
  explicit Problem(const Model& model, BodySystem* bodies = nullptr);

  const Model& model() const { return m_model; }                 ///< the model
  const BlockPattern& pattern() const { return m_pattern; }      ///< matrix sparsity
  std::vector<char>& fixed() { return m_fixed; }                 ///< per dof: 1 = eliminated
  const std::vector<char>& fixed() const { return m_fixed; }     ///< per dof: 1 = eliminated
  VecX& forces() { return m_loads.forces(); }                    ///< dead nodal forces (per dof) [N]
  std::vector<NodalMoment>& moments() { return m_loads.moments(); }  ///< nodal moments
  const AssemblyTimes& times() const { return m_times; }         ///< accumulated timings
  BodySystem* bodies() const { return m_bodies; }                ///< rigid bodies and bindings (or null)
  /// The energy terms, in the order they are summed.
  const std::vector<EnergyTerm*>& terms() const { return m_terms; }

  /// Replaces the contact elements (each is oriented so that a.element < b.element) and the
  /// friction parameters; returns true when the matrix pattern changed (new element pairs),
  /// after which the linear solver's analysis must be redone.
  bool set_contacts(std::vector<ContactElement> contacts, const FrictionParams& friction);
  const std::vector<ContactElement>& contacts() const { return m_contact.contacts(); }  ///< current contact elements
  std::vector<ContactElement>& contacts() { return m_contact.contacts(); }              ///< (normals, laws, history)
  /// Evaluated state of every contact element at q (same order as contacts()).
  std::vector<ContactResponse> contact_responses(const VecX& q) const { return m_contact.responses(q); }
  /// Records the contact elements' responses at a minimization's solution (ContactTerm::set_solution).
  void set_contact_solution(std::vector<ContactResponse> r) { m_contact.set_solution(std::move(r)); }
  /// The responses set_contact_solution recorded.
  const std::vector<ContactResponse>& contact_solution() const { return m_contact.solution(); }
  /// Bounds a Newton step: no dof d moves more than `max_move` / `length_scale`[d] (ContactTerm).
  void set_step_limit(double max_move, VecX length_scale) { m_contact.set_step_limit(max_move, std::move(length_scale)); }

  /// Starts an increment's minimizations at q: every term's begin_lagged.
  void begin_lagged(const VecX& q);
  /// After a minimization converged at q, every term updates its unsettled lagged quantities
  /// (EnergyTerm::update_lagged); true when every term was settled.
  bool update_lagged(const VecX& q, const LaggedTolerance& tolerance);
  /// A detection pass's new elements: every term takes its fixed-point quantities from q
  /// (EnergyTerm::begin_fixed_point).
  void begin_fixed_point(const VecX& q);
  /// After the minimizations of a pass converged at q: every term updates its fixed-point
  /// quantities (EnergyTerm::update_fixed_point); the largest change of each kind.
  FixedPointChange update_fixed_point(const VecX& q);
  /// Every term's EnergyTerm::mark_overshoots for a step dq from q; the parts marked.
  Index mark_overshoots(const VecX& q, const VecX& dq) {
    Index marked = 0;
    for (EnergyTerm* t : m_terms) marked += t->mark_overshoots(q, dq);
    return marked;
  }
  /// The contact elements marked for the tangent above their energy, and to put them back
  /// (ContactTerm::marked, set_marked).
  const std::vector<char>& marked_contacts() const { return m_contact.marked(); }
  void set_marked_contacts(std::vector<char> marked) { m_contact.set_marked(std::move(marked)); }
  /// The contact elements' Hessian (ContactTerm::set_tangent).
  void set_contact_tangent(ContactTangent tangent) { m_contact.set_tangent(tangent); }
  /// The rule the contact term updates its normals with (ContactTerm::set_normal_rule).
  void set_normal_rule(const ContactManager* manager) { m_contact.set_normal_rule(manager); }
  /// Every term's lagged state (EnergyTerm::save).
  LaggedStates save_lagged() const;
  /// Puts back what save_lagged() returned; true when the sparsity pattern changed with it (the
  /// linear solver's analysis must then be redone).
  bool restore_lagged(const LaggedStates& states);
  /// Ends a converged increment at q: every term commits its history (EnergyTerm::commit).
  void commit(VecX& q);
  /// The largest fraction in (0, 1] of the Newton correction dq from q that every term allows.
  double step_bound(const VecX& q, const VecX& dq) const;

  /// Drag (weave, relax and test steps), DragTerm::set: c = 0 removes it.
  void set_drag(double c, const VecX& anchor, double director_weight = 1.0, double axial_weight = 1.0,
                double position_weight = 1.0) {
    m_drag.set(c, anchor, director_weight, axial_weight, position_weight);
  }
  /// Norm of the drag's force at q, each dof's component multiplied by `scale` (e.g. 1/r on
  /// section vectors, making their generalized forces forces) over the dofs of `part`; 0 without
  /// drag.
  double drag_force_norm(const VecX& q, const VecX& scale, DragPart part = DragPart::All) const {
    return m_drag.force_norm(q, scale, part);
  }
  /// The drag's stiffness alone (DragTerm::set_stiffness): 0 takes it off, its former value puts it back.
  void set_drag_stiffness(double c) { m_drag.set_stiffness(c); }
  double drag() const { return m_drag.stiffness(); }            ///< drag stiffness per node [N/m]
  /// The drag whole, to put back with set_drag(const DragSettings&).
  DragSettings drag_settings() const { return m_drag.settings(); }
  void set_drag(const DragSettings& s) { m_drag.set(s); }
  const FrictionParams& friction() const { return m_contact.friction(); }   ///< set_contacts' friction
  /// P u for node `node`'s position (the drag's force per unit stiffness, see DragTerm::set).
  Vec3 drag_projected(Index node, const Vec3& u) const { return m_drag.projected(node, u); }
  /// Sets the state from which moment work is measured in evaluate()'s energy (moment
  /// potentials are only defined up to whole turns, so energies are compared near this state).
  void set_energy_base(const VecX& q) { m_loads.set_energy_base(q); }
  /// Developers' diagnostic of an indefinite tangent: for each term, its local Hessians at q
  /// whose smallest eigenvalue is negative (beyond rounding), the worst with its group. A sum
  /// of positive semi-definite local matrices is positive semi-definite: the terms listed are
  /// where negative curvature comes from.
  std::string local_spectra(const VecX& q) const;
  /// Developers' diagnostic of a step the line search shortened: for each term, its energy's
  /// change from q to q + dq against its quadratic model at q (g . dq + dq . H dq / 2, the
  /// exact local Hessians). A term whose change exceeds its model is what the Newton step
  /// overshoots on.
  std::string step_energies(const VecX& q, const VecX& dq);
  /// Total potential energy at q; fills the gradient of Pi on every dof (f_int - f_ext) and
  /// the Hessian values (free-free block; eliminated dofs get a unit-scaled diagonal).
  double evaluate(const VecX& q, VecX* gradient, std::vector<double>* hessian);
  /// Assembles the Hessian at q into `hessian` with the local Hessians of the terms that have a
  /// projection (EnergyTerm::set_projected) projected where they are indefinite; returns how
  /// many were, 0 (and `hessian` left as it is) when no term has a projection.
  Index projected_hessian(const VecX& q, std::vector<double>& hessian);

 private:
  void build_pattern();
  /// The terms' assembly target into `gradient` and `hessian` (either may be null), with the
  /// groups that hold a fixed dof marked afresh.
  AssemblyTarget target(VecX* gradient, std::vector<double>* hessian);
  const Model& m_model;
  BodySystem* m_bodies = nullptr;
  BeamTerm m_beams;
  ContactTerm m_contact;
  std::unique_ptr<BindingTerm> m_bindings;  // null without bodies
  DragTerm m_drag;
  LoadTerm m_loads;
  std::vector<EnergyTerm*> m_terms;  // summed in this order
  BlockPattern m_pattern;
  std::vector<char> m_fixed;
  std::vector<char> m_group_fixed;  // per group (node or body): some dof fixed (scatter fast path otherwise)
  std::vector<Index> m_diagonal;    // value index of each diagonal entry
  AssemblyTimes m_times;
};

}  // namespace fibra
