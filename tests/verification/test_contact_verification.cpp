// Verification of contact and friction against analytic references (METHOD §2-4):
//  1. crossed fibers pressed together: contact force = applied load = the other fiber's
//     reactions; penetration capped by the penalty adaptation (examples/crossed_fibers);
//  2. a fiber pressed onto a parallel rigid one by a uniform line load: one contact line,
//     evenly spaced contact elements, uniform normal forces summing to the load;
//  3. three-point bending of a fiber by three stiff fibers: P L^3 / (48 E I)
//     (examples/three_point_bending);
//  4. capstan with friction: a rope pulled over a fixed curved rail slides as a whole at
//     T1 / T2 = exp(mu theta R_c / rho) (Euler's exp(mu theta) for a thin rope);
//  5. a helix tightened on a core, and an open overhand knot tightened by its tails;
//  and the slip flag of contacts.vtu. FIBRA_VERBOSE=1 prints every increment.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "fibra/contact/contact_manager.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/resolve.hpp"
#include "fibra/run/run_case.hpp"
#include "fibra/solver/static_solver.hpp"

namespace fibra::test {
namespace {

constexpr double kPi = std::numbers::pi;

/// One converged increment with its contact elements and their responses. The observer runs
/// after the increment's friction history is committed: the responses are evaluated from the
/// committed state (forces are those of the converged state; the `slip` flag is not usable,
/// the trial force equals the committed one).
struct Snapshot {
  IncrementInfo info;
  VecX q;
  std::vector<ContactElement> contacts;
  std::vector<ContactResponse> responses;
};

/// A solved contact case: every converged increment kept.
struct ContactSolved {
  Case c;
  Model model;
  RunResult result;
  SolverStats stats;
  VecX q;
  std::vector<Snapshot> snaps;
  std::vector<std::string> reaction_columns;
  double seconds = 0;

