#include "fibra/contact/contact_element.hpp"

#include "fibra/beam/beam_element.hpp"

namespace fibra {

Vec3 particle_position(const Particle& p, const double* q) {
  double n[3], dn[3];
  beam_shape(p.eta, n, dn);
  Vec3 x = Vec3::Zero();
  for (int a = 0; a < 3; ++a) {
    const Eigen::Map<const Vec3> x0(q + 9 * a), g1(q + 9 * a + 3), g2(q + 9 * a + 6);
    x += n[a] * (x0 + p.xi1 * g1 + p.xi2 * g2);
  }
  return x;
}

namespace {

/// The friction part of an element at separation d = x_B - x_A with normal force fn.
struct FrictionPart {
  double energy = 0;
  FrictionState state;
  double kt = 0;       // stick stiffness mu f_n / delta (0: no friction)
  double fn_cone = 0;  // the normal force that sets the cone
};

FrictionPart friction_part(const ContactElement& c, const Vec3& d, double fn, const FrictionParams& friction) {
  // Friction: return mapping on the tangential relative displacement since the last
  // converged state; the spring's energy f_prev . du + kt/2 |du|^2 (stick) makes the
  // stick response a gradient; slip uses the cone-projected force.
  FrictionPart f;
  const Vec3& nrm = c.normal;
  const Mat3 proj = Mat3::Identity() - nrm * nrm.transpose();
  const Vec3 du = proj * (d - c.separation_previous);
  f.fn_cone = c.friction_normal >= 0.0 ? c.friction_normal : fn;
  // Frozen, the spring acts even on an element that opens during the solve (the energy stays a
  // C1 convex function of the slip); the next freeze, at zero force, removes it.
  if (friction.mu > 0.0 && f.fn_cone > 0.0) {
    f.kt = friction.mu * f.fn_cone / friction.elastic_slip;
    f.state = friction_return_map(c.friction_previous, d - c.separation_previous, nrm, f.fn_cone, friction.mu, f.kt);
    // Potential of the return mapping (frozen cone, limit L = mu f_n): with the trial force
    // f_tr = P f_prev + kt du, (|f_tr|^2 - |P f_prev|^2) / (2 kt) in stick and
    // (L^2 - |P f_prev|^2 + 2 L (|f_tr| - L)) / (2 kt) on the cone: C1 across the cone's edge, and its
    // gradient is the returned force (f_prev included, unlike f . du).
    const Vec3 fprev = proj * c.friction_previous;
    const double limit = friction.mu * f.fn_cone;
    const double fp = fprev.norm();
    f.energy = f.state.slip ? ((limit - fp) * (limit + fp) + 2.0 * limit * (f.state.trial_norm - limit)) / (2.0 * f.kt)
                            : fprev.dot(du) + 0.5 * f.kt * du.squaredNorm();
  }
  return f;
}

}  // namespace

double contact_element_energy(const ContactElement& c, const double* q_a, const double* q_b,
                              const FrictionParams& friction, ContactVec* grad, ContactMat* hess,
                              ContactResponse* response, ContactTangent tangent, bool accumulate) {
  const Vec3 d = particle_position(c.b, q_b) - particle_position(c.a, q_a);
  const Vec3& nrm = c.normal;
  const double gap = d.dot(nrm) + c.offset;
  const double p = -gap;
  const double fn = c.law.force(p);
  double energy = c.law.potential(p);

  const Mat3 proj = Mat3::Identity() - nrm * nrm.transpose();
  const bool frozen = c.friction_normal >= 0.0;
  const FrictionPart part = friction_part(c, d, fn, friction);
  const FrictionState& fr = part.state;
  const double kt = part.kt, fn_cone = part.fn_cone;
  const Vec3 du = proj * (d - c.separation_previous);
  energy += part.energy;
  if (response) {
    response->gap = gap;
    response->normal_force = fn;
    response->friction = fr.force;
    response->slip = fr.slip;
  }
  if (!grad && !hess) return energy;

  // d = x_B - x_A = (c^T (x) I3) [q_A; q_B] with c the 18 coefficients N_a, N_a xi1, N_a xi2
  // of both particles (negative for A): gradient c (x) f_d, Hessian (c c^T) (x) K3.
  Eigen::Matrix<double, 18, 1> coef;
  double na[3], nb[3], dn[3];
  beam_shape(c.a.eta, na, dn);
  beam_shape(c.b.eta, nb, dn);
  for (int a = 0; a < 3; ++a) {
    coef[3 * a] = -na[a];
    coef[3 * a + 1] = -na[a] * c.a.xi1;
    coef[3 * a + 2] = -na[a] * c.a.xi2;
    coef[9 + 3 * a] = nb[a];
    coef[9 + 3 * a + 1] = nb[a] * c.b.xi1;
    coef[9 + 3 * a + 2] = nb[a] * c.b.xi2;
  }
  // Force on d: -fn N (normal, pushes B away from A) + friction force.
  const Vec3 force_d = -fn * nrm + fr.force;
  if (grad) {
    if (accumulate)
      for (int m = 0; m < 18; ++m) grad->segment<3>(3 * m) += coef[m] * force_d;
    else
      for (int m = 0; m < 18; ++m) grad->segment<3>(3 * m) = coef[m] * force_d;
  }
  if (hess) {
    // Majorizing: the law's curvature is at most k (beyond the quadratic start), so the
    // quadratic of curvature k through the energy and force at p lies above the potential.
    const double kn = tangent == ContactTangent::Majorizing ? c.law.stiffness : c.law.stiffness_at(p);
    Mat3 k3 = kn * (nrm * nrm.transpose());
    if (kt > 0.0) {
      const Vec3 t = fr.force.normalized();
      if (!fr.slip) {
        if (tangent != ContactTangent::Consistent) k3 += kt * proj;
      } else if (tangent == ContactTangent::Exact) {
        // kt held fixed: in slip only the turning of the force with the trial direction (exact
        // when the cone is frozen).
        k3 += (kt * friction.mu * fn_cone / fr.trial_norm) * (proj - t * t.transpose());
      } else if (tangent == ContactTangent::Majorizing) {
        // The energy on the cone is L |T| / kt + const, T linear in the slip: a function of
        // s = |T|^2 that is concave (C1 through the stick disc, where it is s / (2 kt)), so
        // its tangent in s, a quadratic in T of curvature L / (kt |T|), lies above it.
        k3 += (kt * friction.mu * fn_cone / fr.trial_norm) * proj;
      }
      if (tangent == ContactTangent::Consistent) {
        // Exact: kt = mu fn / delta depends on the gap, d fn / d d = -fn' N (not when frozen).
        const Vec3 dfn = frozen ? Vec3::Zero() : Vec3(-c.law.stiffness_at(p) * nrm);
        const Mat3 dtrial = kt * proj + (friction.mu / friction.elastic_slip) * du * dfn.transpose();
        if (!fr.slip) {
          k3 += dtrial;
        } else {
          k3 += friction.mu * t * dfn.transpose() +
                (friction.mu * fn_cone / fr.trial_norm) * (Mat3::Identity() - t * t.transpose()) * dtrial;
        }
      }
    }
    if (accumulate) {
      for (int n = 0; n < 18; ++n)
        for (int m = 0; m <= n; ++m) hess->block<3, 3>(3 * m, 3 * n) += (coef[m] * coef[n]) * k3;
    } else {
      for (int n = 0; n < 18; ++n)
        for (int m = 0; m < 18; ++m) hess->block<3, 3>(3 * m, 3 * n) = (coef[m] * coef[n]) * k3;
    }
  }
  return energy;
}

StepModel contact_step_model(const ContactElement& c, const double* q_a, const double* q_b, const double* t_a,
                             const double* t_b, const FrictionParams& friction) {
  const Vec3 d0 = particle_position(c.b, q_b) - particle_position(c.a, q_a);
  const Vec3 d1 = particle_position(c.b, t_b) - particle_position(c.a, t_a);
  const double p0 = -(d0.dot(c.normal) + c.offset), p1 = -(d1.dot(c.normal) + c.offset);
  const FrictionPart f0 = friction_part(c, d0, c.law.force(p0), friction);
  const FrictionPart f1 = friction_part(c, d1, c.law.force(p1), friction);
  const Vec3 step = d1 - d0;
  // The Exact tangent's model: the law's stiffness along the normal; k_t P in stick,
  // k_t L / |T| (P - t t^T) on the cone.
  const double dp = p1 - p0;
  double curvature = c.law.stiffness_at(p0) * dp * dp;
  if (f0.kt > 0.0) {
    const Vec3 across = step - step.dot(c.normal) * c.normal;
    if (!f0.state.slip) {
      curvature += f0.kt * across.squaredNorm();
    } else {
      const double along = across.dot(f0.state.force.normalized());
      curvature += f0.kt * friction.mu * f0.fn_cone / f0.state.trial_norm * (across.squaredNorm() - along * along);
    }
  }
  StepModel m;
  m.change = (c.law.potential(p1) - c.law.potential(p0)) + (f1.energy - f0.energy);
  m.slope = c.law.force(p0) * dp + f0.state.force.dot(step);
  m.excess = m.change - (m.slope + 0.5 * curvature);
  return m;
}

}  // namespace fibra
