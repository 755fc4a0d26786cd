// Robustness corpus, contact and friction (docs/robustness.md): fibers pressed, bent and pulled
// over each other as a user writes them, default solver and contact settings (only the
// friction coefficient is set), each checked against an analytic reference.
#include <gtest/gtest.h>

#include <cmath>

#include "robustness/robustness_support.hpp"

namespace fibra::test {
namespace {

constexpr double kSteel = 210e9, kNu = 0.3, kShear = kSteel / (2 * (1 + kNu));
constexpr double kCowper = 6 * (1 + kNu) / (7 + 6 * kNu);  // shear factor of a circle
constexpr double kCap = 0.05;                              // default contact.max_penetration

double circle_inertia(double r) { return kPi * std::pow(r, 4) / 4; }

/// Largest penetration / radius over the converged increments.
double deepest_penetration(const CaseRun& s) {
  double worst = 0;
  for (const Snapshot& snap : s.snaps) worst = std::max(worst, snap.info.contact.max_penetration_ratio);
  return worst;
}

// ---------------------------------------------------------------------------------------------
// Two identical fibers (r = 0.5 mm, L = 40 mm, clamped at both ends) crossed at 1, 10, 45 and 90
// degrees, b on a, b's middle pushed down by a dead force P = 2 N.
// Reference (linear beam theory, superposition): a carries the contact force distribution p,
// b carries P - p, both with the compliance of a clamped-clamped beam, so the two mid-span
// deflections add up to what P alone gives one fiber, whatever p and the penetration are:
//   w_a + w_b = P (L^3 / (192 E I) + L / (4 k G A)),  k = 0.886 (Cowper).
// Exact for a point contact at mid-span (10, 45, 90 degrees: the contact spreads over about a
// radius, O((r/L)^2) = 2e-4); at 1 degree the fibers touch along several millimetres, at the
// same arc lengths on both, and the sum still holds to the order of the angle. Departures: the
// model's shear factor is 1 (0.07 % of w), geometric nonlinearity O((w/L)^2) ~ 1e-6, the
// membrane force of a clamped-clamped beam O((w/r)^2) ~ 4e-3 of w (measured: the sum is 0.16 %
// low), 20 quadratic elements are exact for cubic deflections. Tolerance 1 %.
// Also: equilibrium, a's and b's reactions balance P to 1e-6; the contact force on a (the sum
// of the elements' normal forces) equals a's reactions to 1e-4 (normals within 1e-2 rad of
// vertical); the penetration stays within the cap, 0.05 r, at every converged increment.
// ---------------------------------------------------------------------------------------------
class CrossedFibers : public ::testing::TestWithParam<const char*> {};

TEST_P(CrossedFibers, DeflectionsAddUpToTheLoadsAndThePenetrationIsCapped) {
  const std::string name = GetParam();
  const double r = 0.5e-3, length = 40e-3, load = 2.0;
  const double compliance = std::pow(length, 3) / (192 * kSteel * circle_inertia(r)) + length / (4 * kCowper * kShear * kPi * r * r);
  const CaseRun s = solve_file(name, 60);
  Checks checks(name);
  if (checks.converged(s)) {
    const int a = s.fiber("a"), b = s.fiber("b");
    const Index mid = (s.num_nodes(a) - 1) / 2;
    const double w = -s.u(s.q, mid, a).z() - s.u(s.q, mid, b).z();
    checks.relative("mid-span deflections of a and b, summed [m]", w, load * compliance, 0.01);
    const Snapshot& last = s.snaps.back();
    const Vec3 ra = s.fiber_reaction(last, "a"), rb = s.fiber_reaction(last, "b");
    checks.at_most("|a's and b's reactions + P| / P", (ra + rb + Vec3(0, 0, -load)).norm() / load, 1e-6);
    checks.relative("sum of the contact normal forces [N]", last.info.contact.total_normal_force, ra.z(), 1e-4);
    checks.at_most("largest penetration / r over the increments", deepest_penetration(s), kCap);
  }
  checks.finish();
}

INSTANTIATE_TEST_SUITE_P(Robustness, CrossedFibers,
                         ::testing::Values("crossed_1deg", "crossed_10deg", "crossed_45deg", "crossed_90deg"),
                         [](const auto& p) { return std::string(p.param); });

// ---------------------------------------------------------------------------------------------
// Two parallel fibers (r = 0.5 mm, L = 40 mm, clamped at both ends, b on a along its length),
// b pushed onto a by a uniform line load q = 100 N/m. Reference: the superposition argument
// above with a uniform load: w_a + w_b = q L^4 / (384 E I) + q L^2 / (8 k G A) at mid-span,
// whatever the contact pressure is (in particular near the clamps, where the penalty lets it
// fall to zero); model departures as above. Tolerance 1 %. Equilibrium: the reactions balance
// the applied nodal forces to 1e-6; the contact force on a equals a's reactions to 1e-4;
// penetration within the cap.
// ---------------------------------------------------------------------------------------------
TEST(Robustness, parallel_pressed) {
  const double r = 0.5e-3, length = 40e-3, q = 100.0, h = length / 20;
  const double reference = q * std::pow(length, 4) / (384 * kSteel * circle_inertia(r)) +
                           q * length * length / (8 * kCowper * kShear * kPi * r * r);
  const double applied = q * length - 2 * q * h / 6;  // the clamped end nodes' shares are left out
  const CaseRun s = solve_file("parallel_pressed", 60);
  Checks checks("parallel_pressed");
  if (checks.converged(s)) {
    const int a = s.fiber("a"), b = s.fiber("b");
    const Index mid = (s.num_nodes(a) - 1) / 2;
    checks.relative("mid-span deflections of a and b, summed [m]", -s.u(s.q, mid, a).z() - s.u(s.q, mid, b).z(),
                    reference, 0.01);
    const Snapshot& last = s.snaps.back();
    const Vec3 ra = s.fiber_reaction(last, "a"), rb = s.fiber_reaction(last, "b");
    checks.at_most("|reactions - applied load| / applied load", (ra + rb + Vec3(0, 0, -applied)).norm() / applied, 1e-6);
    checks.relative("sum of the contact normal forces [N]", last.info.contact.total_normal_force, ra.z(), 1e-4);
    checks.at_most("largest penetration / r over the increments", deepest_penetration(s), kCap);
  }
  checks.finish();
}

// ---------------------------------------------------------------------------------------------
// Three-point bending of a fiber (r = 0.5 mm) on two support fibers 40 mm apart, pushed at
// mid-span by a third; supports and pusher have 100 times its bending stiffness.
// Reference: Euler-Bernoulli with shear, w = P L^3 / (48 E I) + P L / (4 k G A), w the mid-span
// deflection relative to the beam's centroid over the supports (so the penalty compliance and
// the supports' own bending drop out), P the pusher's force. With friction mu the beam's lower
// surface, which lengthens by 2 r theta between the supports (theta = 3 w / L, the slope there),
// slides outwards on them: the friction mu P/2 at each support acts on that surface, a
// compressive force at r below the centroid, a uniform hogging moment mu (P/2) r over the span
// that takes mu P r L^2 / (16 E I) off the deflection: w = P L^3 / (48 E I) (1 - 3 mu r / L)
// (-1.1 % at mu = 0.3, -3 % at mu = 0.8). The slide (r theta ~ 3 um at the end) is 6 times the
// elastic slip, so the friction is on its cone. Other departures (tests/verification
// test_contact_verification.cpp): geometric nonlinearity, contact points moving as the beam
// rotates: < 0.5 %. Tolerance 1 %.
// Equilibrium: the supports' and the pusher's reactions balance to 1e-6 of P; penetration within
// the cap. The frictionless case holds the beam's free rigid motions with fixes that carry no
// load; "_unheld" is the same case as a user first writes it, without them (a mechanism: the
// beam slides and spins freely on frictionless supports, the deflection is still defined); the
// cases with friction have no such fixes: friction holds the beam.
// ---------------------------------------------------------------------------------------------
struct BendingCase {
  const char* name;
  double mu;
};
void PrintTo(const BendingCase& c, std::ostream* os) { *os << c.name; }

class ThreePointBending : public ::testing::TestWithParam<BendingCase> {};

TEST_P(ThreePointBending, DeflectionMatchesBeamTheoryWithTheSupportsFriction) {
  const BendingCase& bc = GetParam();
  const double r = 0.5e-3, span = 40e-3, inertia = circle_inertia(r);
  const CaseRun s = solve_file(bc.name, 60);
  Checks checks(bc.name);
  if (checks.converged(s)) {
    const Snapshot& last = s.snaps.back();
    const int beam = s.fiber("beam");
    ASSERT_NEAR(s.ref_x0(8, beam).x(), -span / 2, 1e-12);
    ASSERT_NEAR(s.ref_x0(72, beam).x(), span / 2, 1e-12);
    const double force = -s.fiber_reaction(last, "pusher").z();
    const auto uz = [&](Index node) { return s.u(s.q, node, beam).z(); };
    const double w = 0.5 * (uz(8) + uz(72)) - uz(40);
    const double reference = force * std::pow(span, 3) / (48 * kSteel * inertia) * (1 - 3 * bc.mu * r / span) +
                             force * span / (4 * kCowper * kShear * kPi * r * r);
    checks.relative("mid-span deflection relative to the supports [m]", w, reference, 0.01);
    const double supports = s.fiber_reaction(last, "left").z() + s.fiber_reaction(last, "right").z();
    checks.at_most("|supports' reactions - pusher's force| / P", std::abs(supports - force) / force, 1e-6);
    checks.at_most("largest penetration / r over the increments", deepest_penetration(s), kCap);
  }
  checks.finish();
}

INSTANTIATE_TEST_SUITE_P(Robustness, ThreePointBending,
                         ::testing::Values(BendingCase{"three_point_bending_mu0", 0.0},
                                           BendingCase{"three_point_bending_mu0_unheld", 0.0},
                                           BendingCase{"three_point_bending_mu03", 0.3},
                                           BendingCase{"three_point_bending_mu08", 0.8}),
                         [](const auto& p) { return std::string(p.param.name); });

// ---------------------------------------------------------------------------------------------
// Capstan: a rope (r = 0.1 mm, an arc at rest) over a fixed drum, tensioned by dead loads T on
// both ends along their tangents (axial strain 1e-4), then its first end pulled along its
// tangent until the rope slides (by 1.5 times the stretch of the stick phase). The rope is held
// in its plane, or along the drum's axis for the full turns (y at every node), and against
// spinning (g1z at its middle node); neither carries load.
// Reference: Euler-Eytelwein for a rope of finite radius r. The friction mu p (p the pressure
// per unit length) acts on the rope's surface, at R_c = rho - r from the drum's axis, the
// tension N at its centroid (radius rho). Along the rope, with the shear force V and the moment
// M: dN/ds = mu p - V/rho, dV/ds = N/rho - p, dM/ds = -V - mu p r. Where M is uniform (the
// rope keeps its curvature) V = -mu p r, so dN/ds = mu p R_c/rho and p (1 + mu r N'/N) = N/rho:
// to first order in mu^2 r / rho,
//   T1 / T2 = exp(mu theta (R_c / rho) (1 - mu^2 r / rho))
// once every contact element slips (the last factor is 0.8 % of the ratio at mu = 0.5 over a
// full turn, 0.9 % at 45 degrees and r / rho = 0.09). Departures: the next order, (mu^2 r /
// rho)^2 mu theta < 3e-4; the contact elements, a rope radius apart, make the exponential a
// product of point-contact factors, exact to O((mu r / rho)^3); the ends turn by the slide over
// rho against the fixed directions of the loads, the rope stretches by up to 2e-3 and sinks by
// the penetration: 0.5 % in all. Checks: at the end of the pull every loaded contact element
// slips, T1 / T2 is within 0.5 % of the reference, and it stays on its plateau once the rope
// slides (the last two increments within 0.5 %).
// ---------------------------------------------------------------------------------------------
struct CapstanCase {
  const char* name;
  double wrap_degrees, mu, ratio;  // ratio: drum surface radius / rope radius
};
void PrintTo(const CapstanCase& c, std::ostream* os) { *os << c.name; }

class Capstan : public ::testing::TestWithParam<CapstanCase> {};

TEST_P(Capstan, SlidesAtTheEulerEytelweinRatio) {
  const CapstanCase& cc = GetParam();
  const double r = 0.1e-3, theta = cc.wrap_degrees * kPi / 180, tension = 1e-4 * kSteel * kPi * r * r;
  const double rho = cc.ratio * r + r - 1e-3 * r;
  const double reference = std::exp(cc.mu * theta * (rho - r) / rho * (1 - cc.mu * cc.mu * r / rho));
  const CaseRun s = solve_file(cc.name, 60);
  const int rope = s.fiber("rope");
  const Vec3 out = -s.g1(s.model.reference, 0, rope).cross(s.g2(s.model.reference, 0, rope));  // first end, outwards
  Checks checks(cc.name);
  std::vector<double> ratios;
  int slipping = 0, loaded = 0;
  for (const Snapshot& snap : s.snaps) {
    if (snap.info.step_index != 1) continue;
    ratios.push_back((tension + s.reaction(snap, "rope", "first").dot(out)) / tension);
    slipping = loaded = 0;
    for (const ContactResponse& resp : snap.info.contact_responses)
      if (resp.normal_force > 0) ++loaded, slipping += resp.slip ? 1 : 0;
    if (std::getenv("FIBRA_VERBOSE"))
      std::printf("   pull %d: T1/T2 %.5f, %d of %d elements slipping\n", snap.info.increment, ratios.back(), slipping,
                  loaded);
  }
  if (checks.converged(s)) {
    checks.expect(loaded > 0 && slipping == loaded,
                  fmt::format("every loaded contact element slips at the end of the pull ({} of {})", slipping, loaded));
    checks.relative("T1 / T2 at the end of the pull", ratios.back(), reference, 0.005);
    checks.relative("T1 / T2, last increment against the one before", ratios.back(), ratios[ratios.size() - 2], 0.005);
  }
  checks.finish();
}

INSTANTIATE_TEST_SUITE_P(Robustness, Capstan,
                         ::testing::Values(CapstanCase{"capstan_45deg_mu05_ratio10", 45, 0.5, 10},
                                           CapstanCase{"capstan_90deg_mu03_ratio20", 90, 0.3, 20},
                                           CapstanCase{"capstan_180deg_mu01_ratio100", 180, 0.1, 100},
                                           CapstanCase{"capstan_180deg_mu03_ratio40", 180, 0.3, 40},
                                           CapstanCase{"capstan_360deg_mu02_ratio50", 360, 0.2, 50},
                                           CapstanCase{"capstan_360deg_mu05_ratio100", 360, 0.5, 100},
                                           CapstanCase{"capstan_drum_90deg_mu03_ratio10", 90, 0.3, 10}),
                         [](const auto& p) { return std::string(p.param.name); });

// ---------------------------------------------------------------------------------------------
// A thin fiber b (r_b = 25 um, 10 mm, clamped at both ends) under a thick one a (r_a = 0.5 mm,
// 40 mm, clamped at both ends) at 90 degrees; a's ends moved down by 0.05 r_b push b's middle
// down. Reference: b is a clamped-clamped beam under the point load P its supports carry,
// w_b = P (L^3 / (192 E I) + L / (4 k G A)) at mid-span: the contact is a point (b's curvature,
// 0.3 /m, is far below a's 2000 /m), the membrane force O((w/r_b)^2) ~ 2.5e-3: tolerance 1 %.
// Equilibrium: a's and b's reactions balance to 1e-6 of P; the contact force on b (the sum of
// the elements' normal forces) equals P to 1e-4; the penetration stays within the cap relative
// to the thinner fiber's radius at every converged increment.
// ---------------------------------------------------------------------------------------------
TEST(Robustness, crossed_radius_ratio_20) {
  const double rb = 25e-6, lb = 10e-3;
  const double compliance = std::pow(lb, 3) / (192 * kSteel * circle_inertia(rb)) + lb / (4 * kCowper * kShear * kPi * rb * rb);
  const CaseRun s = solve_file("crossed_radius_ratio_20", 60);
  Checks checks("crossed_radius_ratio_20");
  if (checks.converged(s)) {
    const int b = s.fiber("b");
    const Snapshot& last = s.snaps.back();
    const Vec3 fa = s.fiber_reaction(last, "a"), fb = s.fiber_reaction(last, "b");
    const double load = fb.z();
    checks.relative("b's mid-span deflection [m]", -s.u(s.q, (s.num_nodes(b) - 1) / 2, b).z(), load * compliance, 0.01);
    checks.at_most("|a's and b's reactions| / P", (fa + fb).norm() / load, 1e-6);
    checks.relative("sum of the contact normal forces [N]", last.info.contact.total_normal_force, load, 1e-4);
    checks.at_most("largest penetration / r_b over the increments", deepest_penetration(s), kCap);
  }
  checks.finish();
}

// ---------------------------------------------------------------------------------------------
// A 1+6 strand (core r_c = 0.28 mm, six wires r = 0.25 mm laid round it, touching it, one turn
// over L = 10 mm, lay angle alpha = 18.4 degrees), clamped at the bottom, its top ends moved
// together along the axis as by a rigid grip: pulled by 20 um (0.2 %) in 5 increments, then
// brought back in 5, with friction 0.2 between the wires. References:
//  * equilibrium: the grip's and the base's reactions balance to 1e-6 of the pull force;
//  * an upper bound of the axial stiffness: Hruska's E (A_c + 6 A cos^3 alpha) / L, the wires
//    stretched along their helices at a fixed lay radius (anything that lets the lay radius
//    shrink, the sections' Poisson contraction or the contacts yielding, lowers it), with 5 %
//    for the wires' own bending and torsion (O(sin^2 alpha (r/R)^2) = 2e-2) and friction;
//  * friction resists the release: at its end the strand is in compression or free, never
//    pulling on its grip (each stuck contact springs back, each slipped one keeps its slip in
//    the direction of the pull); up to 1e-4 of the peak force for the penalty's adaptation,
//    which makes the frictionless release end at 4e-6 of it.
// ---------------------------------------------------------------------------------------------
TEST(Robustness, strand_7_pull_release) {
  const double rc = 0.28e-3, r = 0.25e-3, length = 10e-3, pull = 20e-6;
  const double alpha = std::atan(2 * kPi * (rc + r) / length);
  const double hruska = kSteel * kPi * (rc * rc + 6 * r * r * std::pow(std::cos(alpha), 3)) / length;
  const CaseRun s = solve_file("strand_7_pull_release", 120);
  Checks checks("strand_7_pull_release");
  const char* wires[] = {"core", "w0", "w1", "w2", "w3", "w4", "w5"};
  const auto force_at = [&](const Snapshot& snap, const char* end) {
    Vec3 f = Vec3::Zero();
    for (const char* w : wires) f += s.reaction(snap, w, end);
    return f;
  };
  if (checks.converged(s)) {
    const std::vector<const Snapshot*> ends = s.step_ends();
    const Vec3 peak = force_at(*ends[0], "last");
    checks.at_most("|grip + base reactions| / pull force", (peak + force_at(*ends[0], "first")).norm() / peak.z(), 1e-6);
    checks.at_most("secant stiffness at the end of the pull [N/m]", peak.z() / pull, 1.05 * hruska);
    const Vec3 released = force_at(*ends[1], "last");
    checks.at_most("|grip + base reactions| at the end of the release / peak pull force",
                   (released + force_at(*ends[1], "first")).norm() / peak.z(), 1e-6);
    checks.at_most("grip force at the end of the release / peak pull force", released.z() / peak.z(), 1e-4);
  }
  checks.finish();
}

// ---------------------------------------------------------------------------------------------
// An open overhand knot (a polymer fiber, r = 0.5 mm, the trefoil's three crossings with straight
// tails; tests/verification/test_contact_verification.cpp) tightened by pulling its tails 5 mm
// apart each. References: the knot is free but for its ends, so the two end forces balance to
// 1e-6; the strands touch (self-contact at the end); the penetration stays within the cap at
// every converged increment.
// ---------------------------------------------------------------------------------------------
TEST(Robustness, overhand_knot) {
  const CaseRun s = solve_file("overhand_knot", 60);
  Checks checks("overhand_knot");
  if (checks.converged(s)) {
    const Snapshot& last = s.snaps.back();
    const Vec3 f0 = s.reaction(last, "knot", "first"), f1 = s.reaction(last, "knot", "last");
    checks.at_most("|first end's force + last end's| / |last end's|", (f0 + f1).norm() / f1.norm(), 1e-6);
    checks.at_least("contact zones at the end", last.info.contact.zones, 1);
    checks.at_most("largest penetration / r over the increments", deepest_penetration(s), kCap);
  }
  checks.finish();
}

}  // namespace
}  // namespace fibra::test
