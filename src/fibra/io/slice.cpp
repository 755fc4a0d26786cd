#include "fibra/io/slice.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <optional>
#include <string_view>
#include <unordered_map>

#include "fibra/beam/beam_element.hpp"
#include "fibra/core/error.hpp"
#include "fibra/core/file.hpp"

namespace fibra {

namespace {

namespace fs = std::filesystem;
using Vec2 = Eigen::Vector2d;

/// A fiber crosses the plane as an ellipse when its tangent is within 60 degrees of the
/// plane's normal (|cos| >= 0.5, elongation <= 2); closer to the plane it is drawn as a strip.
constexpr double kCrossingCos = 0.5;
/// Points of the polygon of a crossing.
constexpr int kEllipsePoints = 48;

// ------------------------------------------------------------------------------------------
// Geometry of the cuts.

/// Centroid, section vectors and tangent (d x0 / d eta) at eta of an element (27 dofs).
struct SectionState {
  Vec3 x0, g1, g2, t;
};

SectionState section_state(const double* qe, double eta) {
  double n[3], dn[3];
  beam_shape(eta, n, dn);
  SectionState s{Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Map<const Vec3> x(qe + kNodeDofs * k), g1(qe + kNodeDofs * k + 3), g2(qe + kNodeDofs * k + 6);
    s.x0 += n[k] * x;
    s.g1 += n[k] * g1;
    s.g2 += n[k] * g2;
    s.t += dn[k] * x;
  }
  return s;
}

/// Cosine of the angle between the tangent and the plane's normal (0 when degenerate).
double normal_cosine(const SectionState& s, int axis) {
  const double len = s.t.norm();
  return len > 0 ? s.t[axis] / len : 0.0;
}

/// Roots in [-1, 1] of A eta^2 + B eta + C (each once, sorted).
std::vector<double> quadratic_roots(double A, double B, double C, double scale) {
  std::vector<double> roots;
  const double tiny = 1e-14 * scale;
  if (std::abs(A) <= 1e-9 * std::abs(B) || (std::abs(A) <= tiny && std::abs(B) > tiny)) {
    if (std::abs(B) > tiny) roots.push_back(-C / B);
  } else if (std::abs(A) > tiny) {
    const double disc = B * B - 4 * A * C;
    if (disc >= 0) {
      const double qq = -0.5 * (B + std::copysign(std::sqrt(disc), B));
      if (qq != 0) {
        roots.push_back(qq / A);
        roots.push_back(C / qq);
      } else {
        roots.push_back(0.0);  // B = 0 and C = 0
      }
    }
  }
  std::vector<double> out;
  for (double r : roots) {
    if (!std::isfinite(r)) continue;
    if (std::abs(r - 1) < 1e-10) r = 1;
    if (std::abs(r + 1) < 1e-10) r = -1;
    if (r < -1 || r > 1) continue;
    // One Newton step polishes a root from the cancellation-prone branch.
    const double f = (A * r + B) * r + C, df = 2 * A * r + B;
    if (df != 0 && r > -1 && r < 1) r = std::clamp(r - f / df, -1.0, 1.0);
    out.push_back(r);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end(), [](double x, double y) { return std::abs(x - y) < 1e-9; }), out.end());
  return out;
}

/// What the plane does to the section at one sample of a fiber (strips).
struct Chord {
  bool strip_angle = false;  ///< the fiber runs within 60 degrees of the plane here
  bool exists = false;       ///< the plane cuts the section
  double margin = 0;         ///< R - |d|: >= 0 where the chord exists
  Vec2 left = Vec2::Zero(), right = Vec2::Zero();
};

Chord chord_at(const double* qe, double eta, double a, double b, int axis, double value, const std::array<int, 2>& uv) {
  const SectionState s = section_state(qe, eta);
  Chord c;
  c.strip_angle = std::abs(normal_cosine(s, axis)) < kCrossingCos;
  // a cos(th) g1[axis] + b sin(th) g2[axis] = value - x0[axis], i.e. R cos(th - phi) = d.
  const double alpha = a * s.g1[axis], beta = b * s.g2[axis], d = value - s.x0[axis];
  const double R = std::hypot(alpha, beta);
  c.margin = R - std::abs(d);
  c.exists = R > 0 && c.margin >= 0;
  if (!c.exists) return c;
  const double phi = std::atan2(beta, alpha), half = std::acos(std::clamp(d / R, -1.0, 1.0));
  const Vec2 centre(s.x0[uv[0]], s.x0[uv[1]]);
  Vec2 p[2];
  for (int k = 0; k < 2; ++k) {
    const double th = phi + (k == 0 ? half : -half);
    const Vec3 x = s.x0 + a * std::cos(th) * s.g1 + b * std::sin(th) * s.g2;
    p[k] = Vec2(x[uv[0]], x[uv[1]]);
  }
  const Vec2 normal(-s.t[uv[1]], s.t[uv[0]]);  // the in-plane tangent turned by 90 degrees
  const bool first_left = (p[0] - centre).dot(normal) >= (p[1] - centre).dot(normal);
  c.left = first_left ? p[0] : p[1];
  c.right = first_left ? p[1] : p[0];
  return c;
}

/// A sample along a fiber for the strips.
struct Sample {
  Index element = 0;  ///< global element index
  double eta = 0;
  bool computed = false;
  Chord chord;
};

/// Tip of a strip: the point between a sample with a chord (eta_in) and one without (eta_out)
/// where the chord shrinks to a point (bisection on R - |d|).
Vec2 strip_tip(const double* qe, double eta_in, double eta_out, double a, double b, int axis, double value,
               const std::array<int, 2>& uv) {
  Chord last = chord_at(qe, eta_in, a, b, axis, value, uv);
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (eta_in + eta_out);
    const Chord c = chord_at(qe, mid, a, b, axis, value, uv);
    if (c.exists) {
      eta_in = mid;
      last = c;
    } else {
      eta_out = mid;
    }
  }
  return 0.5 * (last.left + last.right);
}

