#include "fibra/io/slice.hpp"

#include <cairo-svg.h>
#include <cairo.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string_view>

#include "fibra/core/error.hpp"
#include "fibra/core/file.hpp"

namespace fibra {

namespace {

namespace fs = std::filesystem;
using Vec2 = Eigen::Vector2d;

// ------------------------------------------------------------------------------------------
// Colours.

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  Rgb dark() const {
    return {static_cast<std::uint8_t>(r * 6 / 10), static_cast<std::uint8_t>(g * 6 / 10),
            static_cast<std::uint8_t>(b * 6 / 10)};
  }
};

constexpr Rgb kBlack{0, 0, 0}, kGrey{154, 154, 154}, kSubtitle{68, 68, 68};
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
// Page layout.

constexpr double kMarginLeft = 90, kMarginRight = 24, kMarginTop = 70, kMarginBottom = 110;
constexpr double kMaxPlotWidth = 1200 - kMarginLeft - kMarginRight, kMaxPlotHeight = 1400;

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
double scale_bar_length(const SlicePage& l) { return nice_step(l.du / 5, true); }

std::string subtitle(const SlicePage& l, const SlicePlane& plane, const std::vector<SliceCut>& cuts) {
  const int fibers = slice_fiber_count(cuts);
  const std::string count = fmt::format("{} fiber{} cut", fibers, fibers == 1 ? "" : "s");
  if (plane.axis < 0) return fmt::format("{}: {}", plane.caption, count);
  double mm = 1e3 * plane.offset;
  if (std::abs(mm) < 1e-9 * std::max(l.du, l.dv)) mm = 0;  // round-off of a computed plane
  return fmt::format("plane {} = {:.6g} mm: {}", slice_axis_name(plane.axis), mm, count);
}

/// `s` with every byte that is not part of valid UTF-8 replaced by '?' (Cairo refuses such text).
std::string valid_utf8(std::string_view s) {
  std::string out;
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    const size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    bool ok = n > 0 && i + n <= s.size() && !(n > 1 && c < 0xC2) && !(n == 4 && c > 0xF4);
    for (size_t k = 1; ok && k < n; ++k) ok = (static_cast<unsigned char>(s[i + k]) >> 6) == 0x2;
    if (ok && n == 3) {
      const unsigned cp = ((c & 0x0Fu) << 12) | ((static_cast<unsigned char>(s[i + 1]) & 0x3Fu) << 6);
      ok = cp >= 0x800 && (cp < 0xD800 || cp > 0xDFFF);
    }
    if (ok && n == 4) {
      const unsigned cp = ((c & 0x07u) << 18) | ((static_cast<unsigned char>(s[i + 1]) & 0x3Fu) << 12);
      ok = cp >= 0x10000 && cp <= 0x10FFFF;
    }
    if (ok && !(n == 1 && c < 0x20 && c != '\t')) {
      out.append(s.substr(i, n));
      i += n;
    } else {
      out += '?';
      ++i;
    }
  }
  return out;
}

// ------------------------------------------------------------------------------------------
// Drawing, the same onto both surfaces.

void set_colour(cairo_t* cr, const Rgb& c) { cairo_set_source_rgb(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0); }

enum class Align { Left, Centre, Right };

