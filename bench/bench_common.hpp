#pragma once
/// Shared set-up of the benchmarks: a bundle of straight parallel fibers on a hexagonal grid
/// (built as a Case, meshed by build_model) and a smooth deformed state near the reference.
#include <Eigen/Geometry>
#include <omp.h>

#include <algorithm>
#include <memory>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/problem.hpp"

namespace fibra::bench {

/// Glass-like isotropic material (E = 72 GPa, nu = 0.22).
inline MaterialSpec glass() {
  MaterialSpec m;
  m.name = "glass";
  m.model = MaterialSpec::Model::Isotropic;
  m.young = 72e9;
  m.poisson = 0.22;
  return m;
}

/// The `count` points of a hexagonal lattice of spacing `pitch` nearest to the origin
/// (a roughly circular bundle cross-section), in a deterministic order.
inline std::vector<Eigen::Vector2d> hexagonal_points(int count, double pitch) {
  struct P {
    Eigen::Vector2d x;
    double r2;
    int i, j;
  };
  std::vector<P> pts;
  const int n = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count)))) + 2;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      const Eigen::Vector2d x(pitch * (i + 0.5 * j), pitch * (0.5 * std::sqrt(3.0) * j));
      pts.push_back({x, x.squaredNorm(), i, j});
    }
  std::stable_sort(pts.begin(), pts.end(), [](const P& a, const P& b) {
    if (a.r2 != b.r2) return a.r2 < b.r2;
    return a.j != b.j ? a.j < b.j : a.i < b.i;
  });
  pts.resize(static_cast<size_t>(count));
  // Order fibers row by row so neighbouring fibers have neighbouring indices.
  std::sort(pts.begin(), pts.end(), [](const P& a, const P& b) { return a.j != b.j ? a.j < b.j : a.i < b.i; });
  std::vector<Eigen::Vector2d> out;
  for (const P& p : pts) out.push_back(p.x);
  return out;
}

/// A bundle of `fibers` straight parallel fibers along z, each of `elements` quadratic
/// elements, radius `radius`, length `length`, on a hexagonal grid of pitch `pitch` radii
/// (2.5: no contact; 2 or slightly less: touching). The first node of every fiber is clamped.
inline Case bundle_case(int fibers, int elements, double radius = 1e-5, double length = 0.01,
                        double pitch = 2.5) {
  Case c;
  c.name = "bench_bundle";
  c.file = "<bench>";
  c.materials.push_back(glass());
  const std::vector<Eigen::Vector2d> xy = hexagonal_points(fibers, pitch * radius);
  for (int f = 0; f < fibers; ++f) {
    FiberSpec s;
    s.name = std::string("f").append(std::to_string(f));
    s.material = "glass";
    s.radius = radius;
    s.path.kind = PathSpec::Kind::Polyline;
    s.path.points = {Vec3(xy[f].x(), xy[f].y(), 0.0), Vec3(xy[f].x(), xy[f].y(), length)};
    s.elements = elements;
    c.fibers.push_back(s);
    FixSpec fix;
    fix.node.fiber = s.name;
    fix.node.kind = NodeRef::Kind::First;
    c.fixes.push_back(fix);
  }
  return c;
}

/// Amplitudes of the smooth deformation applied by deformed_state().
struct Deformation {
  double bending = 1e-3;  ///< lateral deflection / fiber length (two planes)
  double stretch = 1e-3;  ///< mean axial strain
  double twist = 1e-3;    ///< twist angle amplitude [rad]
};

/// A smooth deformation of the reference state, fiber by fiber: the centroid is displaced by
/// u(X) (bending in two planes, axial stretch with a smooth variation), the section vectors
/// are rotated with the tangent (no shear strain) and twisted about it, keeping their length.
/// The displacement field depends on the fiber's position, so no two fibers of a bundle are
/// identical. The defaults keep the tangent stiffness positive definite with the first node
/// of every fiber clamped: the section vectors keep their length under axial stretch, so the
/// section carries a small transverse tension; without it the in-section rotation (twist)
/// mode, resisted only by torsion, turns indefinite under the transverse stresses of bending.
inline VecX deformed_state(const Model& model, const Deformation& a = {}) {
  const double pi = std::numbers::pi;
  double len = model.length_scale;
  for (const Fiber& f : model.fibers) len = std::min(len, f.length);
  auto u = [&](const Vec3& x) -> Vec3 {
    const double s = x.z() / len;
    return Vec3(a.bending * len * std::sin(pi * s) * (1.0 + 0.2 * std::sin(50.0 * x.x() / len)),
                0.5 * a.bending * len * std::sin(2.0 * pi * s + 100.0 * x.y() / len),
                a.stretch * x.z() + 0.1 * a.stretch * len * std::sin(3.0 * pi * s) / (3.0 * pi));
  };
  VecX q = model.reference;
  for (Index k = 0; k < model.num_nodes(); ++k) {
    const Vec3 x = model.reference.segment<3>(9 * k);
    const Vec3 g1 = model.reference.segment<3>(9 * k + 3);
    const Vec3 g2 = model.reference.segment<3>(9 * k + 6);
    const Vec3 t0 = g1.cross(g2).normalized();
    // Deformed tangent: derivative of x + u(x) along the reference tangent.
    const double h = 1e-6 * len;
    const Vec3 t = t0 + (u(x + h * t0) - u(x - h * t0)) / (2.0 * h);
    const Eigen::Quaterniond bend = Eigen::Quaterniond::FromTwoVectors(t0, t);
    const Eigen::AngleAxisd twist(a.twist * std::sin(pi * x.z() / len), t.normalized());
    q.segment<3>(9 * k) = x + u(x);
    q.segment<3>(9 * k + 3) = twist * (bend * g1);
    q.segment<3>(9 * k + 6) = twist * (bend * g2);
  }
  return q;
}

/// Marks every dof of the first node of every fiber as fixed.
inline void fix_first_nodes(const Model& model, Problem& problem) {
  std::vector<char>& fixed = problem.fixed();
  std::fill(fixed.begin(), fixed.end(), 0);
  for (const Fiber& f : model.fibers)
    for (int d = 0; d < kNodeDofs; ++d) fixed[kNodeDofs * f.first_node + d] = 1;
}

/// Holds the first node of every fiber at its reference value in q.
inline void hold_fixed(const Model& model, const Problem& problem, VecX& q) {
  for (Index d = 0; d < q.size(); ++d)
    if (problem.fixed()[d]) q[d] = model.reference[d];
}

/// A bundle of straight fibers (bundle_case) meshed, its Problem with the first node of every
/// fiber clamped, the deformed state (deformed_state) and the gradient and Hessian there.
struct Bundle {
  Case spec;
  Model model;
  std::unique_ptr<Problem> problem;
  VecX q;                       ///< deformed state
  VecX gradient;                ///< gradient of the potential at q
  VecX residual;                ///< gradient with fixed dofs zeroed (Newton right-hand side, negated)
  std::vector<double> hessian;  ///< upper CSC values at q

  Bundle(int fibers, int elements) : spec(bundle_case(fibers, elements)), model(build_model(spec)) {
    problem = std::make_unique<Problem>(model);
    fix_first_nodes(model, *problem);
    q = deformed_state(model);
    hold_fixed(model, *problem, q);
    problem->evaluate(q, &gradient, &hessian);
    residual = gradient;
    for (Index d = 0; d < residual.size(); ++d)
      if (problem->fixed()[d]) residual[d] = 0.0;
  }
};

}  // namespace fibra::bench
