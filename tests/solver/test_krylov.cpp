// Conjugate gradients preconditioned with a factorization (solver/krylov.hpp), the lazy
// analysis of the linear solvers that keeps the last factor usable, and the Newton solver's
// reuse of factorizations: same converged states as factorizing at every iteration.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "fibra/solver/krylov.hpp"
#include "fibra/solver/linear_solver.hpp"
#include "fibra/solver/shift_search.hpp"
#include "verification/verification_support.hpp"

namespace fibra::test {
namespace {

// A chain of `groups` groups of 3 dofs, each coupled to the next two: a banded block pattern.
struct Chain {
  StencilSet stencils;
  std::unique_ptr<BlockPattern> pattern;
  explicit Chain(Index groups = 12) {
    for (Index g = 0; g + 2 < groups; ++g) {
      const Index s[3] = {g, g + 1, g + 2};
      stencils.add(s);
    }
    stencils.colorize(groups, 2);
    pattern = std::make_unique<BlockPattern>(std::vector<int>(groups, 3), std::vector<const StencilSet*>{&stencils});
  }
  Index n() const { return pattern->rows(); }
  // Upper-triangle values of the dense symmetric matrix `a` (entries outside the pattern are
  // dropped: `a` is built inside it).
  std::vector<double> values(const Eigen::MatrixXd& a) const {
    std::vector<double> v(pattern->nonzeros(), 0.0);
    for (Index j = 0; j < n(); ++j)
      for (Index i = 0; i <= j; ++i)
        if (const Index k = pattern->find(i, j); k >= 0) v[k] = a(i, j);
    return v;
  }
  // A random symmetric matrix inside the pattern, with `diagonal` added on the diagonal.
  Eigen::MatrixXd random(unsigned seed, double diagonal) const {
    std::mt19937 gen(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n(), n());
    for (Index j = 0; j < n(); ++j)
      for (Index i = 0; i <= j; ++i)
        if (pattern->find(i, j) >= 0) a(i, j) = a(j, i) = u(gen);
    a.diagonal().array() += diagonal;
    return a;
  }
};

// The indefinite solver (make_indefinite_solver, load steps' unstable equilibria): a random
// symmetric matrix of the chain's banded pattern, shifted so that exactly three of its
// eigenvalues are negative, is factorized; its negative pivots are its negative eigenvalues
// (Sylvester's law of inertia) and its solves are exact, where the positive definite solvers
// refuse it. With a dof that nothing holds (singular), it fails.
TEST(IndefiniteSolver, CountsTheNegativeEigenvaluesAndSolvesExactly) {
  Chain c;
  // Diagonal shift between the third and fourth smallest eigenvalues of a random matrix.
  const Eigen::MatrixXd base = c.random(5, 0.0);
  const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(base).eigenvalues();
  const double shift = -0.5 * (ev[2] + ev[3]);
  ASSERT_GT(ev[3] - ev[2], 1e-3);
  Eigen::MatrixXd a = base;
  a.diagonal().array() += shift;
  const std::vector<double> values = c.values(a);
  auto solver = make_indefinite_solver();
  solver->analyze(*c.pattern);
  ASSERT_EQ(solver->factorize(values, 0.0), FactorStatus::Ok);
  EXPECT_EQ(solver->negative_pivots(), 3);
  std::mt19937 gen(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  VecX b(c.n()), x;
  for (Index i = 0; i < c.n(); ++i) b[i] = u(gen);
  solver->solve(b, x);
  EXPECT_LT((a * x - b).norm(), 1e-10 * b.norm());
  // The positive definite solvers refuse it.
  for (const char* name : {"cholmod", "eigen"}) {
    auto spd = make_linear_solver(name);
    spd->analyze(*c.pattern);
    EXPECT_EQ(spd->factorize(values, 0.0), FactorStatus::NotPositiveDefinite) << name;
  }
  // A dof that nothing holds (its row and column zero, a free mechanism): singular, whatever
  // the ordering (a matrix singular only to round-off, shifted onto an eigenvalue, kept pivots
  // of 1e-13 of the largest in one build and not in another).
  Eigen::MatrixXd singular = a;
  singular.row(7).setZero();
  singular.col(7).setZero();
  EXPECT_NE(solver->factorize(c.values(singular), 0.0), FactorStatus::Ok);
}

// The shift search of a refused tangent (solver/shift_search.hpp): a random matrix of the
// chain's pattern whose most negative eigenvalue is -3e-7 of its mean diagonal needs a shift
// beta above that. From scratch the search tries 1e-14, 1e-12, ..., 1e-6 of the mean diagonal:
// five factorizations. Started from a hundredth of the last shift that passed (1e-6), it tries
// 1e-8 and 1e-6: two; from a larger last shift (1e-4), one. A matrix that no shift up to its
// mean diagonal makes positive definite ends refused, at the mean diagonal.
TEST(ShiftSearch, StartsFromAHundredthOfTheLastShift) {
  Chain c;
  const Eigen::MatrixXd base = c.random(11, 0.0);
  const double lowest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(base).eigenvalues()[0];
  const double m0 = base.diagonal().mean(), ratio = 3e-7;
  // base + s I: lowest + s = -ratio (m0 + s).
  const double s = (-ratio * m0 - lowest) / (1.0 + ratio);
  Eigen::MatrixXd a = base;
  a.diagonal().array() += s;
  const double mean_diag = a.diagonal().cwiseAbs().mean();
  ASSERT_NEAR(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a).eigenvalues()[0] / mean_diag, -ratio, 1e-9);
  Eigen::MatrixXd far = a;
  far.diagonal().array() -= 2.0 * mean_diag;
  for (const char* name : {"cholmod", "eigen"}) {
    auto solver = make_linear_solver(name);
    solver->analyze(*c.pattern);
    EXPECT_EQ(first_shift(0.0), 1e-14);
    const struct {
      double last;
      int factorizations;
    } expected[] = {{0.0, 5}, {1e-6, 2}, {1e-4, 1}};
    for (const auto& [last, count] : expected) {
      const ShiftSearch r = factorize_shifted(*solver, c.values(a), mean_diag, last);
      EXPECT_EQ(r.status, FactorStatus::Ok) << name << ", last shift " << last;
      EXPECT_EQ(r.factorizations, count) << name << ", last shift " << last;
      EXPECT_NEAR(r.shift / mean_diag, 1e-6, 1e-12) << name << ", last shift " << last;
    }
    const ShiftSearch refused = factorize_shifted(*solver, c.values(far), mean_diag, 0.0);
    EXPECT_EQ(refused.status, FactorStatus::NotPositiveDefinite) << name;
    EXPECT_NEAR(refused.shift / mean_diag, 1.0, 1e-9) << name;
    EXPECT_EQ(refused.factorizations, 8) << name;
  }
}

// The CG budget a factorization is worth: a setting >= 0 as it is; automatic, its flops over 16
// times its nonzeros, between 20 and 100 (the 480-fiber samples' factor: 3.2e11 flops, 1.9e8
// nonzeros, 105 -> 100; a small model's: 20).
TEST(Krylov, TheBudgetIsTheFactorsFlopsPerNonzeroClamped) {
  EXPECT_EQ(krylov_budget(0, 3.2e11, 1.9e8), 0);
  EXPECT_EQ(krylov_budget(40, 3.2e11, 1.9e8), 40);
  EXPECT_EQ(krylov_budget(-1, 3.2e11, 1.9e8), 100);
  EXPECT_EQ(krylov_budget(-1, 1.6e10, 2.0e7), 50);
  EXPECT_EQ(krylov_budget(-1, 4.4e8, 3.0e6), 20);
  EXPECT_EQ(krylov_budget(-1, 0.0, 0.0), 20);
  EXPECT_EQ(krylov_budget(-1, std::nan(""), 1.0), 20);
}

TEST(Krylov, SymmetricMultiplyMatchesTheDenseProduct) {
  const Chain c;
  const Eigen::MatrixXd a = c.random(1, 0.0);
  const VecX x = VecX::LinSpaced(c.n(), -1.0, 2.0);
  VecX y;
  std::vector<VecX> scratch;
  symmetric_multiply(*c.pattern, c.values(a), 0.5, x, y, scratch);
  const VecX expected = a * x + 0.5 * x;
  EXPECT_LT((y - expected).norm(), 1e-13 * expected.norm());
}

TEST(Krylov, ConjugateGradientsSolveAnSpdSystem) {
  const Chain c;
  const Eigen::MatrixXd a = c.random(2, 8.0);  // diagonally dominant: SPD
  ASSERT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a).eigenvalues().minCoeff(), 0.0);
  const VecX b = VecX::LinSpaced(c.n(), 1.0, -3.0);
  const VecX exact = a.ldlt().solve(b);
  const VecX weight = VecX::Ones(c.n());
  PcgWorkspace ws;
  VecX x;
  // Unpreconditioned: converges within n iterations, to the tolerance asked.
  auto identity = [](const VecX& r, VecX& z) { z = r; };
  const PcgResult plain = pcg(*c.pattern, c.values(a), 0.0, b, x, identity, weight, 1e-10, c.n(), ws);
  EXPECT_TRUE(plain.converged);
  EXPECT_FALSE(plain.breakdown);
  EXPECT_GT(plain.iterations, 1);
  EXPECT_LE(plain.relative_residual, 1e-10);
  EXPECT_LT((x - exact).norm(), 1e-8 * exact.norm());
  // The residuals of the call, one per iteration after the start's (FIBRA_DEBUG_NEWTON).
  ASSERT_EQ(ws.history.size(), static_cast<size_t>(plain.iterations) + 1);
  EXPECT_EQ(ws.history.back(), plain.relative_residual);
  EXPECT_GT(ws.history.front(), 1e-10);
  // Preconditioned by the exact inverse: the start x = M^-1 b is the solution.
  const Eigen::LDLT<Eigen::MatrixXd> ldlt = a.ldlt();
  auto exact_inverse = [&](const VecX& r, VecX& z) { z = ldlt.solve(r); };
  const PcgResult direct = pcg(*c.pattern, c.values(a), 0.0, b, x, exact_inverse, weight, 1e-10, 5, ws);
  EXPECT_TRUE(direct.converged);
  EXPECT_EQ(direct.iterations, 0);
  // Preconditioned by the factor of a nearby matrix (an earlier tangent): a few iterations.
  const Eigen::MatrixXd nearby = a + 0.05 * c.random(3, 0.0);
  const Eigen::LDLT<Eigen::MatrixXd> old = nearby.ldlt();
  auto aged = [&](const VecX& r, VecX& z) { z = old.solve(r); };
  const PcgResult reused = pcg(*c.pattern, c.values(a), 0.0, b, x, aged, weight, 1e-10, 20, ws);
  EXPECT_TRUE(reused.converged);
  EXPECT_LT(reused.iterations, plain.iterations);
  EXPECT_LT((x - exact).norm(), 1e-8 * exact.norm());
  // The shift is part of the operator.
  const PcgResult shifted = pcg(*c.pattern, c.values(a), 2.0, b, x, identity, weight, 1e-10, c.n(), ws);
  EXPECT_TRUE(shifted.converged);
  const VecX exact_shifted = (a + 2.0 * Eigen::MatrixXd::Identity(c.n(), c.n())).ldlt().solve(b);
  EXPECT_LT((x - exact_shifted).norm(), 1e-8 * exact_shifted.norm());
  // Not converged within the iterations allowed: reported, with the last iterate.
  const PcgResult short_run = pcg(*c.pattern, c.values(a), 0.0, b, x, identity, weight, 1e-14, 2, ws);
  EXPECT_FALSE(short_run.converged);
  EXPECT_EQ(short_run.iterations, 2);
  EXPECT_GT(short_run.relative_residual, 1e-14);
}

