#pragma once
// Reading back the files of a slice (io/slice.hpp) in the tests: the PNG through Cairo, the SVG
// checked for well-formedness by a small XML scanner, its drawn paths and their fill colours.
#include <cairo.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace fibra::test {

struct Colour {
  int r = 0, g = 0, b = 0;
  bool operator==(const Colour&) const = default;
};

/// The slices' palette (docs/outputs.md, "Slices"): warp and weft tows by index % 4, no tow.
inline const Colour kSliceWarp[4] = {{31, 95, 168}, {95, 168, 220}, {19, 128, 125}, {75, 75, 168}};
inline const Colour kSliceWeft[4] = {{192, 57, 43}, {240, 146, 43}, {142, 36, 82}, {232, 112, 90}};
inline const Colour kSliceGrey{154, 154, 154};

/// A PNG read back with Cairo (cairo_image_surface_create_from_png); width 0 when it is not one.
struct PngImage {
  int width = 0, height = 0;
  std::vector<std::uint32_t> pixels;  ///< Cairo's ARGB32 or RGB24 words, row by row
  std::string error;
  Colour at(int x, int y) const {
    const std::uint32_t p = pixels.at(static_cast<size_t>(y) * width + x);
    return {static_cast<int>((p >> 16) & 0xFF), static_cast<int>((p >> 8) & 0xFF), static_cast<int>(p & 0xFF)};
  }
};

inline PngImage read_png(const std::string& path) {
  PngImage image;
  cairo_surface_t* s = cairo_image_surface_create_from_png(path.c_str());
  if (cairo_surface_status(s) != CAIRO_STATUS_SUCCESS) {
    image.error = cairo_status_to_string(cairo_surface_status(s));
    cairo_surface_destroy(s);
    return image;
  }
  image.width = cairo_image_surface_get_width(s);
  image.height = cairo_image_surface_get_height(s);
  const int stride = cairo_image_surface_get_stride(s);
  const unsigned char* data = cairo_image_surface_get_data(s);
  image.pixels.reserve(static_cast<size_t>(image.width) * image.height);
  for (int y = 0; y < image.height; ++y) {
    const auto* row = reinterpret_cast<const std::uint32_t*>(data + static_cast<size_t>(y) * stride);
    image.pixels.insert(image.pixels.end(), row, row + image.width);
  }
  cairo_surface_destroy(s);
  return image;
}

