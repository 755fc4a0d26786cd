// Fabric generator pieces: weave patterns (named repeats, validation), the packing of fibers
// in a tow's elliptical section (count, no overlap, inside the ellipse, volume fraction as
// computed from the geometry), and the expansion of a [fabric] into tows, bodies and bindings.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/fabric.hpp"
#include "support/fabric_cases.hpp"

namespace fibra {
namespace {

TEST(WeavePatterns, NamedRepeats) {
  std::string error;
  EXPECT_EQ(named_weave("plain", error), (std::vector<std::vector<int>>{{1, 0}, {0, 1}}));
  // Twill 2/1: each warp over two wefts then under one, shifted by one per weft.
  const auto twill = named_weave("twill 2/1", error);
  EXPECT_EQ(twill, (std::vector<std::vector<int>>{{1, 1, 0}, {0, 1, 1}, {1, 0, 1}}));
  const auto basket = named_weave("basket", error);
  ASSERT_EQ(basket.size(), 4u);
  EXPECT_EQ(basket[0], (std::vector<int>{1, 1, 0, 0}));
  EXPECT_EQ(basket[2], (std::vector<int>{0, 0, 1, 1}));
  // Satin 5 (move 2): one interlacing per weft and per warp.
  const auto satin = named_weave("satin 5", error);
  ASSERT_EQ(satin.size(), 5u);
  for (int j = 0; j < 5; ++j) {
    int row = 0, col = 0;
    for (int i = 0; i < 5; ++i) {
      row += satin[j][i] == 0;
      col += satin[i][j] == 0;
    }
    EXPECT_EQ(row, 1);
    EXPECT_EQ(col, 1);
  }
  for (const char* name : {"plain", "twill 2/1", "twill 2/2", "twill 3/1", "basket", "basket 3", "satin 5", "satin 8/3"})
    EXPECT_EQ(check_weave(named_weave(name, error)), "") << name;
  EXPECT_TRUE(named_weave("twil 2/1", error).empty());
  EXPECT_NE(error.find("accepted"), std::string::npos);
  EXPECT_TRUE(named_weave("satin 6/3", error).empty());  // 3 not coprime with 6
}

TEST(WeavePatterns, DegenerateMatricesAreRefused) {
  EXPECT_NE(check_weave({}), "");
  EXPECT_NE(check_weave({{1, 0}, {1}}), "");          // ragged
  EXPECT_NE(check_weave({{1, 2}, {0, 1}}), "");       // not 0/1
  EXPECT_NE(check_weave({{1, 1}, {0, 0}}), "");       // a weft that never interlaces
  EXPECT_NE(check_weave({{1, 0}, {1, 0}}), "");       // a warp that never interlaces
  EXPECT_EQ(check_weave({{1, 0}, {0, 1}}), "");
  EXPECT_TRUE(warp_above({{1, 0}, {0, 1}}, 2, 4));    // tiled
  EXPECT_FALSE(warp_above({{1, 0}, {0, 1}}, 3, 4));
}

class Packing : public ::testing::TestWithParam<int> {};

TEST_P(Packing, CountNoOverlapInsideTheEllipse) {
  const int n = GetParam();
  const double r = 2e-5, width = 0.8e-3, thickness = 0.2e-3;
  const std::vector<Eigen::Vector2d> p = pack_ellipse(n, r, width, thickness);
  ASSERT_EQ(static_cast<int>(p.size()), n);
  double closest = 1e300;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) closest = std::min(closest, (p[i] - p[j]).norm());
  if (n > 1) {
    EXPECT_GE(closest, 2 * r * (1 - 1e-12));
  }
  // Every disc inside the ellipse (its boundary sampled densely).
  for (const auto& c : p)
    for (int s = 0; s < 720; ++s) {
      const double t = 2 * std::numbers::pi * s / 720;
      const double x = c.x() + r * std::cos(t), y = c.y() + r * std::sin(t);
      ASSERT_LE((x / (0.5 * width)) * (x / (0.5 * width)) + (y / (0.5 * thickness)) * (y / (0.5 * thickness)), 1.0 + 1e-9);
    }
  // Volume fraction in the ellipse, as the report defines it for the starting section.
  const double vf = n * r * r / (0.25 * width * thickness);
  EXPECT_GT(vf, 0.0);
  EXPECT_LT(vf, 0.907);  // below hexagonal close packing
}

INSTANTIATE_TEST_SUITE_P(Counts, Packing, ::testing::Values(3, 7, 48, 60));

// The packing is as symmetric as the count allows (pack_ellipse): an even count maps onto
// itself by the half-turn p -> -p; an odd count by the half-turn or by the mirror x -> -x. The
// tows of the corpus and the examples (3 to 60 fibers in sections of 0.8 x 0.2 mm, 1.0 x 0.25 mm
// and the paper's 0.8 x 0.15 mm), each site's image found among the sites to 1e-12 of the
// section.
TEST(Packing, TheSitesAreAsSymmetricAsTheCountAllows) {
  struct Section {
    double r, width, thickness;
  };
  for (const Section& sec : {Section{2e-5, 0.8e-3, 0.2e-3}, Section{2e-5, 1.0e-3, 0.25e-3}, Section{1e-5, 0.8e-3, 0.15e-3},
                             Section{5e-5, 1.0e-3, 0.3e-3}}) {
    for (int n = 3; n <= 60; ++n) {
      const std::vector<Eigen::Vector2d> p = pack_ellipse(n, sec.r, sec.width, sec.thickness);
      if (p.empty()) continue;
      SCOPED_TRACE(::testing::Message() << n << " fibers of radius " << sec.r << " in " << sec.width << " x "
                                        << sec.thickness);
      const auto maps = [&](const Eigen::Vector2d& s) {
        for (const auto& a : p) {
          bool found = false;
          for (const auto& b : p) found = found || (Eigen::Vector2d(s.x() * a.x(), s.y() * a.y()) - b).norm() <= 1e-12 * sec.width;
          if (!found) return false;
        }
        return true;
      };
      const bool half_turn = maps({-1, -1}), mirror = maps({-1, 1});
      if (n % 2 == 0) {
        EXPECT_TRUE(half_turn);
      } else {
        EXPECT_TRUE(half_turn || mirror);
      }
    }
  }
}

TEST(Packing, TooManyFibersDoNotFit) {
  EXPECT_TRUE(pack_ellipse(2000, 2e-5, 0.8e-3, 0.2e-3).empty());
  EXPECT_FALSE(pack_ellipse(48, 2e-5, 0.8e-3, 0.2e-3).empty());
}

// Fibers tiny against the section: the lattice at their touching spacing has billions of sites;
// the packing starts from a spacing near the one it finds and takes as long as for thick fibers.
// The spacing falls with the radius by about 2.1 radii (the fibers kept inside the ellipse):
// 1e-9 m and 1e-12 m give it within 3e-9 m, and 2e-6 m (whose touching lattice, 9e3 sites, is
// listed as before) within 6e-6 m.
TEST(Packing, TinyFibersArePackedAtOnce) {
  const double width = 0.8e-3, thickness = 0.2e-3;
  for (const int n : {3, 7, 48}) {
    const auto closest = [&](double r) {
      const auto start = std::chrono::steady_clock::now();
      const std::vector<Eigen::Vector2d> p = pack_ellipse(n, r, width, thickness);
      EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0) << r;
      EXPECT_EQ(static_cast<int>(p.size()), n) << r;
      double d = 1e300;
      for (size_t i = 0; i < p.size(); ++i) {
        EXPECT_LE(std::pow(p[i].x() / (0.5 * width - r), 2) + std::pow(p[i].y() / (0.5 * thickness - r), 2), 1.0);
        for (size_t j = i + 1; j < p.size(); ++j) d = std::min(d, (p[i] - p[j]).norm());
      }
      return d;
    };
    SCOPED_TRACE(n);
    const double tiny = closest(1e-9), tinier = closest(1e-12), thin = closest(2e-6);
    EXPECT_GT(tiny, 5e-5);
    EXPECT_NEAR(tiny, tinier, 3e-9);
    EXPECT_GT(tiny, thin);
    EXPECT_NEAR(tiny, thin, 6e-6);
  }
}

