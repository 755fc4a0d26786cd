/// Tests of the tow envelopes (export/section_contour, tow_envelope, envelope_separation) and
/// of the mesh checks they rely on: a contour holds its ellipses whole and touches them; a
/// straight tow's envelope encloses every point of its fibers' sections; a one-fiber tow's
/// envelope has the volume of its prism; envelopes are closed and outward, straight or curved;
/// two tows pressed into each other come out apart; the checks themselves fail on an open,
/// a flipped and an intersecting surface.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "export/export_cases.hpp"
#include "fibra/export/envelope_separation.hpp"
#include "fibra/export/export_state.hpp"
#include "fibra/export/section_contour.hpp"
#include "fibra/export/tow_envelope.hpp"
#include "fibra/export/triangle_intersection.hpp"
#include "fibra/export/triangle_mesh.hpp"

namespace fibra {
namespace {

using Eigen::Vector2d;

/// Points of an ellipse of the section, `n` around.
std::vector<Vector2d> ellipse_points(const PlaneEllipse& e, int n) {
  std::vector<Vector2d> out;
  for (int k = 0; k < n; ++k) {
    const double s = 2.0 * std::numbers::pi * k / n;
    out.push_back(e.center + std::cos(s) * e.axis_a + std::sin(s) * e.axis_b);
  }
  return out;
}

/// Signed distance of p from the polygon's edge (a, b) of a counter-clockwise polygon: < 0 inside.
double outside_edge(const Vector2d& a, const Vector2d& b, const Vector2d& p) {
  const Vector2d d = (b - a).normalized();
  return -(d.x() * (p - a).y() - d.y() * (p - a).x());
}

TEST(ExportContour, ACircleGivesItsCircumscribedRegularPolygon) {
  const double r = 0.3;
  const Vector2d c(1.0, -2.0);
  const int m = 16;
  const auto v = circumscribed_contour({{c, Vector2d(r, 0), Vector2d(0, r)}}, std::vector<double>(m, 0.0));
  ASSERT_EQ(v.size(), static_cast<size_t>(m));
  for (int j = 0; j < m; ++j) {
    const double angle = (2 * j + 1) * std::numbers::pi / m;  // between normals j and j + 1
    const Vector2d expected = c + r / std::cos(std::numbers::pi / m) * Vector2d(std::cos(angle), std::sin(angle));
    EXPECT_NEAR((v[j] - expected).norm(), 0.0, 1e-14) << "vertex " << j;
  }
}

TEST(ExportContour, HoldsEveryEllipseWholeAndTouchesItsHull) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<PlaneEllipse> ellipses;
    for (int k = 0; k < 5; ++k)
      ellipses.push_back({Vector2d(u(rng), u(rng)), 0.3 * Vector2d(u(rng), u(rng)), 0.2 * Vector2d(u(rng), u(rng))});
    const int m = 32;
    const auto v = circumscribed_contour(ellipses, std::vector<double>(m, 0.0));
    for (int j = 0; j < m; ++j) {
      double nearest = 1e300;
      for (const PlaneEllipse& e : ellipses)
        for (const Vector2d& p : ellipse_points(e, 2000)) {
          const double d = outside_edge(v[(j + m - 1) % m], v[j], p);
          EXPECT_LE(d, 1e-12) << "trial " << trial << ": a point of an ellipse is outside edge " << j;
          nearest = std::min(nearest, -d);
        }
      EXPECT_LT(nearest, 1e-5) << "trial " << trial << ": edge " << j << " does not touch the ellipses";
    }
  }
}

