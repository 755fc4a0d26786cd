// Contact detection: broad phase against brute force, and proximity zones / contact elements
// on the geometric cases the method must handle: crossings (also at the end of a fiber and
// between radii 1:10), parallel and nearly parallel fibers, a tangent arc, a helix wound
// around a straight fiber, self-contact of a coiled fiber and of a self-crossing path, none
// between neighbouring elements; deterministic for any thread count. The normal update: only
// the elements that carry force decide whether the normals settled.
#include <gtest/gtest.h>

#include <omp.h>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <utility>

#include "fibra/contact/broad_phase.hpp"
#include "fibra/contact/contact_manager.hpp"
#include "fibra/contact/detection.hpp"
#include "fibra/model/model.hpp"

namespace fibra {
namespace {

// Detection parameters with contact elements every (smallest) radius, stated explicitly (the
// default) since these tests count them.
DetectionParams radius_spacing(const Model& model) {
  DetectionParams p;
  p.spacing = 1e300;
  for (const Section& sec : model.sections) p.spacing = std::min({p.spacing, sec.a, sec.b});
  return p;
}

constexpr double kPi = std::numbers::pi;

Case base_case() {
  Case c;
  MaterialSpec m;
  m.name = "m";
  m.young = 1e9;
  m.poisson = 0.3;
  c.materials.push_back(m);
  return c;
}

// A fiber of material "m" (names moved in whole: GCC 12 warns falsely on literal assignment).
FiberSpec fiber(std::string name, double r, int elements) {
  FiberSpec f;
  f.name = std::move(name);
  f.material = std::string("m");
  f.radius = r;
  f.elements = elements;
  return f;
}

FiberSpec polyline(std::string name, std::vector<Vec3> points, double r, int elements) {
  FiberSpec f = fiber(std::move(name), r, elements);
  f.path.kind = PathSpec::Kind::Polyline;
  f.path.points = std::move(points);
  return f;
}

// The detection of the model's reference state, contact elements every `spacing` along a zone.
Detection detect_every(const Model& model, double spacing) {
  DetectionParams params;
  params.spacing = spacing;
  ContactDetector detector(model, params);
  return detector.detect(model.reference);
}

FiberSpec helix(std::string name, double radius, double pitch, double turns, double r, int elements) {
  FiberSpec f = fiber(std::move(name), r, elements);
  f.path.kind = PathSpec::Kind::Helix;
  f.path.center = Vec3::Zero();
  f.path.axis = Vec3::UnitZ();
  f.path.radius = radius;
  f.path.pitch = pitch;
  f.path.turns = turns;
  return f;
}

const double* element_dofs(const Model& model, const VecX& q, Index e) {
  return q.data() + model.elements[e].first_dof;
}
Vec3 position(const Model& model, const VecX& q, const Particle& p) {
  return particle_position(p, element_dofs(model, q, p.element));
}
Vec3 centre(const Model& model, const VecX& q, const Particle& p) {
  return particle_position(Particle{p.element, p.eta, 0.0, 0.0}, element_dofs(model, q, p.element));
}
double gap(const Model& model, const VecX& q, const ContactElement& c) {
  return (position(model, q, c.b) - position(model, q, c.a)).dot(c.normal);
}

// Checks shared by every case: zones and elements consistent, particles on the section borders
// facing each other, normal from centre a to centre b.
void check_consistency(const Model& model, const VecX& q, const Detection& det, double border_tolerance = 1e-12,
                       double facing = 0.7) {
  int expected_first = 0;
  for (size_t z = 0; z < det.zones.size(); ++z) {
    const ProximityZone& zone = det.zones[z];
    EXPECT_EQ(zone.first_element, expected_first);
    EXPECT_GE(zone.num_elements, 1);
    // Fiber i is the sampled one: the lower index, or the thinner one when it is over 3 times
    // thinner (section radius max(a, b), as the broad phase takes it).
    auto radius = [&](int f) {
      const Section& sec = model.sections[model.fibers[f].section];
      return std::max(sec.a, sec.b);
    };
    EXPECT_TRUE(zone.fiber_i <= zone.fiber_j || 3.0 * radius(zone.fiber_i) < radius(zone.fiber_j))
        << zone.fiber_i << " " << zone.fiber_j;
    EXPECT_FALSE(zone.fiber_i < zone.fiber_j && 3.0 * radius(zone.fiber_j) < radius(zone.fiber_i))
        << zone.fiber_i << " " << zone.fiber_j;
    EXPECT_LE(zone.s_begin, zone.s_end);
    expected_first += zone.num_elements;
    if (z > 0) {
      const ProximityZone& prev = det.zones[z - 1];
      EXPECT_TRUE(std::make_pair(prev.fiber_i, prev.fiber_j) < std::make_pair(zone.fiber_i, zone.fiber_j) ||
                  (prev.fiber_i == zone.fiber_i && prev.fiber_j == zone.fiber_j && prev.s_begin <= zone.s_begin));
    }
    for (int k = zone.first_element; k < zone.first_element + zone.num_elements; ++k) {
      const ContactElement& c = det.elements[k];
      EXPECT_EQ(c.zone, static_cast<int>(z));
      EXPECT_EQ(model.elements[c.a.element].fiber, zone.fiber_i);
      EXPECT_EQ(model.elements[c.b.element].fiber, zone.fiber_j);
    }
  }
  EXPECT_EQ(expected_first, static_cast<int>(det.elements.size()));
  for (const ContactElement& c : det.elements) {
    EXPECT_GE(c.a.eta, -1.0);
    EXPECT_LE(c.a.eta, 1.0);
    EXPECT_GE(c.b.eta, -1.0);
    EXPECT_LE(c.b.eta, 1.0);
    EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12);
    const Section& sa = model.sections[model.elements[c.a.element].section];
    const Section& sb = model.sections[model.elements[c.b.element].section];
    const Vec3 ca = centre(model, q, c.a), cb = centre(model, q, c.b);
    // On the border of the section in material coordinates; at distance r from the centre
    // (the interpolated section vectors of curved fibers are unit only at the nodes).
    EXPECT_NEAR(std::hypot(c.a.xi1 / sa.a, c.a.xi2 / sa.b), 1.0, 1e-12);
    EXPECT_NEAR(std::hypot(c.b.xi1 / sb.a, c.b.xi2 / sb.b), 1.0, 1e-12);
    EXPECT_NEAR((position(model, q, c.a) - ca).norm(), sa.a, border_tolerance * sa.a);
    EXPECT_NEAR((position(model, q, c.b) - cb).norm(), sb.a, border_tolerance * sb.a);
    EXPECT_NEAR((cb - ca).normalized().dot(c.normal), 1.0, 1e-9);
    // Each particle faces the other section: along +N on a, along -N on b, up to the tilt of
    // the section plane, at most 45 degrees from the cutting plane on smooth fibers (more at
    // the kinks between elements of sharply bent ones).
    EXPECT_GT((position(model, q, c.a) - ca).dot(c.normal), facing * sa.a);
    EXPECT_GT((position(model, q, c.b) - cb).dot(-c.normal), facing * sb.a);
  }
}

// Two straight fibers crossing at `angle`, centre distance d, both rigidly moved by `rot` and `shift`.
struct Crossing {
  Model model;
  Mat3 rot;
  Vec3 shift;
};

Crossing make_crossing(double r_i, double r_j, double d, double angle, const Mat3& rot, const Vec3& shift,
                       double half_length, int elements, double end_j = 0) {
  Case c = base_case();
  const Vec3 dir_j(std::cos(angle), std::sin(angle), 0.0);
  const Vec3 end = end_j != 0 ? Vec3(Vec3(0, 0, d) + end_j * dir_j) : Vec3(Vec3(0, 0, d) + half_length * dir_j);
  c.fibers.push_back(
      polyline("i", {rot * Vec3(-half_length, 0, 0) + shift, rot * Vec3(half_length, 0, 0) + shift}, r_i, elements));
  c.fibers.push_back(
      polyline("j", {rot * (Vec3(0, 0, d) - half_length * dir_j) + shift, rot * end + shift}, r_j, elements));
  return {build_model(c), rot, shift};
}

TEST(Detection, CrossingGivesOneShortZoneAtTheCommonPerpendicular) {
  const double r = 1e-3, eps = 1e-3 * r;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 6; ++trial) {
    const double angle = trial == 0 ? 0.5 * kPi : (0.3 + 0.2 * trial) * 0.5 * kPi;
    const Mat3 rot = trial == 0
                         ? Mat3::Identity()
                         : Eigen::AngleAxisd(3 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
    const Vec3 shift = trial == 0 ? Vec3::Zero() : Vec3(u(rng), u(rng), u(rng));
    const Crossing x = make_crossing(r, r, 2 * r - eps, angle, rot, shift, 20 * r, 20);
    ContactDetector detector(x.model);
    const VecX& q = x.model.reference;
    const Detection det = detector.detect(q);
    check_consistency(x.model, q, det);
    ASSERT_EQ(det.zones.size(), 1u) << trial;
    EXPECT_EQ(det.zones[0].fiber_i, 0);
    EXPECT_EQ(det.zones[0].fiber_j, 1);
    EXPECT_GE(det.elements.size(), 1u);
    EXPECT_LE(det.elements.size(), 3u);
    const Vec3 perp = rot * Vec3::UnitZ();
    const ContactElement* central = nullptr;
    for (const ContactElement& c : det.elements) {
      // Near the crossing; normal close to the common perpendicular.
      EXPECT_LT((centre(x.model, q, c.a) - shift).norm(), 1.5 * r) << trial;
      EXPECT_GT(c.normal.dot(perp), 0.75) << trial;
      if (!central || c.normal.dot(perp) > central->normal.dot(perp)) central = &c;
    }
    // One element at the closest approach: normal along the common perpendicular, gap -eps.
    EXPECT_GT(central->normal.dot(perp), 1 - 1e-4) << trial;
    EXPECT_NEAR(gap(x.model, q, *central), -eps, 2e-4 * r) << trial;
    EXPECT_LT((centre(x.model, q, central->a) - shift).norm(), 0.05 * r) << trial;
    // The zone is centred on the crossing and short.
    EXPECT_NEAR(0.5 * (det.zones[0].s_begin + det.zones[0].s_end), 20 * r, 0.5 * r);
    EXPECT_LE(det.zones[0].s_end - det.zones[0].s_begin, 4.5 * r / std::sin(angle));
  }
}

TEST(Detection, ParallelTouchingFibersGiveOneUniformContactLine) {
  const double r = 1e-4, length = 100 * r;
  Case c = base_case();
  c.fibers.push_back(polyline("a", {Vec3(0, 0, 0), Vec3(length, 0, 0)}, r, 20));
  c.fibers.push_back(polyline("b", {Vec3(0, 2 * r, 0), Vec3(length, 2 * r, 0)}, r, 20));
  const Model model = build_model(c);
  ContactDetector detector(model, radius_spacing(model));  // contact elements every radius
  const VecX& q = model.reference;
  const Detection det = detector.detect(q);
  check_consistency(model, q, det);
  ASSERT_EQ(det.zones.size(), 1u);
  EXPECT_LT(det.zones[0].s_begin, 0.01 * length);
  EXPECT_GT(det.zones[0].s_end, 0.99 * length);
  const int n = static_cast<int>(det.elements.size());
  EXPECT_NEAR(n, length / r, 1.0);
  std::vector<double> xs;
  for (const ContactElement& e : det.elements) {
    xs.push_back(centre(model, q, e.a).x());
    EXPECT_NEAR(e.normal.dot(Vec3::UnitY()), 1.0, 1e-12);  // perpendicular to the fibers
    EXPECT_NEAR(gap(model, q, e), 0.0, 1e-12 * r);
    EXPECT_NEAR(centre(model, q, e.b).x(), xs.back(), 1e-12 * length);  // same cross-section
  }
  for (int k = 1; k < n; ++k) EXPECT_NEAR(xs[k] - xs[k - 1], length / n, 1e-9 * length);
  EXPECT_NEAR(xs.front(), 0.5 * length / n, 1e-9 * length);
}

TEST(Detection, FarFibersHaveNoZoneAndNoCandidate) {
  const double r = 1e-4;
  Case c = base_case();
  c.fibers.push_back(polyline("a", {Vec3(0, 0, 0), Vec3(0.01, 0, 0)}, r, 20));
  c.fibers.push_back(polyline("b", {Vec3(0, 5 * r, 0), Vec3(0.01, 5 * r, 0)}, r, 20));
  c.fibers.push_back(polyline("c", {Vec3(0.005, -0.005, 3.1 * r), Vec3(0.005, 0.005, 3.1 * r)}, r, 20));
  const Model model = build_model(c);
  ContactDetector detector(model);
  const Detection det = detector.detect(model.reference);
  EXPECT_TRUE(det.zones.empty());
  EXPECT_TRUE(det.elements.empty());
  // Only the crossing of c over a and b gives candidates (c passes 3.1 r above a).
  for (const ElementPair& p : detector.broad_phase().pairs()) EXPECT_EQ(model.elements[p.second].fiber, 2);
}

TEST(Detection, ReusedDetectorFollowsTheMotion) {
  const double r = 1e-4;
  Case c = base_case();
  c.fibers.push_back(polyline("a", {Vec3(0, 0, 0), Vec3(0.01, 0, 0)}, r, 20));
  c.fibers.push_back(polyline("b", {Vec3(0, 5 * r, 0), Vec3(0.01, 5 * r, 0)}, r, 20));
  const Model model = build_model(c);
  ContactDetector detector(model, radius_spacing(model));  // contact elements every radius
  VecX q = model.reference;
  Detection det;
  for (int pass = 0; pass < 3; ++pass) {
    detector.detect(q, det);
    EXPECT_TRUE(det.zones.empty());
    // Move fiber b down to touch a.
    VecX moved = q;
    for (Index k = model.fibers[1].first_node; k < model.fibers[1].first_node + model.fibers[1].num_nodes; ++k)
      moved[9 * k + 1] -= 3 * r;
    detector.detect(moved, det);
    ASSERT_EQ(det.zones.size(), 1u);
    EXPECT_NEAR(det.elements.size(), 100.0, 1.0);
  }
}

TEST(Detection, CrossingAtTheEndOfAFiberIsClipped) {
  const double r = 1e-3, eps = 1e-3 * r;
  // Fiber j ends half a radius past the crossing: elements only within it.
  {
    const Crossing x = make_crossing(r, r, 2 * r - eps, 0.5 * kPi, Mat3::Identity(), Vec3::Zero(), 20 * r, 20, 0.5 * r);
    ContactDetector detector(x.model);
    const VecX& q = x.model.reference;
    const Detection det = detector.detect(q);
    check_consistency(x.model, q, det);
    ASSERT_EQ(det.zones.size(), 1u);
    for (const ContactElement& c : det.elements) EXPECT_LE(centre(x.model, q, c.b).y(), 0.5 * r + 1e-12);
  }
  // Fiber j ends 3 r before fiber i: no contact.
  {
    const Crossing x = make_crossing(r, r, 2 * r - eps, 0.5 * kPi, Mat3::Identity(), Vec3::Zero(), 20 * r, 20, -3 * r);
    ContactDetector detector(x.model);
    EXPECT_TRUE(detector.detect(x.model.reference).zones.empty());
  }
  // Parallel fibers overlapping on half their length: one zone on the overlap only.
  {
    const double length = 0.02;
    Case c = base_case();
    c.fibers.push_back(polyline("a", {Vec3(0, 0, 0), Vec3(length, 0, 0)}, r, 10));
    c.fibers.push_back(polyline("b", {Vec3(0.5 * length, 2 * r, 0), Vec3(1.5 * length, 2 * r, 0)}, r, 10));
    const Model model = build_model(c);
    ContactDetector detector(model);
    const VecX& q = model.reference;
    const Detection det = detector.detect(q);
    check_consistency(model, q, det);
    ASSERT_EQ(det.zones.size(), 1u);
    EXPECT_NEAR(det.zones[0].s_begin, 0.5 * length, 2 * r);
    EXPECT_NEAR(det.zones[0].s_end, length, 1e-12);
    EXPECT_NEAR(det.elements.size(), 0.5 * length / r, 2.0);
    for (const ContactElement& e : det.elements) {
      EXPECT_GE(centre(model, q, e.a).x(), 0.5 * length - 1e-12);
      EXPECT_GE(centre(model, q, e.b).x(), 0.5 * length - 1e-12);
      EXPECT_NEAR(e.normal.dot(Vec3::UnitY()), 1.0, 1e-12);
    }
  }
}

// The end of a fiber pressed against the side of a nearly parallel one (a tow's fibers next to
// a grip that holds their ends across the tow while the tow turns): they come closest at that
// end, and an element must sit there whatever the layout of the zone. Fiber b's end is pressed
// 0.1 r into a's side and b leaves a at 0.08 rad; contact elements every 5 r (the woven
// samples' spacing is 2.5 r). Measured without the end's element (the plane of an element
// dropped when it falls past a fiber's end, short zones anchored at their closest sample): at 7
// of the 17 places of b's end along a the nearest element was 4.8-5.0 r away, its gap +0.3 r
// (the end penetrated by 0.1 r unseen), at the 10 others 0.08-0.37 r inside; with b's end past
// a's, 0.4 r inside a's end.
TEST(Detection, EndOfAFiberPressedAgainstAnotherHasItsElementThere) {
  const double r = 2e-5, length = 125 * r, slope = 0.08;
  for (int k = -16; k <= 16; ++k) {
    SCOPED_TRACE(k);
    const double stagger = 0.25 * k * r;  // b's end along a, from a's end
    Case c = base_case();
    c.fibers.push_back(polyline("a", {Vec3(0, 0, 0), Vec3(0, length, 0)}, r, 20));
    const Vec3 end(1.9 * r, stagger, 0), dir = Vec3(slope, 1.0, 0).normalized();
    c.fibers.push_back(polyline("b", {end, end + length * dir}, r, 20));
    const Model model = build_model(c);
    const VecX& q = model.reference;
    const Detection det = detect_every(model, 5 * r);
    check_consistency(model, q, det, 1e-12, 0.6);
    ASSERT_EQ(det.zones.size(), 1u);
    // Where a and b come closest: b's end when it lies along a, else a's end.
    const bool b_end = stagger >= 0;
    const Vec3 closest = b_end ? end : Vec3::Zero();
    const double lateral = b_end ? 1.9 * r : 1.9 * r - stagger * slope;  // across a (b's axis, from a's end)
    double nearest = 1e300, deepest = 1e300;
    for (const ContactElement& e : det.elements) {
      const Particle& p = b_end ? e.b : e.a;
      nearest = std::min(nearest, (centre(model, q, p) - closest).norm());
      deepest = std::min(deepest, gap(model, q, e));
    }
    EXPECT_LT(nearest, 1e-9 * r);
    EXPECT_NEAR(deepest, lateral - 2 * r, 0.05 * r);
  }
}

// The same end along a long zone: b runs beside a at 0.3 r for 120 r and its last 10 r bend
// in, its end pressed 0.1 r into a's side (a tow's fibers side by side at a grip, one end
// pushed against its neighbour as the tow turns). A long zone's elements sit at the middles of
// equal cells, the first half a spacing in from the zone's end. Without an element at b's end
// (the regular layout alone) the nearest element was 1.6-2.5 r from it at these 17 places,
// the deepest gap -0.03 to 0 r against the end's -0.1 r: the end penetrated unseen until the
// zone split into a short one (on the 480-fiber twill's shear, a pass per increment for the last
// level's 18 increments). Both orders of the fibers (b is the sampled fiber or the other one).
TEST(Detection, EndPressedAlongALongZoneHasItsElementThere) {
  const double r = 2e-5, length = 140 * r;
  for (int order = 0; order < 2; ++order) {
    for (int k = 0; k <= 16; ++k) {
      SCOPED_TRACE(::testing::Message() << "order " << order << " place " << k);
      const double stagger = 0.25 * k * r;  // b's end along a, from a's end
      const Vec3 end(1.9 * r, stagger, 0);
      Case c = base_case();
      auto a = polyline("a", {Vec3(0, 0, 0), Vec3(0, length, 0)}, r, 28);
      auto b = polyline("b", {end, Vec3(2.3 * r, stagger + 10 * r, 0), Vec3(2.3 * r, stagger + 130 * r, 0)}, r, 26);
      if (order == 0) {
        c.fibers.push_back(a);
        c.fibers.push_back(b);
      } else {
        c.fibers.push_back(b);
        c.fibers.push_back(a);
      }
      const Model model = build_model(c);
      const VecX& q = model.reference;
      const Detection det = detect_every(model, 5 * r);
      check_consistency(model, q, det, 1e-3, 0.6);  // sections at the bend interpolated between turned nodes
      ASSERT_EQ(det.zones.size(), 1u);
      ASSERT_GT(det.elements.size(), 20u);  // a long zone: 130 r at 5 r
      const int fiber_b = order == 0 ? 1 : 0;
      double nearest = 1e300, deepest = 1e300;
      std::vector<double> along;  // elements' positions along a
      for (const ContactElement& e : det.elements) {
        const Particle& p = model.elements[e.a.element].fiber == fiber_b ? e.a : e.b;
        nearest = std::min(nearest, (centre(model, q, p) - end).norm());
        deepest = std::min(deepest, gap(model, q, e));
        along.push_back(centre(model, q, p).y());
      }
      EXPECT_LT(nearest, 1e-9 * r);
      EXPECT_NEAR(deepest, -0.1 * r, 0.02 * r);
      // The end's element comes on top of the zone's regular layout, which it leaves alone:
      // the next element is the first regular one, half a spacing in from the zone's extended
      // end (measured: 1.6-2.5 r from b's end), the others 5.00-5.08 r apart.
      std::sort(along.begin(), along.end());
      EXPECT_GT(along[1] - along[0], 1.0 * r);
      EXPECT_LT(along[1] - along[0], 2.6 * r);
      for (size_t m = 2; m < along.size(); ++m) EXPECT_NEAR(along[m] - along[m - 1], 5 * r, 0.15 * r);
    }
  }
}

// b's end given its element where the fibers come together (b from 1.9 r at its end to 2.3 r
// further on) keeps it while they stay pressed there, however they lie: straight at 1.9 r, or
// held 1.97 r apart at the end (that element's force) and 1.9 r further on. With the element only
// where the fibers come together, the second lost it, its ends then penetrated, the next
// detection put it back: the 480-fiber twill's shear went back and forth at every detection of a
// settling level. Parted (2.3 r) it goes, and a detector that never had it leaves fibers pressed
// evenly to their ends with the regular layout alone (a uniform pressure, equal forces).
TEST(Detection, EndKeepsItsElementWhileThePressHolds) {
  const double r = 2e-5, length = 140 * r;
  for (int k = 0; k <= 8; ++k) {
    SCOPED_TRACE(::testing::Message() << "place " << k);
    const double stagger = 0.5 * k * r;
    const Vec3 end(0, stagger, 0);
    // Fiber b: at `d_end` from a at its end, `d_along` from 10 r on.
    auto model_with = [&](double d_end, double d_along) {
      Case c = base_case();
      c.fibers.push_back(polyline("a", {Vec3(0, 0, 0), Vec3(0, length, 0)}, r, 28));
      c.fibers.push_back(polyline("b",
                                  {Vec3(d_end * r, stagger, 0), Vec3(d_along * r, stagger + 10 * r, 0),
                                   Vec3(d_along * r, stagger + 120 * r, 0), Vec3(2.3 * r, stagger + 125 * r, 0),
                                   Vec3(2.3 * r, stagger + 130 * r, 0)},
                                  r, 26));
      return build_model(c);
    };
    const Model together = model_with(1.9, 2.3), straight = model_with(1.9, 1.9), held = model_with(1.97, 1.9),
                parted = model_with(2.3, 2.3);
    // The distance from b's end to the nearest element on b, the elements' spacings along a.
    auto layout = [&](const Detection& det, const VecX& q, std::vector<double>& along) {
      double nearest = 1e300;
      along.clear();
      for (const ContactElement& e : det.elements) {
        const Vec3 x = centre(together, q, e.b);
        nearest = std::min(nearest, std::abs(x.y() - stagger) + std::abs(x.z()));
        along.push_back(x.y());
      }
      std::sort(along.begin(), along.end());
      return nearest;
    };
    DetectionParams params;
    params.spacing = 5 * r;
    ContactDetector detector(together, params);
    std::vector<double> along;
    for (const auto& [name, model] :
         {std::pair<const char*, const Model*>{"together", &together}, {"straight", &straight}, {"held", &held},
          {"straight again", &straight}}) {
      SCOPED_TRACE(name);
      const Detection det = detector.detect(model->reference);
      ASSERT_EQ(det.zones.size(), 1u);
      ASSERT_GT(det.elements.size(), 20u);
      // Within 1e-9 r; 0.02 r where both fibers end together (place 0: the cut meets a's end too).
      EXPECT_LT(layout(det, model->reference, along), (k == 0 ? 2e-2 : 1e-9) * r);
      EXPECT_GT(along[1] - along[0], 1.0 * r);  // then the regular layout, half a spacing in
      EXPECT_LT(along[1] - along[0], 2.6 * r);
      for (size_t m = 2; m < along.size(); ++m) EXPECT_NEAR(along[m] - along[m - 1], 5 * r, 0.15 * r);
    }
    // Parted, then pressed evenly again: the regular layout alone.
    for (const auto& [name, model] :
         {std::pair<const char*, const Model*>{"parted", &parted}, {"straight after parting", &straight}}) {
      SCOPED_TRACE(name);
      const Detection det = detector.detect(model->reference);
      ASSERT_EQ(det.zones.size(), 1u);
      EXPECT_GT(layout(det, model->reference, along), 1.0 * r);
      for (size_t m = 1; m < along.size(); ++m) EXPECT_NEAR(along[m] - along[m - 1], 5 * r, 0.15 * r);
    }
    (void)end;
  }
}

// Where the fibers do not come together at the end (b straight beside a at 0.3 r, its end
// cutting the zone), the zone keeps its regular layout alone: no element more at b's end.
TEST(Detection, ParallelEndKeepsTheRegularLayout) {
  const double r = 2e-5, length = 140 * r;
  for (int k = 0; k <= 8; ++k) {
    SCOPED_TRACE(::testing::Message() << "place " << k);
    const double stagger = 0.5 * k * r;
    Case c = base_case();
    c.fibers.push_back(polyline("a", {Vec3(0, 0, 0), Vec3(0, length, 0)}, r, 28));
    c.fibers.push_back(polyline("b", {Vec3(2.3 * r, stagger, 0), Vec3(2.3 * r, stagger + 130 * r, 0)}, r, 26));
    const Model model = build_model(c);
    const Detection det = detect_every(model, 5 * r);
    ASSERT_EQ(det.zones.size(), 1u);
    std::vector<double> along;
    for (const ContactElement& e : det.elements) along.push_back(centre(model, model.reference, e.b).y());
    std::sort(along.begin(), along.end());
    ASSERT_GT(along.size(), 20u);
    for (size_t m = 1; m < along.size(); ++m) EXPECT_NEAR(along[m] - along[m - 1], 5 * r, 0.15 * r);
    EXPECT_GT(along.front() - stagger, 1.0 * r);  // the first regular element, half a spacing in
  }
}

TEST(Detection, RadiiOneToTen) {
  const double r = 1e-4, big = 10 * r;
  // Thin fiber across a thick one (both orders of the fibers).
  for (int order = 0; order < 2; ++order) {
    const double r_i = order == 0 ? big : r, r_j = order == 0 ? r : big;
    const Crossing x =
        make_crossing(r_i, r_j, big + r - 1e-3 * r, 0.5 * kPi, Mat3::Identity(), Vec3::Zero(), 40 * r, 20);
    ContactDetector detector(x.model);
    const VecX& q = x.model.reference;
    const Detection det = detector.detect(q);
    check_consistency(x.model, q, det);
    ASSERT_EQ(det.zones.size(), 1u);
    EXPECT_GE(det.elements.size(), 1u);
    EXPECT_LE(det.elements.size(), 6u);
    // The thin fiber is sampled whatever the order: its particle is a, the normal from it
    // towards the thick one (check_consistency: from centre a to centre b), across the crossing.
    const double below_to_above = order == 0 ? -1.0 : 1.0;  // the thin fiber is above in order 0
    for (const ContactElement& c : det.elements) {
      EXPECT_EQ(x.model.elements[c.a.element].fiber, order == 0 ? 1 : 0);
      EXPECT_GT(below_to_above * c.normal.z(), 0.95);
      EXPECT_LT(centre(x.model, q, c.a).head<2>().norm(), 3 * r);
    }
  }
  // Thin fiber along a thick one: a contact line with the thin fiber's spacing.
  const double length = 200 * r;
  Case c = base_case();
  c.fibers.push_back(polyline("thick", {Vec3(0, 0, 0), Vec3(length, 0, 0)}, big, 10));
  c.fibers.push_back(polyline("thin", {Vec3(0, big + r, 0), Vec3(length, big + r, 0)}, r, 40));
  const Model model = build_model(c);
  ContactDetector detector(model, radius_spacing(model));  // contact elements every radius
  const Detection det = detector.detect(model.reference);
  check_consistency(model, model.reference, det);
  ASSERT_EQ(det.zones.size(), 1u);
  EXPECT_NEAR(det.elements.size(), length / r, 1.0);
  // Sampled on the thin fiber (above the thick one along y): normals from it, along -y.
  for (const ContactElement& e : det.elements) EXPECT_NEAR(e.normal.dot(Vec3::UnitY()), -1.0, 1e-12);
}

TEST(Detection, NearlyParallelAndTangentFibers) {
  const double r = 1e-4, eps = 1e-3 * r;
  // Crossing at 2 degrees: one long zone, elements in order along it.
  {
    const Crossing x = make_crossing(r, r, 2 * r - eps, 2 * kPi / 180, Mat3::Identity(), Vec3::Zero(), 100 * r, 40);
    ContactDetector detector(x.model);
    const VecX& q = x.model.reference;
    const Detection det = detector.detect(q);
    check_consistency(x.model, q, det);
    ASSERT_EQ(det.zones.size(), 1u);
    // Zone length about 2 sqrt((2.5 r)^2 - (2 r)^2) / sin(2 deg) = 86 r.
    EXPECT_NEAR(det.zones[0].s_end - det.zones[0].s_begin, 3 * r / std::sin(2 * kPi / 180), 5 * r);
    EXPECT_GT(det.elements.size(), 30u);
    double prev = -1e300, best = -1;
    for (const ContactElement& c : det.elements) {
      const double xa = centre(x.model, q, c.a).x();
      EXPECT_GT(xa, prev);
      prev = xa;
      best = std::max(best, c.normal.z());
      EXPECT_NEAR(gap(x.model, q, c), (centre(x.model, q, c.b) - centre(x.model, q, c.a)).norm() - 2 * r, 1e-3 * r);
    }
    EXPECT_GT(best, 0.999);
  }
  // Exactly parallel fibers at the proximity threshold minus a little: still one line.
  {
    Case c = base_case();
    c.fibers.push_back(polyline("a", {Vec3(0, 0, 0), Vec3(50 * r, 0, 0)}, r, 10));
    c.fibers.push_back(polyline("b", {Vec3(0, 0, 2.49 * r), Vec3(50 * r, 0, 2.49 * r)}, r, 10));
    const Model model = build_model(c);
    ContactDetector detector(model, radius_spacing(model));  // contact elements every radius
    const Detection det = detector.detect(model.reference);
    check_consistency(model, model.reference, det);
    ASSERT_EQ(det.zones.size(), 1u);
    EXPECT_NEAR(det.elements.size(), 50.0, 1.0);
  }
  // An arc of radius 50 r touching a straight fiber at its lowest point.
  {
    Case c = base_case();
    c.fibers.push_back(polyline("line", {Vec3(-30 * r, 0, 0), Vec3(30 * r, 0, 0)}, r, 30));
    FiberSpec arc = fiber("arc", r, 80);
    arc.path.kind = PathSpec::Kind::Arc;
    arc.path.center = Vec3(0, 0, 52 * r);
    arc.path.axis = Vec3::UnitY();
    arc.path.radius = 50 * r;
    arc.path.start_angle = 0;
    arc.path.angle = kPi;
    c.fibers.push_back(arc);
    const Model model = build_model(c);
    ContactDetector detector(model);
    const VecX& q = model.reference;
    const Detection det = detector.detect(q);
    check_consistency(model, q, det, 1e-3);
    ASSERT_EQ(det.zones.size(), 1u);
    // Zone half-length sqrt(2 * 50 r * 0.5 r) = 7.1 r on the line.
    EXPECT_NEAR(det.zones[0].s_end - det.zones[0].s_begin, 14.1 * r, 2 * r);
    EXPECT_NEAR(0.5 * (det.zones[0].s_end + det.zones[0].s_begin), 30 * r, 0.5 * r);
    EXPECT_GE(det.elements.size(), 10u);
    EXPECT_LE(det.elements.size(), 18u);
    const ContactElement& mid = det.elements[det.elements.size() / 2];
    EXPECT_GT(mid.normal.z(), 0.99);
  }
}

TEST(Detection, HelixWoundAroundAStraightFiberTouchesAllAlong) {
  const double r = 1e-4, radius = 2 * r, pitch = 2 * kPi * radius, turns = 2;
  Case c = base_case();
  c.fibers.push_back(polyline("core", {Vec3(0, 0, -2 * r), Vec3(0, 0, turns * pitch + 2 * r)}, r, 20));
  c.fibers.push_back(helix("wrap", radius, pitch, turns, r, 48));
  const Model model = build_model(c);
  ContactDetector detector(model);
  const VecX& q = model.reference;
  const Detection det = detector.detect(q);
  check_consistency(model, q, det, 1e-3);
  ASSERT_GE(det.zones.size(), 1u);
  EXPECT_LE(det.zones.size(), 2u);
  double covered = 0;
  for (const ProximityZone& z : det.zones) covered += z.s_end - z.s_begin;
  EXPECT_GT(covered, 0.95 * turns * pitch);
  // Intermediate curve: helix of radius r and the same pitch.
  const double intermediate = turns * std::hypot(2 * kPi * r, pitch);
  EXPECT_NEAR(static_cast<double>(det.elements.size()), intermediate / r, 0.1 * intermediate / r);
  for (const ContactElement& e : det.elements) {
    EXPECT_NEAR(gap(model, q, e), 0.0, 0.02 * r);
    EXPECT_LT(std::abs(e.normal.z()), 0.05);
  }
}

TEST(Detection, SelfContactOfACoilButNotOfNeighbouringElements) {
  const double r = 1e-4;
  // Two turns with pitch 2 r: consecutive turns touch over one turn.
  {
    const double radius = 5 * r, pitch = 2 * r;
    Case c = base_case();
    c.fibers.push_back(helix("coil", radius, pitch, 2, r, 60));
    const Model model = build_model(c);
    ContactDetector detector(model);
    const VecX& q = model.reference;
    const Detection det = detector.detect(q);
    check_consistency(model, q, det, 1e-3);
    ASSERT_EQ(det.zones.size(), 1u);
    EXPECT_EQ(det.zones[0].fiber_i, 0);
    EXPECT_EQ(det.zones[0].fiber_j, 0);
    const double turn = std::hypot(2 * kPi * radius, pitch);
    EXPECT_LT(det.zones[0].s_begin, 0.05 * turn);
    EXPECT_NEAR(det.zones[0].s_end, turn, 0.05 * turn);
    EXPECT_NEAR(static_cast<double>(det.elements.size()), turn / r, 0.1 * turn / r);
    for (const ContactElement& e : det.elements) {
      EXPECT_GT(e.normal.z(), 0.99);
      EXPECT_NEAR(gap(model, q, e), 0.0, 0.02 * r);
      EXPECT_LT(e.a.element, e.b.element);
    }
  }
  // A path crossing itself (a loop closed by a crossing, 40 r of fiber between).
  {
    const double d = 2 * r - 1e-3 * r;
    Case c = base_case();
    c.fibers.push_back(polyline(
        "loop",
        {Vec3(0, 0, 0), Vec3(20 * r, 0, 0), Vec3(20 * r, 10 * r, 0), Vec3(10 * r, 10 * r, d), Vec3(10 * r, -10 * r, d)},
        r, 70));
    const Model model = build_model(c);
    ContactDetector detector(model);
    const VecX& q = model.reference;
    const Detection det = detector.detect(q);
    check_consistency(model, q, det);
    ASSERT_EQ(det.zones.size(), 1u);
    EXPECT_LE(det.elements.size(), 3u);
    for (const ContactElement& e : det.elements) {
      EXPECT_LT((centre(model, q, e.a) - Vec3(10 * r, 0, 0)).norm(), 1.5 * r);
      EXPECT_GT(e.normal.z(), 0.95);
    }
  }
  // A straight fiber with elements shorter than the radius: no self-contact at all.
  {
    Case c = base_case();
    c.fibers.push_back(polyline("straight", {Vec3(0, 0, 0), Vec3(50 * r, 0, 0)}, r, 100));
    const Model model = build_model(c);
    ContactDetector detector(model);
    const Detection det = detector.detect(model.reference);
    EXPECT_TRUE(det.zones.empty());
    EXPECT_TRUE(detector.broad_phase().pairs().empty());
  }
}

// 200 short, slightly bent fibers of various radii at random, plus a few coils (self pairs).
Model random_cloud(unsigned seed, double box) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Case c = base_case();
  for (int k = 0; k < 200; ++k) {
    const double r = 2e-5 + 8e-5 * u(rng);
    const double len = 2e-4 + 8e-4 * u(rng);
    const Vec3 a(box * u(rng), box * u(rng), box * u(rng));
    const Vec3 dir = Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized();
    const Vec3 bend = 0.2 * len * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
    c.fibers.push_back(polyline(std::to_string(k), {a, a + 0.5 * len * dir + bend, a + len * dir}, r,
                                2 + static_cast<int>(3 * u(rng))));
  }
  for (int k = 0; k < 5; ++k) {
    FiberSpec h = helix(std::to_string(1000 + k), 3e-4, 1.5e-4, 2, 5e-5, 30);
    h.path.center = Vec3(box * u(rng), box * u(rng), box * u(rng));
    c.fibers.push_back(h);
  }
  return build_model(c);
}

