#include "fibra/contact/contact_law.hpp"

namespace fibra {

double PenaltyLaw::potential(double p) const {
  const double k = stiffness, pr = regularization;
  if (p <= 0.0) return 0.0;
  if (p <= pr) return k * p * p * p / (6.0 * pr);
  return k * (0.5 * p * p - 0.5 * pr * p + pr * pr / 6.0);
}

double PenaltyLaw::force(double p) const {
  const double k = stiffness, pr = regularization;
  if (p <= 0.0) return 0.0;
  if (p <= pr) return k * p * p / (2.0 * pr);
  return k * (p - 0.5 * pr);
}

double PenaltyLaw::stiffness_at(double p) const {
  const double k = stiffness, pr = regularization;
  if (p <= 0.0) return 0.0;
  if (p <= pr) return k * p / pr;
  return k;
}

FrictionState friction_return_map(const Vec3& previous, const Vec3& slip_increment, const Vec3& normal,
                                  double normal_force, double mu, double kt) {
  FrictionState s;
  const Mat3 proj = Mat3::Identity() - normal * normal.transpose();
  const Vec3 trial = proj * previous + kt * (proj * slip_increment);
  s.trial_norm = trial.norm();
  const double limit = mu * normal_force;
  if (s.trial_norm <= limit || s.trial_norm == 0.0) {
    s.force = trial;
    s.slip = false;
  } else {
    s.force = (limit / s.trial_norm) * trial;
    s.slip = true;
  }
  return s;
}

}  // namespace fibra