  bool converged() const { return result.status == RunResult::Status::Converged; }
  Index node(Index local, int fiber) const {
    const Fiber& f = model.fibers.at(fiber);
    return f.first_node + (local < 0 ? f.num_nodes + local : local);
  }
  Vec3 x0(const VecX& s, Index local, int fiber) const { return s.segment<3>(9 * node(local, fiber)); }
  Vec3 x0(Index local, int fiber) const { return x0(q, local, fiber); }
  Vec3 ref_x0(Index local, int fiber) const { return model.reference.segment<3>(9 * node(local, fiber)); }
  /// Value of reaction column `name` (history.csv naming) in snapshot `s`.
  double reaction(const Snapshot& s, const std::string& name) const {
    for (size_t i = 0; i < reaction_columns.size(); ++i)
      if (reaction_columns[i] == name) return s.info.reactions[i];
    ADD_FAILURE() << "no reaction column " << name;
    return 0.0;
  }
  Vec3 reaction(const Snapshot& s, const std::string& fiber, const std::string& node) const {
    const std::string p = "reaction:" + fiber + ":" + node + ":";
    return {reaction(s, p + "x"), reaction(s, p + "y"), reaction(s, p + "z")};
  }
  /// Fiber of a particle.
  int fiber_of(const Particle& p) const { return model.elements[p.element].fiber; }
  /// Position of a particle / of its section centre.
  Vec3 position(const VecX& s, const Particle& p) const {
    return particle_position(p, s.data() + model.elements[p.element].first_dof);
  }
  Vec3 centre(const VecX& s, const Particle& p) const {
    return particle_position(Particle{p.element, p.eta, 0.0, 0.0}, s.data() + model.elements[p.element].first_dof);
  }
  /// Largest penetration / smaller radius of the contact elements that a fresh detection finds
  /// at state s (particles facing each other at s), as the solver would see them if it
  /// detected again: the accepted state keeps the elements of the previous detection.
  double redetected_penetration_ratio(const VecX& s) const {
    ContactManager manager(model, c.contact);
    const std::vector<ContactElement> fresh = manager.detect(s, s, {});
    double worst = 0;
    for (const ContactElement& ce : fresh) {
      const double gap = ce.normal.dot(position(s, ce.b) - position(s, ce.a));
      const Section& sa = model.sections[model.elements[ce.a.element].section];
      const Section& sb = model.sections[model.elements[ce.b.element].section];
      worst = std::max(worst, -gap / std::min({sa.a, sa.b, sb.a, sb.b}));
    }
    return worst;
  }
  /// Smallest distance between the centroid lines of fibers fi and fj at state s, sampled at
  /// `per_element` points per element; for fi == fj, points closer than `exclusion` along the
  /// fiber (reference arc length) are skipped. Independent of the contact elements: the tubes
  /// overlap by r_i + r_j minus this distance (less any flattening of the sections).
  double min_centroid_distance(const VecX& s, int fi, int fj, double exclusion = 0, int per_element = 16) const {
    const auto samples = [&](int fiber) {
      std::vector<std::pair<double, Vec3>> out;
      const Fiber& f = model.fibers[fiber];
      const double h = f.length / f.num_elements;
      for (Index e = 0; e < f.num_elements; ++e)
        for (int k = 0; k < per_element; ++k) {
          const double eta = -1.0 + 2.0 * (k + 0.5) / per_element;
          out.push_back({h * (static_cast<double>(e) + 0.5 * (eta + 1)), centre(s, Particle{f.first_element + e, eta, 0, 0})});
        }
      return out;
    };
    const auto a = samples(fi), b = samples(fj);
    double best = 1e300;
    for (const auto& [sa, xa] : a)
      for (const auto& [sb, xb] : b)
        if (fi != fj || std::abs(sa - sb) >= exclusion) best = std::min(best, (xa - xb).norm());
    return best;
  }
};

/// Parses `toml` and solves it with StaticSolver, keeping every converged increment.
ContactSolved solve_contact(const std::string& toml, bool verbose = std::getenv("FIBRA_VERBOSE") != nullptr) {
  const auto t0 = std::chrono::steady_clock::now();
  ContactSolved s;
  s.c = parse_case_toml(toml, "contact.toml");
  ResolvedCase r = resolve_case(s.c);
  s.model = r.model;
  StaticSolver solver(s.c, r.model, std::move(r.bodies));
  s.reaction_columns = solver.reaction_columns();
  if (verbose) solver.set_progress([](const std::string& line) { std::printf("  %s\n", line.c_str()); });
  s.result = solver.run([&](const IncrementInfo& info, const VecX& q) {
    Snapshot snap{info, q, solver.problem().contacts(), solver.problem().contact_responses(q)};
    if (verbose)
      std::printf("    contact: zones %d elements %d pen %.4g fn %.6g det %d upd %d raises %d\n", info.contact.zones,
                  info.contact.elements, info.contact.max_penetration_ratio, info.contact.total_normal_force,
                  info.contact.detections, info.contact.normal_updates, info.contact.penalty_raises);
    s.snaps.push_back(std::move(snap));
  });
  s.stats = solver.stats();
  s.q = solver.state();
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (verbose)
    std::printf("  %s: %d increments, %d iterations, %d cuts, %.2f s %s\n", s.result.status_name().c_str(),
                s.stats.increments, s.stats.iterations, s.stats.cuts, s.seconds, s.result.message.c_str());
  return s;
}

/// Text of an example case file, examples/<name>/<name>.toml.
std::string example_toml(const std::string& name) {
  const std::string path = std::string(FIBRA_SOURCE_DIR) + "/examples/" + name + "/" + name + ".toml";
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot open " << path;
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Two crossed steel fibers (r = 0.5 mm, clamped at both ends, 20 mm long), fiber b laid on
/// fiber a, pressed onto it by moving its clamped ends down by `push`. `elements` per fiber;
/// b crosses a at x = `offset`.
std::string crossed_case(double push, int elements, double offset, double max_penetration, int increments) {
  return fmt::format(R"(
[[material]]
name = "steel"
young = 210e9
poisson = 0.3
[[fiber]]
name = "a"
material = "steel"
radius = 0.5e-3
points = [[-10e-3, 0, 0], [10e-3, 0, 0]]
elements = {1}
[[fiber]]
name = "b"
material = "steel"
radius = 0.5e-3
points = [[{2}, -10e-3, 1e-3], [{2}, 10e-3, 1e-3]]
elements = {1}
[[fix]]
fiber = "a"
node = "first"
[[fix]]
fiber = "a"
node = "last"
[[fix]]
fiber = "b"
node = "first"
[[fix]]
fiber = "b"
node = "last"
[contact]
max_penetration = {3}
[[step]]
name = "press"
increments = {4}
  [[step.displacement]]
  fiber = "b"
  node = "first"
  value = [0, 0, {0}]
  [[step.displacement]]
  fiber = "b"
  node = "last"
  value = [0, 0, {0}]
)",
                     -push, elements, offset, max_penetration, increments);
}

/// Checks shared by the crossed-fiber tests at every converged increment: each fiber in
/// equilibrium (a's supports carry what b's apply), and the contact force on b, summed from
/// the contact elements' normal forces along their normals, balances b's end reactions.
/// Returns the applied load (minus the z reaction of b's supports).
double check_crossed_equilibrium(const ContactSolved& s, const Snapshot& snap) {
  const Vec3 rb = s.reaction(snap, "b", "first") + s.reaction(snap, "b", "last");
  const Vec3 ra = s.reaction(snap, "a", "first") + s.reaction(snap, "a", "last");
  const double load = -rb.z();
  EXPECT_GT(load, 0.0);
  EXPECT_LT((ra + rb).norm(), 1e-6 * load) << "reactions a " << ra.transpose() << ", b " << rb.transpose();
  Vec3 on_b = Vec3::Zero();
  for (size_t k = 0; k < snap.contacts.size(); ++k) {
    const ContactElement& c = snap.contacts[k];
    const double sign = s.fiber_of(c.b) == 1 ? 1.0 : -1.0;  // normal points from a's particle to b's
    on_b += sign * snap.responses[k].normal_force * c.normal;
  }
  EXPECT_LT((on_b + rb).norm(), 1e-6 * load)
      << "contact force on b " << on_b.transpose() << " does not balance b's reactions " << rb.transpose();
  return load;
}

// 1. Crossed fibers pressed together, symmetric crossing (both fibers cross at their middle).
// References: equilibrium: the total normal force (history column contact:normal_force) equals
// the applied load, the sum of b's end reactions, and minus a's; by symmetry the normal stays
// vertical, so the scalar sum equals the load to the solver's residual (checked to 1e-6). The
// penalty adaptation keeps the penetration within max_penetration * r at every converged
// increment: the push is large enough that the initial penalty would exceed the cap (raises
// expected). 11 elements: the crossing is at the middle node of an element of each fiber, not
// on an element boundary (see CrossingAtElementBoundaries below).
// The case is examples/crossed_fibers (= crossed_case(0.4e-3, 11, 0, 0.01, 5)).
TEST(ContactCrossed, NormalForceEqualsLoadAndPenetrationIsCapped) {
  const double r = 0.5e-3, cap = 0.01;
  const ContactSolved s = solve_contact(example_toml("crossed_fibers"));
  ASSERT_TRUE(s.converged()) << s.result.message;
  int raises = 0;
  for (const Snapshot& snap : s.snaps) {
    const IncrementInfo& info = snap.info;
    SCOPED_TRACE(fmt::format("load factor {}", info.load_factor));
    raises += info.contact.penalty_raises;
    const double load = check_crossed_equilibrium(s, snap);
    EXPECT_NEAR(info.contact.total_normal_force, load, 1e-6 * load);
    EXPECT_EQ(info.contact.zones, 1) << "one crossing, one zone";
    EXPECT_GE(info.contact.elements, 1);
    EXPECT_LE(info.contact.max_penetration_ratio, cap * (1 + 1e-12));
    EXPECT_GT(info.contact.max_penetration_ratio, 0.0);
  }
  EXPECT_GT(raises, 0) << "the test is meant to exercise the penalty adaptation";
  const Snapshot& last = s.snaps.back();
  EXPECT_LE(last.info.contact.max_penetration_ratio, cap);
  // The cap is active, not trivially met (the adaptation aims at 70 % of it).
  EXPECT_GT(last.info.contact.max_penetration_ratio, 0.3 * cap);
  double deepest = 0;
  for (const ContactResponse& resp : last.responses) deepest = std::max(deepest, -resp.gap);
  EXPECT_NEAR(deepest / r, last.info.contact.max_penetration_ratio, 1e-12);
  std::printf("crossed: load %.8g N, sum of normal forces %.8g N, penetration/r %.5f (cap %.3f), %d raises, "
              "%d increments, %.2f s\n",
              -(s.reaction(last, "b", "first") + s.reaction(last, "b", "last")).z(), last.info.contact.total_normal_force,
              last.info.contact.max_penetration_ratio, cap, raises, s.stats.increments, s.seconds);
}

// Asymmetric crossing (b crosses a 0.37 mm from its middle, inside an element of a, at the
// middle node of an element of b): a's centroid line is sloped at the crossing, the normal tilts
// by ~2e-3 rad, so the scalar sum of normal forces exceeds the vertical load by 1/cos (2e-6); the
// vector sum of the contact forces on b must still balance b's reactions to the residual.
TEST(ContactCrossed, AsymmetricCrossingContactForceBalancesReactions) {
  const ContactSolved s = solve_contact(crossed_case(0.4e-3, 11, 0.37e-3, 0.01, 5));
  ASSERT_TRUE(s.converged()) << s.result.message;
  for (const Snapshot& snap : s.snaps) {
    SCOPED_TRACE(fmt::format("load factor {}", snap.info.load_factor));
    const double load = check_crossed_equilibrium(s, snap);
    EXPECT_EQ(snap.info.contact.zones, 1);
    // |N_z| >= cos(1e-2): the scalar sum is within 1e-4 of the load.
    EXPECT_GE(snap.info.contact.total_normal_force, load * (1 - 1e-6));
    EXPECT_LE(snap.info.contact.total_normal_force, load * (1 + 1e-4));
    EXPECT_LE(snap.info.contact.max_penetration_ratio, 0.01 * (1 + 1e-12));
  }
  const Snapshot& last = s.snaps.back();
  const double load = -(s.reaction(last, "b", "first") + s.reaction(last, "b", "last")).z();
  std::printf("asymmetric crossing: load %.8g N, sum of normal forces %.8g N (ratio - 1 = %.2e)\n", load,
              last.info.contact.total_normal_force, last.info.contact.total_normal_force / load - 1);
}

// The crossing exactly at an element boundary of both fibers (10 elements each, crossing at the
// middle node): one crossing must give one zone, and the increments must converge as smoothly
// as for a crossing inside elements.
TEST(ContactCrossed, CrossingAtElementBoundaries) {
  const ContactSolved s = solve_contact(crossed_case(0.2e-3, 10, 0.0, 0.02, 5));
  ASSERT_TRUE(s.converged()) << s.result.message;
  for (const Snapshot& snap : s.snaps) {
    SCOPED_TRACE(fmt::format("load factor {}", snap.info.load_factor));
    EXPECT_EQ(snap.info.contact.zones, 1);
    check_crossed_equilibrium(s, snap);
  }
  EXPECT_EQ(s.stats.cuts, 0) << "a 5-increment push of touching fibers should need no cut";
  EXPECT_EQ(s.stats.increments, 5);
}

/// Nodal forces of a uniform line load `q` [N/m] along z on a straight fiber of `elements`
/// quadratic elements of length h (consistent loads: q h / 6 at the ends of an element, 2 q h / 3
/// at its middle node), as [[step.load]] entries of fiber `name`.
std::string uniform_line_load(const std::string& name, int elements, double length, double q) {
  const double h = length / elements;
  std::string out;
  for (int n = 0; n <= 2 * elements; ++n) {
    const double f = n % 2 == 1 ? 2.0 * q * h / 3.0 : (n == 0 || n == 2 * elements ? q * h / 6.0 : q * h / 3.0);
    out += fmt::format("  [[step.load]]\n  fiber = \"{}\"\n  node = {}\n  force = [0, 0, {:.17g}]\n", name, n, f);
  }
  return out;
}

/// Sample mean and coefficient of variation.
std::pair<double, double> mean_cv(const std::vector<double>& v) {
  double mean = 0, var = 0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  for (double x : v) var += (x - mean) * (x - mean);
  var /= static_cast<double>(v.size());
  return {mean, std::sqrt(var) / std::abs(mean)};
}

// 2. Two parallel fibers: a rigid support line (fiber a, every node clamped) and fiber b laid on
// it (centre distance 2r - 1e-3 r: a tiny initial overlap, so that b never floats), loaded by a
// uniform line load q (consistent nodal forces). b's axial position is held at its middle node,
// its y at every node (a cylinder on a cylinder is neutrally stable sideways without friction)
// and its spin about its axis by g1z at the middle node; none of these carries load.
// Reference: with a rigid support, a uniform load and free ends, b translates uniformly (a beam
// on a uniform elastic foundation under a uniform load has w = q / k, no bending, even at free
// ends), so the contact line carries a uniform pressure q: one zone, contact elements at a
// uniform spacing, equal normal forces, summing to q L.
TEST(ContactParallel, UniformPressureAlongAContactLine) {
  const double r = 0.5e-3, length = 20e-3, q = 500.0;  // total load 10 N
  const int elements = 10;
  std::string toml = fmt::format(R"(
[[material]]
name = "steel"
young = 210e9
poisson = 0.3
[[fiber]]
name = "a"
material = "steel"
radius = {0}
section_direction = [0, 1, 0]
points = [[0, 0, 0], [{1}, 0, 0]]
elements = {2}
[[fiber]]
name = "b"
material = "steel"
radius = {0}
section_direction = [0, 1, 0]
points = [[0, 0, {3}], [{1}, 0, {3}]]
elements = {2}
[contact]
max_penetration = 0.05
[[fix]]
fiber = "b"
node = {2}
dofs = ["x", "y", "g1z"]
)",
                                 r, length, elements, 2 * r - 1e-3 * r);
  for (int n = 0; n <= 2 * elements; ++n) {
    toml += fmt::format("[[fix]]\nfiber = \"a\"\nnode = {}\n", n);
    if (n != elements) toml += fmt::format("[[fix]]\nfiber = \"b\"\nnode = {}\ndofs = [\"y\"]\n", n);
  }
  toml += "[[step]]\nname = \"press\"\nincrements = 2\n" + uniform_line_load("b", elements, length, -q);
  const ContactSolved s = solve_contact(toml);
  ASSERT_TRUE(s.converged()) << s.result.message;
  const Snapshot& last = s.snaps.back();
  const double total = q * length;
  EXPECT_EQ(last.info.contact.zones, 1);
  EXPECT_NEAR(last.info.contact.total_normal_force, total, 1e-6 * total);
  // Elements along the line, sorted by position.
  std::vector<std::pair<double, double>> xf;  // (x, normal force)
  for (size_t k = 0; k < last.contacts.size(); ++k) {
    const ContactElement& c = last.contacts[k];
    const Vec3 x = 0.5 * (s.position(last.q, c.a) + s.position(last.q, c.b));
    EXPECT_NEAR(c.normal.z(), s.fiber_of(c.b) == 1 ? 1.0 : -1.0, 1e-9);
    xf.push_back({x.x(), last.responses[k].normal_force});
  }
  std::sort(xf.begin(), xf.end());
  const int n = static_cast<int>(xf.size());
  // The spacing defaults to the radius (docs/theory/contact.md); the zone spans the whole
  // line, so there are L / spacing elements.
  const double spacing = r;
  EXPECT_EQ(n, static_cast<int>(std::lround(length / spacing)));
  std::vector<double> gaps, forces;
  for (int k = 0; k + 1 < n; ++k) gaps.push_back(xf[k + 1].first - xf[k].first);
  for (const auto& p : xf) forces.push_back(p.second);
  const auto [mean_gap, cv_gap] = mean_cv(gaps);
  const auto [mean_force, cv_force] = mean_cv(forces);
  EXPECT_LT(cv_gap, 1e-6) << "contact elements are not evenly spaced";
  // The elements cover the whole line: first and last half a spacing from the ends.
  EXPECT_NEAR(xf.front().first, 0.5 * mean_gap, 0.05 * mean_gap);
  EXPECT_NEAR(length - xf.back().first, 0.5 * mean_gap, 0.05 * mean_gap);
  EXPECT_NEAR(mean_gap, spacing, 1e-6 * spacing);
  // Uniform: b spans between discrete contact points and bends a little between them; the
  // measured spread is below 1 % (coefficient of variation 0.3 %), ends included.
  EXPECT_LT(cv_force, 0.01) << "normal forces along the line are not uniform";
  for (double f : forces) EXPECT_NEAR(f, total / n, 0.02 * total / n);
  EXPECT_NEAR(mean_force, total / n, 1e-6 * total / n);
  std::printf("parallel: %d elements, spacing %.4g mm (cv %.2g), force per element %.5g N (cv %.3g, min %.5g, max "
              "%.5g), sum %.8g N for q L = %.8g N, %.2f s\n",
              n, 1e3 * mean_gap, cv_gap, mean_force, cv_force, *std::min_element(forces.begin(), forces.end()),
              *std::max_element(forces.begin(), forces.end()), last.info.contact.total_normal_force, total, s.seconds);
  if (std::getenv("FIBRA_VERBOSE"))
    for (const auto& p : xf) std::printf("   x %.5f mm  fn %.6g N\n", 1e3 * p.first, p.second);
}

// A held load step's stability (IncrementInfo::negative_pivots, history.csv's
// stability:negative_pivots): the three-point bending of the robustness corpus, pushed in one
// increment whose Newton solve may take 4 iterations (it needs 9), fails it and is held (each
// level applied with a drag, repeated until the drag's force is negligible). An increment
// whose level settled is an equilibrium without the drag, and reports the negative pivots of
// its tangent without it: with friction 0.3 none (0: friction holds the beam, as the same case
// unheld reports); frictionless, the beam slides and spins freely on its supports, a mechanism
// whose tangent is singular: unknown (-1). The increments before a level settled report -1.
TEST(ContactThreePointBending, AHeldStepReportsItsSettledStabilityWithoutTheDrag) {
  std::ifstream in(std::string(FIBRA_SOURCE_DIR) + "/tests/robustness/cases/three_point_bending_mu0_unheld.toml");
  std::stringstream text;
  text << in.rdbuf();
  for (const double mu : {0.3, 0.0}) {
    std::string toml = text.str();
    const size_t contact = toml.find("[contact]\n");
    ASSERT_NE(contact, std::string::npos);
    toml.insert(contact + 10, fmt::format("friction = {}\n", mu));
    const size_t increments = toml.find("increments = 4");
    ASSERT_NE(increments, std::string::npos);
    toml.replace(increments, 14, "increments = 1");
    toml += "\n[solver]\nmax_iterations = 4\n";
    const Case c = parse_case_toml(toml, "held.toml");
    ResolvedCase r = resolve_case(c);
    StaticSolver solver(c, r.model, std::move(r.bodies));
    std::vector<IncrementInfo> seen;
    const RunResult result = solver.run([&](const IncrementInfo& info, const VecX&) { seen.push_back(info); });
    ASSERT_EQ(result.status, RunResult::Status::Converged) << "mu " << mu << ": " << result.message;
    ASSERT_GE(seen.size(), 2u) << "mu " << mu;
    EXPECT_GT(seen.front().drag, 0.0) << "mu " << mu << ": held from its first increment";
    int settled = 0;
    for (const IncrementInfo& info : seen) {
      settled += info.settled;
      EXPECT_EQ(info.negative_pivots, info.settled && mu > 0.0 ? 0 : -1)
          << "mu " << mu << ", increment " << info.increment << (info.settled ? " (settled)" : "");
    }
    EXPECT_GE(settled, 1) << "mu " << mu;
    EXPECT_TRUE(seen.back().settled) << "mu " << mu;
  }
}

// 3. Three-point bending (the case is examples/three_point_bending): a fiber (r = 0.5 mm, 40
// elements) resting on two stiff perpendicular support fibers 40 mm apart, pushed at mid-span by
// a third one (prescribed displacement of its clamped ends: 0.04 mm, then 0.08 mm). The beam is
// held by contact only along z; fixes carrying no load remove its free rigid motions (x, y,
// turning about z, spin about its axis: see the case file). Reference: Euler-
// Bernoulli, mid-span deflection w = P L^3 / (48 E I) relative to the supports, P the pusher's
// force (minus the sum of its end reactions), L = 40 mm the distance between the supports' axes.
// The deflection is that of the beam's centroid at mid-span relative to the mean of its
// centroid at the support crossings, so the penalty compliance and the supports' own bending
// drop out. Expected accuracy: shear adds 12 E I / (kappa G A L^2) = 0.14 %, geometric
// nonlinearity (w / L)^2 ~ 1e-5 at w = L / 500, the shift of the support contact points as the
// beam rotates there (r theta, theta = 3 w / L) 0.05 % of L: agreement within 0.5 % expected,
// checked to 1 %.
TEST(ContactThreePointBending, DeflectionMatchesBeamTheory) {
  const double r = 0.5e-3, young = 210e9, span = 40e-3;
  const double inertia = kPi * std::pow(r, 4) / 4;
  const ContactSolved s = solve_contact(example_toml("three_point_bending"));
  ASSERT_TRUE(s.converged()) << s.result.message;
  ASSERT_EQ(s.snaps.back().info.step_index, 1);
  // Beam nodes: 81 over [-25, 25] mm, 0.625 mm apart: node 8 at x = -20 mm, 40 at 0, 72 at 20.
  ASSERT_NEAR(s.ref_x0(8, 0).x(), -span / 2, 1e-12);
  ASSERT_NEAR(s.ref_x0(72, 0).x(), span / 2, 1e-12);
  for (const Snapshot& snap : s.snaps) {
    if (!snap.info.step_end) continue;
    SCOPED_TRACE(fmt::format("step {}", snap.info.step_index));
    const double force = -(s.reaction(snap, "pusher", "first") + s.reaction(snap, "pusher", "last")).z();
    const auto uz = [&](Index node) { return s.x0(snap.q, node, 0).z() - s.ref_x0(node, 0).z(); };
    const double w = 0.5 * (uz(8) + uz(72)) - uz(40);
    const double reference = force * std::pow(span, 3) / (48 * young * inertia);
    // Supports: each carries half of the load (sum of their end reactions), to the solver's
    // equilibrium tolerance: the residual is below 1e-8 of the reference force (about 66 N
    // here, the norm of all reactions), i.e. about 2e-6 of P; measured 1.1e-6 of P.
    const double left = (s.reaction(snap, "left", "first") + s.reaction(snap, "left", "last")).z();
    const double right = (s.reaction(snap, "right", "first") + s.reaction(snap, "right", "last")).z();
    EXPECT_NEAR(left, 0.5 * force, 1e-5 * force);
    EXPECT_NEAR(right, 0.5 * force, 1e-5 * force);
    EXPECT_EQ(snap.info.contact.zones, 3);
    EXPECT_NEAR(w / reference, 1.0, 0.01);
    EXPECT_LT(w, span / 400);  // small deflection
    std::printf("three-point bending: P = %.6g N, w = %.6g mm, P L^3/(48 E I) = %.6g mm, ratio %.5f; "
                "supports %.6g + %.6g N; pusher travel %.4g mm; %.2f s\n",
                force, 1e3 * w, 1e3 * reference, w / reference, left, right,
                -1e3 * (s.x0(snap.q, 0, 3).z() - s.ref_x0(0, 3).z()), s.seconds);
  }
}

/// Capstan: a steel rope of radius r laid over a fixed steel rail (every node clamped) bent into
/// a half circle (rail radius 0.5 mm, arc radius 10 mm) in the plane y = 0, over its outside:
/// the rope's centroid on the arc of radius rho = 10.5 mm + r (touching, overlap 1e-4 r), wrap
/// angle theta = pi, both rope ends at the equator pointing down. Step 1: dead loads T straight
/// down on both rope ends. Step 2: the first end is pulled down by `pull` on top of its load.
std::string capstan_case(double mu, double tension, double pull, int pull_increments, double r = 0.25e-3) {
  const double rail_r = 0.5e-3, arc = 10e-3;
  std::string toml = fmt::format(R"(
title = "Capstan: a rope pulled over a fixed curved rail"
[[material]]
name = "steel"
young = 210e9
poisson = 0.3
[[fiber]]
name = "rail"
material = "steel"
radius = {0}
arc = {{ center = [0, 0, 0], axis = [0, 1, 0], radius = {1}, start_angle = 0, angle = -180 }}
elements = 30
[[fiber]]
name = "rope"
material = "steel"
radius = {2}
section_direction = [0, 1, 0]
arc = {{ center = [0, 0, 0], axis = [0, 1, 0], radius = {3}, start_angle = 0, angle = -180 }}
elements = 30
[contact]
friction = {4}
max_penetration = 0.05
spacing = {5}  # contact elements every half rope element (calibrated with the 1 um pull steps)
# The rope is held by contact and friction only; out of its plane it is held by y at every node
# and its spin about its axis by g1z at its middle node (neither carries load).
[[fix]]
fiber = "rope"
node = 30
dofs = ["y", "g1z"]
)",
                                 rail_r, arc, r, arc + rail_r + r - 1e-4 * r, mu,
                                 std::max(r, 0.5 * kPi * (arc + rail_r + r) / 30.0));
  for (int n = 0; n <= 60; ++n) {
    toml += fmt::format("[[fix]]\nfiber = \"rail\"\nnode = {}\n", n);
    if (n != 30) toml += fmt::format("[[fix]]\nfiber = \"rope\"\nnode = {}\ndofs = [\"y\"]\n", n);
  }
  toml += fmt::format(R"(
[[step]]
name = "tension"
increments = 2
  [[step.load]]
  fiber = "rope"
  node = "first"
  force = [0, 0, {0}]
  [[step.load]]
  fiber = "rope"
  node = "last"
  force = [0, 0, {0}]
[[step]]
name = "pull"
increments = {2}
  [[step.displacement]]
  fiber = "rope"
  node = "first"
  value = ["free", "free", {1}]
)",
                      -tension, -pull, pull_increments);
  return toml;
}