// A solve whose residual falls too slowly to reach its tolerance within `abandon_beyond`
// iterations is given up early, and only then: diagonal matrices of 300 dofs whose eigenvalues
// spread geometrically over a condition number of 1e6 (CG's residual falls slowly) and of 30
// (it falls by about 0.7 per iteration), unpreconditioned, to 1e-10.
TEST(Krylov, HopelessSolvesAreAbandonedEarly) {
  const Chain c(100);
  const VecX b = VecX::LinSpaced(c.n(), 1.0, 2.0), weight = VecX::Ones(c.n());
  auto identity = [](const VecX& r, VecX& z) { z = r; };
  PcgWorkspace ws;
  VecX x;
  auto diagonal = [&](double condition) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(c.n(), c.n());
    for (Index i = 0; i < c.n(); ++i) a(i, i) = std::pow(condition, static_cast<double>(i) / (c.n() - 1));
    return c.values(a);
  };
  for (const double condition : {1e6, 30.0}) {
    const std::vector<double> a = diagonal(condition);
    // Without the rule: the iterations it takes (at most 1,000).
    const PcgResult full = pcg(*c.pattern, a, 0.0, b, x, identity, weight, 1e-10, 1000, ws);
    ASSERT_FALSE(full.abandoned);
    for (const int limit : {20, 40, 100, 400}) {
      const PcgResult r = pcg(*c.pattern, a, 0.0, b, x, identity, weight, 1e-10, 1000, ws, limit);
      if (!full.converged || full.iterations > 2 * limit) {
        // Far beyond the limit: given up, and as soon as the rule looks (15 or 20 iterations).
        EXPECT_TRUE(r.abandoned) << condition << " " << limit;
        EXPECT_FALSE(r.converged);
        EXPECT_LE(r.iterations, std::max(20, limit / 2)) << condition << " " << limit;
      } else if (2 * full.iterations < limit) {
        // Well within it: the same solve as without the rule.
        EXPECT_FALSE(r.abandoned) << condition << " " << limit;
        EXPECT_TRUE(r.converged);
        EXPECT_EQ(r.iterations, full.iterations);
      }
      if (r.abandoned) EXPECT_GT(full.iterations, limit) << "abandoned a solve within the limit";
    }
    std::printf("condition %g: %d iterations to 1e-10 without the rule\n", condition, full.iterations);
  }
}

