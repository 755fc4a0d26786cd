/// Tests of the cuts of a fiber assembly by a plane (model/slice_cuts.hpp): straight,
/// oblique, curved and in-plane fibers against their exact cuts, planes of any direction, the
/// stations of a tow, and a slice along a tow of a fabric's assembly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/model/slice_cuts.hpp"
#include "support/fabric_cases.hpp"
#include "support/straight_fibers.hpp"

namespace fibra {
namespace {

constexpr double kR = 0.05e-3;  // fiber radius [m]

const std::string& kStraight = test::kStraightFibers;


TEST(SliceCuts, StraightFibersAtRightAnglesGiveTheirSections) {
  const Case c = parse_case_toml(kStraight, "straight.toml");
  const Model model = build_model(c);
  const std::vector<SliceCut> cuts = slice_cuts(model, model.reference, c.tows, 0, 0.3e-3);
  ASSERT_EQ(cuts.size(), 5u);
  EXPECT_EQ(slice_fiber_count(cuts), 5);
  // Each fiber once, centred at its (y, z), every point at the radius, coloured by its tow.
  const std::map<std::string, std::pair<Eigen::Vector2d, int>> expected = {{"a1", {{0, 0}, 0}},
                                                                           {"a2", {{0.2e-3, 0.05e-3}, 0}},
                                                                           {"b1", {{-0.3e-3, 0.2e-3}, 1}},
                                                                           {"c1", {{0.5e-3, -0.1e-3}, 2}},
                                                                           {"loose", {{0.8e-3, 0}, -1}}};
  for (const SliceCut& cut : cuts) {
    ASSERT_TRUE(expected.count(cut.name)) << cut.name;
    const auto& [centre, tow] = expected.at(cut.name);
    EXPECT_EQ(cut.kind, SliceCut::Kind::Crossing);
    EXPECT_EQ(cut.tow, tow) << cut.name;
    EXPECT_EQ(model.fibers[cut.fiber].name, cut.name);
    EXPECT_NEAR((cut.center - centre).norm(), 0, 1e-10) << cut.name;
    EXPECT_GE(cut.points.size(), 24u);
    for (const auto& p : cut.points) EXPECT_NEAR((p - centre).norm(), kR, 1e-10) << cut.name;
  }
  const Eigen::AlignedBox2d box = slice_extent(cuts);
  EXPECT_NEAR(box.min().x(), -0.3e-3 - kR, 1e-10);
  EXPECT_NEAR(box.max().x(), 0.8e-3 + kR, 1e-10);
  EXPECT_NEAR(box.max().y(), 0.2e-3 + kR, 1e-10);
}

TEST(SliceCuts, AnObliqueFiberGivesAnEllipseElongatedByOneOverCos) {
  // In the x-y plane at 25, 40 and 55 degrees from x, through (0.3 mm, 0.1 mm, 0).
  for (const double degrees : {25.0, 40.0, 55.0}) {
    const double angle = degrees * std::numbers::pi / 180, L = 1e-3;
    const Vec3 mid(0.3e-3, 0.1e-3, 0), dir(std::cos(angle), std::sin(angle), 0);
    const Vec3 p0 = mid - L * dir, p1 = mid + L * dir;
    const std::string text = fmt::format(R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3

[[fiber]]
name = "oblique"
material = "m"
radius = 0.05e-3
points = [[{}, {}, 0], [{}, {}, 0]]
elements = 7

[[step]]
)",
                                         p0.x(), p0.y(), p1.x(), p1.y());
    const Case c = parse_case_toml(text, "oblique.toml");
    const Model model = build_model(c);
    const std::vector<SliceCut> cuts = slice_cuts(model, model.reference, c.tows, 0, 0.3e-3);
    ASSERT_EQ(cuts.size(), 1u) << degrees;
    EXPECT_EQ(cuts[0].kind, SliceCut::Kind::Crossing);
    EXPECT_EQ(cuts[0].tow, -1);
    EXPECT_NEAR(cuts[0].center.x(), 0.1e-3, 1e-12);
    EXPECT_NEAR(cuts[0].center.y(), 0.0, 1e-12);
    // Every point on the ellipse of semi-axes r / cos(angle) along y and r along z.
    const double along_y = kR / std::cos(angle);
    double max_y = 0, max_z = 0;
    for (const Eigen::Vector2d& p : cuts[0].points) {
      const Eigen::Vector2d d = p - cuts[0].center;
      EXPECT_NEAR(std::pow(d.x() / along_y, 2) + std::pow(d.y() / kR, 2), 1.0, 1e-9) << degrees;
      max_y = std::max(max_y, std::abs(d.x()));
      max_z = std::max(max_z, std::abs(d.y()));
    }
    EXPECT_NEAR(max_y, along_y, 1e-3 * kR) << degrees;
    EXPECT_NEAR(max_z, kR, 1e-3 * kR) << degrees;
  }
}

TEST(SliceCuts, ACurvedFiberCrossingTwiceGivesTwoCuts) {
  // A circle of radius 1 mm about the origin in the x-y plane (an arc of 340 degrees), cut by
  // x = 0.5 mm: at y = +-0.866 mm, crossing at 30 degrees from the plane's normal.
  const std::string text = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3

[[fiber]]
name = "ring"
material = "m"
radius = 0.05e-3
arc = { radius = 1e-3, start_angle = 100, angle = 340 }
elements = 40

[[step]]
)";
  const Case c = parse_case_toml(text, "ring.toml");
  const Model model = build_model(c);
  const std::vector<SliceCut> cuts = slice_cuts(model, model.reference, c.tows, 0, 0.5e-3);
  ASSERT_EQ(cuts.size(), 2u);
  std::vector<double> ys;
  for (const SliceCut& cut : cuts) {
    EXPECT_EQ(cut.kind, SliceCut::Kind::Crossing);
    ys.push_back(cut.center.x());
    EXPECT_NEAR(cut.center.y(), 0, 1e-12);
    // Elongated by 1 / cos(30 degrees) along y (to the interpolation error of the circle).
    double max_y = 0;
    for (const auto& p : cut.points) max_y = std::max(max_y, std::abs(p.x() - cut.center.x()));
    EXPECT_NEAR(max_y, kR / std::cos(std::numbers::pi / 6), 2e-3 * kR);
  }
  std::sort(ys.begin(), ys.end());
  EXPECT_NEAR(ys[0], -std::sqrt(0.75) * 1e-3, 1e-7);
  EXPECT_NEAR(ys[1], std::sqrt(0.75) * 1e-3, 1e-7);
  EXPECT_EQ(slice_fiber_count(cuts), 1);
}