// ------------------------------------------------------------------------------------------
// Colours.

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
  std::string hex() const { return fmt::format("#{:02x}{:02x}{:02x}", r, g, b); }
  Rgb dark() const {
    return {static_cast<std::uint8_t>(r * 6 / 10), static_cast<std::uint8_t>(g * 6 / 10),
            static_cast<std::uint8_t>(b * 6 / 10)};
  }
};

constexpr Rgb kWhite{255, 255, 255}, kBlack{0, 0, 0}, kGrey{154, 154, 154}, kAxisGrey{90, 90, 90};
// Warp: blues (blue, sky, teal, indigo); weft: reds and oranges (red, orange, crimson, salmon).
constexpr std::array<Rgb, 4> kWarp{{{31, 95, 168}, {95, 168, 220}, {19, 128, 125}, {75, 75, 168}}};
constexpr std::array<Rgb, 4> kWeft{{{192, 57, 43}, {240, 146, 43}, {142, 36, 82}, {232, 112, 90}}};

Rgb tow_colour(const std::vector<TowSpec>& tows, int tow) {
  if (tow < 0) return kGrey;
  const TowSpec& t = tows[tow];
  const int i = ((t.index % 4) + 4) % 4;
  return t.direction == TowSpec::Direction::Warp ? kWarp[i] : kWeft[i];
}

// ------------------------------------------------------------------------------------------
// Layout shared by the SVG and the PNG (SVG user units are PNG pixels).

struct Layout {
  int width = 1200, height = 0;   ///< [px]
  double scale = 1;               ///< [px per mm]
  double u0 = 0, v1 = 0;          ///< data coordinates [mm] at the plot's left and top
  double left = 0, top = 0;       ///< plot area origin [px]
  double plot_w = 0, plot_h = 0;  ///< plot area size [px]
  double du = 0, dv = 0;          ///< plot area size [mm]
  double px(double u) const { return left + (u - u0) * scale; }
  double py(double v) const { return top + (v1 - v) * scale; }
};

constexpr double kMarginLeft = 90, kMarginRight = 24, kMarginTop = 70, kMarginBottom = 110;
constexpr double kMaxPlotWidth = 1200 - kMarginLeft - kMarginRight, kMaxPlotHeight = 1400;

Layout make_layout(const std::vector<SliceCut>& cuts) {
  double umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
  for (const SliceCut& c : cuts)
    for (const Vec2& p : c.points) {
      umin = std::min(umin, 1e3 * p.x());
      umax = std::max(umax, 1e3 * p.x());
      vmin = std::min(vmin, 1e3 * p.y());
      vmax = std::max(vmax, 1e3 * p.y());
    }
  if (umin > umax) umin = vmin = -1, umax = vmax = 1;
  double extent = std::max(umax - umin, vmax - vmin);
  if (!(extent > 0)) extent = 1e-3;
  const double pad = 0.05 * extent;
  umin -= pad, umax += pad, vmin -= pad, vmax += pad;
  Layout l;
  l.du = umax - umin;
  l.dv = vmax - vmin;
  l.scale = kMaxPlotWidth / l.du;
  if (l.dv * l.scale > kMaxPlotHeight) l.scale = kMaxPlotHeight / l.dv;
  l.plot_w = l.du * l.scale;
  l.plot_h = l.dv * l.scale;
  l.left = kMarginLeft + 0.5 * (kMaxPlotWidth - l.plot_w);
  l.top = kMarginTop;
  l.u0 = umin;
  l.v1 = vmax;
  l.height = static_cast<int>(std::ceil(kMarginTop + l.plot_h + kMarginBottom));
  return l;
}

