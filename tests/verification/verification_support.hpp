#pragma once
/// Helpers of the verification tests: solve a case written as TOML text with the library's
/// own StaticSolver (no output files), read nodal values, and the reference solutions shared
/// by several tests (the elastica of a cantilever under a dead tip load).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <fmt/format.h>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/resolve.hpp"
#include "fibra/solver/static_solver.hpp"

namespace fibra::test {

inline constexpr double kPi = std::numbers::pi;

/// A solved case: the case, its model, the outcome, and the state at the end of every step.
struct Solved {
  Case c;
  Model model;
  RunResult result;
  SolverStats stats;
  VecX q;                                  ///< final state
  std::vector<VecX> step_end_states;       ///< state at the end of each completed step
  std::vector<IncrementInfo> step_end_info;  ///< increment info at the end of each step
  std::vector<IncrementInfo> increments;   ///< every converged increment

  bool converged() const { return result.status == RunResult::Status::Converged; }

  /// Global index of local node `local` of fiber `fiber` (negative: from the end, -1 = last).
  Index node(Index local, int fiber = 0) const {
    const Fiber& f = model.fibers.at(fiber);
    return f.first_node + (local < 0 ? f.num_nodes + local : local);
  }
  Vec3 x0(Index local, int fiber = 0) const { return q.segment<3>(9 * node(local, fiber)); }
  Vec3 g1(Index local, int fiber = 0) const { return q.segment<3>(9 * node(local, fiber) + 3); }
  Vec3 g2(Index local, int fiber = 0) const { return q.segment<3>(9 * node(local, fiber) + 6); }
  Vec3 ref_x0(Index local, int fiber = 0) const { return model.reference.segment<3>(9 * node(local, fiber)); }
  Vec3 ref_g1(Index local, int fiber = 0) const { return model.reference.segment<3>(9 * node(local, fiber) + 3); }
  Vec3 ref_g2(Index local, int fiber = 0) const { return model.reference.segment<3>(9 * node(local, fiber) + 6); }
  /// Displacement of the centroid of a node.
  Vec3 u(Index local, int fiber = 0) const { return x0(local, fiber) - ref_x0(local, fiber); }
};

/// Parses `toml`, lets `edit` change the case (the solver's method rules, which case files do
/// not set), and solves it with StaticSolver (no output files).
inline Solved solve_toml(const std::string& toml, const std::string& label = "verification.toml",
                         const std::function<void(Case&)>& edit = {}) {
  Solved s;
  s.c = parse_case_toml(toml, label);
  if (edit) edit(s.c);
  ResolvedCase r = resolve_case(s.c);
  s.model = r.model;
  StaticSolver solver(s.c, r.model, std::move(r.bodies));
  s.result = solver.run([&](const IncrementInfo& info, const VecX& q) {
    s.increments.push_back(info);
    if (info.step_end) {
      s.step_end_states.push_back(q);
      s.step_end_info.push_back(info);
    }
  });
  s.stats = solver.stats();
  s.q = solver.state();
  return s;
}

/// The TOML text of one isotropic straight fiber along +x from the origin, clamped at node 0
/// (for the cantilever tests); `extra` is appended (steps, loads, solver settings).
inline std::string straight_cantilever(double length, double radius, int elements, double young, double poisson,
                                       const std::string& extra) {
  return fmt::format(R"(
[[material]]
name = "m"
young = {:.17g}
poisson = {:.17g}

[[fiber]]
name = "beam"
material = "m"
radius = {:.17g}
section_direction = [0, 1, 0]
points = [[0, 0, 0], [{:.17g}, 0, 0]]
elements = {}

[[fix]]
fiber = "beam"
node = "first"
dofs = "all"
{}
)",
                     young, poisson, radius, length, elements, extra);
}