TEST(SliceCuts, AFiberLyingInThePlaneGivesAStrip) {
  // A fiber along y at x = 0.3 mm + r / 2: the plane x = 0.3 mm cuts it along a band of
  // half-width r sqrt(3) / 2 over its whole length; a fiber at x = 0.3 mm + 1.5 r is missed.
  const std::string text = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3

[[fiber]]
name = "along"
material = "m"
radius = 0.05e-3
points = [[0.325e-3, -1e-3, 0.1e-3], [0.325e-3, 1e-3, 0.1e-3]]
elements = 4

[[fiber]]
name = "beside"
material = "m"
radius = 0.05e-3
points = [[0.375e-3, -1e-3, 0], [0.375e-3, 1e-3, 0]]
elements = 4

[[step]]
)";
  const Case c = parse_case_toml(text, "strip.toml");
  const Model model = build_model(c);
  const std::vector<SliceCut> cuts = slice_cuts(model, model.reference, c.tows, 0, 0.3e-3);
  ASSERT_EQ(cuts.size(), 1u);
  EXPECT_EQ(cuts[0].kind, SliceCut::Kind::Strip);
  EXPECT_EQ(cuts[0].name, "along");
  Eigen::AlignedBox2d box;
  for (const auto& p : cuts[0].points) box.extend(p);
  EXPECT_NEAR(box.min().x(), -1e-3, 1e-12);
  EXPECT_NEAR(box.max().x(), 1e-3, 1e-12);
  EXPECT_NEAR(box.min().y(), 0.1e-3 - kR * std::sqrt(0.75), 1e-12);
  EXPECT_NEAR(box.max().y(), 0.1e-3 + kR * std::sqrt(0.75), 1e-12);
  // A slice across it instead: z = 0.1 mm cuts "along" through its axis (full width 2 r).
  const std::vector<SliceCut> flat = slice_cuts(model, model.reference, c.tows, 2, 0.1e-3);
  ASSERT_EQ(flat.size(), 1u);
  Eigen::AlignedBox2d flat_box;
  for (const auto& p : flat[0].points) flat_box.extend(p);
  EXPECT_NEAR(flat_box.sizes().x(), 2 * kR, 1e-12);  // (x, y) coordinates: width along x
}

