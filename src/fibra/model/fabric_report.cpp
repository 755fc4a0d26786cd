#include "fibra/model/fabric_report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>

namespace fibra {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The centroid line of a quadratic element, x0(eta) = c0 + c1 eta + c2 eta^2 (nodes at
/// eta = -1, 0, 1).
struct Curve {
  Vec3 c0, c1, c2;
  Vec3 at(double t) const { return c0 + t * (c1 + t * c2); }
  Vec3 tangent(double t) const { return c1 + 2.0 * t * c2; }  ///< d x0 / d eta
};

Curve element_curve(const Model& model, const VecX& q, Index element) {
  const double* p = q.data() + model.elements[element].first_dof;
  const Vec3 x0(p[0], p[1], p[2]), x1(p[9], p[10], p[11]), x2(p[18], p[19], p[20]);
  return {x1, 0.5 * (x2 - x0), 0.5 * (x0 - 2.0 * x1 + x2)};
}

/// A coordinate along an element's centroid line, u(eta) = c + b eta + a eta^2.
struct Quadratic {
  double a, b, c;
  double at(double t) const { return c + t * (b + t * a); }
};

/// The coordinate x0(eta)[axis].
Quadratic coordinate(const Curve& cu, int axis) { return {cu.c2[axis], cu.c1[axis], cu.c0[axis]}; }

/// The coordinate (x0(eta) - origin) . d along the direction d.
Quadratic coordinate(const Curve& cu, const Vec3& origin, const Vec3& d) {
  return {cu.c2.dot(d), cu.c1.dot(d), (cu.c0 - origin).dot(d)};
}

/// Roots in [-1, 1] of a t^2 + b t + c = 0, ascending; returns their number.
int roots_in_element(double a, double b, double c, double out[2]) {
  const double scale = std::abs(a) + std::abs(b) + std::abs(c);
  if (scale == 0.0) return 0;  // identically zero: no isolated crossing
  const double tol = 1e-12;
  double t[2];
  int n = 0;
  if (std::abs(a) <= 1e-14 * scale) {
    if (b == 0.0) return 0;
    t[n++] = -c / b;
  } else {
    double disc = b * b - 4.0 * a * c;
    if (disc < 0.0) {
      if (disc < -1e-14 * b * b - 1e-300) return 0;
      disc = 0.0;  // tangent to the plane: a double root
    }
    const double s = b >= 0.0 ? std::sqrt(disc) : -std::sqrt(disc);
    const double qq = -0.5 * (b + s);
    t[n++] = qq / a;
    if (qq != 0.0) t[n++] = c / qq;
  }
  int m = 0;
  for (int k = 0; k < n; ++k)
    if (t[k] >= -1.0 - tol && t[k] <= 1.0 + tol) out[m++] = std::clamp(t[k], -1.0, 1.0);
  if (m == 2 && out[0] > out[1]) std::swap(out[0], out[1]);
  return m;
}

/// The parts [t0, t1] of [-1, 1] where lo <= u(eta) <= hi.
template <class Visit>
void for_parts_in_range(const Quadratic& u, double lo, double hi, Visit&& visit) {
  double breaks[6] = {-1.0, 1.0};
  int n = 2;
  for (double v : {lo, hi}) {
    double r[2];
    const int k = roots_in_element(u.a, u.b, u.c - v, r);
    for (int i = 0; i < k; ++i) breaks[n++] = r[i];
  }
  for (int i = 1; i < n; ++i)  // insertion sort of at most 6 values
    for (int j = i; j > 0 && breaks[j - 1] > breaks[j]; --j) std::swap(breaks[j - 1], breaks[j]);
  for (int i = 0; i + 1 < n; ++i) {
    const double t0 = breaks[i], t1 = breaks[i + 1];
    if (t1 - t0 <= 1e-14) continue;
    const double mid = u.at(0.5 * (t0 + t1));
    if (mid >= lo && mid <= hi) visit(t0, t1);
  }
}

/// Arc length of the centroid line over eta in [t0, t1] (5-point Gauss-Legendre; the
/// integrand is the square root of a quadratic).
double arc_length(const Curve& cu, double t0, double t1) {
  static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                              0.9061798459386640};
  static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                              0.2369268850561891};
  const double half = 0.5 * (t1 - t0), mid = 0.5 * (t1 + t0);
  double s = 0.0;
  for (int g = 0; g < 5; ++g) s += w[g] * cu.tangent(mid + half * x[g]).norm();
  return half * s;
}