/// Elastica of a clamped-free beam of length 1 under a dead tip load normal to it:
/// theta'' = -alpha cos(theta), theta(0) = 0, theta'(1) = 0, alpha = P L^2 / (E I); theta is
/// the angle of the tangent from the undeformed axis towards the load. Solved by shooting on
/// theta'(0) with classical RK4 (n steps; the error is O(n^-4), ~1e-13 for n = 4000).
struct Elastica {
  double tip_angle = 0;    ///< theta(1) [rad]
  double deflection = 0;   ///< tip deflection along the load / L
  double shortening = 0;   ///< 1 - (tip position along the undeformed axis) / L
  double root_curvature = 0;  ///< theta'(0) L
};

inline Elastica elastica_rk4(double alpha, int n = 4000) {
  // state: theta, theta', x, y
  auto integrate = [&](double k0, Elastica* out) {
    double th = 0, dth = k0, x = 0, y = 0;
    const double h = 1.0 / n;
    auto f = [&](double t, double dt, double r[4]) {
      r[0] = dt;
      r[1] = -alpha * std::cos(t);
      r[2] = std::cos(t);
      r[3] = std::sin(t);
    };
    for (int i = 0; i < n; ++i) {
      double k1[4], k2[4], k3[4], k4[4];
      f(th, dth, k1);
      f(th + 0.5 * h * k1[0], dth + 0.5 * h * k1[1], k2);
      f(th + 0.5 * h * k2[0], dth + 0.5 * h * k2[1], k3);
      f(th + h * k3[0], dth + h * k3[1], k4);
      th += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
      dth += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
      x += h / 6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2]);
      y += h / 6 * (k1[3] + 2 * k2[3] + 2 * k3[3] + k4[3]);
    }
    if (out) {
      out->tip_angle = th;
      out->deflection = y;
      out->shortening = 1.0 - x;
      out->root_curvature = k0;
    }
    return dth;  // theta'(1), to be zero
  };
  // theta'(1) as a function of theta'(0): bracket the root in (0, alpha] (the root curvature
  // is P x_tip / EI <= alpha) and bisect, then polish with secants.
  double lo = 0.0, hi = alpha;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * alpha; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (integrate(mid, nullptr) < 0) lo = mid; else hi = mid;
  }
  Elastica e;
  integrate(0.5 * (lo + hi), &e);
  return e;
}

/// The same elastica in closed form (Bisshopp & Drucker 1945) with Legendre elliptic integrals:
/// k^2 = (1 + sin theta0) / 2, sin phi1 = 1 / (sqrt(2) k), sqrt(alpha) = K(k) - F(phi1, k),
/// deflection = 1 - 2 (E(k) - E(phi1, k)) / sqrt(alpha), 1 - shortening = sqrt(2 sin theta0 / alpha).
inline Elastica elastica_elliptic(double alpha) {
  auto residual = [&](double th0) {
    const double k = std::sqrt(0.5 * (1.0 + std::sin(th0)));
    const double phi1 = std::asin(1.0 / (std::sqrt(2.0) * k));
    return std::comp_ellint_1(k) - std::ellint_1(k, phi1) - std::sqrt(alpha);
  };
  double lo = 1e-12, hi = 0.5 * kPi - 1e-12;  // residual increases with theta0
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (residual(mid) < 0) lo = mid; else hi = mid;
  }
  const double th0 = 0.5 * (lo + hi);
  const double k = std::sqrt(0.5 * (1.0 + std::sin(th0)));
  const double phi1 = std::asin(1.0 / (std::sqrt(2.0) * k));
  Elastica e;
  e.tip_angle = th0;
  e.deflection = 1.0 - 2.0 * (std::comp_ellint_2(k) - std::ellint_2(k, phi1)) / std::sqrt(alpha);
  e.shortening = 1.0 - std::sqrt(2.0 * std::sin(th0) / alpha);
  e.root_curvature = std::sqrt(2.0 * alpha * std::sin(th0));
  return e;
}

}  // namespace fibra::test
