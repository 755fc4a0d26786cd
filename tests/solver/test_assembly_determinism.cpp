// Threaded assembly is deterministic: gradient and Hessian are bitwise identical for 1 and 2
// OpenMP threads (beams and contact pairs), because the schedule (partitions, then colours)
// does not depend on the thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include <random>

#include "fibra/contact/detection.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/problem.hpp"

namespace fibra {
namespace {

TEST(Assembly, SameBitsForOneAndTwoThreads) {
  Case c;
  c.file = "determinism";
  MaterialSpec m;
  m.name = "glass";
  m.young = 72e9;
  m.poisson = 0.22;
  c.materials.push_back(m);
  const double r = 1e-5;
  for (int f = 0; f < 40; ++f) {  // a 5 x 8 grid of touching parallel fibers
    FiberSpec s;
    s.name = "f" + std::to_string(f);
    s.material = "glass";
    s.radius = r;
    const double x = 1.999 * r * (f % 5), y = 1.999 * r * (f / 5);
    s.path.points = {Vec3(x, y, 0), Vec3(x, y, 2e-3)};
    s.elements = 20;
    c.fibers.push_back(s);
  }
  const Model model = build_model(c);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  VecX q = model.reference;
  for (Index i = 0; i < q.size(); ++i) q[i] += 1e-8 * u(rng);
  ContactDetector detector(model);
  Detection det = detector.detect(q);
  ASSERT_GT(det.elements.size(), 100u);
  for (ContactElement& e : det.elements) e.law = PenaltyLaw{1e4, 1e-7};
  Problem problem(model);
  problem.set_contacts(det.elements, FrictionParams{0.3, 1e-8});
  VecX g1, g2;
  std::vector<double> h1, h2;
  omp_set_num_threads(1);
  const double e1 = problem.evaluate(q, &g1, &h1);
  omp_set_num_threads(2);
  const double e2 = problem.evaluate(q, &g2, &h2);
  EXPECT_EQ(e1, e2);
  EXPECT_TRUE(g1 == g2);
  EXPECT_TRUE(h1 == h2);
}

}  // namespace
}  // namespace fibra

namespace fibra {
namespace {

// The assembled problem with contact pairs (the accumulate fast path of the contact kernel):
// its Hessian is the derivative of its gradient (frictionless: exact), free-free block.
TEST(Assembly, ContactPairsHessianMatchesFiniteDifferences) {
  Case c;
  c.file = "contact-fd";
  MaterialSpec m;
  m.name = "steel";
  m.young = 210e9;
  m.poisson = 0.3;
  c.materials.push_back(m);
  const double r = 0.5e-3;
  FiberSpec a, b;
  a.name = "a";
  a.material = b.material = "steel";
  a.radius = b.radius = r;
  a.path.points = {Vec3(-3e-3, 0, 0), Vec3(3e-3, 0, 0)};
  b.name = "b";
  b.path.points = {Vec3(0.4e-3, -3e-3, 1.99 * r), Vec3(0.2e-3, 3e-3, 1.9 * r)};
  a.elements = b.elements = 3;
  c.fibers = {a, b};
  const Model model = build_model(c);
  ContactDetector detector(model);
  Detection det = detector.detect(model.reference);
  ASSERT_GT(det.elements.size(), 0u);
  for (ContactElement& e : det.elements) e.law = PenaltyLaw{1e6, 1e-6};
  Problem problem(model);
  problem.set_contacts(det.elements, FrictionParams{0.0, 1e-6});
  for (int d = 0; d < 9; ++d) problem.fixed()[d] = 1;  // some eliminated dofs too
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  VecX q = model.reference;
  for (Index i = 0; i < q.size(); ++i) q[i] += 1e-6 * u(rng);
  VecX g;
  std::vector<double> h;
  problem.evaluate(q, &g, &h);
  const Index n = q.size();
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
  const auto& cp = problem.pattern().col_ptr();
  const auto& ri = problem.pattern().row_idx();
  for (Index j = 0; j < n; ++j)
    for (int k = cp[j]; k < cp[j + 1]; ++k) dense(ri[k], j) = dense(j, ri[k]) = h[k];
  const double step = 1e-9;
  Eigen::MatrixXd fd(n, n);
  for (Index i = 0; i < n; ++i) {
    VecX qp = q, qm = q, gp, gm;
    qp[i] += step;
    qm[i] -= step;
    problem.evaluate(qp, &gp, nullptr);
    problem.evaluate(qm, &gm, nullptr);
    fd.col(i) = (gp - gm) / (2 * step);
  }
  std::vector<Index> free;
  for (Index i = 9; i < n; ++i) free.push_back(i);
  Eigen::MatrixXd a_free(free.size(), free.size()), fd_free(free.size(), free.size());
  for (size_t i = 0; i < free.size(); ++i)
    for (size_t j = 0; j < free.size(); ++j) {
      a_free(i, j) = dense(free[i], free[j]);
      fd_free(i, j) = fd(free[i], free[j]);
    }
  EXPECT_LT((a_free - fd_free).norm(), 1e-5 * fd_free.norm());
}

}  // namespace
}  // namespace fibra
