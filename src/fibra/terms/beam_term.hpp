#pragma once
/// Beam elasticity: the strain energy of every beam element (docs/theory/beam.md), the
/// element kernel on its fixed 3-node stencil summed over the model.
#include <atomic>
#include <vector>

#include "fibra/assembly/energy_term.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// The beam elements' strain energy.
class BeamTerm final : public EnergyTerm {
 public:
  /// The elements of `model` (kept by reference).
  explicit BeamTerm(const Model& model);
  std::string name() const override { return "beam elements"; }
  const StencilSet* stencils() const override { return &m_stencils; }
  double assemble(const VecX& q, const AssemblyTarget& target) override;
  Index num_local() const override { return m_stencils.size(); }
  std::span<const Index> local_groups(Index k) const override { return m_stencils.stencil(k); }
  Eigen::MatrixXd local_hessian(Index k, const VecX& q) const override;
  /// Each element's Hessian projected onto the positive semi-definite matrices where it is
  /// indefinite (a compressed or buckling fiber's geometric stiffness), for projected Newton.
  bool set_projected(bool on) override {
    m_projected = on;
    return true;
  }
  Index take_projections() override { return m_projections.exchange(0); }

 private:
  const Model& m_model;
  StencilSet m_stencils;  // one per element: its 3 nodes
  std::vector<double> m_energy_buffer;
  bool m_projected = false;               // assemble() projects indefinite element Hessians
  std::atomic<Index> m_projections = 0;   // element Hessians projected since take_projections()
};

}  // namespace fibra
