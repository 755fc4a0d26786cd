#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include "verification/verification_support.hpp"
#include "fibra/solver/problem.hpp"
namespace fibra::test {
// dense symmetric matrix from upper CSC values
Eigen::MatrixXd dense(const Problem& p, const std::vector<double>& v) {
  const auto& pat = p.pattern();
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(pat.rows(), pat.rows());
  for (Index c = 0; c < pat.rows(); ++c)
    for (int k = pat.col_ptr()[c]; k < pat.col_ptr()[c + 1]; ++k) { m(pat.row_idx()[k], c) = v[k]; m(c, pat.row_idx()[k]) = v[k]; }
  return m;
}
TEST(Scratch, Rollup) {
  const double length = 1.0, radius = 0.01, young = 210e9;
  const double ei = young * kPi * std::pow(radius, 4) / 4.0;
  const double mh = kPi * ei / length;
  for (double lam : {0.1, 0.2, 0.3, 0.4, 0.42, 0.44}) {
    Solved s = solve_toml(straight_cantilever(length, radius, 20, young, 0.3, fmt::format(R"(
[[step]]
increments = 40
  [[step.load]]
  fiber = "beam"
  node = "last"
  moment = [0, {:.17g}, 0]
)", lam * mh)));
    ASSERT_TRUE(s.converged());
    Problem p(s.model);
    for (int d = 0; d < 9; ++d) p.fixed()[d] = 1;
    p.moments().push_back({s.node(-1), Vec3(0, lam * mh, 0)});
    VecX g; std::vector<double> h;
    p.evaluate(s.q, &g, &h);
    Eigen::MatrixXd H = dense(p, h).bottomRightCorner(s.q.size() - 9, s.q.size() - 9);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
    Vec3 g2 = s.g2(-1);
    std::printf("lam %.3f angle %.4f eig: %.3e %.3e %.3e %.3e  resid %.2e\n", lam, std::atan2(g2.x(), g2.z()), es.eigenvalues()[0], es.eigenvalues()[1], es.eigenvalues()[2], es.eigenvalues()[3], g.tail(g.size()-9).norm());
    Eigen::VectorXd v = es.eigenvectors().col(0);
    std::printf("  mode tip: x0 %.3f %.3f %.3f g1 %.3f %.3f %.3f g2 %.3f %.3f %.3f ; mid x0 y %.3f\n", v[v.size()-9], v[v.size()-8], v[v.size()-7], v[v.size()-6], v[v.size()-5], v[v.size()-4], v[v.size()-3], v[v.size()-2], v[v.size()-1], v[9*19+1]);
  }
}
}