// 4. Capstan. The rope, tensioned by T on both ends, has its first end pulled (displacement
// control, on top of its dead load): T1 = T - R_z (R the reaction of the prescribed end) grows
// while the rope sticks and stops growing once it slides as a whole. Reference: Euler's
// capstan equation T1 / T2 = exp(mu theta), theta = pi, for a thin rope. For a rope of finite
// radius r the friction acts on its surface, at radius R_c = rho - r from the centre, and the
// tension at its centroid (radius rho): moments about the centre give rho dT = mu R_c dN (dN
// the normal force on an arc element, = T dphi), so T1 / T2 = exp(mu theta R_c / rho), up to
// O(mu^2 r / rho) from the shear that the surface friction puts in the rope. The three rope
// radii below (R_c / rho = 0.991, 0.977, 0.955) separate the two references: exp(mu theta) is
// 0.9 % to 4.4 % above the thick-rope one. Discretisation: contact elements about 0.55 mm apart
// (dphi = 0.05): a product of (1 + mu dphi R_c / rho) factors, 0.3 % below the exponential.
// Checks: the ratio at the onset of gross slip (first increment with every contact element on
// the Coulomb cone) and at the end of the pull within 1.5 % of exp(mu theta R_c / rho) (measured
// 0.5 % to 0.9 % below) and within 10 % of exp(mu theta); the rope partly sticks, with a lower
// ratio, in the first increment of the pull.
class ContactCapstan : public ::testing::TestWithParam<double> {};