// Normal updates (ContactManager::update_normals): three parallel fibers along x, b pressed
// onto a (centre distance 1.98 r: loaded), c beside a with a gap of 0.4 r (detected, no force).
// A normal is the vector between the section centres in the plane normal to the fibers'
// (bisected) tangents, so fibers sliding along each other keep their normals: sliding b or c
// along x by 0.5 r turns nothing (the vector between the centres tilts by 0.25 rad). Moving c
// sideways (z) by 0.5 r turns the normals of a-c by atan(0.5 / 2.4): they follow at once, but
// the turn reported (which decides whether the normals settled) stays that of a-b, zero.
// Moving b sideways by 1e-4 r turns a-b by less than the tolerance: reported, normals kept
// (the converged state stays consistent with them); by 0.5 r: reported and all a-b normals set.
TEST(NormalUpdate, OnlyElementsCarryingForceDecideTheSettling) {
  const double r = 1e-4, length = 40 * r;
  Case c = base_case();
  c.fibers.push_back(polyline("a", {Vec3(0, 0, 0), Vec3(length, 0, 0)}, r, 8));
  c.fibers.push_back(polyline("b", {Vec3(0, 1.98 * r, 0), Vec3(length, 1.98 * r, 0)}, r, 8));
  c.fibers.push_back(polyline("c", {Vec3(0, -2.4 * r, 0), Vec3(length, -2.4 * r, 0)}, r, 8));
  const Model model = build_model(c);
  ContactSpec spec;
  spec.enabled = true;
  ContactManager manager(model, spec);
  VecX q = model.reference;
  std::vector<ContactElement> contacts = manager.detect(q, q, {});
  const auto pair_of = [&](const ContactElement& e) {
    return std::make_pair(model.elements[e.a.element].fiber, model.elements[e.b.element].fiber);
  };
  int ab = 0, ac = 0;
  for (const ContactElement& e : contacts) {
    if (pair_of(e) == std::make_pair(0, 1)) {
      ++ab;
      EXPECT_LT(gap(model, q, e), -0.01 * r);
    } else if (pair_of(e) == std::make_pair(0, 2)) {
      ++ac;
      EXPECT_GT(gap(model, q, e), 0.3 * r);
    }
  }
  ASSERT_GT(ab, 10);
  ASSERT_GT(ac, 10);
  const auto move = [&](int fiber, const Vec3& by) {
    const Fiber& f = model.fibers[fiber];
    for (Index k = f.first_node; k < f.first_node + f.num_nodes; ++k) q.segment<3>(9 * k) += by;
  };
  // The normal expected at q: the centres' vector without its x part (the fibers' axis).
  const auto in_plane = [&](const ContactElement& e) {
    Vec3 d = centre(model, q, e.b) - centre(model, q, e.a);
    d.x() = 0.0;
    return Vec3(d.normalized());
  };
  const std::vector<ContactElement> before = contacts;
  move(1, Vec3(0.5 * r, 0, 0));
  move(2, Vec3(-0.5 * r, 0, 0));
  double idle = 1.0;
  EXPECT_NEAR(manager.update_normals(contacts, q, &idle), 0.0, 1e-12);
  EXPECT_NEAR(idle, 0.0, 1e-12);
  for (size_t k = 0; k < contacts.size(); ++k) {
    EXPECT_NEAR(contacts[k].normal.dot(before[k].normal), 1.0, 1e-12);
    // The vector between the centres did tilt: by atan(0.5 / 1.98) for a-b.
    if (pair_of(contacts[k]) == std::make_pair(0, 1)) {
      EXPECT_NEAR((centre(model, q, contacts[k].b) - centre(model, q, contacts[k].a)).normalized().dot(before[k].normal),
                  std::cos(std::atan2(0.5, 1.98)), 1e-3);
    }
  }
  move(2, Vec3(0, 0, 0.5 * r));
  EXPECT_NEAR(manager.update_normals(contacts, q, &idle), 0.0, 1e-12);
  EXPECT_NEAR(idle, std::atan2(0.5 * r, 2.4 * r), 0.02);
  for (size_t k = 0; k < contacts.size(); ++k) {
    const ContactElement& e = contacts[k];
    if (pair_of(e) == std::make_pair(0, 2)) {
      EXPECT_NEAR(e.normal.dot(in_plane(e)), 1.0, 1e-12);  // followed the centres
      EXPECT_GT(gap(model, q, e), 0.0);                     // and still carries no force
    } else {
      EXPECT_EQ(e.normal, before[k].normal);
    }
  }
  move(1, Vec3(0, 0, 1e-4 * r));
  const double small = manager.update_normals(contacts, q);
  EXPECT_GT(small, 1e-5);
  EXPECT_LT(small, spec.normal_tolerance);
  for (size_t k = 0; k < contacts.size(); ++k) {
    if (pair_of(contacts[k]) == std::make_pair(0, 1)) {
      EXPECT_EQ(contacts[k].normal, before[k].normal);
    }
  }
  move(1, Vec3(0, 0, 0.5 * r));
  EXPECT_NEAR(manager.update_normals(contacts, q), std::atan2(0.5 * r, 1.98 * r), 0.02);
  for (const ContactElement& e : contacts) {
    if (pair_of(e) == std::make_pair(0, 1)) {
      EXPECT_NEAR(e.normal.dot(in_plane(e)), 1.0, 1e-12);
    }
  }
}