TEST(ExportContour, LinesMovedInwardUnevenlyKeepAConvexCounterClockwisePolygon) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 0.05);
  const std::vector<PlaneEllipse> ellipses = {{Vector2d(-0.2, 0), Vector2d(0.1, 0), Vector2d(0, 0.1)},
                                              {Vector2d(0.2, 0.02), Vector2d(0.1, 0), Vector2d(0, 0.1)}};
  const int m = 64;
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<double> insets(m);
    for (double& i : insets) i = u(rng) * (trial % 2);  // every other trial: none
    const auto v = circumscribed_contour(ellipses, insets);
    for (int j = 0; j < m; ++j) {
      const Vector2d a = v[j], b = v[(j + 1) % m], c = v[(j + 2) % m];
      const double turn = (b - a).x() * (c - b).y() - (b - a).y() * (c - b).x();
      EXPECT_GE(turn, -1e-15) << "trial " << trial << ": the contour turns back at vertex " << j + 1;
    }
  }
}

/// The points x0 + a cos(s) g1 + b sin(s) g2 of every fiber's sections at `positions` places
/// along each fiber (its ends included), `around` per section.
std::vector<Vec3> section_points(const test::BuiltCase& b, int positions, int around) {
  std::vector<Vec3> out;
  for (const Fiber& f : b.model.fibers) {
    const Section& s = b.model.sections[f.section];
    for (int k = 0; k < positions; ++k) {
      const Index node = f.first_node + (f.num_nodes - 1) * k / (positions - 1);
      const Vec3 x = b.q.segment<3>(kNodeDofs * node), g1 = b.q.segment<3>(kNodeDofs * node + 3),
                 g2 = b.q.segment<3>(kNodeDofs * node + 6);
      for (int j = 0; j < around; ++j) {
        const double t = 2.0 * std::numbers::pi * j / around;
        out.push_back(x + s.a * std::cos(t) * g1 + s.b * std::sin(t) * g2);
      }
    }
  }
  return out;
}

TEST(ExportEnvelope, AStraightTowsEnvelopeEnclosesEveryPointOfItsFibersSections) {
  const test::BuiltCase b = test::build_case(test::straight_tow_case());
  const TowFibers tows = tow_fibers(b.model, b.q, b.c.tows);
  const TowEnvelope env = tow_envelope(b.model, b.q, tows, 0, EnvelopeOptions{});
  const std::vector<Vec3> points = section_points(b, 9, 48);
  int outside = 0;
  for (const Vec3& p : points) {
    // A point where a support line touches its section lies on the surface: its winding
    // number is undefined, its distance to the surface zero.
    const bool inside = winding_number(env.surface, p) > 0.5 || distance_to_surface(env.surface, p) < 1e-12;
    if (!inside) ++outside;
  }
  EXPECT_EQ(outside, 0) << "of " << points.size() << " section points";
  // And the envelope is tight: its cross-section is the hull of seven sections, not more.
  const double length = 2e-3, spacing = 0.11e-3, r = 0.05e-3;
  const double hexagon = 1.5 * std::sqrt(3.0) * spacing * spacing;             // hull of the centres
  const double hull = hexagon + 6.0 * spacing * r + std::numbers::pi * r * r;  // grown by r
  EXPECT_GT(signed_volume(env.surface), length * hull * 0.9);                  // three sections are thinner ellipses
  EXPECT_LT(signed_volume(env.surface), length * hull * 1.01);
}

TEST(ExportEnvelope, AOneFiberTowsEnvelopeIsTheCircumscribedPrism) {
  const double r = 0.05e-3, length = 1.5e-3;
  const test::BuiltCase b =
      test::build_case(std::string(test::kMaterial) +
                       test::straight_fiber("f", Vec3(0.1e-3, 0.2e-3, 0.3e-3),
                                            Vec3(0.1e-3, 0.2e-3, 0.3e-3) + length * test::straight_axis(), r, 5) +
                       test::tow("T", "warp", 0, {"f"}) + test::kStep);
  const TowFibers tows = tow_fibers(b.model, b.q, b.c.tows);
  for (int m : {8, 64}) {
    EnvelopeOptions options;
    options.contour_points = m;
    const TowEnvelope env = tow_envelope(b.model, b.q, tows, 0, options);
    EXPECT_EQ(env.stations.size(), 11u);  // two per element, plus one
    const double polygon = m * r * r * std::tan(std::numbers::pi / m);
    EXPECT_NEAR(signed_volume(env.surface) / (polygon * length), 1.0, 1e-9) << m << " contour points";
  }
}