/// 1, 2 or 5 times a power of ten, near `target` (not above it when `at_most`).
double nice_step(double target, bool at_most = false) {
  const double p = std::pow(10.0, std::floor(std::log10(target)));
  const double m = target / p;
  if (at_most) return (m >= 5 ? 5 : m >= 2 ? 2 : 1) * p;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
}

int decimals_for(double step) { return std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9))); }

std::string format_mm(double value, int decimals) {
  std::string s = fmt::format("{:.{}f}", value, decimals);
  if (s.find_first_not_of("-0.") == std::string::npos && s[0] == '-') s.erase(0, 1);  // no "-0.00"
  return s;
}

/// The scale bar: a round length about a fifth of the plot width [mm].
double scale_bar_length(const Layout& l) { return nice_step(l.du / 5, true); }

// ------------------------------------------------------------------------------------------
// SVG.

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  return out;
}

std::string subtitle(const Layout& l, int axis, double value, const std::vector<SliceCut>& cuts) {
  const int fibers = slice_fiber_count(cuts);
  double mm = 1e3 * value;
  if (std::abs(mm) < 1e-9 * std::max(l.du, l.dv)) mm = 0;  // round-off of a computed plane
  return fmt::format("plane {} = {:.6g} mm: {} fiber{} cut", slice_axis_name(axis), mm, fibers, fibers == 1 ? "" : "s");
}

