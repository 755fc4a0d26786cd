#pragma once
/// External work: dead nodal forces (and a body's moments, through its rotation dofs) and
/// moments on nodes' section vectors, conservative about their fixed axes (nodal_load.hpp,
/// docs/theory/beam.md). Its energy is minus the work from the reference state; a moment's
/// work is measured from an energy base near the state (whole turns are not counted).
#include <utility>
#include <vector>

#include "fibra/assembly/energy_term.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// A moment on a node's section vectors (see nodal_load.hpp).
struct NodalMoment {
  Index node = 0;
  Vec3 moment = Vec3::Zero();  ///< [N m]
};

/// The loads' potential.
class LoadTerm final : public EnergyTerm {
 public:
  /// Loads on `model`'s dofs (kept by reference); none at first.
  explicit LoadTerm(const Model& model);
  std::string name() const override { return "external work"; }
  double assemble(const VecX& q, const AssemblyTarget& target) override;
  Index num_local() const override { return static_cast<Index>(m_moments.size()); }
  std::span<const Index> local_groups(Index k) const override { return {&m_moments[k].node, 1}; }
  /// The Hessian of moment k's potential on its node (9 x 9; dead forces have none).
  Eigen::MatrixXd local_hessian(Index k, const VecX& q) const override;
  /// Each moment's Hessian projected onto the positive semi-definite matrices where it is
  /// indefinite, for projected Newton.
  bool set_projected(bool on) override {
    m_projected = on;
    return !m_moments.empty();
  }
  Index take_projections() override { return std::exchange(m_projections, 0); }

  VecX& forces() { return m_forces; }                          ///< dead forces per dof [N]
  std::vector<NodalMoment>& moments() { return m_moments; }    ///< nodal moments
  /// Sets the state from which moment work is measured (moment potentials are defined up to
  /// whole turns, so energies are compared near this state).
  void set_energy_base(const VecX& q) { m_energy_base = q; }

 private:
  const Model& m_model;
  VecX m_forces;
  std::vector<NodalMoment> m_moments;
  VecX m_energy_base;
  bool m_projected = false;  // assemble() projects indefinite moment Hessians
  Index m_projections = 0;   // moment Hessians projected since take_projections()
};

}  // namespace fibra
