// The linear-solver back ends and CHOLMOD orderings give the same solution.
#include <gtest/gtest.h>

#include <omp.h>

#include <cmath>

#include "fibra/core/error.hpp"
#include "fibra/solver/blas_threads.hpp"
#include "verification/verification_support.hpp"

namespace fibra::test {
namespace {

TEST(LinearSolvers, OrderingsAndBackEndsAgree) {
  const std::string base = straight_cantilever(1.0, 0.001, 10, 210e9, 0.3, R"(
[[step]]
increments = 4
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, -3.3e-1]
)");
  const Solved metis = solve_toml(base);
  ASSERT_TRUE(metis.converged()) << metis.result.message;
  ASSERT_EQ(metis.c.solver.method.ordering, "metis");
  for (const char* ordering : {"amd", "auto"}) {
    const Solved s = solve_toml(base, "o.toml", [&](Case& c) { c.solver.method.ordering = ordering; });
    ASSERT_TRUE(s.converged()) << ordering << s.result.message;
    EXPECT_LT((s.q - metis.q).norm(), 1e-9 * metis.q.norm()) << ordering;
  }
  const Solved eigen = solve_toml(base + "[solver]\nlinear_solver = \"eigen\"\n");
  ASSERT_TRUE(eigen.converged()) << eigen.result.message;
  EXPECT_LT((eigen.q - metis.q).norm(), 1e-9 * metis.q.norm());
  // The ordering is the method's, not a setting.
  EXPECT_THROW(parse_case_toml(base + "[solver]\nordering = \"amd\"\n", "o.toml"), InputError);
}

TEST(LinearSolvers, BlasThreadsScopeSetsAndRestoresOpenBlasThreads) {
  if (!blas_threads_available()) GTEST_SKIP() << "the BLAS is not OpenBLAS";
  const int before = blas_threads();
  ASSERT_GE(before, 1);
  {
    const ScopedBlasThreads two(before + 1);
    EXPECT_EQ(blas_threads(), before + 1);
    {
      const ScopedBlasThreads none(0);  // 0: leaves the count as it is
      EXPECT_EQ(blas_threads(), before + 1);
    }
    EXPECT_EQ(blas_threads(), before + 1);
  }
  EXPECT_EQ(blas_threads(), before);
}

// Adaptive BLAS threads (as `fibra` sets them) change who computes the factor, not the result:
// with the threshold at 0 flops every CHOLMOD factorization and solve runs its BLAS on the
// OpenMP thread count, and the BLAS count is restored after each.
TEST(LinearSolvers, AdaptiveBlasThreadsGiveTheSameSolution) {
  const std::string base = straight_cantilever(1.0, 0.001, 40, 210e9, 0.3, R"(
[[step]]
increments = 2
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0.1, -3.3e-1]
)");
  const Solved plain = solve_toml(base);
  ASSERT_TRUE(plain.converged()) << plain.result.message;
  const int before = blas_threads();
  const int omp = omp_get_max_threads();
  omp_set_num_threads(2);
  set_adaptive_blas_threads(true, 0.0);
  const Solved adaptive = solve_toml(base);
  set_adaptive_blas_threads(false);
  omp_set_num_threads(omp);
  ASSERT_TRUE(adaptive.converged()) << adaptive.result.message;
  EXPECT_LT((adaptive.q - plain.q).norm(), 1e-10 * plain.q.norm());
  EXPECT_EQ(blas_threads(), before);
  EXPECT_TRUE(std::isinf(adaptive_blas_min_flops()));
}

}  // namespace
}  // namespace fibra::test
