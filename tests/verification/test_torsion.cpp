// Torsion of a clamped circular fiber by an end torque T (a moment along the fiber axis).
//
// Linear theory: twist phi = T L / (G J), J = pi r^4 / 2, with G = E / (2 (1 + nu)) for the
// isotropic law and G = G_LT (shear_axial) for the transversely isotropic one. A circular
// section does not warp, so this is exact in the linear range for this kinematics, and uniform
// twist is reproduced by the quadratic elements (measured: 3e-9 relative at phi = 0.01).
//
// Large twist is NOT exactly linear, for a physical reason: with twist rate tau the material
// fibres at radius rho become helices, E33 = (lambda^2 - 1 + tau^2 mu^2 rho^2)/2 (lambda: axis
// stretch, mu = |g1| = |g2|: section stretch), and the shear strains 2E13, 2E23 = tau mu^2 xi
// make the shear energy G J tau^2 mu^4 / 2 decrease when the section contracts. St Venant–
// Kirchhoff theory of uniform twist in this kinematics (no axial force; the enhanced section
// modes relax the in-plane stresses of the rho^2 field exactly, so S33 = E_L E33 there):
//   * the section contracts: eps = (mu^2 - 1)/2 minimizes mu^4 (G J tau^2/2 + E_L J r^2 tau^4/48)
//     + A B eps^2 (B = E_T/(1 - nu_TT), the biaxial in-plane modulus; E_T = E, nu_TT = nu when
//     isotropic), so eps = -K/(2(1 + K)), K = (G tau^2 + E_L tau^4 r^2/24) r^2 / B;
//   * T = mu^4 (G J tau + E_L J r^2 tau^3 / 12): to leading order
//     T = G J tau (1 + (E_L/(12 G) - 2 G/B) (r tau)^2), softening for these materials
//     (coefficient -0.32 isotropic nu = 0.3, -0.96 for the carbon law below);
//   * the axis shortens: the mean axial strain e_bar = (lambda^2 - 1)/2 + tau^2 mu^2 r^2/4
//     carries no force, e_bar = -2 nu_LT E_T eps / ((1 - nu_TT) E_L).
// So at phi = 1 rad the linear law is off by 3e-5 (isotropic) / 1e-4 (carbon) for L/r = 100 (the
// brief's "still exact?": yes, to O((r tau)^2)), and by 0.3 % / 0.9 % for L/r = 10, where the
// test checks the SVK prediction instead. Near the clamp the section cannot contract
// (boundary layer ~ r), which stiffens a stubby rod measurably (1.4e-4 / 8e-4 in the tip
// twist at L/r = 10), so the large-twist checks use the twist rate, stretch and section
// stretch measured at the Gauss points of interior elements (s from 0.3 L to 0.8 L).
// Measured agreement with the SVK prediction: twist rate 1e-11..5e-6 relative (the small-angle
// tip twist even matches the predicted 3.2e-9 / 9.6e-9 departure from the linear law), axis
// stretch and section stretch to 2e-3 of lambda - 1, mu - 1; the tests ask for 1e-4 on the twist
// rate and 1 % on these (tiny) strains.
#include <gtest/gtest.h>

#include <cmath>

#include "fibra/beam/beam_element.hpp"
#include "verification/verification_support.hpp"

namespace fibra::test {
namespace {

struct TorsionCase {
  const char* name;
  bool transverse;
  double slenderness;  // L / r
  double phi;          // twist by the linear law [rad] (sets the torque)
};

struct Law {
  double e_l, e_t, nu_lt, nu_tt, g;
};
const Law kSteel{210e9, 210e9, 0.3, 0.3, 210e9 / 2.6};
const Law kCarbon{230e9, 15e9, 0.2, 0.45, 24e9};

std::string material_toml(bool transverse) {
  if (!transverse) return "[[material]]\nname = \"m\"\nyoung = 210e9\npoisson = 0.3\n";
  return "[[material]]\nname = \"m\"\nmodel = \"transverse\"\nyoung = 230e9\npoisson = 0.2\n"
         "young_transverse = 15e9\nshear_axial = 24e9\npoisson_transverse = 0.45\n";
}

// Interpolated axis vectors (x0', g1, ...) at Gauss point gp of element e of the fiber.
AxisVectors at_gauss(const Solved& s, int e, int gp) {
  const BeamElement& el = s.model.elements.at(s.model.fibers[0].first_element + e);
  return beam_axis_vectors(s.q.data() + el.first_dof, beam_gauss_point(gp), el.gauss[gp].inv_jac);
}

double twist_of(const Vec3& g1) { return std::atan2(g1.z(), g1.y()); }  // about +x, from +y

class Torsion : public ::testing::TestWithParam<TorsionCase> {};

TEST_P(Torsion, TwistMatchesLinearAndStVenantKirchhoffTheory) {
  const TorsionCase& tc = GetParam();
  const Law law = tc.transverse ? kCarbon : kSteel;
  const double length = 1.0, radius = length / tc.slenderness;
  const int elements = 10;
  const double polar = kPi * std::pow(radius, 4) / 2.0, area = kPi * radius * radius;
  const double torque = tc.phi * law.g * polar / length;
  const Solved s = solve_toml(material_toml(tc.transverse) + fmt::format(R"(
[[fiber]]
name = "rod"
material = "m"
radius = {:.17g}
section_direction = [0, 1, 0]
points = [[0, 0, 0], [{:.17g}, 0, 0]]
elements = {}

[[fix]]
fiber = "rod"
node = "first"

[[step]]
increments = {}
  [[step.load]]
  fiber = "rod"
  node = "last"
  moment = [{:.17g}, 0, 0]
)",
                                                                         radius, length, elements,
                                                                         tc.phi > 0.5 ? 4 : 1, torque));
  ASSERT_TRUE(s.converged()) << s.result.message;

