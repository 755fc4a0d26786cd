// Contact law and contact element: force, potential and tangent against finite differences,
// across the kinks of the law (zero gap, end of the quadratic part) and of friction
// (stick / slip), with random large-deformation element states.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <random>

#include <fmt/format.h>

#include "fibra/contact/contact_element.hpp"
#include "support/finite_difference.hpp"

namespace fibra {
namespace {

TEST(PenaltyLaw, ContinuousForceAndStiffnessAndConsistentPotential) {
  PenaltyLaw law{2.0e5, 1e-6};
  const double pr = law.regularization;
  // Continuity at p = 0 and p = p_r.
  EXPECT_EQ(law.force(0.0), 0.0);
  EXPECT_NEAR(law.force(pr * (1 - 1e-12)), law.force(pr * (1 + 1e-12)), 1e-9 * law.force(pr));
  EXPECT_NEAR(law.stiffness_at(pr * (1 - 1e-12)), law.stiffness_at(pr * (1 + 1e-12)), 1e-9 * law.stiffness);
  EXPECT_NEAR(law.potential(pr * (1 - 1e-12)), law.potential(pr * (1 + 1e-12)), 1e-9 * law.potential(pr));
  // Values: f(p_r) = k p_r / 2, beyond slope k.
  EXPECT_NEAR(law.force(pr), 0.5 * law.stiffness * pr, 1e-12 * law.stiffness * pr);
  EXPECT_NEAR(law.force(3 * pr), 2.5 * law.stiffness * pr, 1e-12 * law.stiffness * pr);
  // f = phi' and df/dp = f' by central differences on both sides of each kink.
  for (double p : {-0.5 * pr, 1e-3 * pr, 0.3 * pr, 0.999 * pr, 1.001 * pr, 2 * pr, 50 * pr}) {
    // Step small enough to stay on one side of each kink (0.001 p_r away).
    const double h = test::fd_step(std::max(std::abs(p), pr)) * 1e-2;
    const double scale = std::max(law.force(p), law.stiffness * pr);
    EXPECT_NEAR((law.potential(p + h) - law.potential(p - h)) / (2 * h), law.force(p), 1e-6 * scale) << p;
    EXPECT_NEAR((law.force(p + h) - law.force(p - h)) / (2 * h), law.stiffness_at(p), 1e-6 * law.stiffness) << p;
  }
}

TEST(FrictionReturnMap, StickInsideConeSlipOnIt) {
  const Vec3 n = Vec3::UnitZ();
  const FrictionState stick = friction_return_map(Vec3(0.1, 0, 0), Vec3(1e-7, 0, 3.0), n, 1.0, 0.3, 1e6);
  EXPECT_FALSE(stick.slip);
  EXPECT_NEAR(stick.force.x(), 0.2, 1e-12);  // 0.1 + 1e6 * 1e-7, normal part of du ignored
  EXPECT_NEAR(stick.force.z(), 0.0, 1e-15);
  const FrictionState slip = friction_return_map(Vec3(0.1, 0, 0), Vec3(0, 1e-6, 0), n, 1.0, 0.3, 1e6);
  EXPECT_TRUE(slip.slip);
  EXPECT_NEAR(slip.force.norm(), 0.3, 1e-12);
  EXPECT_NEAR(slip.force.normalized().dot(Vec3(0.1, 1.0, 0).normalized()), 1.0, 1e-12);
}

// Two elements in a random large rotation, element B placed so that the particles are at a
// chosen gap along the normal, with random section distortions.
struct Pair {
  ContactElement c;
  Eigen::Matrix<double, kElementDofs, 1> qa, qb;
};

Pair make_pair(std::mt19937& rng, double gap, const Vec3& tangential) {
  std::uniform_real_distribution<double> u(-1, 1);
  const double r = 1e-3;
  Pair s;
  const Mat3 rot = Eigen::AngleAxisd(3 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
  auto element = [&](const Vec3& origin, const Vec3& dir, Eigen::Matrix<double, kElementDofs, 1>& q) {
    const Vec3 t = dir.normalized();
    Vec3 g1 = t.unitOrthogonal(), g2 = t.cross(g1);
    for (int a = 0; a < 3; ++a) {
      q.segment<3>(9 * a) = rot * (origin + 0.5 * (a - 1) * 0.01 * t) + 1e-4 * Vec3(u(rng), u(rng), u(rng));
      q.segment<3>(9 * a + 3) = rot * g1 + 0.05 * Vec3(u(rng), u(rng), u(rng));
      q.segment<3>(9 * a + 6) = rot * g2 + 0.05 * Vec3(u(rng), u(rng), u(rng));
    }
  };
  element(Vec3::Zero(), Vec3(1, 0, 0), s.qa);
  element(Vec3(0, 0, 2 * r), Vec3(0.3, 1, 0), s.qb);
  s.c.a = {0, 0.1 * u(rng), 0.2 * r * u(rng), r};
  s.c.b = {1, 0.1 * u(rng), 0.2 * r * u(rng), -r};
  s.c.normal = rot * Vec3::UnitZ();
  s.c.law = {1e6, 1e-6};
  // Shift B along the normal to reach the requested gap.
  const double g0 = (particle_position(s.c.b, s.qb.data()) - particle_position(s.c.a, s.qa.data())).dot(s.c.normal);
  for (int a = 0; a < 3; ++a) s.qb.segment<3>(9 * a) += (gap - g0) * s.c.normal;
  s.c.separation_previous = particle_position(s.c.b, s.qb.data()) - particle_position(s.c.a, s.qa.data()) - tangential;
  s.c.friction_previous = Vec3::Zero();
  return s;
}

void check_derivatives(const Pair& s, const FrictionParams& fp, bool consistent, double tol, const char* what) {
  Eigen::VectorXd q(kContactDofs);
  q << s.qa, s.qb;
  auto grad_of = [&](const Eigen::VectorXd& x) {
    ContactVec g;
    contact_element_energy(s.c, x.data(), x.data() + kElementDofs, fp, &g, nullptr, nullptr);
    return Eigen::VectorXd(g);
  };
  ContactVec g;
  ContactMat h;
  contact_element_energy(s.c, q.data(), q.data() + kElementDofs, fp, &g, &h, nullptr,
                         consistent ? ContactTangent::Consistent : ContactTangent::Exact);
  const double step = test::fd_step(1e-6);
  const Eigen::MatrixXd hfd = test::fd_jacobian(grad_of, q, step);
  EXPECT_LT(test::rel_error(h, hfd, 1e-300), tol) << what;
  if (fp.mu == 0.0) {
    // Frictionless: the gradient is that of the energy.
    auto energy_of = [&](const Eigen::VectorXd& x) {
      return contact_element_energy(s.c, x.data(), x.data() + kElementDofs, fp, nullptr, nullptr, nullptr);
    };
    const Eigen::VectorXd gfd = test::fd_gradient(energy_of, q, step);
    // The energy of a barely penetrating element is tiny (k p^3 / 6 p_r): round-off in the
    // differences limits the agreement to about 1e-5.
    EXPECT_LT(test::rel_error(g, gfd, 1e-300), 2e-5) << what;
  }
}

// The gradient is the finite-difference derivative of the energy.
void expect_gradient_of_energy(const Pair& s, const FrictionParams& fp, const char* what) {
  Eigen::VectorXd q(kContactDofs);
  q << s.qa, s.qb;
  auto energy_of = [&](const Eigen::VectorXd& x) {
    return contact_element_energy(s.c, x.data(), x.data() + kElementDofs, fp, nullptr, nullptr, nullptr);
  };
  ContactVec g;
  contact_element_energy(s.c, q.data(), q.data() + kElementDofs, fp, &g, nullptr, nullptr);
  EXPECT_LT(test::rel_error(g, test::fd_gradient(energy_of, q, test::fd_step(1e-6)), 1e-300), 2e-5) << what;
}

TEST(ContactElement, NormalDerivativesAcrossTheKinksOfTheLaw) {
  std::mt19937 rng(7);
  const FrictionParams none{0.0, 1e-6};
  // gap > 0 (no force), just penetrating, mid quadratic, around p_r, deep.
  for (double gap : {1e-6, -1e-9, -0.5e-6, -0.99e-6, -1.01e-6, -5e-6}) {
    for (int trial = 0; trial < 5; ++trial) {
      const Pair s = make_pair(rng, gap, Vec3::Zero());
      ContactResponse r;
      contact_element_energy(s.c, s.qa.data(), s.qb.data(), none, nullptr, nullptr, &r);
      EXPECT_NEAR(r.gap, gap, 1e-12);
      if (gap > 0) {
        EXPECT_EQ(r.normal_force, 0.0);
        continue;
      }
      check_derivatives(s, none, false, 1e-5, "normal");
    }
  }
}

TEST(ContactElement, FrictionConsistentTangentInStickAndSlip) {
  std::mt19937 rng(11);
  const FrictionParams fp{0.3, 1e-6};
  for (double slide : {1e-8, 0.5e-6, 3e-6}) {  // well inside, near, beyond the cone
    for (int trial = 0; trial < 5; ++trial) {
      std::uniform_real_distribution<double> u(-1, 1);
      const Pair s = make_pair(rng, -3e-6, slide * Vec3(u(rng), u(rng), u(rng)).normalized());
      ContactResponse r;
      contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, nullptr, &r);
      EXPECT_LE(r.friction.norm(), fp.mu * r.normal_force * (1 + 1e-12));
      EXPECT_NEAR(r.friction.dot(s.c.normal), 0.0, 1e-12 * r.normal_force);
      check_derivatives(s, fp, true, 1e-5, r.slip ? "slip" : "stick");
    }
  }
}

TEST(ContactElement, SymmetricTangentIsTheSymmetricApproximation) {
  std::mt19937 rng(5);
  const FrictionParams fp{0.3, 1e-6};
  const Pair s = make_pair(rng, -3e-6, Vec3(1e-8, 0, 0));
  ContactMat h;
  contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, &h, nullptr, ContactTangent::Exact);
  EXPECT_LT((h - h.transpose()).norm(), 1e-12 * h.norm());
  Eigen::SelfAdjointEigenSolver<ContactMat> eig(h);
  EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-9 * h.norm());  // positive semi-definite
}