TEST_P(ContactCapstan, SlipOnsetAtEulerRatio) {
  const double r = GetParam();
  const double mu = 0.3, tension = 1.0, rho = 10.5e-3 + r;
  const double euler = std::exp(mu * kPi), thick = std::exp(mu * kPi * (rho - r) / rho);
  const ContactSolved s = solve_contact(capstan_case(mu, tension, 10e-6, 10, r));
  ASSERT_TRUE(s.converged()) << s.result.message;
  double onset = 0, first_ratio = 0, last_ratio = 0, max_ratio = 0;
  int slipping_at_end = 0, elements_at_end = 0;
  for (const Snapshot& snap : s.snaps) {
    if (snap.info.step_index != 1) continue;
    const double t1 = tension - s.reaction(snap, "rope", "first").z();
    const double ratio = t1 / tension;
    // Slipping elements: friction on the Coulomb cone. (ContactResponse::slip is not usable
    // here: the snapshot's responses are evaluated after the increment's friction history was
    // committed, where the trial force equals the committed one.)
    int slipping = 0, loaded = 0;
    for (const ContactResponse& resp : snap.responses)
      if (resp.normal_force > 0) {
        ++loaded;
        slipping += resp.friction.norm() >= (1 - 1e-6) * mu * resp.normal_force ? 1 : 0;
      }
    if (first_ratio == 0) {
      first_ratio = ratio;
      EXPECT_LT(slipping, loaded) << "the rope slides at once";
    }
    if (onset == 0 && loaded > 0 && slipping == loaded) onset = ratio;
    last_ratio = ratio;
    max_ratio = std::max(max_ratio, ratio);
    slipping_at_end = slipping;
    elements_at_end = loaded;
    EXPECT_EQ(snap.info.contact.zones, 1);
    EXPECT_LE(snap.info.contact.max_penetration_ratio, 0.05);
    if (std::getenv("FIBRA_VERBOSE"))
      std::printf("   pull %.3g um  T1/T2 %.5f  slipping %d / %d\n",
                  1e6 * -(s.x0(snap.q, 0, 1).z() - s.ref_x0(0, 1).z()), ratio, slipping, loaded);
  }
  std::printf("capstan r = %.2f mm: T1/T2 at slip onset %.5f, at the end %.5f (max %.5f), first increment %.5f; "
              "exp(mu theta R_c/rho) = %.5f (ratio %.4f), exp(mu theta) = %.5f (ratio %.4f); %d / %d elements "
              "slipping; %d increments, %.2f s\n",
              1e3 * r, onset, last_ratio, max_ratio, first_ratio, thick, last_ratio / thick, euler,
              last_ratio / euler, slipping_at_end, elements_at_end, s.stats.increments, s.seconds);
  ASSERT_GT(onset, 0) << "the rope never slid as a whole";
  EXPECT_EQ(slipping_at_end, elements_at_end);
  EXPECT_GT(elements_at_end, 50);
  EXPECT_NEAR(onset / thick, 1.0, 0.015);
  EXPECT_NEAR(last_ratio / thick, 1.0, 0.015);
  EXPECT_NEAR(max_ratio / thick, 1.0, 0.015);
  EXPECT_NEAR(onset / euler, 1.0, 0.10);
  EXPECT_LT(first_ratio, 0.9 * thick);
}