/// Lowest and highest u(eta) over eta in [t0, t1].
void extremes(const Quadratic& u, double t0, double t1, double& lo, double& hi) {
  for (const double t : {t0, t1}) {
    lo = std::min(lo, u.at(t));
    hi = std::max(hi, u.at(t));
  }
  if (u.a != 0.0) {
    const double t = -u.b / (2.0 * u.a);
    if (t > t0 && t < t1) {
      lo = std::min(lo, u.at(t));
      hi = std::max(hi, u.at(t));
    }
  }
}

/// The direction in the fabric plane of the principal axis of a fiber's nodes' second moments
/// (the line of least squared distances to them), oriented along `nominal` (+x or +y); zero
/// when its nodes coincide.
Eigen::Vector2d principal_direction(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& nominal) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  double cxx = 0.0, cyy = 0.0, cxy = 0.0;
  for (const auto& p : points) {
    const Eigen::Vector2d d = p - mean;
    cxx += d.x() * d.x();
    cyy += d.y() * d.y();
    cxy += d.x() * d.y();
  }
  if (cxx + cyy == 0.0) return Eigen::Vector2d::Zero();
  const double angle = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
  const Eigen::Vector2d d(std::cos(angle), std::sin(angle));
  return d.dot(nominal) < 0.0 ? Eigen::Vector2d(-d) : d;
}

/// Where a fiber first crosses each plane u = planes[k] (sorted ascending), u = x0[axis]:
/// `out[k]` is the centroid there, or stays NaN when the fiber does not reach the plane.
void cut_fiber(const Model& model, const VecX& q, const Fiber& f, int axis, const std::vector<double>& planes,
               std::vector<Vec3>& out) {
  out.assign(planes.size(), Vec3::Constant(kNaN));
  std::vector<double> first_eta(planes.size(), kNaN);
  for (Index e = 0; e < f.num_elements; ++e) {
    const Curve cu = element_curve(model, q, f.first_element + e);
    const double a = cu.c2[axis], b = cu.c1[axis], c = cu.c0[axis];
    double umin = std::min(c - b + a, c + b + a), umax = std::max(c - b + a, c + b + a);
    if (a != 0.0) {
      const double t = -b / (2.0 * a);
      if (t > -1.0 && t < 1.0) {
        umin = std::min(umin, cu.at(t)[axis]);
        umax = std::max(umax, cu.at(t)[axis]);
      }
    }
    const double tol = 1e-12 * (std::abs(umin) + std::abs(umax) + 1e-300);
    auto it = std::lower_bound(planes.begin(), planes.end(), umin - tol);
    for (; it != planes.end() && *it <= umax + tol; ++it) {
      const size_t k = static_cast<size_t>(it - planes.begin());
      if (!std::isnan(out[k].x())) continue;
      double r[2];
      const int n = roots_in_element(a, b, c - *it, r);
      if (n == 0) continue;
      out[k] = cu.at(r[0]);
    }
  }
}

double fiber_radius(const Model& model, const Fiber& f) {
  const Section& s = model.sections[f.section];
  return std::sqrt(s.a * s.b);
}

double mean_finite(const std::vector<double>& v) {
  double s = 0.0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x)) {
      s += x;
      ++n;
    }
  return n > 0 ? s / n : kNaN;
}

/// Plane half-way between the two middle values of sorted `axes` (the single value when there
/// is one, 0 when none).
double middle_gap(const std::vector<double>& axes) {
  const size_t m = axes.size();
  if (m == 0) return 0.0;
  if (m == 1) return axes[0];
  const size_t k = (m - 2) / 2;
  return 0.5 * (axes[k] + axes[k + 1]);
}

/// The fibers cut by one plane, gathered for section_geometry: centres (across, z), their
/// section areas and radii.
struct SectionCut {
  std::vector<Eigen::Vector2d> centres;
  double area = 0.0, radius_sum = 0.0;
  void add(const Eigen::Vector2d& centre, const Section& sec) {
    centres.push_back(centre);
    area += std::numbers::pi * sec.a * sec.b;
    radius_sum += std::sqrt(sec.a * sec.b);
  }
};

}  // namespace

