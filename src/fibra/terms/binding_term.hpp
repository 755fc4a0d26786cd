#pragma once
/// Averaged bindings of fiber nodes and bodies to rigid bodies (METHOD §5), enforced by an
/// augmented Lagrangian whose multipliers are lagged: the energy term of a BodySystem
/// (body/bodies.hpp, docs/theory/bodies.md).
#include "fibra/assembly/energy_term.hpp"
#include "fibra/body/bodies.hpp"

namespace fibra {

/// The bindings of a BodySystem as an energy term.
class BindingTerm final : public EnergyTerm {
 public:
  /// The bindings of `bodies` (kept by reference).
  explicit BindingTerm(BodySystem& bodies) : m_bodies(bodies) {}
  std::string name() const override { return "bindings"; }
  const StencilSet* stencils() const override { return &m_bodies.stencils(); }
  double assemble(const VecX& q, const AssemblyTarget& target) override {
    return m_bodies.evaluate(q, target, target.gradient != nullptr, target.values != nullptr);
  }
  Index num_local() const override { return m_bodies.num_bindings(); }
  std::span<const Index> local_groups(Index k) const override { return m_bodies.stencils().stencil(k); }
  Eigen::MatrixXd local_hessian(Index k, const VecX& q) const override { return m_bodies.local_hessian(k, q); }
  /// The proximal anchors of the bound fiber nodes take q.
  void begin_lagged(const VecX& q) override { m_bodies.set_anchors(q); }
  /// Augmented Lagrangian: the multipliers are updated when a condition is violated by more than
  /// the length tolerance, and the anchors follow the solution when they drifted by more than it
  /// and their springs pull with more than a thousandth of the force left unresolved.
  bool update_lagged(const VecX& q, const LaggedTolerance& tolerance) override;
  /// The bodies' committed frames and rotations and the bindings' multipliers (a snapshot).
  std::unique_ptr<LaggedState> save() const override {
    auto s = std::make_unique<State>();
    s->values = m_bodies.snapshot();
    return s;
  }
  bool restore(const LaggedState& state) override {
    m_bodies.restore(dynamic_cast<const State&>(state).values);
    return false;
  }
  /// The bindings' indefinite local Hessians projected (BodySystem::set_projected).
  bool set_projected(bool on) override {
    m_bodies.set_projected(on);
    return true;
  }
  Index take_projections() override { return m_bodies.take_projections(); }
  /// The bodies' rotations are committed; their rotation dofs start the next increment at zero.
  void commit(VecX& q) override { m_bodies.commit(q); }

 private:
  struct State final : LaggedState {
    std::vector<double> values;
  };
  BodySystem& m_bodies;
};

}  // namespace fibra