INSTANTIATE_TEST_SUITE_P(RopeRadius, ContactCapstan, ::testing::Values(0.1e-3, 0.25e-3, 0.5e-3),
                         [](const auto& p) { return fmt::format("r{}um", static_cast<int>(std::lround(p.param * 1e6))); });

// 5a. A fiber wound around a straight one (two turns of a helix of radius r1 + r2 - 1e-3 r2,
// pitch 4 mm, about a core of radius r1 clamped at both ends), tightened by pulling its ends
// apart along the axis (their x, y held). References: the helix presses onto the core all along
// (one contact line over its whole length, every contact element loaded); the penetration stays
// below the cap; the axial forces at the two ends balance (the core carries no net axial force
// without friction).
TEST(ContactWinding, HelixTightenedOnACore) {
  const double r1 = 0.5e-3, r2 = 0.25e-3, pitch = 4e-3, turns = 2, cap = 0.05;
  const double pull = 50e-6;
  const std::string toml = fmt::format(R"(
[[material]]
name = "steel"
young = 210e9
poisson = 0.3
[[fiber]]
name = "core"
material = "steel"
radius = {0}
points = [[0, 0, -2e-3], [0, 0, 10e-3]]
elements = 12
[[fiber]]
name = "helix"
material = "steel"
radius = {1}
helix = {{ center = [0, 0, 0], axis = [0, 0, 1], radius = {2}, pitch = {3}, turns = {4} }}
elements = 48
[contact]
max_penetration = {5}
[[fix]]
fiber = "core"
node = "first"
[[fix]]
fiber = "core"
node = "last"
[[step]]
name = "pull"
increments = 4
  [[step.displacement]]
  fiber = "helix"
  node = "first"
  value = [0, 0, {6}]
  [[step.displacement]]
  fiber = "helix"
  node = "last"
  value = [0, 0, {7}]
)",
                                       r1, r2, r1 + r2 - 1e-3 * r2, pitch, turns, cap, -pull, pull);
  const ContactSolved s = solve_contact(toml);
  ASSERT_TRUE(s.converged()) << s.result.message;
  const Snapshot& last = s.snaps.back();
  const double helix_length = turns * std::hypot(2 * kPi * (r1 + r2), pitch);
  // Contact elements: arc length of their particle on the helix, normal force.
  std::vector<std::pair<double, double>> sf;
  for (size_t k = 0; k < last.contacts.size(); ++k) {
    const ContactElement& c = last.contacts[k];
    const Particle& p = s.fiber_of(c.a) == 1 ? c.a : c.b;
    EXPECT_NE(s.fiber_of(c.a), s.fiber_of(c.b)) << "no self-contact expected";
    const Fiber& f = s.model.fibers[1];
    const double h = f.length / f.num_elements;
    sf.push_back({h * (static_cast<double>(p.element - f.first_element) + 0.5 * (p.eta + 1)), last.responses[k].normal_force});
  }
  std::sort(sf.begin(), sf.end());
  ASSERT_FALSE(sf.empty());
  double largest_gap = 0, min_force = 1e300, max_force = 0;
  for (size_t k = 0; k + 1 < sf.size(); ++k) largest_gap = std::max(largest_gap, sf[k + 1].first - sf[k].first);
  int loaded = 0;
  for (const auto& [arc, f] : sf) {
    loaded += f > 0 ? 1 : 0;
    min_force = std::min(min_force, f);
    max_force = std::max(max_force, f);
  }
  const Vec3 r_first = s.reaction(last, "helix", "first"), r_last = s.reaction(last, "helix", "last");
  std::printf("helix: %d zones, %d contact elements (%d loaded) over s = %.3g..%.3g of %.3g mm, largest spacing "
              "%.3g mm, normal force %.4g..%.4g N, sum %.4g N; end forces z %.5g, %.5g N; penetration/r %.4f; %d "
              "increments, %d iterations, %.2f s\n",
              last.info.contact.zones, static_cast<int>(sf.size()), loaded, 1e3 * sf.front().first, 1e3 * sf.back().first,
              1e3 * helix_length, 1e3 * largest_gap, min_force, max_force, last.info.contact.total_normal_force,
              r_first.z(), r_last.z(), last.info.contact.max_penetration_ratio, s.stats.increments, s.stats.iterations,
              s.seconds);
  EXPECT_EQ(last.info.contact.zones, 1);
  EXPECT_LT(sf.front().first, 0.05 * helix_length);
  EXPECT_GT(sf.back().first, 0.95 * helix_length);
  EXPECT_LT(largest_gap, 2.0 * std::max(r2, 0.5 * helix_length / 48));
  EXPECT_EQ(loaded, static_cast<int>(sf.size()));
  for (const Snapshot& snap : s.snaps) EXPECT_LE(snap.info.contact.max_penetration_ratio, cap * (1 + 1e-12));
  // Independent of the contact elements: the helix's centroid line stays at r1 + r2 from the
  // core's, less the cap (2 cap r2 allows for the flattening of the sections).
  const double closest = s.min_centroid_distance(last.q, 0, 1);
  std::printf("helix: closest centroid distance %.5f (r1 + r2) = r1 + r2 - %.4f r2\n", closest / (r1 + r2), (r1 + r2 - closest) / r2);
  EXPECT_GE(closest, r1 + r2 - 2 * cap * r2);
  EXPECT_LE(s.redetected_penetration_ratio(last.q), cap);
  EXPECT_GT(r_last.z(), 0.0);
  // The core's axial reaction is not exactly zero: each normal joins the centres of the two
  // sections cut by a plane normal to the bisector of the tangents, which for a helix on a core is
  // not exactly radial; within 1e-4 of the end force.
  EXPECT_NEAR(r_first.z(), -r_last.z(), 1e-4 * r_last.z());
}