TowSectionReport section_geometry(const std::vector<Eigen::Vector2d>& centres, double radius, double fiber_area) {
  TowSectionReport s;
  s.fibers = static_cast<int>(centres.size());
  if (centres.empty()) {
    s.width = s.thickness = s.area = s.volume_fraction = s.center_z = s.tilt = kNaN;
    return s;
  }
  Eigen::Vector2d lo = centres[0], hi = centres[0], mean = Eigen::Vector2d::Zero();
  for (const auto& p : centres) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    mean += p / static_cast<double>(centres.size());
  }
  s.width = hi.x() - lo.x() + 2.0 * radius;
  s.thickness = hi.y() - lo.y() + 2.0 * radius;
  s.center_z = mean.y();
  // Principal axis of the centres' second moments about their mean.
  double cuu = 0.0, czz = 0.0, cuz = 0.0;
  for (const auto& p : centres) {
    const Eigen::Vector2d d = p - mean;
    cuu += d.x() * d.x();
    czz += d.y() * d.y();
    cuz += d.x() * d.y();
  }
  s.tilt = centres.size() < 2 ? kNaN : 0.5 * std::atan2(2.0 * cuz, cuu - czz);
  // Convex hull (Andrew's monotone chain, collinear points dropped).
  std::vector<Eigen::Vector2d> p = centres;
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return u.x() < v.x() || (u.x() == v.x() && u.y() < v.y());
  });
  p.erase(std::unique(p.begin(), p.end()), p.end());
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> hull;
  if (p.size() < 3) {
    hull = p;
  } else {
    hull.resize(2 * p.size());
    size_t k = 0;
    for (size_t i = 0; i < p.size(); ++i) {
      while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0) --k;
      hull[k++] = p[i];
    }
    for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
      while (k >= t && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0) --k;
      hull[k++] = p[i];
    }
    hull.resize(k - 1);
  }
  double area = 0.0, perimeter = 0.0;
  for (size_t i = 0; i < hull.size() && hull.size() > 1; ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d& b = hull[(i + 1) % hull.size()];
    area += 0.5 * (a.x() * b.y() - b.x() * a.y());
    perimeter += (b - a).norm();
  }
  s.area = std::abs(area) + perimeter * radius + std::numbers::pi * radius * radius;
  s.volume_fraction = fiber_area / s.area;
  return s;
}

namespace {
/// section_geometry of a gathered cut (the mean radius of its fibers), at `position`.
TowSectionReport cut_report(const SectionCut& cut, double position) {
  const size_t n = cut.centres.size();
  TowSectionReport s = section_geometry(cut.centres, n == 0 ? 0.0 : cut.radius_sum / n, cut.area);
  s.position = position;
  return s;
}
}  // namespace

TowSectionReport tow_section(const Model& model, const VecX& q, const TowSpec& tow, double position) {
  const int axis = tow.direction == TowSpec::Direction::Warp ? 0 : 1, across = 1 - axis;
  const std::vector<double> plane{position};
  std::vector<Vec3> cut;
  SectionCut section;
  for (const std::string& name : tow.fibers) {
    const int fi = model.fiber_index(name);
    if (fi < 0) continue;
    const Fiber& f = model.fibers[fi];
    cut_fiber(model, q, f, axis, plane, cut);
    if (!std::isnan(cut[0].x())) section.add({cut[0][across], cut[0].z()}, model.sections[f.section]);
  }
  return cut_report(section, position);
}

