#include "fibra/model/fiber_path.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace fibra {
namespace {

// Orthonormal (u, v) completing the unit axis n to a right-handed frame.
void plane_basis(const Vec3& n, Vec3& u, Vec3& v) {
  Vec3 trial = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  u = (trial - trial.dot(n) * n).normalized();
  v = n.cross(u);
}

double helix_rise(const PathSpec& p) { return p.pitch / (2.0 * std::numbers::pi); }

}  // namespace

double path_length(const PathSpec& p) {
  switch (p.kind) {
    case PathSpec::Kind::Polyline: {
      double len = 0;
      for (size_t i = 1; i < p.points.size(); ++i) len += (p.points[i] - p.points[i - 1]).norm();
      return len;
    }
    case PathSpec::Kind::Arc:
      return std::abs(p.angle) * p.radius;
    case PathSpec::Kind::Helix:
      return 2.0 * std::numbers::pi * p.turns * std::hypot(p.radius, helix_rise(p));
  }
  return 0;
}

void path_point(const PathSpec& p, double s, Vec3& x, Vec3& t) {
  switch (p.kind) {
    case PathSpec::Kind::Polyline: {
      double acc = 0;
      for (size_t i = 1; i < p.points.size(); ++i) {
        const Vec3 d = p.points[i] - p.points[i - 1];
        const double len = d.norm();
        if (s <= acc + len || i + 1 == p.points.size()) {
          const double u = std::clamp((s - acc) / len, 0.0, 1.0);
          x = p.points[i - 1] + u * d;
          t = d / len;
          return;
        }
        acc += len;
      }
      return;
    }
    case PathSpec::Kind::Arc: {
      Vec3 u, v;
      plane_basis(p.axis, u, v);
      const double sign = p.angle >= 0 ? 1.0 : -1.0;
      const double phi = p.start_angle + sign * s / p.radius;
      x = p.center + p.radius * (std::cos(phi) * u + std::sin(phi) * v);
      t = sign * (-std::sin(phi) * u + std::cos(phi) * v);
      return;
    }
    case PathSpec::Kind::Helix: {
      Vec3 u, v;
      plane_basis(p.axis, u, v);
      const double c = helix_rise(p);
      const double speed = std::hypot(p.radius, c);
      const double turn = s / speed;  // angle turned from the start
      const double phi = p.start_angle + turn;
      x = p.center + p.radius * (std::cos(phi) * u + std::sin(phi) * v) + c * turn * p.axis;
      t = (p.radius * (-std::sin(phi) * u + std::cos(phi) * v) + c * p.axis) / speed;
      return;
    }
  }
}

std::vector<PathFrame> sample_path(const PathSpec& p, int count, const std::optional<Vec3>& direction) {
  const double len = path_length(p);
  std::vector<PathFrame> frames(count);
  for (int k = 0; k < count; ++k) {
    const double s = count > 1 ? len * k / (count - 1) : 0.0;
    path_point(p, s, frames[k].position, frames[k].tangent);
  }
  // Polyline vertices that fall on a node: use the mean of the adjacent segment tangents.
  if (p.kind == PathSpec::Kind::Polyline && p.points.size() > 2) {
    for (int k = 1; k + 1 < count; ++k) {
      Vec3 xa, ta, xb, tb;
      const double s = len * k / (count - 1), eps = 1e-9 * len;
      path_point(p, s - eps, xa, ta);
      path_point(p, s + eps, xb, tb);
      if ((ta - tb).norm() > 1e-12) frames[k].tangent = (ta + tb).normalized();
    }
  }
  const Vec3& t0 = frames[0].tangent;
  Vec3 g1;
  if (direction && (*direction - direction->dot(t0) * t0).norm() > 1e-8 * direction->norm()) {
    g1 = (*direction - direction->dot(t0) * t0).normalized();
  } else {
    Vec3 u, v;
    plane_basis(t0, u, v);
    // Prefer a world axis for readability: the one most orthogonal to t0.
    Eigen::Index best;
    t0.cwiseAbs().minCoeff(&best);
    Vec3 e = Vec3::Zero();
    e[best] = 1.0;
    g1 = (e - e.dot(t0) * t0).normalized();
  }
  for (int k = 0; k < count; ++k) {
    if (k > 0) {
      const Eigen::Quaterniond r = Eigen::Quaterniond::FromTwoVectors(frames[k - 1].tangent, frames[k].tangent);
      g1 = r * g1;
      g1 = (g1 - g1.dot(frames[k].tangent) * frames[k].tangent).normalized();
    }
    frames[k].g1 = g1;
    frames[k].g2 = frames[k].tangent.cross(g1);
  }
  return frames;
}

}  // namespace fibra