TEST(Krylov, NegativeCurvatureIsABreakdown) {
  const Chain c;
  const Eigen::MatrixXd a = -c.random(4, 8.0);  // negative definite
  const VecX b = VecX::Ones(c.n());
  PcgWorkspace ws;
  VecX x;
  auto identity = [](const VecX& r, VecX& z) { z = r; };
  const PcgResult r = pcg(*c.pattern, c.values(a), 0.0, b, x, identity, VecX::Ones(c.n()), 1e-10, c.n(), ws);
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(r.breakdown);
}

// analyze() of a new pattern keeps the last factor usable until the next factorization.
TEST(Krylov, LastFactorSurvivesANewPattern) {
  for (const char* kind : {"cholmod", "eigen"}) {
    const Chain c;
    const Eigen::MatrixXd a = c.random(5, 8.0);
    std::unique_ptr<LinearSolver> s = make_linear_solver(kind);
    s->analyze(*c.pattern);
    EXPECT_FALSE(s->has_factor()) << kind;
    ASSERT_EQ(s->factorize(c.values(a), 0.0), FactorStatus::Ok) << kind;
    EXPECT_TRUE(s->has_factor()) << kind;
    const VecX b = VecX::LinSpaced(c.n(), 1.0, 2.0);
    VecX x;
    s->solve(b, x);
    EXPECT_LT((a * x - b).norm(), 1e-12 * b.norm()) << kind;
    // A wider pattern (every group coupled to the next three): the old factor still solves.
    Chain wide;
    for (Index g = 0; g + 3 < 12; ++g) {
      const Index st[2] = {g, g + 3};
      wide.stencils.add(st);
    }
    wide.stencils.colorize(12, 2);
    wide.pattern = std::make_unique<BlockPattern>(std::vector<int>(12, 3), std::vector<const StencilSet*>{&wide.stencils});
    s->analyze(*wide.pattern);
    EXPECT_TRUE(s->has_factor()) << kind;
    VecX y;
    s->solve(b, y);
    EXPECT_LT((y - x).norm(), 1e-14 * x.norm()) << kind;
    // The next factorization analyses the new pattern.
    const Eigen::MatrixXd w = wide.random(6, 10.0);
    ASSERT_EQ(s->factorize(wide.values(w), 0.0), FactorStatus::Ok) << kind;
    s->solve(b, y);
    EXPECT_LT((w * y - b).norm(), 1e-12 * b.norm()) << kind;
    // A failed factorization leaves no factor.
    EXPECT_EQ(s->factorize(wide.values(-w), 0.0), FactorStatus::NotPositiveDefinite) << kind;
    EXPECT_FALSE(s->has_factor()) << kind;
  }
}