/// Empty when `text` is well-formed XML (one root element, every element closed in order,
/// attributes quoted, entities known, nothing but white space outside the root); else what is
/// wrong and where.
inline std::string xml_error(const std::string& text) {
  std::vector<std::string> open;
  int roots = 0;
  size_t i = 0;
  auto where = [&](const std::string& what) { return what + " at byte " + std::to_string(i); };
  auto name_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == ':';
  };
  auto entity_ok = [&](size_t at) {
    const size_t end = text.find(';', at);
    if (end == std::string::npos || end - at > 10) return false;
    const std::string e = text.substr(at + 1, end - at - 1);
    if (e == "amp" || e == "lt" || e == "gt" || e == "quot" || e == "apos") return true;
    if (e.size() >= 2 && e[0] == '#') return e.find_first_not_of("0123456789", 1) == std::string::npos ||
                                             (e[1] == 'x' && e.size() > 2 &&
                                              e.find_first_not_of("0123456789abcdefABCDEF", 2) == std::string::npos);
    return false;
  };
  while (i < text.size()) {
    if (text[i] != '<') {
      if (open.empty() && !std::isspace(static_cast<unsigned char>(text[i]))) return where("text outside the root");
      if (text[i] == '&' && !entity_ok(i)) return where("unknown entity");
      ++i;
      continue;
    }
    if (text.compare(i, 4, "<!--") == 0) {
      const size_t end = text.find("-->", i);
      if (end == std::string::npos) return where("unterminated comment");
      i = end + 3;
    } else if (text.compare(i, 2, "<?") == 0) {
      const size_t end = text.find("?>", i);
      if (end == std::string::npos) return where("unterminated declaration");
      i = end + 2;
    } else if (text.compare(i, 2, "</") == 0) {
      size_t j = i + 2;
      while (j < text.size() && name_char(text[j])) ++j;
      const std::string name = text.substr(i + 2, j - i - 2);
      while (j < text.size() && std::isspace(static_cast<unsigned char>(text[j]))) ++j;
      if (j >= text.size() || text[j] != '>') return where("malformed end tag");
      if (open.empty() || open.back() != name) return where("end tag </" + name + "> does not close the open element");
      open.pop_back();
      i = j + 1;
    } else {
      size_t j = i + 1;
      while (j < text.size() && name_char(text[j])) ++j;
      const std::string name = text.substr(i + 1, j - i - 1);
      if (name.empty()) return where("malformed start tag");
      std::vector<std::string> attributes;
      while (true) {
        while (j < text.size() && std::isspace(static_cast<unsigned char>(text[j]))) ++j;
        if (j >= text.size()) return where("unterminated tag <" + name + ">");
        if (text[j] == '>' || text.compare(j, 2, "/>") == 0) break;
        const size_t a = j;
        while (j < text.size() && name_char(text[j])) ++j;
        const std::string attribute = text.substr(a, j - a);
        if (attribute.empty() || j >= text.size() || text[j] != '=') return where("malformed attribute in <" + name + ">");
        for (const std::string& seen : attributes)
          if (seen == attribute) return where("attribute " + attribute + " twice in <" + name + ">");
        attributes.push_back(attribute);
        ++j;
        if (j >= text.size() || (text[j] != '"' && text[j] != '\'')) return where("unquoted attribute " + attribute);
        const size_t end = text.find(text[j], j + 1);
        if (end == std::string::npos) return where("unterminated attribute " + attribute);
        for (size_t k = j + 1; k < end; ++k) {
          if (text[k] == '<') return where("'<' in attribute " + attribute);
          if (text[k] == '&' && !entity_ok(k)) return where("unknown entity in attribute " + attribute);
        }
        j = end + 1;
      }
      if (open.empty()) ++roots;
      if (roots > 1) return where("a second root element <" + name + ">");
      if (text[j] == '>') {
        open.push_back(name);
        i = j + 1;
      } else {
        i = j + 2;
      }
    }
  }
  if (!open.empty()) return "element <" + open.back() + "> not closed";
  if (roots != 1) return "no root element";
  return "";
}

/// The value of attribute `name` in the tag starting at `at` (empty when absent).
inline std::string tag_attribute(const std::string& text, size_t at, const std::string& name) {
  const size_t end = text.find('>', at);
  const size_t a = text.find(" " + name + "=\"", at);
  if (a == std::string::npos || a > end) return "";
  const size_t from = a + name.size() + 3;
  return text.substr(from, text.find('"', from) - from);
}

/// The fill colour of each <path> drawn in an SVG of Cairo's (after its <defs>, where the
/// glyphs are), in order; a path without a fill colour gives {-1, -1, -1}.
inline std::vector<Colour> svg_path_fills(const std::string& svg) {
  std::vector<Colour> fills;
  const size_t defs = svg.find("</defs>");
  size_t at = defs == std::string::npos ? 0 : defs;
  while ((at = svg.find("<path ", at)) != std::string::npos) {
    const std::string style = tag_attribute(svg, at, "style");
    Colour c{-1, -1, -1};
    const size_t f = style.find("fill:rgb(");
    double r = 0, g = 0, b = 0;
    if (f != std::string::npos && std::sscanf(style.c_str() + f, "fill:rgb(%lf%%,%lf%%,%lf%%)", &r, &g, &b) == 3)
      c = {static_cast<int>(std::lround(2.55 * r)), static_cast<int>(std::lround(2.55 * g)),
           static_cast<int>(std::lround(2.55 * b))};
    fills.push_back(c);
    ++at;
  }
  return fills;
}

/// How many of `fills` are `colour`.
inline int count_colour(const std::vector<Colour>& fills, const Colour& colour) {
  int n = 0;
  for (const Colour& c : fills) n += c == colour;
  return n;
}

}  // namespace fibra::test
