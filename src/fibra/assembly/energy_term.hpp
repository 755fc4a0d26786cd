#pragma once
/// One term of the total potential that each increment minimizes (beam elasticity, contact
/// and friction, averaged bindings, the proximal drag, the external work): its energy, its
/// gradient and Hessian added into a global assembly, its local Hessians, and the hooks by
/// which the solver handles its lagged state (saved, put back, committed) and its bound on a
/// Newton step. `Problem` (solver/problem.hpp) is the sum of its terms; the solver knows no
/// term by its physics.
#include <Eigen/Core>
#include <memory>
#include <span>
#include <string>

#include "fibra/assembly/assembler.hpp"
#include "fibra/assembly/block_pattern.hpp"

namespace fibra {

/// What a term holds fixed through a minimization and changes only between minimizations or at
/// an increment's end (contact elements with their normals, penalties and friction history; the
/// bindings' multipliers and the bodies' committed frames): saved before an increment, put back
/// when it fails. Each term defines its own.
class LaggedState {
 public:
  virtual ~LaggedState() = default;
};

/// What a term's lagged state is settled against after a minimization (EnergyTerm::update_lagged).
struct LaggedTolerance {
  double length = 0;  ///< a condition's violation, a lagged anchor's drift [m]
  double force = 0;   ///< the force the minimization leaves unresolved (its tolerance times the reference force) [N]
};

/// How far an update of a term's fixed-point quantities moved them (EnergyTerm::update_fixed_point).
struct FixedPointChange {
  double turn = 0;       ///< largest turn of a lagged direction that carries force (a contact normal) [rad]
  double idle_turn = 0;  ///< largest turn of one that carries none [rad]
  double relative = 0;   ///< largest change of a lagged force, relative to the largest such force (a friction cone's normal force)
  double slide = 0;      ///< largest distance across its normal between a loaded pair's particles, relative to their radii' sum
};

/// An energy term on the model's dofs (9 per node, then 6 per rigid body).
class EnergyTerm {
 public:
  virtual ~EnergyTerm() = default;
  /// What the term is, in diagnostics: "beam elements", "contact pairs", ...
  virtual std::string name() const = 0;
  /// The stencils whose matrix blocks the term fills, for the sparsity pattern; null for a
  /// term that fills only blocks within single groups (always in the pattern).
  virtual const StencilSet* stencils() const { return nullptr; }
  /// Called after the sparsity pattern is rebuilt (terms that keep positions of values in it).
  virtual void pattern_changed(const BlockPattern& pattern) { (void)pattern; }
  /// Energy at q [J]; adds the gradient on every dof into `target.gradient` and the Hessian's
  /// free-free upper values into `target.values` when they are not null.
  virtual double assemble(const VecX& q, const AssemblyTarget& target) = 0;
  /// Number of local Hessians: the term's kernels on their fixed stencils.
  virtual Index num_local() const { return 0; }
  /// Groups of local Hessian k, in the order of its rows.
  virtual std::span<const Index> local_groups(Index k) const {
    (void)k;
    return {};
  }
  /// Local Hessian k at q (rows and columns over local_groups(k), every dof of them).
  virtual Eigen::MatrixXd local_hessian(Index k, const VecX& q) const {
    (void)k;
    (void)q;
    return {};
  }

  /// Starts an increment's minimizations at q (a lagged anchor takes q).
  virtual void begin_lagged(const VecX& q) { (void)q; }
  /// After a minimization converged at q: updates the lagged quantities the term finds
  /// unsettled against `tolerance` (multipliers, anchors); true when all were settled and
  /// nothing changed, false when the minimization must be run again.
  virtual bool update_lagged(const VecX& q, const LaggedTolerance& tolerance) {
    (void)q;
    (void)tolerance;
    return true;
  }
  /// Lagged quantities iterated to their fixed point around an increment's minimizations (the
  /// contact's normals between section centres and its frozen friction cones): begin_fixed_point
  /// takes them from q when the term's elements are new (a detection pass), update_fixed_point
  /// after a minimization converged at q (update_lagged settled), returning how far they moved.
  virtual void begin_fixed_point(const VecX& q) { (void)q; }
  virtual FixedPointChange update_fixed_point(const VecX& q) {
    (void)q;
    return {};
  }
  /// The term's lagged state, to be put back by restore(); null for a term without one.
  virtual std::unique_ptr<LaggedState> save() const { return nullptr; }
  /// Puts back a state that save() returned; true when the term's stencils changed with it (the
  /// sparsity pattern must then be rebuilt).
  virtual bool restore(const LaggedState& state) {
    (void)state;
    return false;
  }
  /// Ends a converged increment at q: the term's history takes q's values (friction's previous
  /// force, a body's committed rotation). A term whose dofs hold increments of its history
  /// rewrites them in q (a body's rotation dofs start the next increment at zero).
  virtual void commit(VecX& q) { (void)q; }
  /// Whether assemble() adds the term's local Hessians projected onto the positive semi-definite
  /// matrices where they are indefinite (the exact ones otherwise, as the derivative checks
  /// compare them); false for a term that has no projection.
  virtual bool set_projected(bool on) {
    (void)on;
    return false;
  }
  /// Local Hessians assemble() projected since the last call (the count is reset).
  virtual Index take_projections() { return 0; }
  /// The largest fraction in (0, 1] of the Newton correction dq from q that the term allows
  /// (1: no bound).
  virtual double step_bound(const VecX& q, const VecX& dq) const {
    (void)q;
    (void)dq;
    return 1.0;
  }
  /// A Newton step dq from q that the line search shortened: the term gives the parts whose
  /// quadratic model fell below their energy along dq a tangent that lies above it, until its
  /// stencils change; returns how many parts it marked (0 for a term without such parts).
  virtual Index mark_overshoots(const VecX& q, const VecX& dq) {
    (void)q;
    (void)dq;
    return 0;
  }
  /// Developers' diagnostic of a Newton step dq from q that the line search shortened: what in
  /// the term the quadratic model misses, beyond its total (Problem::step_energies); empty for
  /// a term with nothing to add.
  virtual std::string explain_step(const VecX& q, const VecX& dq) const {
    (void)q;
    (void)dq;
    return {};
  }
};

}  // namespace fibra