// The Newton solver with factorizations reused through conjugate gradients converges to the
// same states as with a factorization at every iteration, with fewer factorizations. Two
// crossed fibers pressed together with friction (contact, friction cones, new contact
// patterns) and a bent cantilever.
TEST(Krylov, NewtonReusingFactorizationsReachesTheSameStates) {
  std::ifstream in(std::string(FIBRA_SOURCE_DIR) + "/examples/crossed_fibers/crossed_fibers.toml");
  ASSERT_TRUE(in.good());
  std::stringstream text;
  text << in.rdbuf();
  const std::string crossed = text.str();
  const std::string cantilever = straight_cantilever(1.0, 0.001, 10, 210e9, 0.3, R"(
[[step]]
increments = 4
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, -3.3e-1]
)");
  for (const std::string& base : {crossed, cantilever}) {
    const Solved fresh = solve_toml(base, "fresh.toml", [](Case& c) { c.solver.method.krylov_iterations = 0; });
    const Solved reuse = solve_toml(base);
    ASSERT_TRUE(fresh.converged()) << fresh.result.message;
    ASSERT_TRUE(reuse.converged()) << reuse.result.message;
    EXPECT_EQ(fresh.stats.reused_factorizations, 0);
    EXPECT_EQ(fresh.stats.krylov_iterations, 0);
    EXPECT_GT(reuse.stats.reused_factorizations, 0);
    EXPECT_LT(reuse.stats.factorizations, fresh.stats.factorizations);
    const double scale = (fresh.q - fresh.model.reference).norm();
    EXPECT_LT((reuse.q - fresh.q).norm(), 1e-6 * scale);
    std::printf("factorizations %d -> %d, %d Newton iterations solved by CG (%d CG iterations)\n",
                fresh.stats.factorizations, reuse.stats.factorizations, reuse.stats.reused_factorizations,
                reuse.stats.krylov_iterations);
  }
}

}  // namespace
}  // namespace fibra::test
