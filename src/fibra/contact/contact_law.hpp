#pragma once
/// Normal contact and friction laws (METHOD §3).
///
/// Normal: penalty with a quadratic start. With stiffness k [N/m] and regularization depth
/// p_r [m], the normal force for penetration p is 0 (p <= 0), k p^2 / (2 p_r) (0 < p <= p_r),
/// k (p - p_r/2) beyond; f and df/dp are continuous. It derives from the potential phi(p).
/// Friction: Coulomb with an elastic slip delta: k_t = mu f_n / delta, trial
/// f_t = f_t,prev + k_t du_t, projected on the cone |f_t| <= mu f_n (return mapping).
#include "fibra/core/types.hpp"

namespace fibra {

/// The regularized penalty law of one contact element.
struct PenaltyLaw {
  double stiffness = 0;       ///< k [N/m]
  double regularization = 0;  ///< p_r [m]
  double potential(double p) const;  ///< phi(p) [J]
  double force(double p) const;      ///< f = phi'(p) [N]
  double stiffness_at(double p) const;  ///< df/dp [N/m]
};

/// Result of the friction return mapping.
struct FrictionState {
  Vec3 force = Vec3::Zero();  ///< tangential force on particle j (opposite on i) [N]
  bool slip = false;          ///< on the Coulomb cone
  double trial_norm = 0;      ///< |trial force| [N]
};

/// Return mapping: previous tangential force `previous` (projected on the plane normal to
/// `normal`), tangential relative displacement `slip_increment` over the increment, normal
/// force `normal_force`, coefficient `mu`, tangential stiffness `kt` = mu f_n / delta.
FrictionState friction_return_map(const Vec3& previous, const Vec3& slip_increment, const Vec3& normal,
                                  double normal_force, double mu, double kt);

}  // namespace fibra
