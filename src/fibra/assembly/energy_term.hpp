#pragma once
/// One term of the total potential that each increment minimizes (beam elasticity, contact
/// and friction, averaged bindings, the proximal drag, the external work): its energy, its
/// gradient and Hessian added into a global assembly, and its local Hessians. `Problem`
/// (solver/problem.hpp) is the sum of its terms; the solver knows no term by its physics.
#include <Eigen/Core>
#include <span>
#include <string>

#include "fibra/assembly/assembler.hpp"
#include "fibra/assembly/block_pattern.hpp"

namespace fibra {

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
};

}  // namespace fibra