TEST(SliceCuts, APlaneThatMissesEverythingCutsNothing) {
  const Case c = parse_case_toml(kStraight, "straight.toml");
  const Model model = build_model(c);
  EXPECT_TRUE(slice_cuts(model, model.reference, c.tows, 0, 2e-3).empty());
  EXPECT_TRUE(slice_cuts(model, model.reference, c.tows, 1, 5e-3).empty());
  const Eigen::AlignedBox3d box = centroid_bounds(model, model.reference);
  EXPECT_DOUBLE_EQ(box.min().x(), -0.3e-3);
  EXPECT_DOUBLE_EQ(box.max().x(), 1e-3);
  EXPECT_DOUBLE_EQ(box.max().y(), 0.8e-3);
}


TEST(SliceCuts, APlaneOfAnyDirectionCutsAsItsAxisPlaneDoes) {
  const Case c = parse_case_toml(kStraight, "straight.toml");
  const Model model = build_model(c);
  // The plane x = 0.3 mm given by its normal, not by its axis: the same cuts.
  SlicePlane plane;
  plane.normal = Vec3::UnitX();
  plane.u = Vec3::UnitY();
  plane.v = Vec3::UnitZ();
  plane.offset = 0.3e-3;
  plane.axis = -1;
  const std::vector<SliceCut> given = slice_cuts(model, model.reference, c.tows, plane);
  const std::vector<SliceCut> by_axis = slice_cuts(model, model.reference, c.tows, 0, 0.3e-3);
  ASSERT_EQ(given.size(), by_axis.size());
  for (size_t k = 0; k < given.size(); ++k) {
    EXPECT_EQ(given[k].name, by_axis[k].name);
    ASSERT_EQ(given[k].points.size(), by_axis[k].points.size());
    for (size_t j = 0; j < given[k].points.size(); ++j)
      EXPECT_NEAR((given[k].points[j] - by_axis[k].points[j]).norm(), 0, 1e-15);
  }
  // A fiber along d (35 degrees from x in the plane z = 0.1 mm) cut at right angles by the plane
  // normal to d through its point p: the section, a circle of radius r about (u . p, v . p).
  const double angle = 35 * std::numbers::pi / 180;
  const Vec3 d(std::cos(angle), std::sin(angle), 0), p(0.2e-3, 0.1e-3, 0.1e-3);
  const Vec3 a = p - 1e-3 * d, b = p + 1e-3 * d;
  const Case oblique = parse_case_toml(fmt::format(R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3

[[fiber]]
name = "f"
material = "m"
radius = 0.05e-3
points = [[{}, {}, {}], [{}, {}, {}]]
elements = 5

[[step]]
)",
                                                   a.x(), a.y(), a.z(), b.x(), b.y(), b.z()),
                                       "oblique.toml");
  const Model m = build_model(oblique);
  SlicePlane normal_to_d;
  normal_to_d.normal = d;
  normal_to_d.u = Vec3(-d.y(), d.x(), 0);
  normal_to_d.v = Vec3::UnitZ();
  normal_to_d.offset = d.dot(p);
  normal_to_d.axis = -1;
  const std::vector<SliceCut> cuts = slice_cuts(m, m.reference, oblique.tows, normal_to_d);
  ASSERT_EQ(cuts.size(), 1u);
  EXPECT_EQ(cuts[0].kind, SliceCut::Kind::Crossing);
  const Eigen::Vector2d centre(normal_to_d.u.dot(p), normal_to_d.v.dot(p));
  EXPECT_NEAR((cuts[0].center - centre).norm(), 0, 1e-12);
  for (const auto& q : cuts[0].points) EXPECT_NEAR((q - centre).norm(), kR, 1e-10);
}

/// The cuts of tow `tow` (index into the case's tows) among `cuts`.
std::vector<SliceCut> cuts_of_tow(const std::vector<SliceCut>& cuts, int tow) {
  std::vector<SliceCut> own;
  for (const SliceCut& c : cuts)
    if (c.tow == tow) own.push_back(c);
  return own;
}

/// Each of `fibers` is cut exactly once among `cuts`, as a crossing, and nothing else is.
void expect_each_fiber_cut_once(const std::vector<SliceCut>& cuts, const std::vector<std::string>& fibers,
                                const std::string& where) {
  std::map<std::string, int> count;
  for (const SliceCut& c : cuts) {
    ++count[c.name];
    EXPECT_EQ(c.kind, SliceCut::Kind::Crossing) << c.name << " " << where;
  }
  EXPECT_EQ(count.size(), fibers.size()) << where;
  for (const std::string& f : fibers) EXPECT_EQ(count[f], 1) << f << " " << where;
}

