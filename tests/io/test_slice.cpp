/// Tests of the drawn slices (io/slice.hpp): the PNG read back with Cairo (size, the tows'
/// colours at the cuts' centres, white around them, the text and the scale bar drawn), the SVG
/// well-formed with one path per cut in its tow's colour, the page shared by the slices of a
/// tow's stations, and text Cairo would refuse.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/io/slice.hpp"
#include "fibra/model/model.hpp"
#include "support/scratch_dir.hpp"
#include "support/slice_files.hpp"
#include "support/straight_fibers.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;
using test::Colour;
using test::slurp;

const std::string& kStraight = test::kStraightFibers;

/// The colour drawn for a cut of tow `tow` (index into `tows`; -1: none).
Colour colour_of(const std::vector<TowSpec>& tows, int tow) {
  if (tow < 0) return test::kSliceGrey;
  const TowSpec& t = tows[tow];
  return t.direction == TowSpec::Direction::Warp ? test::kSliceWarp[t.index % 4] : test::kSliceWeft[t.index % 4];
}

/// Equal within one unit per channel (the colour's round trip through Cairo's 16 bits).
bool near(const Colour& a, const Colour& b) {
  return std::abs(a.r - b.r) <= 1 && std::abs(a.g - b.g) <= 1 && std::abs(a.b - b.b) <= 1;
}

std::string show(const Colour& c) { return fmt::format("({}, {}, {})", c.r, c.g, c.b); }

/// Pixels in rows [y0, y1) that are not white.
int inked(const test::PngImage& png, int y0, int y1) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < png.width; ++x) n += !(png.at(x, y) == Colour{255, 255, 255});
  return n;
}

class Slice : public test::ScratchDirTest {
 protected:
  Slice() : ScratchDirTest("fibra_slice_") {}
};

TEST_F(Slice, ThePngAndTheSvgDrawEveryCutInItsTowsColour) {
  const Case c = parse_case_toml(kStraight, "straight.toml");
  const Model model = build_model(c);
  const std::vector<SliceCut> cuts = slice_cuts(model, model.reference, c.tows, 0, 0.3e-3);
  ASSERT_EQ(cuts.size(), 5u);
  const std::string stem = (m_dir / "sub" / "cut").string();
  EXPECT_EQ(write_slice(stem, model, model.reference, c.tows, 0, 0.3e-3, "Straight fibers"), 5);
  const SlicePage page = slice_page(cuts);
  EXPECT_EQ(page.width, 1200);
  EXPECT_NEAR(page.plot_w, 1086, 1e-9);  // the cuts are wider than high: the plot is as wide as it can be

  // The PNG: Cairo reads it back, of the page's size; each cut's centre in its tow's colour.
  const test::PngImage png = test::read_png(stem + ".png");
  ASSERT_TRUE(png.error.empty()) << png.error;
  EXPECT_EQ(png.width, page.width);
  EXPECT_EQ(png.height, page.height);
  for (const SliceCut& cut : cuts) {
    const Eigen::Vector2d p = page.to_page(cut.center);
    const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
    ASSERT_TRUE(x >= 0 && y >= 0 && x < png.width && y < png.height) << cut.name;
    EXPECT_TRUE(near(png.at(x, y), colour_of(c.tows, cut.tow))) << cut.name << ": " << show(png.at(x, y));
    // A radius away, past the outline, the page is white again.
    const Eigen::Vector2d out = page.to_page(cut.center + Eigen::Vector2d(0, 1.3 * 0.05e-3));
    EXPECT_EQ(png.at(static_cast<int>(out.x()), static_cast<int>(out.y())), (Colour{255, 255, 255})) << cut.name;
  }
  // Warp blue, weft red, no tow grey; neighbouring warp tows differ.
  const Colour a = colour_of(c.tows, 0), b = colour_of(c.tows, 1), cc = colour_of(c.tows, 2);
  EXPECT_GT(a.b, a.r);
  EXPECT_GT(cc.b, cc.r);
  EXPECT_GT(b.r, b.b);
  EXPECT_FALSE(a == cc);
  EXPECT_EQ(png.at(3, 3), (Colour{255, 255, 255}));
  // Between a1 (0, 0) and b1 (-0.3, 0.2) mm: white.
  const Eigen::Vector2d between = page.to_page(Eigen::Vector2d(-0.15e-3, 0.1e-3));
  EXPECT_EQ(png.at(static_cast<int>(between.x()), static_cast<int>(between.y())), (Colour{255, 255, 255}));
  // The title, the subtitle and the tick labels are drawn (a font was found), and the scale bar.
  EXPECT_GT(inked(png, 10, 36), 200) << "title";
  EXPECT_GT(inked(png, 40, 60), 200) << "subtitle";
  const int bottom = static_cast<int>(page.top + page.plot_h);
  EXPECT_GT(inked(png, bottom + 8, bottom + 26), 100) << "tick labels";
  EXPECT_EQ(png.at(static_cast<int>(page.left) + 3, bottom + 77), (Colour{0, 0, 0})) << "scale bar";

  // The SVG: well-formed, the page's size, one path per cut in its tow's colour (and one swatch
  // per direction in the legend: warp, weft, no tow), text drawn as glyphs.
  const std::string svg = slurp(stem + ".svg");
  ASSERT_FALSE(svg.empty());
  EXPECT_EQ(test::xml_error(svg), "");
  const size_t root = svg.find("<svg ");
  ASSERT_NE(root, std::string::npos);
  EXPECT_EQ(test::tag_attribute(svg, root, "width"), "1200");
  EXPECT_EQ(test::tag_attribute(svg, root, "height"), std::to_string(page.height));
  const std::vector<Colour> fills = test::svg_path_fills(svg);
  EXPECT_EQ(test::count_colour(fills, test::kSliceWarp[0]), 2 + 1);  // a1, a2, swatch
  EXPECT_EQ(test::count_colour(fills, test::kSliceWarp[1]), 1);      // c1
  EXPECT_EQ(test::count_colour(fills, test::kSliceWeft[0]), 1 + 1);  // b1, swatch
  EXPECT_EQ(test::count_colour(fills, test::kSliceGrey), 1 + 1);     // loose, swatch
  EXPECT_NE(svg.find("<use "), std::string::npos) << "no text";
}