/// An open overhand knot: the trefoil (sin t + 2 sin 2t, cos t - 2 cos 2t, -sin 3t) scaled by
/// `scale`, for t in [pi + 0.8, 3 pi - 0.8] (the lobe around t = pi is removed; the three
/// crossings remain), with straight tails of length 4 * scale along the end tangents. Strands
/// are 1.214 * scale apart at the crossings, the tails stay clear of the knot.
struct OpenKnot {
  std::vector<Vec3> points;
  Vec3 out_first, out_last;  ///< unit directions of the tails, outwards
};
OpenKnot open_overhand_knot(double scale, int samples) {
  const auto p = [&](double t) -> Vec3 {
    return Vec3(std::sin(t) + 2 * std::sin(2 * t), std::cos(t) - 2 * std::cos(2 * t), -std::sin(3 * t)) * scale;
  };
  const auto dp = [&](double t) -> Vec3 {
    return Vec3(std::cos(t) + 4 * std::cos(2 * t), -std::sin(t) + 4 * std::sin(2 * t), -3 * std::cos(3 * t)).normalized();
  };
  const double t0 = kPi + 0.8, t1 = 3 * kPi - 0.8, tail = 4 * scale;
  OpenKnot k;
  k.out_first = -dp(t0);
  k.out_last = dp(t1);
  k.points.push_back(p(t0) + tail * k.out_first);
  for (int i = 0; i < samples; ++i) k.points.push_back(p(t0 + (t1 - t0) * i / (samples - 1)));
  k.points.push_back(p(t1) + tail * k.out_last);
  return k;
}

