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