TEST_F(Slice, AStripIsOnePathAndATinyCutStillShows) {
  // "along" lies in the plane x = 0.3 mm (a strip 2 mm long); "hair" (r = 0.5 um) crosses it
  // 3 mm away, its cut a fifth of a pixel across.
  const Case c = parse_case_toml(R"(
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
name = "hair"
material = "m"
radius = 0.5e-6
points = [[0, 3e-3, 0], [1e-3, 3e-3, 0]]
elements = 2

[[tow]]
name = "W"
direction = "weft"
index = 2
fibers = ["along"]

[[step]]
)",
                                 "strip.toml");
  const Model model = build_model(c);
  const std::vector<SliceCut> cuts = slice_cuts(model, model.reference, c.tows, 0, 0.3e-3);
  ASSERT_EQ(cuts.size(), 2u);
  EXPECT_EQ(cuts[0].kind, SliceCut::Kind::Strip);
  const std::string stem = (m_dir / "strip").string();
  EXPECT_EQ(write_slice(stem, cuts, c.tows, 0, 0.3e-3, "strip"), 2);
  const SlicePage page = slice_page(cuts);
  const std::string svg = slurp(stem + ".svg");
  EXPECT_EQ(test::xml_error(svg), "");
  const std::vector<Colour> fills = test::svg_path_fills(svg);
  EXPECT_EQ(test::count_colour(fills, test::kSliceWeft[2]), 1);     // the strip (no swatch: weft's is index 0)
  EXPECT_EQ(test::count_colour(fills, test::kSliceWeft[0]), 1);     // the swatch
  EXPECT_EQ(test::count_colour(fills, test::kSliceGrey), 1 + 1);    // hair, swatch
  const test::PngImage png = test::read_png(stem + ".png");
  ASSERT_TRUE(png.error.empty()) << png.error;
  EXPECT_EQ(png.height, page.height);
  const Eigen::Vector2d s = page.to_page(cuts[0].center), h = page.to_page(cuts[1].center);
  EXPECT_TRUE(near(png.at(static_cast<int>(s.x()), static_cast<int>(s.y())), test::kSliceWeft[2]));
  const Colour hair = png.at(static_cast<int>(h.x()), static_cast<int>(h.y()));
  EXPECT_LT(hair.r, 230) << show(hair);  // well off white, towards its grey
  EXPECT_NEAR(hair.r, hair.b, 2) << show(hair);
}

TEST_F(Slice, SlicesGivenOneFrameShareTheirPage) {
  const Case c = parse_case_toml(kStraight, "straight.toml");
  const Model model = build_model(c);
  const std::vector<SliceCut> near_cuts = slice_cuts(model, model.reference, c.tows, 0, 0.3e-3);
  std::vector<SliceCut> one{near_cuts[0]};  // a1 only
  Eigen::AlignedBox2d frame = slice_extent(near_cuts);
  const SlicePage all = slice_page(near_cuts), alone = slice_page(one), framed = slice_page(one, frame);
  EXPECT_NE(alone.scale, all.scale);
  EXPECT_EQ(framed.scale, all.scale);
  EXPECT_EQ(framed.u0, all.u0);
  EXPECT_EQ(framed.v1, all.v1);
  EXPECT_EQ(framed.height, all.height);
  const std::string stem = (m_dir / "framed").string();
  write_slice(stem, one, c.tows, axis_plane(0, 0.3e-3), "framed", frame);
  const test::PngImage png = test::read_png(stem + ".png");
  EXPECT_EQ(png.height, all.height);
  const Eigen::Vector2d p = all.to_page(one[0].center);
  EXPECT_TRUE(near(png.at(static_cast<int>(p.x()), static_cast<int>(p.y())), test::kSliceWarp[0]));
}

TEST_F(Slice, TextCairoWouldRefuseIsDrawnAndAnUnwritablePlaceIsARunError) {
  const Case c = parse_case_toml(kStraight, "straight.toml");
  const Model model = build_model(c);
  // A title that is not UTF-8 (a Latin-1 byte) and holds a line break.
  const std::string stem = (m_dir / "latin1").string();
  EXPECT_EQ(write_slice(stem, model, model.reference, c.tows, 0, 0.3e-3, "caf\xe9\nau lait <&>"), 5);
  EXPECT_EQ(test::xml_error(slurp(stem + ".svg")), "");
  EXPECT_TRUE(test::read_png(stem + ".png").error.empty());
  // A stem under a regular file.
  std::ofstream(m_dir / "file") << "x";
  EXPECT_THROW(write_slice((m_dir / "file" / "cut").string(), model, model.reference, c.tows, 0, 0.3e-3, "t"),
               RunError);
}

}  // namespace
}  // namespace fibra