std::string make_svg(const Layout& l, const std::vector<SliceCut>& cuts, const std::vector<TowSpec>& tows, int axis,
                     double value, const std::string& title) {
  const std::array<int, 2> uv = slice_plane_axes(axis);
  const char* axis_names = "xyz";
  fmt::memory_buffer b;
  auto out = std::back_inserter(b);
  fmt::format_to(out,
                 "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
                 "font-family=\"sans-serif\">\n"
                 "<title>{2}</title>\n"
                 "<rect x=\"0\" y=\"0\" width=\"{0}\" height=\"{1}\" fill=\"#ffffff\"/>\n",
                 l.width, l.height, xml_escape(title));
  fmt::format_to(out, "<text x=\"{}\" y=\"30\" text-anchor=\"middle\" font-size=\"20\">{}</text>\n", l.width / 2,
                 xml_escape(title));
  fmt::format_to(out, "<text x=\"{}\" y=\"54\" text-anchor=\"middle\" font-size=\"15\" fill=\"#444444\">{}</text>\n",
                 l.width / 2, xml_escape(subtitle(l, axis, value, cuts)));
  // The cuts, in mm, mapped to the page by one transform (v up).
  // (The outline's width is in mm too: half a pixel.)
  fmt::format_to(out, "<g id=\"cuts\" transform=\"matrix({:.9g} 0 0 {:.9g} {:.9g} {:.9g})\" stroke-width=\"{:.4g}\">\n",
                 l.scale, -l.scale, l.left - l.u0 * l.scale, l.top + l.v1 * l.scale, 0.5 / l.scale);
  for (const SliceCut& c : cuts) {
    const Rgb colour = tow_colour(tows, c.tow);
    const std::string tow = c.tow >= 0 ? tows[c.tow].name : "";
    fmt::format_to(out,
                   "<polygon data-fiber=\"{}\" data-tow=\"{}\" data-kind=\"{}\" fill=\"{}\" stroke=\"{}\" points=\"",
                   xml_escape(c.name), xml_escape(tow), c.kind == SliceCut::Kind::Crossing ? "crossing" : "strip",
                   colour.hex(), colour.dark().hex());
    for (size_t k = 0; k < c.points.size(); ++k)
      fmt::format_to(out, "{}{:.9g},{:.9g}", k ? " " : "", 1e3 * c.points[k].x(), 1e3 * c.points[k].y());
    fmt::format_to(out, "\"><title>{}{}</title></polygon>\n", xml_escape(c.name),
                   tow.empty() ? std::string() : " (" + xml_escape(tow) + ")");
  }
  fmt::format_to(out, "</g>\n");
  // Frame, ticks and tick labels.
  const double bottom = l.top + l.plot_h;
  fmt::format_to(out,
                 "<g id=\"axes\" stroke=\"#000000\" stroke-width=\"1\" fill=\"none\">\n"
                 "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\"/>\n",
                 l.left, l.top, l.plot_w, l.plot_h);
  std::string labels;
  const double step_u = nice_step(l.du / 6), step_v = nice_step(l.dv / 4);
  for (long k = static_cast<long>(std::ceil(l.u0 / step_u)); k * step_u <= l.u0 + l.du; ++k) {
    const double x = l.px(k * step_u);
    fmt::format_to(out, "<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\"/>\n", x, bottom, bottom + 6);
    labels += fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\">{}</text>\n", x, bottom + 22,
                          format_mm(k * step_u, decimals_for(step_u)));
  }
  for (long k = static_cast<long>(std::ceil((l.v1 - l.dv) / step_v)); k * step_v <= l.v1; ++k) {
    const double y = l.py(k * step_v);
    fmt::format_to(out, "<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{2:.2f}\" y2=\"{1:.2f}\"/>\n", l.left - 6, y, l.left);
    labels += fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"end\">{}</text>\n", l.left - 9, y + 5,
                          format_mm(k * step_v, decimals_for(step_v)));
  }
  fmt::format_to(out, "</g>\n<g id=\"labels\" font-size=\"14\">\n{}", labels);
  fmt::format_to(out, "<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\" font-size=\"16\">{} [mm]</text>\n",
                 l.left + 0.5 * l.plot_w, bottom + 46, axis_names[uv[0]]);
  fmt::format_to(out,
                 "<text x=\"{0:.2f}\" y=\"{1:.2f}\" text-anchor=\"middle\" font-size=\"16\" "
                 "transform=\"rotate(-90 {0:.2f} {1:.2f})\">{2} [mm]</text>\n",
                 l.left - 62, l.top + 0.5 * l.plot_h, axis_names[uv[1]]);
  fmt::format_to(out, "</g>\n");
  // Scale bar (bottom left) and legend (bottom right).
  const double bar = scale_bar_length(l), bar_px = bar * l.scale, bar_y = bottom + 80;
  fmt::format_to(out,
                 "<g id=\"scale-bar\">\n"
                 "<rect x=\"{0:.2f}\" y=\"{1:.2f}\" width=\"{2:.2f}\" height=\"5\" fill=\"#000000\"/>\n"
                 "<text x=\"{3:.2f}\" y=\"{4:.2f}\" font-size=\"15\">{5} mm</text>\n</g>\n",
                 l.left, bar_y - 5, bar_px, l.left + bar_px + 10, bar_y + 1, format_mm(bar, decimals_for(bar)));
  bool has[3] = {false, false, false};
  for (const SliceCut& c : cuts) has[c.tow < 0 ? 2 : tows[c.tow].direction == TowSpec::Direction::Warp ? 0 : 1] = true;
  const char* names[3] = {"warp", "weft", "no tow"};
  const Rgb swatch[3] = {kWarp[0], kWeft[0], kGrey};
  double x = l.left + l.plot_w;
  fmt::format_to(out, "<g id=\"legend\" font-size=\"15\">\n");
  for (int k = 2; k >= 0; --k) {
    if (!has[k]) continue;
    x -= 10 + 8.5 * std::strlen(names[k]);
    fmt::format_to(out, "<text x=\"{:.2f}\" y=\"{:.2f}\">{}</text>\n", x, bar_y + 1, names[k]);
    x -= 20;
    fmt::format_to(out, "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"14\" height=\"14\" fill=\"{}\" stroke=\"{}\"/>\n", x,
                   bar_y - 12, swatch[k].hex(), swatch[k].dark().hex());
    x -= 14;
  }
  fmt::format_to(out, "</g>\n</svg>\n");
  return fmt::to_string(b);
}

// ------------------------------------------------------------------------------------------
// PNG: 8-bit palette image, zlib stream of stored (uncompressed) deflate blocks.

class Raster {
 public:
  Raster(int width, int height) : m_w(width), m_h(height), m_pixels(static_cast<size_t>(width) * height, 0) {
    colour(kWhite);  // index 0: background
  }
  int width() const { return m_w; }
  int height() const { return m_h; }
  const std::vector<std::uint8_t>& pixels() const { return m_pixels; }
  const std::vector<Rgb>& palette() const { return m_palette; }

