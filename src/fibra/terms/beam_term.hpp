#pragma once
/// Beam elasticity: the strain energy of every beam element (docs/theory/beam.md), the
/// element kernel on its fixed 3-node stencil summed over the model.
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

 private:
  const Model& m_model;
  StencilSet m_stencils;  // one per element: its 3 nodes
  std::vector<double> m_energy_buffer;
};

}  // namespace fibra