std::string points_toml(const std::vector<Vec3>& pts) {
  std::string out = "[";
  for (size_t i = 0; i < pts.size(); ++i)
    out += fmt::format("{}[{:.17g}, {:.17g}, {:.17g}]", i ? ", " : "", pts[i].x(), pts[i].y(), pts[i].z());
  return out + "]";
}

/// The open overhand knot (r = 0.5 mm, 60 elements, strands 1.21 mm apart at its three crossings)
/// with its tails pulled apart by `pull` each (ends displaced along the tails, their sections
/// held, which removes the rigid rotation about the line of the ends), solved; prints the
/// increments and the closest approaches of the strands.
ContactSolved solve_knot(double pull, int increments, double r, double cap) {
  const OpenKnot knot = open_overhand_knot(1e-3, 200);
  const Vec3 u0 = pull * knot.out_first, u1 = pull * knot.out_last;
  const std::string toml = fmt::format(R"(
[[material]]
name = "polymer"
young = 1e9
poisson = 0.3
[[fiber]]
name = "knot"
material = "polymer"
radius = {0}
points = {1}
elements = 60
[contact]
max_penetration = {2}
[[fix]]
fiber = "knot"
node = "first"
dofs = "sections"
[[fix]]
fiber = "knot"
node = "last"
dofs = "sections"
[[step]]
name = "tighten"
increments = {9}
max_increments = 2000
  [[step.displacement]]
  fiber = "knot"
  node = "first"
  value = [{3}, {4}, {5}]
  [[step.displacement]]
  fiber = "knot"
  node = "last"
  value = [{6}, {7}, {8}]
)",
                                       r, points_toml(knot.points), cap, u0.x(), u0.y(), u0.z(), u1.x(), u1.y(),
                                       u1.z(), increments);
  ContactSolved s = solve_contact(toml);
  std::printf("knot, pull %.1f mm per end: %s, %d increments, %d iterations, %d cuts, %.2f s; last converged load "
              "factor %.4g %s\n",
              1e3 * pull, s.result.status_name().c_str(), s.stats.increments, s.stats.iterations, s.stats.cuts,
              s.seconds, s.snaps.empty() ? 0.0 : s.snaps.back().info.load_factor, s.result.message.c_str());
  for (const Snapshot& snap : s.snaps) {
    if (!std::getenv("FIBRA_VERBOSE") && &snap != &s.snaps.back()) continue;
    const double closest = s.min_centroid_distance(snap.q, 0, 0, 3e-3);
    std::printf("   load %.4f: zones %d, elements %d, penetration/r %.4f (detected again: %.4f; strands' centroids "
                "%.4f r apart: overlap %.4f r), sum of normal forces %.4g N, pull force %.4g N, %d iterations\n",
                snap.info.load_factor, snap.info.contact.zones, snap.info.contact.elements,
                snap.info.contact.max_penetration_ratio, s.redetected_penetration_ratio(snap.q), closest / r, 2 - closest / r,
                snap.info.contact.total_normal_force, s.reaction(snap, "knot", "last").dot(knot.out_last),
                snap.info.iterations);
  }
  return s;
}

/// Checks on a converged knot: self-contact, penetration within the cap at every increment by
/// the contact elements' own measure, by the elements a new detection finds at the accepted
/// state, and, independently of contact elements, by the distance between strands (points
/// farther than 3 mm apart along the fiber; 2 cap r allows for the flattening of the sections);
/// the end forces in balance (the knot is otherwise free).
void check_knot(const ContactSolved& s, double r, double cap) {
  ASSERT_TRUE(s.converged()) << s.result.message;
  const Snapshot& last = s.snaps.back();
  EXPECT_GE(last.info.contact.zones, 1);
  for (const Snapshot& snap : s.snaps) {
    EXPECT_LE(snap.info.contact.max_penetration_ratio, cap * (1 + 1e-12)) << "load factor " << snap.info.load_factor;
    EXPECT_LE(s.redetected_penetration_ratio(snap.q), cap) << "load factor " << snap.info.load_factor;
    EXPECT_GE(s.min_centroid_distance(snap.q, 0, 0, 3e-3), (2 - 2 * cap) * r) << "load factor " << snap.info.load_factor;
  }
  for (const ContactElement& c : last.contacts) EXPECT_EQ(s.fiber_of(c.a), s.fiber_of(c.b));
  const Vec3 f0 = s.reaction(last, "knot", "first"), f1 = s.reaction(last, "knot", "last");
  EXPECT_LT((f0 + f1).norm(), 1e-6 * f1.norm());
  EXPECT_GT(last.info.contact.total_normal_force, 0.0);
}