  /// Palette index of a colour (added on first use; the palette stays far below 256).
  std::uint8_t colour(const Rgb& c) {
    for (size_t k = 0; k < m_palette.size(); ++k)
      if (m_palette[k] == c) return static_cast<std::uint8_t>(k);
    m_palette.push_back(c);
    return static_cast<std::uint8_t>(m_palette.size() - 1);
  }
  void set(int x, int y, std::uint8_t c) {
    if (x >= 0 && y >= 0 && x < m_w && y < m_h) m_pixels[static_cast<size_t>(y) * m_w + x] = c;
  }
  void rect(double x0, double y0, double x1, double y1, std::uint8_t c) {
    for (int y = static_cast<int>(std::lround(y0)); y < std::lround(y1); ++y)
      for (int x = static_cast<int>(std::lround(x0)); x < std::lround(x1); ++x) set(x, y, c);
  }
  /// Fills the pixels whose centre is inside the polygon (nonzero winding); a polygon too small
  /// to hold a pixel centre still sets the pixel holding `seed` (its centre), so it shows.
  void fill(const std::vector<Vec2>& p, const Vec2& seed, std::uint8_t c) {
    double ymin = 1e300, ymax = -1e300;
    for (const Vec2& v : p) ymin = std::min(ymin, v.y()), ymax = std::max(ymax, v.y());
    bool any = false;
    std::vector<std::pair<double, int>> xs;
    const int y_first = std::max(0, static_cast<int>(std::floor(ymin))),
              y_last = std::min(m_h - 1, static_cast<int>(std::ceil(ymax)));
    for (int y = y_first; y <= y_last; ++y) {
      const double yc = y + 0.5;
      xs.clear();
      for (size_t k = 0; k < p.size(); ++k) {
        const Vec2& a = p[k];
        const Vec2& b = p[(k + 1) % p.size()];
        if ((a.y() <= yc) != (b.y() <= yc))
          xs.emplace_back(a.x() + (yc - a.y()) * (b.x() - a.x()) / (b.y() - a.y()), b.y() > a.y() ? 1 : -1);
      }
      std::sort(xs.begin(), xs.end());
      int winding = 0;
      for (size_t k = 0; k + 1 < xs.size(); ++k) {
        winding += xs[k].second;
        if (winding == 0) continue;
        const int x0 = std::max(0, static_cast<int>(std::ceil(xs[k].first - 0.5)));
        const int x1 = std::min(m_w - 1, static_cast<int>(std::ceil(xs[k + 1].first - 0.5)) - 1);
        for (int x = x0; x <= x1; ++x) {
          m_pixels[static_cast<size_t>(y) * m_w + x] = c;
          any = true;
        }
      }
    }
    if (!any) set(static_cast<int>(std::floor(seed.x())), static_cast<int>(std::floor(seed.y())), c);
  }
  /// The polygon's outline, one pixel wide.
  void outline(const std::vector<Vec2>& p, std::uint8_t c) {
    for (size_t k = 0; k < p.size(); ++k) line(p[k], p[(k + 1) % p.size()], c);
  }
  void line(const Vec2& a, const Vec2& b, std::uint8_t c) {
    const int n = std::max(1, static_cast<int>(std::ceil(2 * (b - a).cwiseAbs().maxCoeff())));
    for (int i = 0; i <= n; ++i) {
      const Vec2 p = a + (b - a) * (static_cast<double>(i) / n);
      set(static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())), c);
    }
  }
  /// Text in a 5 x 7 pixel font (digits, '.', '-', 'm', ' '), each font pixel `size` pixels;
  /// (x, y) is the top left corner.
  void text(int x, int y, const std::string& s, int size, std::uint8_t c) {
    for (char ch : s) {
      const std::array<std::uint8_t, 7>* g = glyph(ch);
      if (g)
        for (int row = 0; row < 7; ++row)
          for (int col = 0; col < 5; ++col)
            if ((*g)[row] & (0x10 >> col))
              for (int dy = 0; dy < size; ++dy)
                for (int dx = 0; dx < size; ++dx) set(x + col * size + dx, y + row * size + dy, c);
      x += 6 * size;
    }
  }

 private:
  static const std::array<std::uint8_t, 7>* glyph(char ch) {
    static const std::array<std::array<std::uint8_t, 7>, 10> digits{{
        {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E},  // 0
        {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E},  // 1
        {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F},  // 2
        {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E},  // 3
        {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02},  // 4
        {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E},  // 5
        {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E},  // 6
        {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08},  // 7
        {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E},  // 8
        {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C},  // 9
    }};
    static const std::array<std::uint8_t, 7> dot{0, 0, 0, 0, 0, 0x0C, 0x0C}, minus{0, 0, 0, 0x1F, 0, 0, 0},
        m{0, 0, 0x1A, 0x15, 0x15, 0x11, 0x11};
    if (ch >= '0' && ch <= '9') return &digits[ch - '0'];
    if (ch == '.') return &dot;
    if (ch == '-') return &minus;
    if (ch == 'm') return &m;
    return nullptr;
  }

  int m_w, m_h;
  std::vector<std::uint8_t> m_pixels;
  std::vector<Rgb> m_palette;
};

