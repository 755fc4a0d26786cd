#include "fibra/model/slice_cuts.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <unordered_map>

#include "fibra/beam/beam_element.hpp"

namespace fibra {

namespace {

using Vec2 = Eigen::Vector2d;

/// A fiber crosses the plane as an ellipse when its tangent is within 60 degrees of the
/// plane's normal (|cos| >= 0.5, elongation <= 2); closer to the plane it is drawn as a strip.
constexpr double kCrossingCos = 0.5;
/// Points of the polygon of a crossing.
constexpr int kEllipsePoints = 48;

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

/// The plane's coordinates (u . p, v . p) of a point.
Vec2 in_plane(const SlicePlane& plane, const Vec3& p) { return {plane.u.dot(p), plane.v.dot(p)}; }

/// Cosine of the angle between the tangent and the plane's normal (0 when degenerate).
double normal_cosine(const SectionState& s, const SlicePlane& plane) {
  const double len = s.t.norm();
  return len > 0 ? plane.normal.dot(s.t) / len : 0.0;
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

Chord chord_at(const double* qe, double eta, double a, double b, const SlicePlane& plane) {
  const SectionState s = section_state(qe, eta);
  Chord c;
  c.strip_angle = std::abs(normal_cosine(s, plane)) < kCrossingCos;
  // a cos(th) n.g1 + b sin(th) n.g2 = offset - n.x0, i.e. R cos(th - phi) = d.
  const Vec3& n = plane.normal;
  const double alpha = a * n.dot(s.g1), beta = b * n.dot(s.g2), d = plane.offset - n.dot(s.x0);
  const double R = std::hypot(alpha, beta);
  c.margin = R - std::abs(d);
  c.exists = R > 0 && c.margin >= 0;
  if (!c.exists) return c;
  const double phi = std::atan2(beta, alpha), half = std::acos(std::clamp(d / R, -1.0, 1.0));
  const Vec2 centre = in_plane(plane, s.x0);
  Vec2 p[2];
  for (int k = 0; k < 2; ++k) {
    const double th = phi + (k == 0 ? half : -half);
    p[k] = in_plane(plane, s.x0 + a * std::cos(th) * s.g1 + b * std::sin(th) * s.g2);
  }
  const Vec2 t = in_plane(plane, s.t);
  const Vec2 normal(-t.y(), t.x());  // the in-plane tangent turned by 90 degrees
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
Vec2 strip_tip(const double* qe, double eta_in, double eta_out, double a, double b, const SlicePlane& plane) {
  Chord last = chord_at(qe, eta_in, a, b, plane);
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (eta_in + eta_out);
    const Chord c = chord_at(qe, mid, a, b, plane);
    if (c.exists) {
      eta_in = mid;
      last = c;
    } else {
      eta_out = mid;
    }
  }
  return 0.5 * (last.left + last.right);
}

/// n . (node k's centroid) of an element.
double node_height(const double* qe, int k, const Vec3& n) { return n.dot(Eigen::Map<const Vec3>(qe + kNodeDofs * k)); }

}  // namespace

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

SlicePlane axis_plane(int axis, double value) {
  const std::array<int, 2> uv = slice_plane_axes(axis);
  SlicePlane p;
  p.normal = Vec3::Unit(axis);
  p.u = Vec3::Unit(uv[0]);
  p.v = Vec3::Unit(uv[1]);
  p.offset = value;
  p.axis = axis;
  p.u_name = slice_axis_name(uv[0]);
  p.v_name = slice_axis_name(uv[1]);
  return p;
}

std::vector<SliceCut> slice_cuts(const Model& model, const VecX& q, const std::vector<TowSpec>& tows,
                                 const SlicePlane& plane) {
  if (q.size() != model.num_dofs())
    throw std::invalid_argument(
        fmt::format("slice: state has {} values, the model has {} dofs", q.size(), model.num_dofs()));
  const Vec3& n = plane.normal;
  const double value = plane.offset;
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

    // Crossings: roots of n . x0(eta) = value on each element, each crossing counted once
    // (eta in [-1, 1), and eta = 1 on the fiber's last element).
    samples.clear();
    for (Index e = fiber.first_element; e < fiber.first_element + fiber.num_elements; ++e) {
      const double* qe = q.data() + model.elements[e].first_dof;
      const double X0 = node_height(qe, 0, n), X1 = node_height(qe, 1, n), X2 = node_height(qe, 2, n);
      const double A = 0.5 * (X0 - 2 * X1 + X2), B = 0.5 * (X2 - X0), C = X1 - value;
      const double scale = std::abs(X0) + std::abs(X1) + std::abs(X2) + std::abs(value) + element_length;
      const bool last_element = e + 1 == fiber.first_element + fiber.num_elements;
      for (double eta : quadratic_roots(A, B, C, scale)) {
        if (eta == 1 && !last_element) continue;
        const SectionState s = section_state(qe, eta);
        const double len = s.t.norm(), tn = n.dot(s.t);
        if (!(len > 0) || std::abs(tn) < kCrossingCos * len) continue;  // a strip
        SliceCut cut;
        cut.kind = SliceCut::Kind::Crossing;
        cut.fiber = static_cast<int>(fi);
        cut.name = fiber.name;
        cut.tow = tow;
        cut.center = in_plane(plane, s.x0);
        cut.points.reserve(kEllipsePoints);
        for (int k = 0; k < kEllipsePoints; ++k) {
          const double th = 2 * std::numbers::pi * k / kEllipsePoints;
          Vec3 p = s.x0 + a * std::cos(th) * s.g1 + b * std::sin(th) * s.g2;
          p += (value - n.dot(p)) / tn * s.t;  // along the fiber onto the plane
          cut.points.push_back(in_plane(plane, p));
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
          smp.chord = chord_at(qe, smp.eta, a, b, plane);
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
          tip_start = strip_tip(qe, s.eta, previous_eta(i), a, b, plane);
        lefts.push_back(s.chord.left);
        rights.push_back(s.chord.right);
      } else if (!lefts.empty()) {
        std::optional<Vec2> tip;
        if (s.computed && s.chord.strip_angle && !s.chord.exists)
          tip = strip_tip(qe, previous_eta(i), s.eta, a, b, plane);
        close_run(tip);
      }
    }
    close_run(std::nullopt);
  }
  return cuts;
}

std::vector<SliceCut> slice_cuts(const Model& model, const VecX& q, const std::vector<TowSpec>& tows, int axis,
                                 double value) {
  return slice_cuts(model, q, tows, axis_plane(axis, value));
}

int slice_fiber_count(const std::vector<SliceCut>& cuts) {
  std::vector<int> fibers;
  for (const SliceCut& c : cuts) fibers.push_back(c.fiber);
  std::sort(fibers.begin(), fibers.end());
  return static_cast<int>(std::unique(fibers.begin(), fibers.end()) - fibers.begin());
}

Eigen::AlignedBox2d slice_extent(const std::vector<SliceCut>& cuts) {
  Eigen::AlignedBox2d box;
  for (const SliceCut& c : cuts)
    for (const Vec2& p : c.points) box.extend(p);
  return box;
}

Eigen::AlignedBox3d centroid_bounds(const Model& model, const VecX& q) {
  Eigen::AlignedBox3d box;
  for (Index n = 0; n < model.num_nodes(); ++n) box.extend(Vec3(q.segment<3>(kNodeDofs * n)));
  return box;
}

TowStations tow_stations(const Model& model, const VecX& q, const TowSpec& tow, int count) {
  if (count < 1) throw std::invalid_argument(fmt::format("tow_stations: count must be at least 1, got {}", count));
  if (q.size() != model.num_dofs())
    throw std::invalid_argument(
        fmt::format("tow_stations: state has {} values, the model has {} dofs", q.size(), model.num_dofs()));
  std::vector<const Fiber*> fibers;
  for (const std::string& name : tow.fibers) {
    const int f = model.fiber_index(name);
    if (f >= 0) fibers.push_back(&model.fibers[f]);
  }
  if (fibers.empty()) throw std::invalid_argument(fmt::format("tow_stations: tow {} has no fiber in the model", tow.name));
  auto node = [&](const Fiber& f, Index k) { return Vec3(q.segment<3>(kNodeDofs * (f.first_node + k))); };

  // The mean of the fibers' end-to-end directions, each turned to the nominal axis.
  const Vec3 nominal = tow.direction == TowSpec::Direction::Warp ? Vec3::UnitX() : Vec3::UnitY();
  Vec3 d = Vec3::Zero();
  for (const Fiber* f : fibers) {
    const Vec3 chord = node(*f, f->num_nodes - 1) - node(*f, 0);
    if (chord.norm() > 0) d += (chord.dot(nominal) < 0 ? -1.0 : 1.0) * chord.normalized();
  }
  if (!(d.norm() > 0)) throw std::invalid_argument(fmt::format("tow_stations: tow {} has no direction", tow.name));
  d.normalize();

  TowStations st;
  st.direction = d;
  st.start = -std::numeric_limits<double>::infinity();
  st.end = std::numeric_limits<double>::infinity();
  for (const Fiber* f : fibers) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (Index k = 0; k < f->num_nodes; ++k) {
      const double s = d.dot(node(*f, k));
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    st.start = std::max(st.start, lo);
    st.end = std::min(st.end, hi);
  }
  if (!(st.end > st.start))
    throw std::invalid_argument(
        fmt::format("tow_stations: the fibers of tow {} cover no common span along its direction", tow.name));

  // Upwards (+z, or +y for a tow along z) made normal to the tow; across = up x direction,
  // turned to +y for a warp, +x for a weft.
  const Vec3 up = std::abs(d.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitY();
  const Vec3 v = (up - up.dot(d) * d).normalized();
  Vec3 u = v.cross(d).normalized();
  const Vec3 across = tow.direction == TowSpec::Direction::Warp ? Vec3::UnitY() : Vec3::UnitX();
  if (u.dot(across) < 0) u = -u;
  const double length = st.end - st.start;
  for (int k = 1; k <= count; ++k) {
    SlicePlane p;
    p.normal = d;
    p.u = u;
    p.v = v;
    p.offset = st.start + length * k / (count + 1);
    p.axis = -1;
    p.u_name = "across";
    p.v_name = "up";
    p.caption = fmt::format("tow {}, station {} of {} ({:.4g} of {:.4g} mm along it)", tow.name, k, count,
                            1e3 * (p.offset - st.start), 1e3 * length);
    st.planes.push_back(std::move(p));
  }
  return st;
}

}  // namespace fibra