TEST(ExportEnvelope, StraightAndCurvedEnvelopesAreClosedAndOutward) {
  for (const std::string& text : {test::straight_tow_case(), test::curved_tow_case()}) {
    const test::BuiltCase b = test::build_case(text);
    const TowEnvelope env = tow_envelope(b.model, b.q, tow_fibers(b.model, b.q, b.c.tows), 0, EnvelopeOptions{});
    EXPECT_EQ(unpaired_edges(env.surface), 0);
    EXPECT_GT(signed_volume(env.surface), 0.0);
    // Outward at every point: the winding number is 1 just inside the centre line, 0 far out.
    const Vec3 inside = env.stations[env.stations.size() / 2].center;
    EXPECT_NEAR(winding_number(env.surface, inside), 1.0, 1e-9);
    EXPECT_NEAR(winding_number(env.surface, inside + Vec3(0, 0, 1e-3)), 0.0, 1e-9);
  }
}

TEST(ExportEnvelope, TheCurvedTowsEnvelopeFollowsItsArc) {
  const test::BuiltCase b = test::build_case(test::curved_tow_case());
  const TowEnvelope env = tow_envelope(b.model, b.q, tow_fibers(b.model, b.q, b.c.tows), 0, EnvelopeOptions{});
  // The mean radius is that of the middle arc; the tow's cross-section is about its hull.
  for (const TowStation& st : env.stations) {
    EXPECT_NEAR(Eigen::Vector2d(st.center.x(), st.center.y()).norm(), 2.12e-3, 1e-6);
    EXPECT_NEAR(st.direction.z(), 0.0, 1e-12);
  }
  const double hull = 0.24e-3 * 2 * 0.05e-3 + std::numbers::pi * 0.05e-3 * 0.05e-3;  // a stadium
  const double path = 2.12e-3 * std::numbers::pi / 3.0;
  EXPECT_NEAR(signed_volume(env.surface) / (hull * path), 1.0, 0.02);
}

TEST(ExportEnvelope, TwoTowsPressedIntoEachOtherComeOutApart) {
  // Tow A along x and tow B along y cross with their fibers overlapping by 10 % of their
  // diameter (deeper than a penalty contact leaves them): their hulls intersect, their
  // envelopes not.
  const double r = 0.05e-3, gap = 2 * r * 0.9;
  std::string text = test::kMaterial;
  for (int k = 0; k < 3; ++k) {
    const double o = (k - 1) * 2.05 * r;
    text += test::straight_fiber(fmt::format("a{}", k), Vec3(-1e-3, o, 0), Vec3(1e-3, o, 0), r, 8);
    text += test::straight_fiber(fmt::format("b{}", k), Vec3(o, -1e-3, gap), Vec3(o, 1e-3, gap), r, 8);
  }
  text += test::tow("A", "warp", 0, {"a0", "a1", "a2"}) + test::tow("B", "weft", 0, {"b0", "b1", "b2"}) + test::kStep;
  const test::BuiltCase b = test::build_case(text);
  const TowFibers tows = tow_fibers(b.model, b.q, b.c.tows);
  std::vector<TowEnvelope> hulls = {tow_envelope(b.model, b.q, tows, 0, {}), tow_envelope(b.model, b.q, tows, 1, {})};
  ASSERT_FALSE(intersecting_triangles(hulls[0].surface, hulls[1].surface).empty()) << "the case does not test anything";
  Separation separation;
  const std::vector<TowEnvelope> envelopes = tow_envelopes(b.model, b.q, tows, EnvelopeOptions{}, &separation);
  EXPECT_TRUE(separation.remaining.empty());
  EXPECT_TRUE(intersecting_triangles(envelopes[0].surface, envelopes[1].surface).empty());
  // Each gave up at least half the overlap (0.1 r), less than all of it (the straight pieces
  // between stations cross the other tow's edge lower than the stations), and only near the
  // crossing.
  EXPECT_GE(separation.largest_inset, 0.1 * r);
  EXPECT_LE(separation.largest_inset, 0.2 * r);
  for (const TowEnvelope& env : envelopes) {
    EXPECT_EQ(unpaired_edges(env.surface), 0);
    EXPECT_DOUBLE_EQ(env.insets.front().front(), 0.0) << "an end of the tow, far from the crossing, moved";
  }
  // No vertex of one lies inside the other (a check apart from the triangle tests).
  for (int a = 0; a < 2; ++a)
    for (const Vec3& p : envelopes[a].surface.points) EXPECT_LT(winding_number(envelopes[1 - a].surface, p), 0.5);
}

