#include "fibra/export/tow_stations.hpp"

#include <algorithm>
#include <cmath>

#include "fibra/export/fiber_curve.hpp"

namespace fibra {

namespace {

/// A fiber's parameter t in [0, elements] at the fraction s of its length along its tow.
double fiber_parameter(const Fiber& fiber, double sign, double s) {
  const double n = static_cast<double>(fiber.num_elements);
  return sign > 0 ? s * n : (1.0 - s) * n;
}

/// The parameter near t0 where the fiber's centroid line meets the plane through c of unit
/// normal d: Newton on (x(t) - c) . d, kept within [0, elements] (at an end when the plane
/// lies beyond it).
double plane_crossing(const Model& model, const VecX& q, const Fiber& fiber, double t0, const Vec3& c, const Vec3& d) {
  const double end = static_cast<double>(fiber.num_elements);
  double t = t0;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const SectionPoint p = fiber_point(model, q, fiber, t);
    const double g = (p.x - c).dot(d), slope = 2.0 * p.dx.dot(d);  // dx/dt = 2 dx/deta
    if (std::abs(slope) < 1e-12 * p.dx.norm()) break;              // runs along the plane
    const double next = std::clamp(t - g / slope, 0.0, end);
    if (std::abs(next - t) < 1e-12 * std::max(1.0, end)) return next;
    t = next;
  }
  return t;
}

/// The in-plane vector u carried from the previous station (the smallest turn), or, at the
/// first station, across the tow and level: z x d (y x d for a tow along z).
Vec3 station_u(const Vec3& d, const Vec3* previous) {
  if (previous) {
    const Vec3 u = *previous - previous->dot(d) * d;
    if (u.norm() > 1e-6) return u.normalized();
  }
  const Vec3 across = Vec3::UnitZ().cross(d);
  return across.norm() > 0.1 ? Vec3(across.normalized()) : Vec3(Vec3::UnitY().cross(d).normalized());
}

/// The section of fiber point p carried along its unit tangent tau onto the plane (c, d),
/// in (u, w) coordinates about c.
PlaneEllipse carried_section(const SectionPoint& p, const Vec3& tau, double a, double b, const TowStation& st) {
  const Vec3& d = st.direction;
  const double cos_angle = tau.dot(d);
  // Oblique projection along the tangent: the cut of a locally straight fiber. Beyond 60
  // degrees it would stretch the section more than twice: project orthogonally instead.
  auto onto_plane = [&](const Vec3& v) -> Vec3 {
    return cos_angle >= 0.5 ? Vec3(v - tau * (v.dot(d) / cos_angle)) : Vec3(v - d * v.dot(d));
  };
  auto in_plane = [&](const Vec3& v) { return Eigen::Vector2d(v.dot(st.u), v.dot(st.w)); };
  PlaneEllipse e;
  e.center = in_plane(onto_plane(p.x - st.center));
  e.axis_a = in_plane(onto_plane(a * p.g1));
  e.axis_b = in_plane(onto_plane(b * p.g2));
  return e;
}

}  // namespace

int default_station_count(const Model& model, const std::vector<int>& fibers) {
  Index elements = 1;
  for (int f : fibers) elements = std::max(elements, model.fibers[f].num_elements);
  return static_cast<int>(2 * elements + 1);
}

std::vector<TowStation> tow_stations(const Model& model, const VecX& q, const TowFibers& tows, int tow, int count) {
  const std::vector<int>& fibers = tows.fibers[tow];
  std::vector<TowStation> stations(count);
  for (int k = 0; k < count; ++k) {
    const double s = static_cast<double>(k) / static_cast<double>(count - 1);
    TowStation& st = stations[k];
    Vec3 center = Vec3::Zero(), tangent = Vec3::Zero();
    for (int f : fibers) {
      const SectionPoint p = fiber_point(model, q, model.fibers[f], fiber_parameter(model.fibers[f], tows.sign[f], s));
      center += p.x;
      tangent += tows.sign[f] * p.dx.normalized();
    }
    st.center = center / static_cast<double>(fibers.size());
    st.direction = tangent.norm() > 0 ? Vec3(tangent.normalized()) : tows.direction[tow];
    st.u = station_u(st.direction, k > 0 ? &stations[k - 1].u : nullptr);
    st.w = st.direction.cross(st.u);
    for (int f : fibers) {
      const Fiber& fiber = model.fibers[f];
      Index element = 0;
      const double t =
          plane_crossing(model, q, fiber, fiber_parameter(fiber, tows.sign[f], s), st.center, st.direction);
      const SectionPoint p = fiber_point(model, q, fiber, t, &element);
      const Section& section = model.sections[model.elements[element].section];
      st.cuts.push_back(carried_section(p, tows.sign[f] * p.dx.normalized(), section.a, section.b, st));
    }
  }
  return stations;
}

}  // namespace fibra
