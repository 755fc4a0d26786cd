/// Tests of the slices (io/slice.hpp): the cuts of straight, oblique, curved and in-plane
/// fibers, the SVG read back (one polygon per cut, centre, radius, colours by tow), the PNG
/// decoded by the test itself (signature, chunks and their CRCs, zlib stream of stored blocks,
/// Adler-32, pixels).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/io/slice.hpp"
#include "fibra/model/model.hpp"
#include "support/scratch_dir.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

constexpr double kR = 0.05e-3;  // fiber radius [m]

/// Five fibers along x crossing the plane x = 0.3e-3 at right angles: a1, a2 in warp tow "A",
/// b1 in weft tow "B", c1 in warp tow "C" (index 1), loose in no tow. The plane is not at a node
/// of any of them except `loose`, whose middle node lies on it.
const std::string kStraight = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3

[[fiber]]
name = "a1"
material = "m"
radius = 0.05e-3
points = [[0, 0, 0], [1e-3, 0, 0]]
elements = 3

[[fiber]]
name = "a2"
material = "m"
radius = 0.05e-3
points = [[0, 0.2e-3, 0.05e-3], [1e-3, 0.2e-3, 0.05e-3]]
elements = 3

[[fiber]]
name = "b1"
material = "m"
radius = 0.05e-3
points = [[0, -0.3e-3, 0.2e-3], [1e-3, -0.3e-3, 0.2e-3]]
elements = 5

[[fiber]]
name = "c1"
material = "m"
radius = 0.05e-3
points = [[0, 0.5e-3, -0.1e-3], [1e-3, 0.5e-3, -0.1e-3]]
elements = 3

[[fiber]]
name = "loose"
material = "m"
radius = 0.05e-3
points = [[-0.3e-3, 0.8e-3, 0], [0.9e-3, 0.8e-3, 0]]
elements = 2

[[tow]]
name = "A"
direction = "warp"
index = 0
fibers = ["a1", "a2"]

[[tow]]
name = "B"
direction = "weft"
index = 0
fibers = ["b1"]

[[tow]]
name = "C"
direction = "warp"
index = 1
fibers = ["c1"]

[[step]]
)";

using test::slurp;

/// A polygon of the SVG.
struct SvgPolygon {
  std::string fiber, tow, kind, fill;
  std::vector<Eigen::Vector2d> points;  // [mm]
  Eigen::Vector2d centre() const {
    Eigen::Vector2d c = Eigen::Vector2d::Zero();
    for (const auto& p : points) c += p;
    return c / static_cast<double>(points.size());
  }
};