// A tow far wider than its fibers (a width of 50 m for fibers of 50 um, a typo of the kind the
// fuzzing of the case readers made: docs/sanitizers.md): its lattices have millions of sites, each
// formerly sampled along its disc in every step of the bisection (25 s on the reference machine,
// more than a minute instrumented); now a second or two.
TEST(Packing, WideTowsArePackedAtOnce) {
  const double r = 5e-5, width = 50.0, thickness = 2.5e-4;
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Eigen::Vector2d> p = pack_ellipse(3, r, width, thickness);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0);
  ASSERT_EQ(p.size(), 3u);
  for (const auto& c : p)
    EXPECT_LE(std::pow(c.x() / (0.5 * width - r), 2) + std::pow(c.y() / (0.5 * thickness - r), 2), 1.0);
  EXPECT_GT(std::abs((p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x()), 0.0)
      << "three sites on one line";
}

// The size read_case checks before expanding is that of the expansion: fibers, their elements
// (the fewest not longer than the element length, at least 2) and bodies.
TEST(FabricExpansion, SizeBeforeExpandingIsTheExpansions) {
  for (const double element_length : {2.0e-4, 3.0e-4, 1.0, 1.0e-6}) {
    Case c = parse_case_toml(R"(
[[material]]
name = "glass"
young = 72e9
poisson = 0.22
[fabric]
pattern = "twill 2/1"
warp = { tows = 3, spacing = 1.0e-3 }
weft = { tows = 4, spacing = 1.2e-3, tow = { fibers = 5 } }
  [fabric.tow]
  fibers = 7
  width = 0.7e-3
  thickness = 0.25e-3
  [fabric.fiber]
  radius = 5.0e-5
  material = "glass"
  element_length = 1
[[step]]
name = "weave"
kind = "weave"
)", "fabric.toml");
    c.fabric->warp.fiber.element_length = c.fabric->weft.fiber.element_length = element_length;
    c.fibers.clear();
    c.bodies.clear();
    c.bindings.clear();
    c.tows.clear();
    const ModelSize size = fabric_size(*c.fabric);
    expand_fabric(c);
    SCOPED_TRACE(element_length);
    // Warps span the 4 wefts (3 x 1.2 mm) plus two margins of 0.6 mm; wefts 2 x 1 mm + 1.2 mm.
    EXPECT_NEAR(fabric_fiber_length(*c.fabric, true), 4.8e-3, 1e-15);
    EXPECT_NEAR(fabric_fiber_length(*c.fabric, false), 3.2e-3, 1e-15);
    double elements = 0;
    for (const FiberSpec& f : c.fibers) {
      const bool warp = f.name.rfind("warp", 0) == 0;
      EXPECT_EQ(f.elements, fabric_fiber_elements(*c.fabric, warp)) << f.name;
      EXPECT_EQ(f.elements, std::max(2.0, std::ceil((warp ? 4.8e-3 : 3.2e-3) / element_length - 1e-6))) << f.name;
      elements += f.elements;
    }
    EXPECT_EQ(size.fibers, static_cast<double>(c.fibers.size()));
    EXPECT_EQ(size.fibers, 3 * 7 + 4 * 5);
    EXPECT_EQ(size.elements, elements);
    EXPECT_EQ(size.bodies, static_cast<double>(c.bodies.size()));
  }
}

