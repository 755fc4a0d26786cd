#pragma once
/// What an increment that cannot converge says about the model: the motion that meets the
/// least resistance (the tangent's softest mode), where the failed attempt moved most, and
/// what the user can change. See docs/theory/solver.md, "When an increment cannot converge".
#include <string>

#include "fibra/core/types.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// Where a motion of the whole model (one value per dof) is concentrated, in the user's words:
/// the fiber and its node range (numbered from 0 as a case file's `node`), or the
/// body, and what moves there (centre line along a direction, sections turning or deforming,
/// a body's centre or rotation). `length_scale` weighs the dofs into lengths (1 on positions,
/// the section radius on section vectors). Empty for a zero motion.
std::string describe_motion(const Model& model, const VecX& motion, const VecX& length_scale);

/// The diagnosis of a stalled increment.
struct StallDiagnosis {
  /// What the tangent at the last equilibrium is: indefinite (that equilibrium is unstable:
  /// buckling, a snap or a limit load), singular (a mechanism: nothing resists the softest
  /// mode), positive definite (well posed: Newton failed on the increment's changes), or not
  /// determined (no factorization could be made).
  enum class Tangent { Indefinite, Singular, Definite, Unknown };
  Tangent tangent = Tangent::Unknown;
  /// Whether a stalled increment was diagnosed: a run can fail with every increment converged
  /// (a weave whose tows stay too deep in each other), and then there is nothing to diagnose.
  bool made = false;
  double softest_stiffness = 0;  ///< v.Hv of the unit softest mode (dofs weighed into lengths) [N/m]
  double bending_stiffness = 0;  ///< scale: the softest fiber bent as a whole cantilever, 3 E I / L^3 [N/m]
  std::string softest_mode;      ///< describe_motion of the softest mode
  std::string largest_motion;    ///< describe_motion of the failed attempt's motion
  /// Why the contact loop refused the failed attempt (fibers through each other, loops that did
  /// not settle), or empty when it did not: Newton then failed.
  std::string refusal;
  /// The diagnosis as sentences for the failure report: what moves without resisting, where
  /// the attempt went, and what the user can change; empty when none was made.
  std::string text() const;
  /// "indefinite", "singular", "definite" or "unknown".
  std::string tangent_name() const;
};

}  // namespace fibra