// 5b. An open overhand knot tightened by pulling its tails 2 mm apart each (1.2 N at the end):
// the strands close in at one crossing (touching from load factor 0.4, contact zone with 3
// elements, overlap 0.03 r at the end). References: converges; self-contact; penetration within
// the cap, also by the strands' distance; end forces in balance.
TEST(ContactWinding, OverhandKnotTightens) {
  const double r = 0.5e-3, cap = 0.05;
  const ContactSolved s = solve_knot(2e-3, 20, r, cap);
  check_knot(s, r, cap);
}

// The same knot pulled further (5 mm per end). Disabled: it fails with the current library
// (measured with the missing analyze() of the solver's new-element branch added; without it the
// run stops at the first contact, load factor 0.18). From 2.4 mm per end (load factor 0.475) the
// accepted increments keep contact elements whose particles no longer face each other: the
// solver reports penetrations of 0.023-0.032 r, a new detection at the same states finds up to
// 0.20 r and the strands' centroids are 1.79 r apart (overlap 0.21 r, four times the cap) at
// load factor 0.575. The next increment fails at any size: its first detection sees that
// overlap, the first Newton solve turns the normals by 0.14-0.17 rad, and the normal loop (each
// update turning them 0.6-0.8 times as much as the previous one) does not settle within
// max_normal_updates = 12. (With max_normal_updates = 60 the run reached load factor 0.644 and
// then failed in the detection loop: 5 and 6 elements alternating, one fresh each time.)
// Since then the increment is accepted only when a fresh detection sees no penetration beyond
// the cap and no new penetrating element, and max_normal_updates defaults to 30: the run now
// reaches load factor 0.677 with every accepted state within the cap (fresh detection 0.047 r
// at most), then fails: the contact set of the tightening crossing keeps changing (6 and 7
// elements) and the loops do not settle. Since the contact loop raises the zones that a fresh
// detection finds beyond the cap (docs/theory/contact.md, "Layouts that alternate"), the run
// reaches its end (5 mm per end) and fails two checks only: the strands' centroids come to
// 0.942-0.950 mm apart at three snapshots where the cap allows 0.95 mm (between the contact
// elements, up to 1.03 times the cap), and the tightened knot has one contact zone where the
// test asks for two. Still a known limit. Run with --gtest_also_run_disabled_tests.
TEST(ContactWinding, DISABLED_OverhandKnotTightensFurther) {
  const double r = 0.5e-3, cap = 0.05;
  const ContactSolved s = solve_knot(5e-3, 40, r, cap);
  check_knot(s, r, cap);
  EXPECT_GE(s.snaps.back().info.contact.zones, 2);
}

/// Named point-data arrays of a .vtu written by OutputWriter (appended raw data, UInt64
/// headers), as raw bytes.
std::map<std::string, std::string> read_vtu_arrays(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  std::map<std::string, std::string> out;
  const size_t appended = text.find("<AppendedData encoding=\"raw\">");
  if (appended == std::string::npos) return out;
  const size_t base = text.find('_', appended) + 1;
  const auto attribute = [](const std::string& tag, const std::string& name) {
    const size_t p = tag.find(" " + name + "=\"");
    if (p == std::string::npos) return std::string();
    const size_t b = p + name.size() + 3;
    return tag.substr(b, tag.find('"', b) - b);
  };
  for (size_t pos = text.find("<DataArray"); pos != std::string::npos && pos < appended;
       pos = text.find("<DataArray", pos + 1)) {
    const std::string tag = text.substr(pos, text.find('>', pos) - pos);
    const size_t offset = std::stoull(attribute(tag, "offset"));
    std::uint64_t bytes = 0;
    std::memcpy(&bytes, text.data() + base + offset, sizeof bytes);
    out[attribute(tag, "Name")] = text.substr(base + offset + 8, bytes);
  }
  return out;
}

template <class T>
std::vector<T> as_vector(const std::string& bytes) {
  std::vector<T> v(bytes.size() / sizeof(T));
  std::memcpy(v.data(), bytes.data(), v.size() * sizeof(T));
  return v;
}

// The slip flag written to contacts_NNNNNN.vtu (docs/outputs.md: 1 on the Coulomb cone, 0
// sticking) at the end of the capstan pull, where the rope slides as a whole: every contact
// element's friction is on the cone (|friction| = mu normal_force, from the same file), so every
// flag must be 1.
TEST(ContactOutput, SlipFlagMarksFrictionOnTheCone) {
  namespace fs = std::filesystem;
  const double mu = 0.3;
  Case c = parse_case_toml(capstan_case(mu, 1.0, 10e-6, 10, 0.25e-3), "capstan.toml");
  const fs::path dir = fs::temp_directory_path() / fmt::format("fibra_contact_slip_{}", static_cast<long>(::getpid()));
  std::error_code ec;
  fs::remove_all(dir, ec);
  RunOptions options;
  options.out_dir = dir.string();
  const RunReport report = run_case(c, options);
  ASSERT_EQ(report.result.status, RunResult::Status::Converged) << report.result.message;
  fs::path last;
  for (const fs::directory_entry& e : fs::directory_iterator(dir / "contacts"))
    if (e.path().filename().string().rfind("contacts_", 0) == 0 && e.path().extension() == ".vtu" &&
        (last.empty() || e.path().filename() > last.filename()))
      last = e.path();
  ASSERT_FALSE(last.empty()) << "no contacts/contacts_*.vtu in " << dir;
  const auto arrays = read_vtu_arrays(last);
  ASSERT_TRUE(arrays.count("slip") && arrays.count("friction") && arrays.count("normal_force")) << last;
  const std::vector<std::int32_t> slip = as_vector<std::int32_t>(arrays.at("slip"));
  const std::vector<double> friction = as_vector<double>(arrays.at("friction"));
  const std::vector<double> force = as_vector<double>(arrays.at("normal_force"));
  ASSERT_EQ(friction.size(), 3 * slip.size());
  ASSERT_GT(slip.size(), 50u);
  int on_cone = 0, flagged = 0;
  for (size_t k = 0; k < slip.size(); ++k) {
    const double ft = Vec3(friction[3 * k], friction[3 * k + 1], friction[3 * k + 2]).norm();
    const bool cone = force[k] > 0 && ft >= (1 - 1e-6) * mu * force[k];
    on_cone += cone ? 1 : 0;
    flagged += slip[k] ? 1 : 0;
    EXPECT_EQ(slip[k] != 0, cone) << "element " << k << ": |friction| " << ft << ", mu fn " << mu * force[k];
  }
  std::printf("contacts output %s: %zu elements, %d with friction on the cone, %d flagged slip\n",
              last.filename().c_str(), slip.size(), on_cone, flagged);
  EXPECT_EQ(on_cone, static_cast<int>(slip.size()));
  fs::remove_all(dir, ec);
}

}  // namespace
}  // namespace fibra::test