FabricReport fabric_report(const Case& c, const Model& model, const VecX& q,
                           const std::vector<ContactElement>* contacts,
                           const std::vector<ContactResponse>* responses) {
  FabricReport r;
  std::unordered_map<std::string, int> fiber_of;
  fiber_of.reserve(model.fibers.size());
  for (size_t i = 0; i < model.fibers.size(); ++i) fiber_of.emplace(model.fibers[i].name, static_cast<int>(i));

  // Tows: their fibers, axis (0: x for warp, 1: y for weft), the position of their axis
  // across (mean over their nodes) now and in the reference state, and their mean line in the
  // fabric plane now (crimp is measured along it).
  struct Tow {
    std::vector<int> fibers;
    int axis = 0;
    double across = 0, across_ref = 0;
    Eigen::Vector2d centre, direction;
  };
  std::vector<Tow> tows(c.tows.size());
  std::vector<double> axes[2], axes_ref[2];  // [0]: warp axes (y), [1]: weft axes (x)
  for (size_t t = 0; t < c.tows.size(); ++t) {
    Tow& tw = tows[t];
    const bool warp = c.tows[t].direction == TowSpec::Direction::Warp;
    tw.axis = warp ? 0 : 1;
    const int across = 1 - tw.axis;
    double sum = 0.0, sum_ref = 0.0;
    Index nodes = 0;
    for (const std::string& name : c.tows[t].fibers) {
      const auto it = fiber_of.find(name);
      if (it == fiber_of.end()) continue;
      tw.fibers.push_back(it->second);
      const Fiber& f = model.fibers[it->second];
      for (Index k = 0; k < f.num_nodes; ++k) {
        sum += q[9 * (f.first_node + k) + across];
        sum_ref += model.reference[9 * (f.first_node + k) + across];
      }
      nodes += f.num_nodes;
    }
    // The mean line: through the mean of the nodes, along the mean of the fibers' own directions.
    // Each fiber's nodes give its direction, so that the ends of a tow cut obliquely (a sheared
    // tow, its fibers' ends on the turned edge) do not tilt the line as the whole cloud's
    // second moments would.
    const Eigen::Vector2d nominal = warp ? Eigen::Vector2d::UnitX() : Eigen::Vector2d::UnitY();
    Eigen::Vector2d centre = Eigen::Vector2d::Zero(), direction = Eigen::Vector2d::Zero();
    std::vector<Eigen::Vector2d> points;
    for (int fi : tw.fibers) {
      const Fiber& f = model.fibers[fi];
      points.clear();
      for (Index k = 0; k < f.num_nodes; ++k) points.push_back(q.segment<2>(9 * (f.first_node + k)));
      for (const auto& p : points) centre += p;
      direction += principal_direction(points, nominal);
    }
    tw.centre = nodes > 0 ? Eigen::Vector2d(centre / static_cast<double>(nodes)) : Eigen::Vector2d::Constant(kNaN);
    tw.direction = direction.norm() > 0.0 ? Eigen::Vector2d(direction.normalized()) : nominal;
    tw.across = nodes > 0 ? sum / static_cast<double>(nodes) : kNaN;
    tw.across_ref = nodes > 0 ? sum_ref / static_cast<double>(nodes) : kNaN;
    if (nodes > 0) {
      axes[warp ? 0 : 1].push_back(tw.across);
      axes_ref[warp ? 0 : 1].push_back(tw.across_ref);
    }
  }
  for (auto* v : {&axes[0], &axes[1], &axes_ref[0], &axes_ref[1]}) std::sort(v->begin(), v->end());
  const std::vector<double>& warp_axes = axes[0];  // y positions
  const std::vector<double>& weft_axes = axes[1];  // x positions
  r.x_min = weft_axes.empty() ? kNaN : weft_axes.front();
  r.x_max = weft_axes.empty() ? kNaN : weft_axes.back();
  r.y_min = warp_axes.empty() ? kNaN : warp_axes.front();
  r.y_max = warp_axes.empty() ? kNaN : warp_axes.back();
  r.section_x = middle_gap(weft_axes);
  r.section_y = middle_gap(warp_axes);

  double zlo = std::numeric_limits<double>::infinity(), zhi = -zlo;
  std::vector<double> warp_crimps, weft_crimps, fractions;
  std::vector<Vec3> cut;
  for (size_t t = 0; t < c.tows.size(); ++t) {
    const Tow& tw = tows[t];
    TowReport tr;
    tr.name = c.tows[t].name;
    tr.direction = c.tows[t].direction;
    tr.index = c.tows[t].index;
    tr.axis = tw.across;
    const std::vector<double>& crossings = tw.axis == 0 ? weft_axes : warp_axes;
    const int m = static_cast<int>(crossings.size());
    tr.crossings = m;
    tr.start = m > 0 ? crossings.front() : kNaN;
    tr.end = m > 0 ? crossings.back() : kNaN;
    tr.crimp = tr.z_amplitude = kNaN;
    const int across = 1 - tw.axis;

    // The fabric's thickness over the woven range [start, end].
    if (m >= 2 && tr.end > tr.start)
      for (int fi : tw.fibers) {
        const Fiber& f = model.fibers[fi];
        const double rad = fiber_radius(model, f);
        for (Index e = 0; e < f.num_elements; ++e) {
          const Curve cu = element_curve(model, q, f.first_element + e);
          for_parts_in_range(coordinate(cu, tw.axis), tr.start, tr.end, [&](double t0, double t1) {
            double a = std::numeric_limits<double>::infinity(), b = -a;
            extremes(coordinate(cu, 2), t0, t1, a, b);
            zlo = std::min(zlo, a - rad);
            zhi = std::max(zhi, b + rad);
          });
        }
      }

    // Crimp, along the tow's own mean line: s = (x - centre) . direction. The crossings are where
    // that line meets the mean lines of the tows of the other direction; each fiber is measured
    // between the first and the last, its arc length over the length of its projection on the
    // line (never shorter than the projection: the crimp is >= 0, and 0 for a straight fiber
    // whatever its direction).
    tr.angle = std::isnan(tw.centre.x()) ? kNaN
                                         : std::atan2(tw.axis == 0 ? tw.direction.y() : -tw.direction.x(),
                                                      tw.axis == 0 ? tw.direction.x() : tw.direction.y());
    std::vector<double> along;
    for (const Tow& other : tows) {
      if (other.axis == tw.axis || std::isnan(other.centre.x()) || std::isnan(tw.centre.x())) continue;
      const auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); };
      const double sine = cross(tw.direction, other.direction);
      if (std::abs(sine) < 1e-9) continue;  // parallel lines do not cross
      along.push_back(cross(other.centre - tw.centre, other.direction) / sine);
    }
    if (along.size() >= 2) {
      const auto [first, last] = std::minmax_element(along.begin(), along.end());
      const Vec3 origin(tw.centre.x(), tw.centre.y(), 0.0), d(tw.direction.x(), tw.direction.y(), 0.0);
      std::vector<double> crimps;
      for (int fi : tw.fibers) {
        const Fiber& f = model.fibers[fi];
        double arc = 0.0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (Index e = 0; e < f.num_elements; ++e) {
          const Curve cu = element_curve(model, q, f.first_element + e);
          const Quadratic u = coordinate(cu, origin, d);
          for_parts_in_range(u, *first, *last, [&](double t0, double t1) {
            arc += arc_length(cu, t0, t1);
            extremes(u, t0, t1, lo, hi);
          });
        }
        // arc >= hi - lo exactly; the max takes out round-off on a straight fiber.
        if (hi > lo) crimps.push_back(std::max(0.0, arc / (hi - lo) - 1.0));
      }
      tr.crimp = mean_finite(crimps);
    }

    // Planes: samples of the mean centre z over the woven range (16 per crossing interval),
    // the mid-section and the crossing section.
    std::vector<double> planes;
    const int per_interval = 16;
    if (m >= 2)
      for (int i = 0; i + 1 < m; ++i)
        for (int s = 0; s < per_interval; ++s)
          planes.push_back(crossings[i] + (crossings[i + 1] - crossings[i]) * s / per_interval);
    if (m >= 1) planes.push_back(crossings.back());
    const double mid_at = m >= 2 ? middle_gap(crossings) : kNaN;
    const double cross_at = m >= 1 ? crossings[m / 2] : kNaN;
    const size_t samples = planes.size();
    if (m >= 2) planes.push_back(mid_at);
    if (m >= 1) planes.push_back(cross_at);
    std::vector<size_t> order(planes.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return planes[a] < planes[b]; });
    std::vector<double> sorted(planes.size());
    for (size_t k = 0; k < order.size(); ++k) sorted[k] = planes[order[k]];

    std::vector<double> zsum(samples, 0.0);
    std::vector<int> zcount(samples, 0);
    SectionCut mid, crossing;
    for (int fi : tw.fibers) {
      const Fiber& f = model.fibers[fi];
      cut_fiber(model, q, f, tw.axis, sorted, cut);
      const Section& sec = model.sections[f.section];
      for (size_t k = 0; k < sorted.size(); ++k) {
        const Vec3& x = cut[k];
        if (std::isnan(x.x())) continue;
        const size_t which = order[k];
        const Eigen::Vector2d centre(x[across], x.z());
        if (which < samples) {
          zsum[which] += x.z();
          ++zcount[which];
        } else {
          (m >= 2 && which == samples ? mid : crossing).add(centre, sec);
        }
      }
    }
    if (m >= 2) {
      double a = std::numeric_limits<double>::infinity(), b = -a;
      for (size_t k = 0; k < samples; ++k)
        if (zcount[k] > 0) {
          a = std::min(a, zsum[k] / zcount[k]);
          b = std::max(b, zsum[k] / zcount[k]);
        }
      tr.z_amplitude = b >= a ? b - a : kNaN;
    }
    tr.mid = cut_report(mid, mid_at);
    tr.crossing = cut_report(crossing, cross_at);
    fractions.push_back(tr.mid.volume_fraction);
    fractions.push_back(tr.crossing.volume_fraction);
    (tr.direction == TowSpec::Direction::Warp ? warp_crimps : weft_crimps).push_back(tr.crimp);
    r.tows.push_back(std::move(tr));
  }
  r.warp_crimp = mean_finite(warp_crimps);
  r.weft_crimp = mean_finite(weft_crimps);
  r.thickness = zhi >= zlo ? zhi - zlo : kNaN;
  r.volume_fraction = mean_finite(fractions);

  // Shrinkage: the edge bodies when the generator made them, else the outer tow axes.
  auto shrinkage = [&](const char* minus, const char* plus, int axis, const std::vector<double>& now,
                       const std::vector<double>& ref) {
    const int bm = model.body_index(minus), bp = model.body_index(plus);
    if (bm >= 0 && bp >= 0) {
      const double l0 = model.bodies[bp].center[axis] - model.bodies[bm].center[axis];
      const double l = q[model.bodies[bp].first_dof + axis] - q[model.bodies[bm].first_dof + axis];
      if (l0 != 0.0) return 1.0 - l / l0;
    }
    if (now.size() < 2 || ref.back() == ref.front()) return kNaN;
    return 1.0 - (now.back() - now.front()) / (ref.back() - ref.front());
  };
  r.shrinkage_x = shrinkage("edge.x-", "edge.x+", 0, weft_axes, axes_ref[1]);
  r.shrinkage_y = shrinkage("edge.y-", "edge.y+", 1, warp_axes, axes_ref[0]);

  // Remaining penetration: the geometric gap of each contact element (the weave offset,
  // which hides penetration from the law, taken out).
  r.has_penetration = contacts != nullptr && responses != nullptr;
  r.max_penetration = r.max_penetration_ratio = r.has_penetration ? 0.0 : kNaN;
  if (r.has_penetration) {
    const size_t n = std::min(contacts->size(), responses->size());
    for (size_t k = 0; k < n; ++k) {
      const ContactElement& ce = (*contacts)[k];
      const double pen = -((*responses)[k].gap - ce.offset);
      if (!(pen > 0.0)) continue;
      const Section& sa = model.sections[model.fibers[model.elements[ce.a.element].fiber].section];
      const Section& sb = model.sections[model.fibers[model.elements[ce.b.element].fiber].section];
      const double rmin = std::min({sa.a, sa.b, sb.a, sb.b});
      r.max_penetration = std::max(r.max_penetration, pen);
      r.max_penetration_ratio = std::max(r.max_penetration_ratio, pen / rmin);
    }
  }
  return r;
}