  // SVK theory of uniform twist (header): solve T(tau) = torque by bisection.
  const double biaxial = law.e_t / (1.0 - law.nu_tt);
  auto eps_of = [&](double t) {
    const double k = (law.g * t * t + law.e_l * std::pow(t, 4) * radius * radius / 24.0) * radius * radius / biaxial;
    return -k / (2.0 * (1.0 + k));
  };
  auto torque_of = [&](double t) {
    const double mu2 = 1.0 + 2.0 * eps_of(t);
    return mu2 * mu2 * (law.g * polar * t + law.e_l * polar * radius * radius * t * t * t / 12.0);
  };
  double lo = 0.0, hi = 2.0 * torque / (law.g * polar);
  for (int it = 0; it < 200; ++it) (torque_of(0.5 * (lo + hi)) < torque ? lo : hi) = 0.5 * (lo + hi);
  const double tau = 0.5 * (lo + hi);
  const double eps = eps_of(tau), mu = std::sqrt(1.0 + 2.0 * eps);
  const double e_bar = -2.0 * law.nu_lt * law.e_t * eps / ((1.0 - law.nu_tt) * law.e_l);
  const double stretch = std::sqrt(1.0 + 2.0 * e_bar - 0.5 * tau * tau * mu * mu * radius * radius);
  (void)area;

  // Tip twist against the linear law (both section vectors).
  const double phi_linear = torque * length / (law.g * polar);
  const double phi1 = twist_of(s.g1(-1)), phi2 = std::atan2(-s.g2(-1).y(), s.g2(-1).z());
  EXPECT_NEAR(phi1, phi2, 1e-9);
  // Interior twist rate: between nodes 6 and 16 (s = 0.3 L .. 0.8 L).
  const double tau_fe = (twist_of(s.g1(16)) - twist_of(s.g1(6))) / (0.5 * length);
  // Interior axis stretch and section stretch at the Gauss points of elements 3..7.
  double stretch_fe = 0.0, mu_fe = 0.0;
  for (int e = 3; e < 8; ++e)
    for (int gp = 0; gp < kBeamGauss; ++gp) {
      const AxisVectors v = at_gauss(s, e, gp);
      stretch_fe += v.col(0).norm() / 10.0;
      mu_fe += 0.5 * (v.col(1).norm() + v.col(2).norm()) / 10.0;
    }
  std::printf("%-24s tip twist / linear - 1 = %+.2e (SVK theory %+.2e); interior: tau / theory - 1 = %+.2e, "
              "(lambda-1) %.4e / theory %.4e, (mu-1) %.4e / theory %.4e\n",
              tc.name, phi1 / phi_linear - 1, tau * length / phi_linear - 1, tau_fe / tau - 1, stretch_fe - 1,
              stretch - 1, mu_fe - 1, mu - 1);

  if (tc.slenderness >= 100) {
    // Slender: the linear law holds at the tip to O((r tau)^2) ~ 1e-4 even at 1 rad.
    EXPECT_NEAR(phi1 / phi_linear, 1.0, tc.phi < 0.1 ? 1e-6 : 2e-4);
  } else {
    // Stubby, 1 rad: the linear law is off by the SVK softening (0.3 %, 0.9 %); it must show.
    EXPECT_GT(phi1 / phi_linear - 1.0, 0.5 * (tau * length / phi_linear - 1.0));
  }
  EXPECT_NEAR(tau_fe / tau, 1.0, 1e-4);
  if (tc.phi > 0.5) {
    EXPECT_NEAR((stretch_fe - 1.0) / (stretch - 1.0), 1.0, 1e-2);
    EXPECT_NEAR((mu_fe - 1.0) / (mu - 1.0), 1.0, 1e-2);
  }
  // The axis stays straight, the section circular (|g1| = |g2|, g1 . g2 = 0).
  const Vec3 u = s.u(-1);
  EXPECT_LT(std::hypot(u.y(), u.z()), 1e-9 * length);
  EXPECT_NEAR(s.g1(-1).norm(), s.g2(-1).norm(), 1e-9);
  EXPECT_NEAR(s.g1(-1).dot(s.g2(-1)), 0.0, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, Torsion,
    ::testing::Values(TorsionCase{"isotropic_small", false, 100, 0.01}, TorsionCase{"isotropic_1rad", false, 100, 1.0},
                      TorsionCase{"isotropic_stubby_1rad", false, 10, 1.0},
                      TorsionCase{"transverse_small", true, 100, 0.01}, TorsionCase{"transverse_1rad", true, 100, 1.0},
                      TorsionCase{"transverse_stubby_1rad", true, 10, 1.0}),
    [](const auto& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace fibra::test
