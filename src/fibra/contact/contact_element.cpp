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
  Mat3 proj;           // onto the tangent plane, I - N N^T
  Vec3 du;             // the tangential slip since the last converged state
};

FrictionPart friction_part(const ContactElement& c, const Vec3& d, double fn, const FrictionParams& friction) {
  // Friction: return mapping on the tangential relative displacement since the last
  // converged state; the spring's energy f_prev . du + kt/2 |du|^2 (stick) makes the
  // stick response a gradient; slip uses the cone-projected force.
  FrictionPart f;
  const Vec3& nrm = c.normal;
  f.proj = Mat3::Identity() - nrm * nrm.transpose();
  f.du = f.proj * (d - c.separation_previous);
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
    const Vec3 fprev = f.proj * c.friction_previous;
    const double limit = friction.mu * f.fn_cone;
    const double fp = fprev.norm();
    f.energy = f.state.slip ? ((limit - fp) * (limit + fp) + 2.0 * limit * (f.state.trial_norm - limit)) / (2.0 * f.kt)
                            : fprev.dot(f.du) + 0.5 * f.kt * f.du.squaredNorm();
  }
  return f;
}

/// The `tangent`'s second derivative of the element's energy with respect to the separation
/// d = x_B - x_A at penetration p: the normal law's curvature along N and the friction part's
/// 3 x 3 block (non-symmetric for Consistent).
struct SeparationStiffness {
  double normal = 0;
  Mat3 friction = Mat3::Zero();
};

SeparationStiffness separation_stiffness(const ContactElement& c, double p, const FrictionPart& part,
                                         const FrictionParams& friction, ContactTangent tangent) {
  SeparationStiffness k;
  // Majorizing: the law's curvature is at most k (beyond the quadratic start), so the
  // quadratic of curvature k through the energy and force at p lies above the potential.
  k.normal = tangent == ContactTangent::Majorizing ? c.law.stiffness : c.law.stiffness_at(p);
  const double kt = part.kt;
  if (kt <= 0.0) return k;
  const FrictionState& fr = part.state;
  const Mat3& proj = part.proj;
  const Vec3 t = fr.force.normalized();
  // On the cone, the curvature across the trial force's direction.
  const double across = fr.slip ? kt * friction.mu * part.fn_cone / fr.trial_norm : 0.0;
  if (!fr.slip) {
    if (tangent != ContactTangent::Consistent) k.friction = kt * proj;
  } else if (tangent == ContactTangent::Exact) {
    // kt held fixed: in slip only the turning of the force with the trial direction (exact
    // when the cone is frozen).
    k.friction = across * (proj - t * t.transpose());
  } else if (tangent == ContactTangent::Majorizing) {
    // The energy on the cone is L |T| / kt + const, T linear in the slip: a function of
    // s = |T|^2 that is concave (C1 through the stick disc, where it is s / (2 kt)), so
    // its tangent in s, a quadratic in T of curvature L / (kt |T|), lies above it.
    k.friction = across * proj;
  }
  if (tangent == ContactTangent::Consistent) {
    // Exact: kt = mu fn / delta depends on the gap, d fn / d d = -fn' N (not when frozen).
    const bool frozen = c.friction_normal >= 0.0;
    const Vec3 dfn = frozen ? Vec3::Zero() : Vec3(-c.law.stiffness_at(p) * c.normal);
    const Mat3 dtrial = kt * proj + (friction.mu / friction.elastic_slip) * part.du * dfn.transpose();
    if (!fr.slip) {
      k.friction = dtrial;
    } else {
      k.friction = friction.mu * t * dfn.transpose() +
                   (friction.mu * part.fn_cone / fr.trial_norm) * (Mat3::Identity() - t * t.transpose()) * dtrial;
    }
  }
  return k;
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

  const FrictionPart part = friction_part(c, d, fn, friction);
  const FrictionState& fr = part.state;
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
    const SeparationStiffness k = separation_stiffness(c, p, part, friction, tangent);
    const Mat3 k3 = k.normal * (nrm * nrm.transpose()) + k.friction;
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
                             const double* t_b, const FrictionParams& friction, ContactTangent tangent) {
  const Vec3 d0 = particle_position(c.b, q_b) - particle_position(c.a, q_a);
  const Vec3 d1 = particle_position(c.b, t_b) - particle_position(c.a, t_a);
  const double p0 = -(d0.dot(c.normal) + c.offset), p1 = -(d1.dot(c.normal) + c.offset);
  const double fn0 = c.law.force(p0), fn1 = c.law.force(p1);
  const FrictionPart f0 = friction_part(c, d0, fn0, friction);
  const FrictionPart f1 = friction_part(c, d1, fn1, friction);
  // d is linear in the element's dofs: the model along the step is that of d's change.
  const Vec3 step = d1 - d0;
  const double dp = p1 - p0;
  const SeparationStiffness k = separation_stiffness(c, p0, f0, friction, tangent);
  StepModel m;
  m.normal_change = c.law.potential(p1) - c.law.potential(p0);
  m.normal_model = fn0 * dp + 0.5 * k.normal * dp * dp;
  m.friction_change = f1.energy - f0.energy;
  m.friction_model = f0.state.force.dot(step) + 0.5 * step.dot(k.friction * step);
  m.slope = fn0 * dp + f0.state.force.dot(step);
  m.start = {-p0, fn0, f0.state.force, f0.state.slip};
  m.end = {-p1, fn1, f1.state.force, f1.state.slip};
  return m;
}

}  // namespace fibra
