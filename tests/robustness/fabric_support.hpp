#pragma once
/// Checks of the corpus's fabric cases (test_robustness_fabrics*.cpp, docs/robustness.md): edge
/// forces and loading curves from the edge bodies, the pattern's order at the crossings from the
/// fibers' positions, the relaxed state's equilibrium, crimp and the biaxial curves' shape.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <ostream>

#include "fibra/model/fabric_report.hpp"
#include "robustness/robustness_support.hpp"

namespace fibra::test {

inline constexpr double kCap = 0.05;  // default contact.max_penetration, a fraction of the radius
inline constexpr std::array<const char*, 4> kEdgeNames = {"edge.x-", "edge.x+", "edge.y-", "edge.y+"};

/// The four edge bodies of a fabric at one converged increment: centres and forces on the fabric.
struct Edges {
  std::array<Vec3, 4> centre{}, force{};
  /// |in-plane sum of the four edges' forces|: the fabric's unbalanced external force [N].
  double imbalance() const {
    Vec3 sum = Vec3::Zero();
    for (const Vec3& f : force) sum += f;
    return sum.head<2>().norm();
  }
  /// The largest edge force: the load scale [N].
  double scale() const {
    double m = 0;
    for (const Vec3& f : force) m = std::max(m, f.norm());
    return m;
  }
};

/// Edge bodies of a snapshot.
inline Edges edges(const CaseRun& s, const Snapshot& snap) {
  Edges e;
  for (int k = 0; k < 4; ++k) {
    const int b = s.model.body_index(kEdgeNames[k]);
    e.centre[k] = snap.info.bodies.at(b).center;
    e.force[k] = snap.info.bodies.at(b).force;
  }
  return e;
}

/// The last converged increment of step `step`, or null when the run did not end it.
inline const Snapshot* step_end(const CaseRun& s, const std::string& step) {
  for (const Snapshot& snap : s.snaps)
    if (snap.info.step == step && snap.info.step_end) return &snap;
  return nullptr;
}

/// One point of a loading curve (as curves_STEP.csv, strains from `origin`).
struct CurvePoint {
  double warp_strain = 0, weft_strain = 0, warp_force = 0, weft_force = 0, angle = 0, shear_force = 0;
  double imbalance = 0, scale = 0;
};

inline CurvePoint curve_point(const Edges& e, const Edges& origin) {
  CurvePoint p;
  const double lx = origin.centre[1].x() - origin.centre[0].x(), ly = origin.centre[3].y() - origin.centre[2].y();
  p.warp_strain = (e.centre[1].x() - e.centre[0].x()) / lx - 1.0;
  p.weft_strain = (e.centre[3].y() - e.centre[2].y()) / ly - 1.0;
  p.warp_force = e.force[1].x();
  p.weft_force = e.force[3].y();
  const double offset = (e.centre[3].x() - e.centre[2].x()) - (origin.centre[3].x() - origin.centre[2].x());
  p.angle = std::atan2(offset, e.centre[3].y() - e.centre[2].y()) * 180.0 / kPi;
  p.shear_force = e.force[3].x();
  p.imbalance = e.imbalance();
  p.scale = e.scale();
  return p;
}

/// The curve of test step `step`: the state at its start, then each settled load level; strains
/// and angles from the edges at `origin` (the step's own start when null).
inline std::vector<CurvePoint> curve(const CaseRun& s, const std::string& step, const Edges* origin = nullptr) {
  std::vector<CurvePoint> out;
  const Snapshot* before = nullptr;
  Edges start;
  for (const Snapshot& snap : s.snaps) {
    if (snap.info.step != step) {
      if (out.empty()) before = &snap;
      continue;
    }
    if (out.empty()) {
      if (!before) return out;
      start = edges(s, *before);
      out.push_back(curve_point(start, origin ? *origin : start));
    }
    if (snap.info.settled) out.push_back(curve_point(edges(s, snap), origin ? *origin : start));
  }
  return out;
}

/// The pattern's order at every crossing, measured from the fibers' positions: the mean z of
/// the warp's fibers cut at the weft's axis against that of the weft's fibers cut at the warp's.
struct Order {
  int crossings = 0;
  int wrong = 0;
  double least_gap = std::numeric_limits<double>::infinity();  ///< smallest z gap in the right sense [m]
};

inline Order crossing_order(const CaseRun& s, const VecX& q) {
  const FabricReport rep = fabric_report(s.c, s.model, q);
  auto axis = [&](const std::string& name) {
    for (const TowReport& t : rep.tows)
      if (t.name == name) return t.axis;
    ADD_FAILURE() << "no tow " << name << " in the fabric report";
    return 0.0;
  };
  const size_t rows = s.c.weave.size(), cols = s.c.weave.at(0).size();
  Order o;
  for (const TowSpec& warp : s.c.tows) {
    if (warp.direction != TowSpec::Direction::Warp) continue;
    for (const TowSpec& weft : s.c.tows) {
      if (weft.direction != TowSpec::Direction::Weft) continue;
      const double z_warp = tow_section(s.model, q, warp, axis(weft.name)).center_z;
      const double z_weft = tow_section(s.model, q, weft, axis(warp.name)).center_z;
      const bool warp_above = s.c.weave[weft.index % rows][warp.index % cols] == 1;
      const double gap = warp_above ? z_warp - z_weft : z_weft - z_warp;
      ++o.crossings;
      if (!(gap > 0)) ++o.wrong;
      o.least_gap = std::min(o.least_gap, gap);
    }
  }
  return o;
}

/// What every fabric case checks of its weave and relax steps:
/// - the weave step ends with every contact within the penetration cap (METHOD §6: the weaving
///   goes on until no interpenetration remains; the cap, 0.05 r, is what the solver accepts);
/// - every crossing in the pattern's order at the end of the relax step;
/// - the relaxed state in equilibrium: the in-plane forces of the four edge bodies (the only
///   in-plane loads on the fabric) sum to zero within 1e-6 of the largest of them (the corpus's
///   equilibrium tolerance; a relaxed state is an equilibrium without drag);
/// - with `symmetric` (a weave mapped onto itself by x -> -x, z -> -z: plain, basket), no shear
///   force: the x-force of the held top edge (edge.y+) within 1e-6 of the load scale, since
///   that mirror maps it to its opposite. Only the shear test asks it: the generator packs an
///   odd row of fibers above the other in every tow, so the samples are mirror images of
///   themselves at the scale of the tows only (docs/robustness.md).
/// Returns the relaxed state's edges (null when the run did not end its relax).
inline const Snapshot* check_woven_and_relaxed(Checks& checks, const CaseRun& s, bool symmetric) {
  const Snapshot* weave = step_end(s, "weave");
  if (!checks.expect(weave != nullptr, "the weave step ended: " + s.outcome())) return nullptr;
  checks.at_most("largest penetration / r at the end of the weave", weave->info.contact.max_penetration_ratio, kCap);
  const Snapshot* relax = step_end(s, "relax");
  if (!checks.expect(relax != nullptr, "the relax step ended: " + s.outcome())) return nullptr;
  const Order o = crossing_order(s, relax->q);
  checks.expect(o.wrong == 0, fmt::format("crossings in the pattern's order after the relax: {} of {} (smallest gap "
                                          "{:.3g} m)", o.crossings - o.wrong, o.crossings, o.least_gap));
  const Edges e = edges(s, *relax);
  checks.at_most("relaxed: |in-plane sum of the edge forces| / largest edge force", e.imbalance() / e.scale(), 1e-6);
  if (symmetric)
    checks.at_most("relaxed symmetric weave: |shear force (x-force of edge.y+)| / largest edge force",
                   std::abs(e.force[3].x()) / e.scale(), 1e-6);
  return relax;
}

/// The crimp of a balanced symmetric weave relaxed under equal tensions is the same in warp and
/// weft (swapping x and y with z -> -z maps the sample onto itself). Tolerance 1 % of the crimp:
/// the two directions differ only through the order in which the solver meets them (contact
/// detection, friction's stick and slip on the way); a real asymmetry (tows of one direction
/// held differently, one direction straighter) changes the crimp by tens of percent.
inline void check_crimp_balanced(Checks& checks, const CaseRun& s, const Snapshot& relax) {
  const FabricReport rep = fabric_report(s.c, s.model, relax.q);
  checks.relative("relaxed: warp crimp against weft crimp", rep.warp_crimp, rep.weft_crimp, 0.01);
  checks.at_least("relaxed: warp crimp (the weave is crimped)", rep.warp_crimp, 1e-4);
}

/// A biaxial curve: the force of each direction that is pulled grows at every level, with a
/// stiffness that does not fall (J-shaped: the crimp interchange first, then the fibers
/// stretching); every point an equilibrium. A curve point is settled when the drag force is
/// below the test step's tolerance, 1e-4 of the reference force (docs/case-file.md), so its edge
/// forces balance to about that: the equilibrium check asks 1e-4 of the load scale, and the
/// stiffness of a level may fall short of the last one by no more than the two points' measured
/// imbalances allow (their errors over the strain steps).
inline void check_biaxial_curve(Checks& checks, const std::vector<CurvePoint>& c, double ratio) {
  if (!checks.expect(c.size() >= 4, fmt::format("curve points: {} (at least the start and 3 levels)", c.size()))) return;
  double worst = 0;
  for (size_t k = 1; k < c.size(); ++k) worst = std::max(worst, c[k].imbalance / c[k].scale);
  checks.at_most("every load level: |in-plane sum of the edge forces| / largest edge force", worst, 1e-4);
  const int directions = ratio > 0 ? 2 : 1;
  for (int d = 0; d < directions; ++d) {
    const char* what = d == 0 ? "warp" : "weft";
    auto force = [&](size_t k) { return d == 0 ? c[k].warp_force : c[k].weft_force; };
    auto strain = [&](size_t k) { return d == 0 ? c[k].warp_strain : c[k].weft_strain; };
    int rising = 0, stiffening = 0;
    std::string first_bad;
    double last_stiffness = -std::numeric_limits<double>::infinity(), last_error = 0;
    for (size_t k = 1; k < c.size(); ++k) {
      const double ds = strain(k) - strain(k - 1);
      const double stiffness = (force(k) - force(k - 1)) / ds;
      const double error = (c[k].imbalance + c[k - 1].imbalance) / ds;
      if (force(k) > force(k - 1)) ++rising;
      else if (first_bad.empty()) first_bad = fmt::format("{} force falls at level {}", what, k);
      if (stiffness >= last_stiffness - error - last_error) ++stiffening;
      else if (first_bad.empty())
        first_bad = fmt::format("{} stiffness {:.4g} N at level {} below {:.4g} N at the level before", what, stiffness,
                                k, last_stiffness);
      last_stiffness = stiffness;
      last_error = error;
    }
    const int levels = static_cast<int>(c.size()) - 1;
    checks.expect(rising == levels && stiffening == levels,
                  fmt::format("{} curve rising at {} of {} levels, stiffness not falling at {} of {}{}{} (to {:.4g} N "
                              "at {:.4g} strain)",
                              what, rising, levels, stiffening, levels, first_bad.empty() ? "" : ": ", first_bad,
                              force(c.size() - 1), strain(c.size() - 1)));
  }
}


// ---------------------------------------------------------------------------------------------
// Biaxial tests of woven samples: each case is woven, relaxed, then pulled by a `biaxial` step
// named "pull" with its ratio; the checks above (weave cap, crossing order, relaxed equilibrium,
// J-shaped curves in equilibrium), the crossing order again at the end of the test, and for a
// balanced symmetric weave the crimp equal in warp and weft.
// ---------------------------------------------------------------------------------------------
struct BiaxialCase {
  const char* name;
  double ratio;    ///< the pull step's ratio, as in the case file
  bool balanced;   ///< also by swapping warp and weft (equal crimps)
  double budget;   ///< wall-time budget [s]
};

/// GoogleTest prints a parameterized case by its case file's name.
inline void PrintTo(const BiaxialCase& c, std::ostream* os) { *os << c.name; }

/// Runs a biaxial case and checks it (the comment above).
inline void run_biaxial_case(const BiaxialCase& p) {
  const CaseRun s = solve_file(p.name, p.budget);
  Checks checks(p.name);
  checks.converged(s);
  if (const Snapshot* relax = check_woven_and_relaxed(checks, s, false)) {
    if (p.balanced) check_crimp_balanced(checks, s, *relax);
    if (step_end(s, "pull")) {
      check_biaxial_curve(checks, curve(s, "pull"), p.ratio);
      const Order o = crossing_order(s, s.q);
      checks.expect(o.wrong == 0, fmt::format("crossings in the pattern's order after the test: {} of {}",
                                              o.crossings - o.wrong, o.crossings));
    }
  }
  checks.finish();
}

}  // namespace fibra::test