std::string attribute(const std::string& element, const std::string& name) {
  const std::regex re(" " + name + "=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(element, m, re) ? m[1].str() : std::string();
}

std::vector<SvgPolygon> svg_polygons(const std::string& svg) {
  std::vector<SvgPolygon> out;
  size_t at = 0;
  while ((at = svg.find("<polygon ", at)) != std::string::npos) {
    const size_t end = svg.find('>', at);
    const std::string element = svg.substr(at, end - at);
    SvgPolygon p;
    p.fiber = attribute(element, "data-fiber");
    p.tow = attribute(element, "data-tow");
    p.kind = attribute(element, "data-kind");
    p.fill = attribute(element, "fill");
    std::stringstream ss(attribute(element, "points"));
    std::string pair;
    while (ss >> pair) {
      const size_t comma = pair.find(',');
      p.points.emplace_back(std::stod(pair.substr(0, comma)), std::stod(pair.substr(comma + 1)));
    }
    out.push_back(p);
    at = end;
  }
  return out;
}

/// The transform of the cuts' group: page = (a u + e, d v + f) for (u, v) in mm.
struct PageMap {
  double a = 0, d = 0, e = 0, f = 0;
};
PageMap svg_page_map(const std::string& svg) {
  const std::regex re("<g id=\"cuts\" transform=\"matrix\\(([^ ]+) 0 0 ([^ ]+) ([^ ]+) ([^ )]+)\\)\"");
  std::smatch m;
  PageMap map;
  if (!std::regex_search(svg, m, re)) {
    ADD_FAILURE() << "no cuts group in the SVG";
    return map;
  }
  map.a = std::stod(m[1]);
  map.d = std::stod(m[2]);
  map.e = std::stod(m[3]);
  map.f = std::stod(m[4]);
  return map;
}

struct Rgb {
  int r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};
Rgb hex_colour(const std::string& hex) {
  return {std::stoi(hex.substr(1, 2), nullptr, 16), std::stoi(hex.substr(3, 2), nullptr, 16),
          std::stoi(hex.substr(5, 2), nullptr, 16)};
}

// ------------------------------------------------------------------------------------------
// A PNG decoder for exactly what the writer makes (palette, 8 bits, stored deflate blocks),
// with its own CRC-32 (bitwise, not table-driven) and Adler-32.

std::uint32_t crc32_bitwise(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char c : bytes) {
    crc ^= c;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xFFFFFFFFu;
}

std::uint32_t be32(const std::string& s, size_t at) {
  return (std::uint32_t(std::uint8_t(s[at])) << 24) | (std::uint32_t(std::uint8_t(s[at + 1])) << 16) |
         (std::uint32_t(std::uint8_t(s[at + 2])) << 8) | std::uint32_t(std::uint8_t(s[at + 3]));
}

struct Png {
  int width = 0, height = 0;
  std::vector<Rgb> palette;
  std::vector<std::uint8_t> pixels;  // palette indices
  std::vector<std::string> chunks;   // chunk types in order
  Rgb at(int x, int y) const { return palette.at(pixels.at(static_cast<size_t>(y) * width + x)); }
};

Png decode_png(const std::string& file) {
  Png png;
  EXPECT_GE(file.size(), 8u);
  EXPECT_EQ(file.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << "PNG signature";
  std::string idat, ihdr;
  size_t at = 8;
  while (at + 12 <= file.size()) {
    const std::uint32_t length = be32(file, at);
    EXPECT_LE(at + 12 + length, file.size()) << "chunk runs past the end";
    if (at + 12 + length > file.size()) return png;
    const std::string type = file.substr(at + 4, 4), data = file.substr(at + 8, length);
    EXPECT_EQ(be32(file, at + 8 + length), crc32_bitwise(type + data)) << "CRC of chunk " << type;
    png.chunks.push_back(type);
    if (type == "IHDR") ihdr = data;
    if (type == "PLTE")
      for (size_t k = 0; k + 2 < data.size(); k += 3)
        png.palette.push_back({std::uint8_t(data[k]), std::uint8_t(data[k + 1]), std::uint8_t(data[k + 2])});
    if (type == "IDAT") idat += data;
    at += 12 + length;
  }
  EXPECT_EQ(at, file.size()) << "bytes after the last chunk";
  EXPECT_FALSE(png.chunks.empty());
  if (png.chunks.empty()) return png;
  EXPECT_EQ(png.chunks.front(), "IHDR");
  EXPECT_EQ(png.chunks.back(), "IEND");
  EXPECT_EQ(ihdr.size(), 13u);
  if (ihdr.size() != 13) return png;
  png.width = static_cast<int>(be32(ihdr, 0));
  png.height = static_cast<int>(be32(ihdr, 4));
  EXPECT_EQ(ihdr[8], 8) << "bit depth";
  EXPECT_EQ(ihdr[9], 3) << "colour type: palette";
  EXPECT_EQ(ihdr[10], 0);
  EXPECT_EQ(ihdr[11], 0);
  EXPECT_EQ(ihdr[12], 0);
  EXPECT_GE(png.palette.size(), 2u);
  EXPECT_LE(png.palette.size(), 256u);

  // zlib: header, stored deflate blocks, Adler-32.
  EXPECT_GE(idat.size(), 6u);
  const auto cmf = std::uint8_t(idat[0]), flg = std::uint8_t(idat[1]);
  EXPECT_EQ(cmf & 0x0F, 8) << "deflate";
  EXPECT_LE(cmf >> 4, 7) << "window";
  EXPECT_EQ((cmf * 256 + flg) % 31, 0) << "zlib header check";
  EXPECT_EQ(flg & 0x20, 0) << "no preset dictionary";
  std::string raw;
  size_t p = 2;
  bool final_block = false;
  while (!final_block && p < idat.size()) {
    const auto header = std::uint8_t(idat[p]);
    final_block = header & 1;
    EXPECT_EQ((header >> 1) & 3, 0) << "stored block";
    if (((header >> 1) & 3) != 0) return png;
    const unsigned len = std::uint8_t(idat[p + 1]) | (std::uint8_t(idat[p + 2]) << 8);
    const unsigned nlen = std::uint8_t(idat[p + 3]) | (std::uint8_t(idat[p + 4]) << 8);
    EXPECT_EQ(len ^ 0xFFFFu, nlen) << "NLEN";
    raw += idat.substr(p + 5, len);
    p += 5 + len;
  }
  EXPECT_TRUE(final_block);
  EXPECT_EQ(p + 4, idat.size()) << "Adler-32 ends the stream";
  std::uint32_t a = 1, b = 0;
  for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
  EXPECT_EQ(be32(idat, p), (b << 16) | a) << "Adler-32";

  EXPECT_EQ(raw.size(), static_cast<size_t>(png.height) * (png.width + 1));
  if (raw.size() != static_cast<size_t>(png.height) * (png.width + 1)) return png;
  for (int y = 0; y < png.height; ++y) {
    EXPECT_EQ(raw[static_cast<size_t>(y) * (png.width + 1)], 0) << "filter type of row " << y;
    const auto row = raw.begin() + static_cast<std::ptrdiff_t>(y) * (png.width + 1) + 1;
    png.pixels.insert(png.pixels.end(), row, row + png.width);
  }
  for (std::uint8_t v : png.pixels)
    if (v >= png.palette.size()) {
      ADD_FAILURE() << "pixel index " << int(v) << " beyond the palette";
      break;
    }
  return png;
}

class Slice : public test::ScratchDirTest {
 protected:
  Slice() : ScratchDirTest("fibra_slice_") {}
};

// ------------------------------------------------------------------------------------------

TEST_F(Slice, StraightFibersAtRightAnglesGiveTheirSections) {
  const Case c = parse_case_toml(kStraight, "straight.toml");
  const Model model = build_model(c);
  const std::string stem = (m_dir / "sub" / "cut").string();
  const int fibers = write_slice(stem, model, model.reference, c.tows, 0, 0.3e-3, "Straight fibers");
  EXPECT_EQ(fibers, 5);
  const std::string svg = slurp(stem + ".svg");
  ASSERT_FALSE(svg.empty());
  EXPECT_NE(svg.find("Straight fibers"), std::string::npos);
  EXPECT_NE(svg.find("y [mm]"), std::string::npos);
  EXPECT_NE(svg.find("z [mm]"), std::string::npos);
  EXPECT_NE(svg.find("id=\"scale-bar\""), std::string::npos);
  EXPECT_NE(svg.find("5 fibers cut"), std::string::npos);

  const std::vector<SvgPolygon> polygons = svg_polygons(svg);
  ASSERT_EQ(polygons.size(), 5u) << svg;
  // Each fiber once, centred at its (y, z), every point at the radius [mm].
  const std::map<std::string, Eigen::Vector2d> centres = {
      {"a1", {0, 0}}, {"a2", {0.2, 0.05}}, {"b1", {-0.3, 0.2}}, {"c1", {0.5, -0.1}}, {"loose", {0.8, 0}}};
  std::map<std::string, SvgPolygon> by_fiber;
  for (const SvgPolygon& p : polygons) {
    EXPECT_TRUE(by_fiber.emplace(p.fiber, p).second) << "fiber " << p.fiber << " twice";
    ASSERT_TRUE(centres.count(p.fiber)) << p.fiber;
    EXPECT_EQ(p.kind, "crossing");
    EXPECT_GE(p.points.size(), 24u);
    const Eigen::Vector2d expected = centres.at(p.fiber);
    EXPECT_NEAR(p.centre().x(), expected.x(), 1e-7) << p.fiber;
    EXPECT_NEAR(p.centre().y(), expected.y(), 1e-7) << p.fiber;
    for (const auto& q : p.points) EXPECT_NEAR((q - expected).norm(), 1e3 * kR, 1e-7) << p.fiber;
  }
  // Colours by tow: one colour per tow, warp blue, weft red, no tow grey.
  EXPECT_EQ(by_fiber["a1"].tow, "A");
  EXPECT_EQ(by_fiber["b1"].tow, "B");
  EXPECT_EQ(by_fiber["loose"].tow, "");
  EXPECT_EQ(by_fiber["a1"].fill, by_fiber["a2"].fill);
  EXPECT_NE(by_fiber["a1"].fill, by_fiber["c1"].fill);  // neighbouring warp tows differ
  EXPECT_NE(by_fiber["a1"].fill, by_fiber["b1"].fill);
  for (const char* warp : {"a1", "c1"}) {
    const Rgb c1 = hex_colour(by_fiber[warp].fill);
    EXPECT_GT(c1.b, c1.r) << warp << " " << by_fiber[warp].fill;
  }
  const Rgb weft = hex_colour(by_fiber["b1"].fill), grey = hex_colour(by_fiber["loose"].fill);
  EXPECT_GT(weft.r, weft.b) << by_fiber["b1"].fill;
  EXPECT_EQ(grey.r, grey.g);
  EXPECT_EQ(grey.g, grey.b);

  // The PNG: valid, the size of the SVG page, the fibers' centres in their colours, white
  // away from them.
  const Png png = decode_png(slurp(stem + ".png"));
  EXPECT_EQ(png.width, 1200);
  EXPECT_EQ(attribute(svg, "width"), "1200");
  EXPECT_EQ(attribute(svg, "height"), std::to_string(png.height));
  ASSERT_EQ(png.pixels.size(), static_cast<size_t>(png.width) * png.height);
  const PageMap map = svg_page_map(svg);
  EXPECT_GT(map.a, 0);
  EXPECT_DOUBLE_EQ(map.d, -map.a) << "equal aspect ratio";
  for (const auto& [name, centre] : centres) {
    const int x = static_cast<int>(std::floor(map.a * centre.x() + map.e));
    const int y = static_cast<int>(std::floor(map.d * centre.y() + map.f));
    ASSERT_TRUE(x >= 0 && y >= 0 && x < png.width && y < png.height) << name;
    EXPECT_EQ(png.at(x, y), hex_colour(by_fiber[name].fill)) << name;
  }
  const Rgb white{255, 255, 255};
  EXPECT_EQ(png.at(3, 3), white);
  // Inside the plot, between a1 (0, 0) and b1 (-0.3, 0.2): at (-0.15, 0.1) mm.
  EXPECT_EQ(png.at(static_cast<int>(map.a * -0.15 + map.e), static_cast<int>(map.d * 0.1 + map.f)), white);
}

TEST_F(Slice, AnObliqueFiberGivesAnEllipseElongatedByOneOverCos) {
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
    // The same through the SVG.
    const std::string stem = (m_dir / fmt::format("oblique_{}", degrees)).string();
    EXPECT_EQ(write_slice(stem, cuts, c.tows, 0, 0.3e-3, "oblique"), 1);
    const std::vector<SvgPolygon> polygons = svg_polygons(slurp(stem + ".svg"));
    ASSERT_EQ(polygons.size(), 1u);
    double svg_max_y = 0;
    for (const auto& p : polygons[0].points) svg_max_y = std::max(svg_max_y, std::abs(p.x() - 0.1));
    EXPECT_NEAR(svg_max_y, 1e3 * along_y, 1e-3 * 1e3 * kR);
  }
}

TEST_F(Slice, ACurvedFiberCrossingTwiceGivesTwoCuts) {
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

TEST_F(Slice, AFiberLyingInThePlaneGivesAStrip) {
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

TEST_F(Slice, APlaneThatMissesEverythingCutsNothing) {
  const Case c = parse_case_toml(kStraight, "straight.toml");
  const Model model = build_model(c);
  EXPECT_TRUE(slice_cuts(model, model.reference, c.tows, 0, 2e-3).empty());
  EXPECT_TRUE(slice_cuts(model, model.reference, c.tows, 1, 5e-3).empty());
  const Eigen::AlignedBox3d box = centroid_bounds(model, model.reference);
  EXPECT_DOUBLE_EQ(box.min().x(), -0.3e-3);
  EXPECT_DOUBLE_EQ(box.max().x(), 1e-3);
  EXPECT_DOUBLE_EQ(box.max().y(), 0.8e-3);
}

}  // namespace
}  // namespace fibra