// Two fibers crossing at a right angle, b pressed onto a from above (+z). The sign of the
// tangents' dot product, which picks one of the two bisectors, flips as b turns by +-0.01 rad
// about z; the normals must not follow that flip: each update keeps the cutting plane that
// keeps the normal closest to its current one. Elements off the crossing's centre (a wide
// detection margin) tilt by up to 0.78 rad from the vertical; turning b by 0.01 rad moves their
// normals by 0.004 rad, and choosing the bisector by that sign flipped them by 0.78 rad.
TEST(NormalUpdate, NormalsAtARightAngleCrossingDoNotFlip) {
  const double r = 1e-4, length = 20 * r;
  Case c = base_case();
  c.fibers.push_back(polyline("a", {Vec3(-0.5 * length, 0, 0), Vec3(0.5 * length, 0, 0)}, r, 10));
  c.fibers.push_back(polyline("b", {Vec3(0, -0.5 * length, 1.98 * r), Vec3(0, 0.5 * length, 1.98 * r)}, r, 10));
  const Model model = build_model(c);
  ContactSpec spec;
  spec.enabled = true;
  spec.margin = 2.0 * r;   // a zone long enough for elements off the crossing's centre
  spec.spacing = 0.25 * r;
  ContactManager manager(model, spec);
  const VecX q0 = model.reference;
  std::vector<ContactElement> contacts = manager.detect(q0, q0, {});
  ASSERT_GE(contacts.size(), 3u);
  double off_centre = 0.0;  // the largest tilt of a normal from the vertical at the detection
  for (const ContactElement& e : contacts) off_centre = std::max(off_centre, std::acos(std::min(1.0, e.normal.z())));
  EXPECT_GT(off_centre, 0.05);
  std::printf("%zu elements, largest tilt %.3f rad\n", contacts.size(), off_centre);
  // b turned about the vertical axis through the crossing by `angle` (positions only; the
  // section vectors turn alike).
  const auto turned = [&](double angle) {
    VecX q = q0;
    const Eigen::Matrix3d rot = Eigen::AngleAxisd(angle, Vec3::UnitZ()).toRotationMatrix();
    const Fiber& f = model.fibers[1];
    for (Index k = f.first_node; k < f.first_node + f.num_nodes; ++k) {
      const Vec3 x = q0.segment<3>(9 * k);
      q.segment<3>(9 * k) = rot * Vec3(x.x(), x.y(), 0.0) + Vec3(0, 0, x.z());
      q.segment<3>(9 * k + 3) = rot * q0.segment<3>(9 * k + 3);
      q.segment<3>(9 * k + 6) = rot * q0.segment<3>(9 * k + 6);
    }
    return q;
  };
  const std::vector<ContactElement> before = contacts;
  double largest = 0.0;
  for (const double angle : {0.01, -0.01, 0.01, -0.01}) {
    manager.update_normals(contacts, turned(angle));
    for (size_t k = 0; k < contacts.size(); ++k)
      largest = std::max(largest, std::acos(std::clamp(contacts[k].normal.dot(before[k].normal), -1.0, 1.0)));
  }
  EXPECT_LT(largest, 0.02);  // b turned by 0.01 rad
}

