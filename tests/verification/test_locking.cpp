// No shear locking and no Poisson locking: a cantilever under a small tip load, 10 elements,
// L/r = 10, 100, 1000 and nu = 0, 0.2, 0.3, 0.45, against beam theory.
//
// Reference: Euler–Bernoulli delta_b = P L^3 / (3 E I) plus the Timoshenko shear deflection
// delta_s = P L / (k G A). This kinematics has a constant shear strain over the section (no
// warping), so its shear factor is k = 1 (docs/theory/beam.md); the elasticity value for a
// circle, k = 6 (1 + nu) / (7 + 6 nu) (0.857..0.906), differs from it by 10-17 % of delta_s. For
// L/r = 10, delta_s / delta_b = 3 E I / (k G A L^2) = 1.5 (1 + nu) (r/L)^2 / k = 1.5 % .. 2.2 %, so
// the choice of k moves the reference by at most 0.3 % of the deflection: the test checks the
// model against its own k = 1 theory to 0.1 %, and against Timoshenko with the elasticity k to
// 0.5 % (the brief). For L/r >= 100 the shear term is below 2.2e-4 and both references agree.
//
// A shear-locked element would be too stiff by a factor growing like (L/r)^2 (the 1000 case
// would deflect ~0 with 10 elements); a Poisson-locked section bends with (lambda + 2 mu) I
// instead of E I (nu = 0.45: 2.6 times too stiff). The load is small (delta ~ 1e-4 L), so the
// geometric nonlinearity is O(1e-8). Measured: every case that converges is within 1.1e-8 of the
// k = 1 theory, and 2.5e-3 (L/r = 10) / 2.5e-5 / 2.6e-7 below Timoshenko with the elasticity k.
// L/r = 1000 with nu = 0.45 does not converge with the default tolerances (round-off floor of the
// residual above residual_tolerance; reported as a library issue, the test is kept as is).
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "verification/verification_support.hpp"

namespace fibra::test {
namespace {

class Locking : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(Locking, SmallTipLoadDeflectionMatchesBeamTheory) {
  const auto [slenderness, nu] = GetParam();
  const double length = 1.0, radius = length / slenderness, young = 100e9;
  const double inertia = kPi * std::pow(radius, 4) / 4.0, area = kPi * radius * radius;
  const double shear = young / (2.0 * (1.0 + nu));
  const double load = 3.0 * young * inertia * 1e-4 / (length * length);  // delta_b = 1e-4 L
  const Solved s = solve_toml(straight_cantilever(length, radius, 10, young, nu, fmt::format(R"(
[[step]]
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, {:.17g}]
)",
                                                                                             -load)));
  ASSERT_TRUE(s.converged()) << s.result.message;
  const double deflection = -s.u(-1).z();
  const double bending = load * std::pow(length, 3) / (3.0 * young * inertia);
  const double k_timoshenko = 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu);
  const double ref_model = bending + load * length / (shear * area);  // k = 1
  const double ref_timoshenko = bending + load * length / (k_timoshenko * shear * area);
  std::printf("L/r %5.0f nu %.2f: deflection / (P L^3/3EI) = %.6f, rel. error vs k=1 theory %+.2e, "
              "vs Timoshenko k=%.3f %+.2e\n",
              slenderness, nu, deflection / bending, deflection / ref_model - 1, k_timoshenko,
              deflection / ref_timoshenko - 1);
  EXPECT_NEAR(deflection / ref_model, 1.0, 1e-3);
  EXPECT_NEAR(deflection / ref_timoshenko, 1.0, 5e-3);
  if (slenderness >= 100) {
    EXPECT_NEAR(deflection / bending, 1.0, 5e-3);
  }
}

INSTANTIATE_TEST_SUITE_P(SlendernessAndPoisson, Locking,
                         ::testing::Combine(::testing::Values(10.0, 100.0, 1000.0),
                                            ::testing::Values(0.0, 0.2, 0.3, 0.45)),
                         [](const auto& p) {
                           return fmt::format("L_r{}_nu{}", static_cast<int>(std::get<0>(p.param)),
                                              static_cast<int>(std::lround(100 * std::get<1>(p.param))));
                         });

}  // namespace
}  // namespace fibra::test