nlohmann::json to_json(const FabricReport& r) {
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  auto section = [&](const TowSectionReport& s) {
    return nlohmann::json{{"position", num(s.position)}, {"fibers", s.fibers},
                          {"width", num(s.width)},       {"thickness", num(s.thickness)},
                          {"area", num(s.area)},         {"volume_fraction", num(s.volume_fraction)},
                          {"center_z", num(s.center_z)}, {"tilt", num(s.tilt)}};
  };
  nlohmann::json tows = nlohmann::json::array();
  for (const TowReport& t : r.tows)
    tows.push_back({{"name", t.name},
                    {"direction", t.direction == TowSpec::Direction::Warp ? "warp" : "weft"},
                    {"index", t.index},
                    {"axis", num(t.axis)},
                    {"crossings", t.crossings},
                    {"woven_range", {num(t.start), num(t.end)}},
                    {"crimp", num(t.crimp)},
                    {"angle", num(t.angle)},
                    {"z_amplitude", num(t.z_amplitude)},
                    {"mid_section", section(t.mid)},
                    {"crossing_section", section(t.crossing)}});
  return {{"warp_crimp", num(r.warp_crimp)},
          {"weft_crimp", num(r.weft_crimp)},
          {"thickness", num(r.thickness)},
          {"shrinkage_x", num(r.shrinkage_x)},
          {"shrinkage_y", num(r.shrinkage_y)},
          {"max_penetration", num(r.max_penetration)},
          {"max_penetration_ratio", num(r.max_penetration_ratio)},
          {"volume_fraction", num(r.volume_fraction)},
          {"woven_region", {{"x", {num(r.x_min), num(r.x_max)}}, {"y", {num(r.y_min), num(r.y_max)}}}},
          {"section_x", num(r.section_x)},
          {"section_y", num(r.section_y)},
          {"tows", tows}};
}

}  // namespace fibra