std::uint32_t crc32(const std::uint8_t* data, size_t n, std::uint32_t crc = 0) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

std::uint32_t adler32(const std::vector<std::uint8_t>& data) {
  std::uint32_t a = 1, b = 0;
  for (std::uint8_t byte : data) {
    a = (a + byte) % 65521;
    b = (b + a) % 65521;
  }
  return (b << 16) | a;
}

void put32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<std::uint8_t>(v >> s));
}

void chunk(std::vector<std::uint8_t>& png, const char type[4], const std::vector<std::uint8_t>& data) {
  put32(png, static_cast<std::uint32_t>(data.size()));
  const size_t start = png.size();
  png.insert(png.end(), type, type + 4);
  png.insert(png.end(), data.begin(), data.end());
  put32(png, crc32(png.data() + start, png.size() - start));
}

std::vector<std::uint8_t> encode_png(const Raster& r) {
  std::vector<std::uint8_t> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<std::uint8_t> header;
  put32(header, static_cast<std::uint32_t>(r.width()));
  put32(header, static_cast<std::uint32_t>(r.height()));
  header.insert(header.end(), {8, 3, 0, 0, 0});  // 8 bits, palette, deflate, adaptive filters, no interlace
  chunk(png, "IHDR", header);
  std::vector<std::uint8_t> palette;
  for (const Rgb& c : r.palette()) palette.insert(palette.end(), {c.r, c.g, c.b});
  chunk(png, "PLTE", palette);
  // Scanlines, each with filter type 0 (none).
  std::vector<std::uint8_t> raw;
  raw.reserve(static_cast<size_t>(r.height()) * (r.width() + 1));
  for (int y = 0; y < r.height(); ++y) {
    raw.push_back(0);
    const auto row = r.pixels().begin() + static_cast<std::ptrdiff_t>(y) * r.width();
    raw.insert(raw.end(), row, row + r.width());
  }
  std::vector<std::uint8_t> z{0x78, 0x01};  // deflate, 32 K window, no dictionary, (0x7801 % 31 == 0)
  for (size_t at = 0; at < raw.size() || at == 0; at += 65535) {
    const size_t n = std::min<size_t>(65535, raw.size() - at);
    const bool last = at + n >= raw.size();
    z.push_back(last ? 1 : 0);  // BFINAL, BTYPE = 00 (stored)
    z.insert(z.end(), {static_cast<std::uint8_t>(n & 0xFF), static_cast<std::uint8_t>(n >> 8),
                       static_cast<std::uint8_t>(~n & 0xFF), static_cast<std::uint8_t>((~n >> 8) & 0xFF)});
    z.insert(z.end(), raw.begin() + static_cast<std::ptrdiff_t>(at), raw.begin() + static_cast<std::ptrdiff_t>(at + n));
    if (last) break;
  }
  put32(z, adler32(raw));
  chunk(png, "IDAT", z);
  chunk(png, "IEND", {});
  return png;
}

std::vector<std::uint8_t> make_png(const Layout& l, const std::vector<SliceCut>& cuts,
                                   const std::vector<TowSpec>& tows) {
  Raster r(l.width, l.height);
  const std::uint8_t black = r.colour(kBlack), frame = r.colour(kAxisGrey);
  std::vector<Vec2> px;
  for (const SliceCut& c : cuts) {
    const Rgb colour = tow_colour(tows, c.tow);
    px.clear();
    Eigen::AlignedBox2d box;
    for (const Vec2& p : c.points) {
      px.emplace_back(l.px(1e3 * p.x()), l.py(1e3 * p.y()));
      box.extend(px.back());
    }
    r.fill(px, Vec2(l.px(1e3 * c.center.x()), l.py(1e3 * c.center.y())), r.colour(colour));
    if (box.sizes().minCoeff() >= 8) r.outline(px, r.colour(colour.dark()));  // tells touching fibers apart
  }
  // Frame, scale bar and its length.
  const double right = l.left + l.plot_w, bottom = l.top + l.plot_h;
  r.line(Vec2(l.left - 1, l.top - 1), Vec2(right, l.top - 1), frame);
  r.line(Vec2(l.left - 1, bottom), Vec2(right, bottom), frame);
  r.line(Vec2(l.left - 1, l.top - 1), Vec2(l.left - 1, bottom), frame);
  r.line(Vec2(right, l.top - 1), Vec2(right, bottom), frame);
  const double bar = scale_bar_length(l), bar_y = bottom + 80;
  r.rect(l.left, bar_y - 5, l.left + bar * l.scale, bar_y, black);
  r.text(static_cast<int>(std::lround(l.left + bar * l.scale + 10)), static_cast<int>(std::lround(bar_y - 13)),
         format_mm(bar, decimals_for(bar)) + " mm", 2, black);
  return encode_png(r);
}

}  // namespace