/// Text with its baseline at y, aligned on x; turned by `angle` [rad] about (x, y).
void text(cairo_t* cr, double x, double y, const std::string& s, double size, Align align, const Rgb& colour,
          double angle = 0) {
  cairo_save(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  const std::string t = valid_utf8(s);
  cairo_text_extents_t e;
  cairo_text_extents(cr, t.c_str(), &e);
  cairo_translate(cr, x, y);
  cairo_rotate(cr, angle);
  const double shift = align == Align::Left ? 0 : align == Align::Centre ? -0.5 * e.x_advance : -e.x_advance;
  cairo_move_to(cr, shift, 0);
  set_colour(cr, colour);
  cairo_show_text(cr, t.c_str());
  cairo_restore(cr);
}

double text_width(cairo_t* cr, const std::string& s, double size) {
  cairo_save(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, valid_utf8(s).c_str(), &e);
  cairo_restore(cr);
  return e.x_advance;
}

/// A line of one pixel between pixel centres, crisp on the raster.
void pixel_line(cairo_t* cr, double x0, double y0, double x1, double y1) {
  cairo_move_to(cr, std::round(x0) + 0.5, std::round(y0) + 0.5);
  cairo_line_to(cr, std::round(x1) + 0.5, std::round(y1) + 0.5);
}

void draw_slice(cairo_t* cr, const SlicePage& l, const std::vector<SliceCut>& cuts, const std::vector<TowSpec>& tows,
                const SlicePlane& plane, const std::string& title) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  text(cr, 0.5 * l.width, 30, title, 20, Align::Centre, kBlack);
  text(cr, 0.5 * l.width, 54, subtitle(l, plane, cuts), 15, Align::Centre, kSubtitle);

  // The cuts, one path each: filled in the tow's colour; outlined darker when at least 8 px
  // across (tells touching fibers apart), and in its own colour when less than a pixel across
  // (so that it still shows).
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  for (const SliceCut& c : cuts) {
    if (c.points.empty()) continue;
    Eigen::AlignedBox2d box;
    for (size_t k = 0; k < c.points.size(); ++k) {
      const Vec2 p = l.to_page(c.points[k]);
      box.extend(p);
      if (k == 0)
        cairo_move_to(cr, p.x(), p.y());
      else
        cairo_line_to(cr, p.x(), p.y());
    }
    cairo_close_path(cr);
    const Rgb colour = tow_colour(tows, c.tow);
    set_colour(cr, colour);
    const double size = box.sizes().minCoeff(), extent = box.sizes().maxCoeff();
    if (size >= 8) {
      cairo_fill_preserve(cr);
      set_colour(cr, colour.dark());
      cairo_set_line_width(cr, 0.75);
      cairo_stroke(cr);
    } else if (extent < 1) {
      cairo_fill_preserve(cr);
      cairo_set_line_width(cr, 1);
      cairo_stroke(cr);
    } else {
      cairo_fill(cr);
    }
  }

  // Frame, ticks, tick labels and axis titles.
  const double right = l.left + l.plot_w, bottom = l.top + l.plot_h;
  set_colour(cr, kBlack);
  cairo_set_line_width(cr, 1);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_MITER);
  cairo_rectangle(cr, std::round(l.left) - 0.5, std::round(l.top) - 0.5, std::round(right) - std::round(l.left) + 1,
                  std::round(bottom) - std::round(l.top) + 1);
  const double step_u = nice_step(l.du / 6), step_v = nice_step(l.dv / 4);
  for (long k = static_cast<long>(std::ceil(l.u0 / step_u)); k * step_u <= l.u0 + l.du; ++k) {
    const double x = l.left + (k * step_u - l.u0) * l.scale;
    pixel_line(cr, x, bottom + 1, x, bottom + 6);
  }
  for (long k = static_cast<long>(std::ceil((l.v1 - l.dv) / step_v)); k * step_v <= l.v1; ++k) {
    const double y = l.top + (l.v1 - k * step_v) * l.scale;
    pixel_line(cr, l.left - 6, y, l.left - 1, y);
  }
  cairo_stroke(cr);
  for (long k = static_cast<long>(std::ceil(l.u0 / step_u)); k * step_u <= l.u0 + l.du; ++k)
    text(cr, l.left + (k * step_u - l.u0) * l.scale, bottom + 22, format_mm(k * step_u, decimals_for(step_u)), 14,
         Align::Centre, kBlack);
  for (long k = static_cast<long>(std::ceil((l.v1 - l.dv) / step_v)); k * step_v <= l.v1; ++k)
    text(cr, l.left - 9, l.top + (l.v1 - k * step_v) * l.scale + 5, format_mm(k * step_v, decimals_for(step_v)), 14,
         Align::Right, kBlack);
  text(cr, l.left + 0.5 * l.plot_w, bottom + 46, plane.u_name + " [mm]", 16, Align::Centre, kBlack);
  text(cr, l.left - 62, l.top + 0.5 * l.plot_h, plane.v_name + " [mm]", 16, Align::Centre, kBlack,
       -0.5 * std::numbers::pi);

  // Scale bar (bottom left) and legend (bottom right).
  const double bar = scale_bar_length(l), bar_px = bar * l.scale, bar_y = bottom + 80;
  set_colour(cr, kBlack);
  cairo_rectangle(cr, l.left, bar_y - 5, bar_px, 5);
  cairo_fill(cr);
  text(cr, l.left + bar_px + 10, bar_y + 1, format_mm(bar, decimals_for(bar)) + " mm", 15, Align::Left, kBlack);
  bool has[3] = {false, false, false};
  for (const SliceCut& c : cuts) has[c.tow < 0 ? 2 : tows[c.tow].direction == TowSpec::Direction::Warp ? 0 : 1] = true;
  const char* names[3] = {"warp", "weft", "no tow"};
  const Rgb swatch[3] = {kWarp[0], kWeft[0], kGrey};
  double x = right;
  for (int k = 2; k >= 0; --k) {
    if (!has[k]) continue;
    x -= text_width(cr, names[k], 15);
    text(cr, x, bar_y + 1, names[k], 15, Align::Left, kBlack);
    x -= 20;
    cairo_rectangle(cr, x, bar_y - 12, 14, 14);
    set_colour(cr, swatch[k]);
    cairo_fill_preserve(cr);
    set_colour(cr, swatch[k].dark());
    cairo_set_line_width(cr, 1);
    cairo_stroke(cr);
    x -= 24;
  }
}