// Frozen cone (the solver's choice): the normal force that sets the cone and the stick
// stiffness is a given number, so the friction energy is a function of the slip alone; its
// gradient is the friction force and the symmetric tangent is exact (no fn coupling), in stick
// and in slip; the cone's radius is mu times the frozen force, whatever the current one.
TEST(ContactElement, FrozenConeGivesAnExactSymmetricTangent) {
  std::mt19937 rng(23);
  const FrictionParams fp{0.3, 1e-6};
  std::uniform_real_distribution<double> u(-1, 1);
  for (double slide : {1e-8, 0.5e-6, 3e-6}) {
    for (int trial = 0; trial < 4; ++trial) {
      Pair s = make_pair(rng, -3e-6, slide * Vec3(u(rng), u(rng), u(rng)).normalized());
      ContactResponse now;
      contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, nullptr, &now);
      s.c.friction_normal = 0.7 * now.normal_force;  // a cone set at another state
      ContactResponse r;
      contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, nullptr, &r);
      EXPECT_EQ(r.normal_force, now.normal_force);
      EXPECT_LE(r.friction.norm(), fp.mu * s.c.friction_normal * (1 + 1e-12));
      if (r.slip) {
        EXPECT_NEAR(r.friction.norm(), fp.mu * s.c.friction_normal, 1e-12 * r.normal_force);
      }
      const char* what = r.slip ? "frozen slip" : "frozen stick";
      check_derivatives(s, fp, false, 1e-5, what);
      check_derivatives(s, fp, true, 1e-5, what);
      ContactMat h;
      contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, &h, nullptr, ContactTangent::Consistent);
      EXPECT_LT((h - h.transpose()).norm(), 1e-12 * h.norm()) << what << ": the exact tangent is symmetric";
      // The gradient is that of the energy (a potential of the slip), away from the cone's edge.
      expect_gradient_of_energy(s, fp, what);
    }
  }
  // With a friction force carried over from the last increment (the solver's usual case), in
  // stick and on the cone, the energy is the potential of the returned force: f . du is not
  // (its gradient adds (df/du)^T du, which vanishes only when f_prev = 0).
  for (double carried : {0.4, 0.9, 1.6}) {  // |f_prev| / (mu f_n): inside, near, beyond the cone
    for (double slide : {1e-8, 0.3e-6, 3e-6}) {
      Pair s = make_pair(rng, -3e-6, slide * Vec3(u(rng), u(rng), u(rng)).normalized());
      ContactResponse now;
      contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, nullptr, &now);
      s.c.friction_normal = now.normal_force;
      const Vec3 n = s.c.normal;
      Vec3 dir = Vec3(u(rng), u(rng), u(rng));
      dir = (dir - dir.dot(n) * n).normalized();
      s.c.friction_previous = carried * fp.mu * now.normal_force * dir;
      ContactResponse r;
      contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, nullptr, &r);
      const std::string what = fmt::format("carried {} slide {:.0e} ({})", carried, slide, r.slip ? "slip" : "stick");
      check_derivatives(s, fp, true, 1e-5, what.c_str());
      expect_gradient_of_energy(s, fp, what.c_str());
    }
  }
  // A cone frozen at zero force: no friction, even on a penetrating element.
  Pair s = make_pair(rng, -3e-6, Vec3(1e-7, 0, 0));
  s.c.friction_normal = 0.0;
  ContactResponse r;
  contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, nullptr, &r);
  EXPECT_GT(r.normal_force, 0.0);
  EXPECT_EQ(r.friction.norm(), 0.0);
}

