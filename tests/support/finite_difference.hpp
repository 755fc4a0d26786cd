#pragma once
/// One finite-difference harness for every energy term: central differences with step
/// h = cbrt(eps) * scale (truncation O(h^2) and round-off O(eps/h) balance there).
#include <Eigen/Core>
#include <cmath>
#include <limits>

namespace fibra::test {

/// Default relative step for central differences.
inline double fd_step(double scale) { return std::cbrt(std::numeric_limits<double>::epsilon()) * scale; }

/// Central-difference gradient of a scalar function f(x).
template <class F>
Eigen::VectorXd fd_gradient(F&& f, const Eigen::VectorXd& x, double h) {
  Eigen::VectorXd g(x.size());
  Eigen::VectorXd xp = x;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    xp[i] = x[i] + h;
    const double fp = f(xp);
    xp[i] = x[i] - h;
    const double fm = f(xp);
    xp[i] = x[i];
    g[i] = (fp - fm) / (2 * h);
  }
  return g;
}

/// Central-difference Jacobian of a vector function g(x) (the Hessian when g is a gradient).
template <class G>
Eigen::MatrixXd fd_jacobian(G&& g, const Eigen::VectorXd& x, double h) {
  const Eigen::VectorXd g0 = g(x);
  Eigen::MatrixXd j(g0.size(), x.size());
  Eigen::VectorXd xp = x;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    xp[i] = x[i] + h;
    const Eigen::VectorXd gp = g(xp);
    xp[i] = x[i] - h;
    const Eigen::VectorXd gm = g(xp);
    xp[i] = x[i];
    j.col(i) = (gp - gm) / (2 * h);
  }
  return j;
}

/// Relative error ||a - b|| / max(||b||, floor).
inline double rel_error(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double floor = 1e-300) {
  return (a - b).norm() / std::max(b.norm(), floor);
}

}  // namespace fibra::test