// A warp tow of three straight fibers that begin and end at different x: the stations share
// the span all three cover, [0.1, 0.95] mm, and are spaced evenly inside it, ends excluded.
TEST(SliceCuts, TowStationsAreEvenlySpacedBetweenTheTowsEndsAndCutEachFiberOnce) {
  const Case c = parse_case_toml(R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3

[[fiber]]
name = "f0"
material = "m"
radius = 0.05e-3
points = [[0, 0, 0], [1e-3, 0, 0]]
elements = 4

[[fiber]]
name = "f1"
material = "m"
radius = 0.05e-3
points = [[1.1e-3, 0.15e-3, 0], [0.1e-3, 0.15e-3, 0]]
elements = 5

[[fiber]]
name = "f2"
material = "m"
radius = 0.05e-3
points = [[0.05e-3, -0.15e-3, 0], [0.95e-3, -0.15e-3, 0]]
elements = 3

[[fiber]]
name = "w"
material = "m"
radius = 0.05e-3
points = [[0.44e-3, -1e-3, 0.2e-3], [0.44e-3, 1e-3, 0.2e-3]]
elements = 4

[[tow]]
name = "T"
direction = "warp"
index = 0
fibers = ["f0", "f1", "f2"]

[[tow]]
name = "W"
direction = "weft"
index = 0
fibers = ["w"]

[[step]]
)",
                                 "tow.toml");
  const Model model = build_model(c);
  const TowStations st = tow_stations(model, model.reference, c.tows[0], 4);
  EXPECT_NEAR((st.direction - Vec3::UnitX()).norm(), 0, 1e-15);  // f1 runs backwards: turned
  EXPECT_NEAR(st.start, 0.1e-3, 1e-15);
  EXPECT_NEAR(st.end, 0.95e-3, 1e-15);
  ASSERT_EQ(st.planes.size(), 4u);
  const double expected[4] = {0.27e-3, 0.44e-3, 0.61e-3, 0.78e-3};
  for (int k = 0; k < 4; ++k) {
    const SlicePlane& p = st.planes[k];
    EXPECT_NEAR(p.offset, expected[k], 1e-15) << k;
    EXPECT_EQ(p.axis, -1);
    EXPECT_NEAR((p.normal - Vec3::UnitX()).norm(), 0, 1e-15);
    EXPECT_NEAR((p.u - Vec3::UnitY()).norm(), 0, 1e-15);  // across, towards +y
    EXPECT_NEAR((p.v - Vec3::UnitZ()).norm(), 0, 1e-15);  // up
    EXPECT_NE(p.caption.find(fmt::format("station {} of 4", k + 1)), std::string::npos) << p.caption;
    const std::vector<SliceCut> cuts = slice_cuts(model, model.reference, c.tows, p);
    expect_each_fiber_cut_once(cuts_of_tow(cuts, 0), c.tows[0].fibers, fmt::format("station {}", k + 1));
    for (const SliceCut& cut : cuts_of_tow(cuts, 0))
      for (const auto& q : cut.points) EXPECT_NEAR((q - cut.center).norm(), kR, 1e-10) << cut.name;
  }
  // The second station lies on the weft fiber w: the whole slice has it as a strip.
  const std::vector<SliceCut> second = cuts_of_tow(slice_cuts(model, model.reference, c.tows, st.planes[1]), 1);
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(second[0].kind, SliceCut::Kind::Strip);

  // What cannot be done.
  EXPECT_THROW(tow_stations(model, model.reference, c.tows[0], 0), std::invalid_argument);
  TowSpec ghost = c.tows[0];
  ghost.fibers = {"nobody"};
  EXPECT_THROW(tow_stations(model, model.reference, ghost, 3), std::invalid_argument);
}