TEST(BroadPhase, CandidatePairsEqualBruteForce) {
  for (double box : {2e-3, 5e-3}) {
    const Model model = random_cloud(11, box);
    BroadPhase broad(model);
    const std::vector<ElementPair> pairs = broad.find_pairs(model.reference);
    const Index n = static_cast<Index>(model.elements.size());
    std::vector<ElementPair> brute;
    for (Index a = 0; a < n; ++a)
      for (Index b = a + 1; b < n; ++b)
        if (broad.boxes()[a].overlaps(broad.boxes()[b]) && !broad.excluded(a, b)) brute.push_back({a, b});
    EXPECT_GT(brute.size(), 50u);
    EXPECT_EQ(pairs.size(), brute.size());
    EXPECT_TRUE(pairs == brute);
    // Same-fiber pairs exist (the coils), none closer than the exclusion length.
    int self = 0;
    for (const ElementPair& p : pairs) self += model.elements[p.first].fiber == model.elements[p.second].fiber;
    EXPECT_GT(self, 0);
    // Boxes contain the curves inflated by the radius.
    for (Index e = 0; e < n; ++e) {
      const CentroidCurve curve = centroid_curve(model.reference.data() + model.elements[e].first_dof);
      for (double eta = -1; eta <= 1; eta += 0.125) {
        const Vec3 x = curve.value(eta);
        const double r = broad.info(e).radius;
        EXPECT_TRUE((x.array() - r >= broad.boxes()[e].lo.array()).all() &&
                    (x.array() + r <= broad.boxes()[e].hi.array()).all());
      }
    }
  }
}