// The tangent above the energy (ContactTangent::Majorizing): the normal law's largest curvature
// k whatever the penetration, and on the friction cone the across-curvature k_t L / |T| along
// the trial force too. Its quadratic model, g . dq + dq . H dq / 2, lies above the element's
// energy change for every step dq: open, in the law's quadratic start and beyond it; in stick
// and in slip with friction carried over; steps that turn the slip back, bring it into stick,
// slide it further, press or open. The Exact model falls below the energy on some of those
// steps (the test tells the two apart), and contact_step_model measures by how much.
TEST(ContactElement, MajorizingTangentLiesAboveTheEnergy) {
  std::mt19937 rng(31);
  const FrictionParams fp{0.3, 1e-6};
  std::uniform_real_distribution<double> u(-1, 1);
  struct Along {
    double change, majorizing, exact;
  };
  auto along = [&](const Pair& s, const Eigen::VectorXd& dq) {
    Eigen::VectorXd q(kContactDofs);
    q << s.qa, s.qb;
    const Eigen::VectorXd t = q + dq;
    auto energy = [&](const Eigen::VectorXd& x) {
      return contact_element_energy(s.c, x.data(), x.data() + kElementDofs, fp, nullptr, nullptr, nullptr);
    };
    auto model = [&](ContactTangent tangent) {
      ContactVec g;
      ContactMat h;
      contact_element_energy(s.c, q.data(), q.data() + kElementDofs, fp, &g, &h, nullptr, tangent);
      const ContactVec d = dq;
      return g.dot(d) + 0.5 * d.dot(h * d);
    };
    return Along{energy(t) - energy(q), model(ContactTangent::Majorizing), model(ContactTangent::Exact)};
  };
  int below_exact = 0, slipping = 0, open = 0;
  for (double gap : {1e-6, -0.5e-6, -3e-6}) {  // open, in the quadratic start (p_r = 1e-6), beyond
    for (double carried : {0.0, 0.5, 1.6}) {  // |f_prev| / (mu f_n)
      for (double slide : {1e-8, 0.5e-6, 3e-6}) {
        Pair s = make_pair(rng, gap, slide * Vec3(u(rng), u(rng), u(rng)).normalized());
        ContactResponse now;
        contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, nullptr, &now);
        // The cone frozen at the force of 2 um of penetration, open elements too (a frozen spring
        // acts on an element that opens during a solve).
        s.c.friction_normal = s.c.law.force(2e-6);
        const Vec3 n = s.c.normal;
        Vec3 dir = Vec3(u(rng), u(rng), u(rng));
        dir = (dir - dir.dot(n) * n).normalized();
        s.c.friction_previous = carried * fp.mu * s.c.friction_normal * dir;
        ContactResponse r;
        contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, nullptr, &r);
        slipping += r.slip;
        open += r.gap > 0.0;
        ContactMat hm, he;
        contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, &hm, nullptr, ContactTangent::Majorizing);
        contact_element_energy(s.c, s.qa.data(), s.qb.data(), fp, nullptr, &he, nullptr, ContactTangent::Exact);
        EXPECT_LT((hm - hm.transpose()).norm(), 1e-12 * hm.norm());
        if (!r.slip && gap < -1e-6) {
          EXPECT_EQ(hm, he) << "stick beyond the quadratic start: the exact Hessian";
        }
        // What the majorizer adds is positive semi-definite.
        EXPECT_GT(Eigen::SelfAdjointEigenSolver<ContactMat>(hm - he).eigenvalues().minCoeff(), -1e-9 * hm.norm());
        // Steps of B's dofs of 0.01 to 10 elastic slips: random, and against the friction force
        // (through stick to a reversed slip) and along the normal (pressing).
        for (double size : {1e-8, 1e-7, 1e-6, 1e-5}) {
          for (int k = 0; k < 5; ++k) {
            Vec3 v = Vec3(u(rng), u(rng), u(rng)).normalized();
            if (k == 0 && r.friction.norm() > 0) v = -r.friction.normalized();
            if (k == 1) v = -n;
            Eigen::VectorXd dq = Eigen::VectorXd::Zero(kContactDofs);
            for (int a = 0; a < 3; ++a) dq.segment<3>(kElementDofs + 9 * a) = size * v;
            const Along m = along(s, dq);
            const double scale = (r.normal_force + fp.mu * s.c.friction_normal) * size + s.c.law.stiffness * size * size;
            const std::string what = fmt::format("gap {:.0e} carried {} slide {:.0e} ({}) step {:.0e} #{}", gap, carried,
                                                 slide, r.slip ? "slip" : "stick", size, k);
            EXPECT_LE(m.change, m.majorizing + 1e-9 * scale) << what;
            below_exact += m.change > m.exact + 1e-6 * scale;
            // contact_step_model: the same change and each tangent's excess, its normal part
            // that of the element without friction.
            const Eigen::VectorXd t = (Eigen::VectorXd(kContactDofs) << s.qa, s.qb).finished() + dq;
            for (ContactTangent tangent : {ContactTangent::Exact, ContactTangent::Majorizing}) {
              const StepModel sm =
                  contact_step_model(s.c, s.qa.data(), s.qb.data(), t.data(), t.data() + kElementDofs, fp, tangent);
              const double model = tangent == ContactTangent::Exact ? m.exact : m.majorizing;
              EXPECT_NEAR(sm.change(), m.change, 1e-9 * scale) << what;
              EXPECT_NEAR(sm.excess(), m.change - model, 1e-9 * scale) << what;
              const StepModel sn = contact_step_model(s.c, s.qa.data(), s.qb.data(), t.data(), t.data() + kElementDofs,
                                                      FrictionParams{}, tangent);
              EXPECT_EQ(sn.friction_change, 0.0);
              EXPECT_NEAR(sn.normal_change - sn.normal_model, sm.normal_change - sm.normal_model, 1e-12 * scale);
            }
          }
        }
      }
    }
  }
  EXPECT_GT(slipping, 0);
  EXPECT_GT(open, 0);
  EXPECT_GT(below_exact, 0) << "no step where the exact Hessian's model falls below the energy";
}

}  // namespace
}  // namespace fibra