// ------------------------------------------------------------------------------------------

std::array<int, 2> slice_plane_axes(int axis) {
  switch (axis) {
    case 0:
      return {1, 2};
    case 1:
      return {0, 2};
    case 2:
      return {0, 1};
  }
  throw std::invalid_argument(fmt::format("slice: axis must be 0, 1 or 2, got {}", axis));
}

const char* slice_axis_name(int axis) {
  static const char* names[3] = {"x", "y", "z"};
  slice_plane_axes(axis);  // checks
  return names[axis];
}

std::vector<SliceCut> slice_cuts(const Model& model, const VecX& q, const std::vector<TowSpec>& tows, int axis,
                                 double value) {
  const std::array<int, 2> uv = slice_plane_axes(axis);
  if (q.size() != model.num_dofs())
    throw std::invalid_argument(
        fmt::format("slice: state has {} values, the model has {} dofs", q.size(), model.num_dofs()));
  std::unordered_map<std::string, int> tow_of;
  for (size_t t = 0; t < tows.size(); ++t)
    for (const std::string& f : tows[t].fibers) tow_of.emplace(f, static_cast<int>(t));

  std::vector<SliceCut> cuts;
  std::vector<Sample> samples;
  for (size_t fi = 0; fi < model.fibers.size(); ++fi) {
    const Fiber& fiber = model.fibers[fi];
    const auto it = tow_of.find(fiber.name);
    const int tow = it == tow_of.end() ? -1 : it->second;
    const Section& section = model.sections[fiber.section];
    const double a = section.a, b = section.b;
    const double element_length = fiber.length / static_cast<double>(std::max<Index>(1, fiber.num_elements));
    const int per_element = std::clamp(static_cast<int>(std::ceil(element_length / (0.5 * std::min(a, b)))), 4, 64);

    // Crossings: roots of x0(eta)[axis] = value on each element, each crossing counted once
    // (eta in [-1, 1), and eta = 1 on the fiber's last element).
    samples.clear();
    for (Index e = fiber.first_element; e < fiber.first_element + fiber.num_elements; ++e) {
      const double* qe = q.data() + model.elements[e].first_dof;
      const double X0 = qe[axis], X1 = qe[kNodeDofs + axis], X2 = qe[2 * kNodeDofs + axis];
      const double A = 0.5 * (X0 - 2 * X1 + X2), B = 0.5 * (X2 - X0), C = X1 - value;
      const double scale = std::abs(X0) + std::abs(X1) + std::abs(X2) + std::abs(value) + element_length;
      const bool last_element = e + 1 == fiber.first_element + fiber.num_elements;
      for (double eta : quadratic_roots(A, B, C, scale)) {
        if (eta == 1 && !last_element) continue;
        const SectionState s = section_state(qe, eta);
        const double len = s.t.norm();
        if (!(len > 0) || std::abs(s.t[axis]) < kCrossingCos * len) continue;  // a strip
        SliceCut cut;
        cut.kind = SliceCut::Kind::Crossing;
        cut.fiber = static_cast<int>(fi);
        cut.name = fiber.name;
        cut.tow = tow;
        cut.center = Vec2(s.x0[uv[0]], s.x0[uv[1]]);
        cut.points.reserve(kEllipsePoints);
        for (int k = 0; k < kEllipsePoints; ++k) {
          const double th = 2 * std::numbers::pi * k / kEllipsePoints;
          Vec3 p = s.x0 + a * std::cos(th) * s.g1 + b * std::sin(th) * s.g2;
          p += (value - p[axis]) / s.t[axis] * s.t;  // along the fiber onto the plane
          cut.points.emplace_back(p[uv[0]], p[uv[1]]);
        }
        cuts.push_back(std::move(cut));
      }
      // Samples for the strips, skipping elements too far from the plane to touch it.
      double lo = std::min(X0, X2), hi = std::max(X0, X2);
      if (A != 0) {
        const double ext = -B / (2 * A);
        if (ext > -1 && ext < 1) {
          const double fe = (A * ext + B) * ext + X1;
          lo = std::min(lo, fe);
          hi = std::max(hi, fe);
        }
      }
      double reach = 0;
      for (int k = 0; k < 3; ++k)
        reach = std::max(reach, std::max(a, b) * (Eigen::Map<const Vec3>(qe + kNodeDofs * k + 3).norm() +
                                                  Eigen::Map<const Vec3>(qe + kNodeDofs * k + 6).norm()));
      const bool near = value >= lo - 2 * reach && value <= hi + 2 * reach;
      for (int j = e == fiber.first_element ? 0 : 1; j <= per_element; ++j) {
        Sample smp;
        smp.element = e;
        smp.eta = -1.0 + 2.0 * j / per_element;
        if (j == per_element) smp.eta = 1.0;
        if (near) {
          smp.computed = true;
          smp.chord = chord_at(qe, smp.eta, a, b, axis, value, uv);
        }
        samples.push_back(smp);
      }
    }

    // Strips: runs of consecutive samples where the fiber runs near the plane's direction and
    // the plane cuts the section; closed by a tip where the chord vanishes.
    std::vector<Vec2> lefts, rights;
    std::optional<Vec2> tip_start;
    auto valid = [](const Sample& s) { return s.computed && s.chord.strip_angle && s.chord.exists; };
    // The previous sample's eta in the element of sample i (samples at element ends are shared).
    auto previous_eta = [&](size_t i) {
      return samples[i - 1].element == samples[i].element ? samples[i - 1].eta : -1.0;
    };
    auto close_run = [&](std::optional<Vec2> tip_end) {
      if (lefts.empty()) return;
      SliceCut cut;
      cut.kind = SliceCut::Kind::Strip;
      cut.fiber = static_cast<int>(fi);
      cut.name = fiber.name;
      cut.tow = tow;
      if (tip_start) cut.points.push_back(*tip_start);
      cut.points.insert(cut.points.end(), lefts.begin(), lefts.end());
      if (tip_end) cut.points.push_back(*tip_end);
      cut.points.insert(cut.points.end(), rights.rbegin(), rights.rend());
      if (cut.points.size() >= 3) {
        cut.center.setZero();
        for (const Vec2& p : cut.points) cut.center += p;
        cut.center /= static_cast<double>(cut.points.size());
        cuts.push_back(std::move(cut));
      }
      lefts.clear();
      rights.clear();
      tip_start.reset();
    };
    for (size_t i = 0; i < samples.size(); ++i) {
      const Sample& s = samples[i];
      const double* qe = q.data() + model.elements[s.element].first_dof;
      if (valid(s)) {
        if (lefts.empty() && i > 0 && samples[i - 1].computed && samples[i - 1].chord.strip_angle &&
            !samples[i - 1].chord.exists)
          tip_start = strip_tip(qe, s.eta, previous_eta(i), a, b, axis, value, uv);
        lefts.push_back(s.chord.left);
        rights.push_back(s.chord.right);
      } else if (!lefts.empty()) {
        std::optional<Vec2> tip;
        if (s.computed && s.chord.strip_angle && !s.chord.exists)
          tip = strip_tip(qe, previous_eta(i), s.eta, a, b, axis, value, uv);
        close_run(tip);
      }
    }
    close_run(std::nullopt);
  }
  return cuts;
}