TEST(Detection, DeterministicForAnyThreadCount) {
  const Model model = random_cloud(5, 1.5e-3);
  const int saved = omp_get_max_threads();
  Detection runs[2];
  for (int t = 0; t < 2; ++t) {
    omp_set_num_threads(t == 0 ? 1 : 3);
    ContactDetector detector(model);
    runs[t] = detector.detect(model.reference);
  }
  omp_set_num_threads(saved);
  check_consistency(model, model.reference, runs[0], 0.05, 0.25);
  EXPECT_GT(runs[0].zones.size(), 10u);
  ASSERT_EQ(runs[0].zones.size(), runs[1].zones.size());
  ASSERT_EQ(runs[0].elements.size(), runs[1].elements.size());
  for (size_t k = 0; k < runs[0].zones.size(); ++k) {
    EXPECT_EQ(runs[0].zones[k].s_begin, runs[1].zones[k].s_begin);
    EXPECT_EQ(runs[0].zones[k].first_element, runs[1].zones[k].first_element);
  }
  for (size_t k = 0; k < runs[0].elements.size(); ++k) {
    const ContactElement &a = runs[0].elements[k], &b = runs[1].elements[k];
    EXPECT_EQ(a.a.element, b.a.element);
    EXPECT_EQ(a.b.element, b.b.element);
    EXPECT_EQ(a.a.eta, b.a.eta);
    EXPECT_EQ(a.b.xi1, b.b.xi1);
    EXPECT_EQ(a.normal, b.normal);
  }
}

}  // namespace
}  // namespace fibra