// A count beyond an int is stopped before its conversion, also when the case was not read.
TEST(FabricExpansion, ElementCountBeyondAnIntIsAnInputError) {
  // Warp fibers of 1 mm + 2 margins of 0.9 mm: 2.8e9 elements of a picometre.
  Case c = parse_case_toml(
      test::glass_fabric("plain", 2, 3, 2e-5, 1e-4, "", "[[step]]\nname = \"weave\"\nkind = \"weave\"\n", 0.9e-3),
      "fabric.toml");
  c.fibers.clear();
  c.bodies.clear();
  c.bindings.clear();
  c.tows.clear();
  c.fabric->warp.fiber.element_length = 1e-12;
  try {
    expand_fabric(c);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "fabric.warp.fiber.element_length");
    EXPECT_NE(std::string(e.what()).find("into 2.8e+09 elements each, more than an int holds"), std::string::npos)
        << e.what();
  }
}

TEST(FabricExpansion, TowsBodiesAndBindings) {
  const Case c = parse_case_toml(R"(
[[material]]
name = "glass"
young = 72e9
poisson = 0.22
[fabric]
pattern = "twill 2/1"
warp = { tows = 3, spacing = 1.0e-3 }
weft = { tows = 4, spacing = 1.2e-3 }
  [fabric.tow]
  fibers = 7
  width = 0.7e-3
  thickness = 0.25e-3
  [fabric.fiber]
  radius = 5.0e-5
  material = "glass"
  element_length = 2.0e-4
[[step]]
name = "weave"
kind = "weave"
)", "fabric.toml");
  EXPECT_EQ(c.fibers.size(), 7u * 7u);
  EXPECT_EQ(c.tows.size(), 7u);
  EXPECT_EQ(c.bodies.size(), 2u * 7u + 4u);           // two ends per tow, four edges
  EXPECT_EQ(c.bindings.size(), 2u * 7u + 4u);
  EXPECT_EQ(c.weave.size(), 3u);
  // Warp tows along x at y = -1, 0, +1 mm; their fibers span the weft axes plus the margin.
  for (const FiberSpec& f : c.fibers)
    if (f.name.rfind("warp", 0) == 0) {
      EXPECT_NEAR(f.path.points.front().x(), -1.8e-3 - 0.6e-3, 1e-15);  // margin: half the larger spacing
      EXPECT_NEAR(f.path.points.back().x(), 1.8e-3 + 0.6e-3, 1e-15);
    }
  // The edge bodies hold the tow ends of their side.
  for (const BindingSpec& b : c.bindings)
    if (b.body == "edge.x+") {
      EXPECT_EQ(b.bodies.size(), 3u);
      EXPECT_EQ(b.bodies.front(), "warp0.end");
    }
  // First-step conditions: the x-/y- edges held, the x+/y+ edges free along their tows under
  // the tension; every tow end held in rotation and out of the plane (z), free in the plane.
  const StepSpec& first = c.steps.front();
  ASSERT_EQ(first.bodies.size(), 4u + 2u * 7u);
  int tow_ends = 0;
  for (const BodyStepSpec& b : first.bodies) {
    EXPECT_TRUE(b.has_rotation) << b.name;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(b.rotation[k], std::optional<double>(0.0)) << b.name;
    if (b.name.rfind("edge.", 0) == 0) {
      EXPECT_TRUE(b.has_displacement) << b.name;
      EXPECT_EQ(b.force.has_value(), b.name == "edge.x+" || b.name == "edge.y+") << b.name;
    } else {
      EXPECT_TRUE(b.has_displacement) << b.name;
      EXPECT_FALSE(b.displacement[0].has_value()) << b.name;
      EXPECT_FALSE(b.displacement[1].has_value()) << b.name;
      EXPECT_EQ(b.displacement[2], std::optional<double>(0.0)) << b.name;
      EXPECT_FALSE(b.force.has_value()) << b.name;
      ++tow_ends;
    }
  }
  EXPECT_EQ(tow_ends, 14);
  // Spacing below the tow width, or more fibers than fit: errors naming the key.
  auto error_of = [](const std::string& text) {
    try {
      parse_case_toml(text, "bad.toml");
    } catch (const InputError& e) {
      return e.key();
    }
    return std::string("no error");
  };
  const std::string base = R"(
[[material]]
name = "glass"
young = 72e9
poisson = 0.22
[fabric]
pattern = "plain"
weft = { tows = 2, spacing = 1.0e-3 }
  [fabric.fiber]
  radius = 5.0e-5
  material = "glass"
  element_length = 2.0e-4
[[step]]
name = "s"
)";
  EXPECT_EQ(error_of(base + "[fabric.warp]\ntows = 2\nspacing = 0.5e-3\n[fabric.tow]\nfibers = 5\nwidth = 0.7e-3\nthickness = 0.25e-3\n"),
            "fabric.warp.spacing");
  EXPECT_EQ(error_of(base + "[fabric.warp]\ntows = 2\nspacing = 1e-3\n[fabric.tow]\nfibers = 500\nwidth = 0.7e-3\nthickness = 0.25e-3\n"),
            "fabric.warp.tow.fibers");
}

// A tow end (or edge) the user lists in any step keeps the user's conditions: the expansion
// adds its defaults only for the bodies no step mentions.
TEST(FabricExpansion, UserConditionsOnATowEndReplaceTheDefault) {
  const Case c = parse_case_toml(test::glass_fabric("plain", 2, 3, 5.0e-5, 2.0e-4, "", R"([[step]]
name = "weave"
kind = "weave"
  [[step.body]]
  name = "weft1.end"
  rotation = ["free", "free", 0]
)"),
                                 "fabric.toml");
  int entries = 0;
  for (const BodyStepSpec& b : c.steps.front().bodies) {
    if (b.name != "weft1.end") continue;
    ++entries;
    EXPECT_FALSE(b.rotation[0].has_value());
    EXPECT_FALSE(b.rotation[1].has_value());
    EXPECT_EQ(b.rotation[2], std::optional<double>(0.0));
  }
  EXPECT_EQ(entries, 1);
  EXPECT_EQ(c.steps.front().bodies.size(), 4u + 8u);
}

}  // namespace
}  // namespace fibra