/// A closed octahedron (outward) about c, of half-diagonal h.
TriangleMesh octahedron(const Vec3& c, double h) {
  TriangleMesh m;
  for (int axis = 0; axis < 3; ++axis)
    for (double s : {1.0, -1.0}) m.points.push_back(c + s * h * Vec3::Unit(axis));
  // Points: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z.
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

TEST(ExportMesh, TheChecksFailOnAnOpenAFlippedAndAnInsideOutSurface) {
  const TriangleMesh closed = octahedron(Vec3(1, 2, 3), 0.5);
  EXPECT_EQ(unpaired_edges(closed), 0);
  EXPECT_NEAR(signed_volume(closed), 4.0 / 3.0 * 0.125, 1e-15);
  TriangleMesh open = closed;
  open.triangles.pop_back();
  EXPECT_EQ(unpaired_edges(open), 3);
  TriangleMesh flipped = closed;
  std::swap(flipped.triangles[0][0], flipped.triangles[0][1]);
  EXPECT_GT(unpaired_edges(flipped), 0);
  TriangleMesh inside_out = closed;
  for (auto& t : inside_out.triangles) std::swap(t[0], t[1]);
  EXPECT_EQ(unpaired_edges(inside_out), 0);
  EXPECT_LT(signed_volume(inside_out), 0.0);
  EXPECT_NEAR(winding_number(closed, Vec3(1, 2, 3)), 1.0, 1e-12);
  EXPECT_NEAR(winding_number(inside_out, Vec3(1, 2, 3)), -1.0, 1e-12);
}

TEST(ExportMesh, TrianglesIntersectWhenTheyCrossOrTouchOnly) {
  const Triangle t = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_TRUE(triangles_intersect(t, {Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), Vec3(0.3, 0.25, 1)}));  // pierces
  EXPECT_FALSE(triangles_intersect(t, {Vec3(2, 2, -1), Vec3(2, 2, 1), Vec3(3, 2, 1)}));              // beside
  EXPECT_FALSE(triangles_intersect(t, {Vec3(0, 0, 0.1), Vec3(1, 0, 0.1), Vec3(0, 1, 0.1)}));         // above
  EXPECT_TRUE(triangles_intersect(t, {Vec3(0.6, 0.6, -1), Vec3(0.6, 0.6, 1), Vec3(0.4, 0.4, 1)}));   // crosses an edge
  EXPECT_TRUE(triangles_intersect(t, {Vec3(0.2, 0.2, 0), Vec3(2, 0.2, 0), Vec3(0.2, 2, 0)}));  // coplanar, overlapping
  EXPECT_FALSE(triangles_intersect(t, {Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 2, 0)}));         // coplanar, apart
  EXPECT_TRUE(triangles_intersect(t, {Vec3(0.5, 0.5, 0), Vec3(0.5, 0.5, 1), Vec3(1, 1, 1)}));  // touches an edge
  // Two octahedra: apart, then overlapping.
  EXPECT_TRUE(intersecting_triangles(octahedron(Vec3(0, 0, 0), 1), octahedron(Vec3(2.1, 0, 0), 1)).empty());
  EXPECT_FALSE(intersecting_triangles(octahedron(Vec3(0, 0, 0), 1), octahedron(Vec3(1.5, 0.1, 0.2), 1)).empty());
}

}  // namespace
}  // namespace fibra