int slice_fiber_count(const std::vector<SliceCut>& cuts) {
  std::vector<int> fibers;
  for (const SliceCut& c : cuts) fibers.push_back(c.fiber);
  std::sort(fibers.begin(), fibers.end());
  return static_cast<int>(std::unique(fibers.begin(), fibers.end()) - fibers.begin());
}

int write_slice(const std::string& stem, const std::vector<SliceCut>& cuts, const std::vector<TowSpec>& tows, int axis,
                double value, const std::string& title) {
  slice_plane_axes(axis);  // checks the axis
  for (const SliceCut& c : cuts)
    if (c.tow >= static_cast<int>(tows.size()))
      throw std::invalid_argument(fmt::format("slice: cut of fiber {} names tow {} of {}", c.name, c.tow, tows.size()));
  const fs::path parent = fs::path(stem).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) throw RunError(fmt::format("cannot create directory '{}': {}", parent.string(), ec.message()));
  }
  const Layout layout = make_layout(cuts);
  const std::string svg = make_svg(layout, cuts, tows, axis, value, title);
  write_file_atomic(stem + ".svg", svg);
  const std::vector<std::uint8_t> png = make_png(layout, cuts, tows);
  write_file_atomic(stem + ".png", std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
  return slice_fiber_count(cuts);
}

int write_slice(const std::string& stem, const Model& model, const VecX& q, const std::vector<TowSpec>& tows, int axis,
                double value, const std::string& title) {
  return write_slice(stem, slice_cuts(model, q, tows, axis, value), tows, axis, value, title);
}

Eigen::AlignedBox3d centroid_bounds(const Model& model, const VecX& q) {
  Eigen::AlignedBox3d box;
  for (Index n = 0; n < model.num_nodes(); ++n) box.extend(Vec3(q.segment<3>(kNodeDofs * n)));
  return box;
}

}  // namespace fibra