// A weft tow turned 20 degrees in the fabric plane (as a shear turns it): the planes are normal
// to its fibers, so each cut is the fiber's circular section; across points towards +x.
TEST(SliceCuts, TheStationsOfATurnedTowAreNormalToItsFibers) {
  const double angle = 20 * std::numbers::pi / 180;
  const Vec3 d(std::sin(angle), std::cos(angle), 0), across(std::cos(angle), -std::sin(angle), 0);
  std::string text = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
)";
  for (int k = 0; k < 3; ++k) {
    const Vec3 a = (k - 1) * 0.12e-3 * across - 1e-3 * d + Vec3(0, 0, 0.01e-3 * k), b = a + 2e-3 * d;
    text += fmt::format(R"(
[[fiber]]
name = "f{}"
material = "m"
radius = 0.05e-3
points = [[{}, {}, {}], [{}, {}, {}]]
elements = 6
)",
                        k, a.x(), a.y(), a.z(), b.x(), b.y(), b.z());
  }
  text += "\n[[tow]]\nname = \"weft3\"\ndirection = \"weft\"\nindex = 3\nfibers = [\"f0\", \"f1\", \"f2\"]\n\n[[step]]\n";
  const Case c = parse_case_toml(text, "turned.toml");
  const Model model = build_model(c);
  const TowStations st = tow_stations(model, model.reference, c.tows[0], 3);
  EXPECT_NEAR((st.direction - d).norm(), 0, 1e-12);
  EXPECT_NEAR(st.end - st.start, 2e-3, 1e-12);
  ASSERT_EQ(st.planes.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    const SlicePlane& p = st.planes[k];
    EXPECT_NEAR(p.offset - st.start, 0.5e-3 * (k + 1), 1e-12);
    EXPECT_NEAR((p.u - across).norm(), 0, 1e-12);
    EXPECT_NEAR((p.v - Vec3::UnitZ()).norm(), 0, 1e-12);
    const std::vector<SliceCut> cuts = slice_cuts(model, model.reference, c.tows, p);
    expect_each_fiber_cut_once(cuts, c.tows[0].fibers, fmt::format("station {}", k + 1));
    for (const SliceCut& cut : cuts) {
      for (const auto& q : cut.points) EXPECT_NEAR((q - cut.center).norm(), kR, 1e-10) << cut.name;
      // Across the tow, the fibers sit 0.12 mm apart in their order.
      const int f = cut.name.back() - '0';
      EXPECT_NEAR(cut.center.x(), (f - 1) * 0.12e-3, 1e-12) << cut.name;
    }
  }
}

// The starting assembly of a plain weave: a slice along a warp tow's middle fiber shows that
// fiber as a strip and crosses the fibers of both wefts; the tow's stations cut each of its
// fibers once.
TEST(SliceCuts, ASliceAlongAWarpOfAFabricShowsItAndTheWeftsItCrosses) {
  const Case c = parse_case_toml(test::glass_fabric("plain", 2, 3, 5.0e-5, 2.0e-4, "",
                                                    "[[step]]\nname = \"weave\"\nkind = \"weave\"\n"),
                                 "fabric.toml");
  const Model model = build_model(c);
  int warp0 = -1;
  for (size_t t = 0; t < c.tows.size(); ++t)
    if (c.tows[t].name == "warp0") warp0 = static_cast<int>(t);
  ASSERT_GE(warp0, 0);
  const Fiber& middle = model.fibers[model.fiber_index(c.tows[warp0].fibers[1])];
  double y = 0;
  for (Index k = 0; k < middle.num_nodes; ++k) y += model.reference[kNodeDofs * (middle.first_node + k) + 1];
  y /= static_cast<double>(middle.num_nodes);
  const std::vector<SliceCut> cuts = slice_cuts(model, model.reference, c.tows, 1, y);
  int strips = 0, weft_crossings = 0;
  for (const SliceCut& cut : cuts) {
    if (cut.tow == warp0 && cut.kind == SliceCut::Kind::Strip) ++strips;
    if (cut.tow >= 0 && c.tows[cut.tow].direction == TowSpec::Direction::Weft) {
      EXPECT_EQ(cut.kind, SliceCut::Kind::Crossing) << cut.name;
      ++weft_crossings;
    }
  }
  EXPECT_GT(strips, 0);
  EXPECT_EQ(weft_crossings, 6);  // 2 wefts of 3 fibers

  const TowStations st = tow_stations(model, model.reference, c.tows[warp0], 5);
  ASSERT_EQ(st.planes.size(), 5u);
  for (size_t k = 0; k < st.planes.size(); ++k)
    expect_each_fiber_cut_once(cuts_of_tow(slice_cuts(model, model.reference, c.tows, st.planes[k]), warp0),
                               c.tows[warp0].fibers, fmt::format("station {}", k + 1));
}

}  // namespace
}  // namespace fibra
