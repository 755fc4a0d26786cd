// The linear-solver back ends and CHOLMOD orderings give the same solution.
#include <gtest/gtest.h>

#include "fibra/core/error.hpp"
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
  const Solved metis = solve_toml(base + "[solver]\nordering = \"metis\"\n");
  ASSERT_TRUE(metis.converged()) << metis.result.message;
  for (const char* extra : {"[solver]\nordering = \"amd\"\n", "[solver]\nordering = \"auto\"\n",
                            "[solver]\nlinear_solver = \"eigen\"\n"}) {
    const Solved s = solve_toml(base + extra);
    ASSERT_TRUE(s.converged()) << extra << s.result.message;
    EXPECT_LT((s.q - metis.q).norm(), 1e-9 * metis.q.norm()) << extra;
  }
  EXPECT_THROW(parse_case_toml(base + "[solver]\nordering = \"nested\"\n", "o.toml"), InputError);
}

}  // namespace
}  // namespace fibra::test