// ------------------------------------------------------------------------------------------
// Surfaces.

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};
using Surface = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using Context = std::unique_ptr<cairo_t, ContextDeleter>;

cairo_status_t append_bytes(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

void check(cairo_status_t status, const std::string& file, const char* what) {
  if (status != CAIRO_STATUS_SUCCESS)
    throw RunError(fmt::format("cannot draw '{}': {}: {}", file, what, cairo_status_to_string(status)));
}

/// Draws onto `surface` and checks the drawing.
void draw_onto(cairo_surface_t* surface, const std::string& file, const SlicePage& l,
               const std::vector<SliceCut>& cuts, const std::vector<TowSpec>& tows, const SlicePlane& plane,
               const std::string& title) {
  check(cairo_surface_status(surface), file, "surface");
  const Context cr(cairo_create(surface));
  draw_slice(cr.get(), l, cuts, tows, plane, title);
  check(cairo_status(cr.get()), file, "drawing");
}

std::string render_svg(const std::string& file, const SlicePage& l, const std::vector<SliceCut>& cuts,
                       const std::vector<TowSpec>& tows, const SlicePlane& plane, const std::string& title) {
  std::string bytes;
  {
    const Surface surface(cairo_svg_surface_create_for_stream(append_bytes, &bytes, l.width, l.height));
    cairo_svg_surface_set_document_unit(surface.get(), CAIRO_SVG_UNIT_USER);
    draw_onto(surface.get(), file, l, cuts, tows, plane, title);
    cairo_surface_finish(surface.get());
    check(cairo_surface_status(surface.get()), file, "SVG");
  }
  return bytes;
}

std::string render_png(const std::string& file, const SlicePage& l, const std::vector<SliceCut>& cuts,
                       const std::vector<TowSpec>& tows, const SlicePlane& plane, const std::string& title) {
  const Surface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, l.width, l.height));
  draw_onto(surface.get(), file, l, cuts, tows, plane, title);
  cairo_surface_flush(surface.get());
  std::string bytes;
  check(cairo_surface_write_to_png_stream(surface.get(), append_bytes, &bytes), file, "PNG");
  return bytes;
}

}  // namespace

// ------------------------------------------------------------------------------------------

SlicePage slice_page(const std::vector<SliceCut>& cuts, const Eigen::AlignedBox2d& extent) {
  Eigen::AlignedBox2d box = extent.isEmpty() ? slice_extent(cuts) : extent;
  double umin = -1, umax = 1, vmin = -1, vmax = 1;
  if (!box.isEmpty()) {
    umin = 1e3 * box.min().x();
    umax = 1e3 * box.max().x();
    vmin = 1e3 * box.min().y();
    vmax = 1e3 * box.max().y();
  }
  double size = std::max(umax - umin, vmax - vmin);
  if (!(size > 0)) size = 1e-3;
  const double pad = 0.05 * size;
  umin -= pad, umax += pad, vmin -= pad, vmax += pad;
  SlicePage l;
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

int write_slice(const std::string& stem, const std::vector<SliceCut>& cuts, const std::vector<TowSpec>& tows,
                const SlicePlane& plane, const std::string& title, const Eigen::AlignedBox2d& extent) {
  if (plane.axis >= 0) slice_plane_axes(plane.axis);  // checks the axis
  for (const SliceCut& c : cuts)
    if (c.tow >= static_cast<int>(tows.size()))
      throw std::invalid_argument(fmt::format("slice: cut of fiber {} names tow {} of {}", c.name, c.tow, tows.size()));
  const fs::path parent = fs::path(stem).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) throw RunError(fmt::format("cannot create directory '{}': {}", parent.string(), ec.message()));
  }
  const SlicePage page = slice_page(cuts, extent);
  write_file_atomic(stem + ".svg", render_svg(stem + ".svg", page, cuts, tows, plane, title));
  write_file_atomic(stem + ".png", render_png(stem + ".png", page, cuts, tows, plane, title));
  return slice_fiber_count(cuts);
}

int write_slice(const std::string& stem, const std::vector<SliceCut>& cuts, const std::vector<TowSpec>& tows, int axis,
                double value, const std::string& title) {
  return write_slice(stem, cuts, tows, axis_plane(axis, value), title);
}

int write_slice(const std::string& stem, const Model& model, const VecX& q, const std::vector<TowSpec>& tows, int axis,
                double value, const std::string& title) {
  const SlicePlane plane = axis_plane(axis, value);
  return write_slice(stem, slice_cuts(model, q, tows, plane), tows, plane, title);
}

}  // namespace fibra
