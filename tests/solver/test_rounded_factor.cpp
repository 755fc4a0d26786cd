// The rounded copy of CHOLMOD's supernodal factor that preconditions conjugate gradients
// (solver/rounded_factor.hpp), in floats and in halves: its substitutions against the double
// factor's, the half conversions, the same result on one thread and two, the split of the
// elimination tree, and the Newton solver reaching the same states in every precision.
#include <cholmod.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <bit>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "fibra/assembly/block_pattern.hpp"
#include "fibra/solver/linear_solver.hpp"
#include "fibra/solver/cholmod_view.hpp"
#include "fibra/solver/rounded_factor.hpp"
#include "verification/verification_support.hpp"

namespace fibra::test {
namespace {

// A square grid of side x side groups of 3 dofs, each coupled to its neighbours along both axes
// and the diagonals (stencils of 4 groups, one per cell): a 2D mesh, whose nested-dissection
// tree has many levels. Values: a random SPD matrix inside the pattern (a sum of random
// positive semi-definite cell matrices plus a small diagonal), with a spread of scales.
struct Grid {
  Index side;
  StencilSet stencils;
  std::unique_ptr<BlockPattern> pattern;
  std::vector<double> values;

  explicit Grid(Index side_) : side(side_) {
    auto id = [&](Index i, Index j) { return i * side + j; };
    for (Index i = 0; i + 1 < side; ++i)
      for (Index j = 0; j + 1 < side; ++j) {
        const Index s[4] = {id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)};
        stencils.add(s);
      }
    stencils.colorize(side * side, 4);
    pattern = std::make_unique<BlockPattern>(std::vector<int>(side * side, 3), std::vector<const StencilSet*>{&stencils});
    values.assign(pattern->nonzeros(), 0.0);
    std::mt19937 gen(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::uniform_real_distribution<double> e(0.0, 6.0);
    for (Index i = 0; i + 1 < side; ++i)
      for (Index j = 0; j + 1 < side; ++j) {
        const Index g[4] = {id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)};
        Eigen::Matrix<double, 12, 12> b;
        for (int r = 0; r < 12; ++r)
          for (int c = 0; c < 12; ++c) b(r, c) = u(gen);
        const Eigen::Matrix<double, 12, 12> k = std::pow(10.0, e(gen)) * (b * b.transpose());
        for (int a = 0; a < 4; ++a)
          for (int c = 0; c < 4; ++c)
            for (int ra = 0; ra < 3; ++ra)
              for (int rc = 0; rc < 3; ++rc) {
                const Index row = 3 * g[a] + ra, col = 3 * g[c] + rc;
                if (row > col) continue;
                values[pattern->find(row, col)] += k(3 * a + ra, 3 * c + rc);
              }
      }
    for (Index d = 0; d < pattern->rows(); ++d) values[pattern->find(d, d)] += 1e-3;
  }
  Index n() const { return pattern->rows(); }
};

VecX random_vector(Index n, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  VecX v(n);
  for (Index i = 0; i < n; ++i) v[i] = u(gen);
  return v;
}

// CHOLMOD's supernodal factor of a grid's matrix, read directly (METIS, postordered, as
// fibra's back end makes it): its values, its view for RoundedFactor, and CHOLMOD's solve.
struct DirectFactor {
  cholmod_common common;
  cholmod_factor* f = nullptr;
  Index n = 0;

  explicit DirectFactor(Grid& grid) : n(grid.n()) {
    cholmod_start(&common);
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_METIS;
    common.postorder = 1;
    cholmod_sparse a = cholmod_upper(*grid.pattern, grid.values.data());
    f = cholmod_analyze(&a, &common);
    if (f) cholmod_factorize(&a, f, &common);
  }
  ~DirectFactor() {
    if (f) cholmod_free_factor(&f, &common);
    cholmod_finish(&common);
  }
  bool ok() const { return f && f->is_super && common.status == CHOLMOD_OK; }
  double* values() { return static_cast<double*>(f->x); }
  Index stored() const { return static_cast<const int*>(f->px)[f->nsuper]; }
  SupernodalView view() const { return supernodal_view(*f); }
  VecX solve(const VecX& b) {
    cholmod_dense rhs{};
    rhs.nrow = rhs.nzmax = rhs.d = n;
    rhs.ncol = 1;
    rhs.x = const_cast<double*>(b.data());
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* sol = cholmod_solve(CHOLMOD_A, f, &rhs, &common);
    if (!sol) return VecX();
    const VecX x = Eigen::Map<const VecX>(static_cast<double*>(sol->x), n);
    cholmod_free_dense(&sol, &common);
    return x;
  }
};

// Solves with a precision; returns precondition(b) and, through `exact`, solve(b).
VecX precondition_with(const Grid& grid, KrylovPrecision precision, const VecX& b, VecX& exact, bool& single) {
  auto solver = make_linear_solver("cholmod");
  solver->set_krylov_precision(precision);
  solver->analyze(*grid.pattern);
  EXPECT_EQ(solver->factorize(grid.values, 0.0), FactorStatus::Ok);
  single = solver->rounded_preconditioner();
  VecX x;
  solver->precondition(b, x);
  solver->solve(b, exact);
  return x;
}

TEST(RoundedFactor, SubstitutionsMatchTheDoubleFactorToSinglePrecision) {
  const Grid grid(40);  // 4 800 dofs
  const VecX b = random_vector(grid.n(), 3);
  VecX exact;
  bool single = false;
  const VecX x = precondition_with(grid, KrylovPrecision::Single, b, exact, single);
  ASSERT_TRUE(single);
  const double difference = (x - exact).norm() / exact.norm();
  // Rounded values: not the double solve, but within a few float roundings times the growth
  // of the triangular solves on this matrix (condition number up to ~1e9 by construction).
  EXPECT_GT(difference, 1e-12);
  EXPECT_LT(difference, 1e-3);
  std::printf("single vs double substitutions: relative difference %.2e\n", difference);
}

// Halves: 11 significant bits after each row is scaled to unit length, whatever the scales of
// the matrix's rows (here spread over 6 decades).
TEST(RoundedFactor, HalfSubstitutionsMatchTheDoubleFactorToHalfPrecision) {
  const Grid grid(40);
  const VecX b = random_vector(grid.n(), 3);
  VecX exact, single_x;
  bool rounded = false;
  const VecX x = precondition_with(grid, KrylovPrecision::Half, b, exact, rounded);
  ASSERT_TRUE(rounded);
  single_x = precondition_with(grid, KrylovPrecision::Single, b, exact, rounded);
  const double difference = (x - exact).norm() / exact.norm();
  const double single_difference = (single_x - exact).norm() / exact.norm();
  std::printf("half vs double substitutions: relative difference %.2e (single %.2e)\n", difference, single_difference);
  // A half's unit roundoff is 2^-11 = 4.9e-4, a float's 2^-24 = 6.0e-8: the difference grows
  // with the roundoff, by the same growth of the triangular solves.
  EXPECT_GT(difference, 100.0 * single_difference);
  EXPECT_LT(difference, 8.0 * 8192.0 * single_difference);
  EXPECT_LT(difference, 0.1);
}

// The software conversions against values known by construction, and against the processor's
// (F16C) on every half and on a million floats, ties and subnormals among them.
TEST(RoundedFactor, HalvesRoundToNearestEvenLikeTheProcessor) {
  const std::pair<float, std::uint16_t> known[] = {
      {1.0f, 0x3c00}, {-2.0f, 0xc000}, {65504.0f, 0x7bff}, {65519.0f, 0x7bff}, {65520.0f, 0x7c00},
      {0x1p-14f, 0x0400}, {0x1p-24f, 0x0001}, {0x1p-25f, 0x0000}, {0x1.8p-25f, 0x0001}, {0x1.8p-24f, 0x0002},
      {1.0f + 0x1p-11f, 0x3c00}, {1.0f + 0x3p-11f, 0x3c02}, {1.0f + 0x1p-10f, 0x3c01}, {0.0f, 0x0000},
      {-0.0f, 0x8000}, {1e-30f, 0x0000}, {1e30f, 0x7c00}};
  for (const auto& [value, bits] : known) {
    EXPECT_EQ(float_to_half_in_software(value), bits) << value;
    EXPECT_EQ(float_to_half(value), bits) << value;
  }
  for (std::uint32_t h = 0; h < 0x10000u; ++h) {
    const auto bits = static_cast<std::uint16_t>(h);
    const bool nan = (h & 0x7c00u) == 0x7c00u && (h & 0x3ffu) != 0;
    const float value = half_to_float_in_software(bits);
    if (nan) {
      EXPECT_TRUE(std::isnan(value));
      continue;
    }
    ASSERT_EQ(std::bit_cast<std::uint32_t>(value), std::bit_cast<std::uint32_t>(half_to_float(bits))) << h;
    ASSERT_EQ(float_to_half_in_software(value), bits) << h;
    // Halfway to the next half up (in magnitude): a tie, to the even one of the two.
    if ((h & 0x7fffu) < 0x7bffu) {
      const float next = half_to_float_in_software(static_cast<std::uint16_t>(h + 1));
      const float middle = static_cast<float>((static_cast<double>(value) + next) / 2.0);
      ASSERT_EQ(float_to_half_in_software(middle), (h & 1u) ? h + 1 : h) << h;
      ASSERT_EQ(float_to_half(middle), (h & 1u) ? h + 1 : h) << h;
    }
  }
  if (!halves_in_hardware()) GTEST_SKIP() << "no F16C in this build: the software conversions are the only ones";
  // Floats from 2^-26 to 2^16 (subnormal halves to beyond the largest), either sign; a quarter
  // of them ties between two halves (the 13 bits a half drops set to exactly one half unit),
  // and a tenth anywhere among all floats.
  std::mt19937 gen(11);
  std::uniform_int_distribution<std::uint32_t> magnitude(0x32800000u, 0x47800000u), any;
  for (int k = 0; k < 1000000; ++k) {
    std::uint32_t bits = k % 10 == 0 ? any(gen) : magnitude(gen) | (k % 2 ? 0x80000000u : 0u);
    if (k % 4 == 1) bits = (bits & ~0x1fffu) | 0x1000u;
    const float value = std::bit_cast<float>(bits);
    if (std::isnan(value)) continue;
    ASSERT_EQ(float_to_half_in_software(value), float_to_half(value)) << value;
  }
}

// Halves on a matrix whose unknowns' units span 20 decades (D A D, D = diag(10^u), u in
// [-10, 10]): unscaled, its factor's values would overflow a half or vanish. The halves' solve
// is exactly the solve with the factor whose rows are scaled, rounded to halves and scaled
// back (the pivots unrounded), which CHOLMOD does here with the factor so rounded in place;
// and it stays within the halves' rounding of the double solve, with the matrix's diagonal or
// with the rows' lengths summed from the factor.
TEST(RoundedFactor, HalvesAreTheRowScaledFactorRounded) {
  Grid grid(30);
  const Index n = grid.n();
  std::mt19937 gen(13);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  std::vector<double> unit(n);
  for (double& d : unit) d = std::pow(10.0, u(gen));
  const auto& col_ptr = grid.pattern->col_ptr();
  const auto& row_idx = grid.pattern->row_idx();
  std::vector<double> diagonal(n, 0.0);
  for (Index c = 0; c < n; ++c)
    for (Index k = col_ptr[c]; k < col_ptr[c + 1]; ++k) {
      grid.values[k] *= unit[row_idx[k]] * unit[c];
      if (row_idx[k] == c) diagonal[c] = grid.values[k];
    }
  DirectFactor factor(grid);
  ASSERT_TRUE(factor.ok());
  SupernodalView v = factor.view();
  v.diagonal = diagonal.data();
  VecX b = random_vector(n, 8);
  for (Index k = 0; k < n; ++k) b[k] *= unit[k];
  const VecX exact = factor.solve(b);
  RoundedFactor half, summed;
  half.assign(v, FactorStorage::Half);
  v.diagonal = nullptr;
  summed.assign(v, FactorStorage::Half);
  VecX x, x_summed;
  half.solve(b, x);
  summed.solve(b, x_summed);
  const double difference = (x - exact).norm() / exact.norm();
  std::printf("halves, units over 20 decades: relative difference %.2e to the double solve, %.2e between the scales\n",
              difference, (x_summed - x).norm() / x.norm());
  EXPECT_GT(difference, 1e-7);
  EXPECT_LT(difference, 1e-2);
  EXPECT_LT((x_summed - x).norm(), 1e-6 * x.norm());
  // The factor rounded in place as the halves are: row r (of P A P^T) scaled by 1 / sqrt(A_rr).
  double* lx = factor.values();
  for (Index s = 0; s < v.nsuper; ++s) {
    const Index nscol = v.super[s + 1] - v.super[s], nsrow = v.pi[s + 1] - v.pi[s];
    const int* rows = v.s_rows + v.pi[s];
    for (Index j = 0; j < nscol; ++j)
      for (Index i = j + 1; i < nsrow; ++i) {
        const double scale = 1.0 / std::sqrt(diagonal[v.perm[rows[i]]]);
        double& value = lx[v.px[s] + j * nsrow + i];
        value = static_cast<double>(half_to_float(float_to_half(static_cast<float>(value * scale)))) / scale;
      }
  }
  const VecX reference = factor.solve(b);
  EXPECT_LT((x - reference).norm(), 1e-9 * reference.norm());
}

TEST(RoundedFactor, DoublePrecisionPreconditionsWithTheFactorItself) {
  const Grid grid(20);
  const VecX b = random_vector(grid.n(), 4);
  VecX exact;
  bool single = true;
  const VecX x = precondition_with(grid, KrylovPrecision::Double, b, exact, single);
  EXPECT_FALSE(single);
  EXPECT_EQ((x - exact).norm(), 0.0);
  // Auto keeps small factors in double.
  single = true;
  const VecX y = precondition_with(grid, KrylovPrecision::Auto, b, exact, single);
  EXPECT_FALSE(single);
  EXPECT_EQ((y - exact).norm(), 0.0);
}

TEST(RoundedFactor, SameResultOnOneThreadAndTwo) {
  const Grid grid(40);
  const VecX b = random_vector(grid.n(), 5);
  const int previous = omp_get_max_threads();
  for (const KrylovPrecision precision : {KrylovPrecision::Single, KrylovPrecision::Half}) {
    VecX exact, one, two;
    bool rounded = false;
    omp_set_num_threads(1);
    one = precondition_with(grid, precision, b, exact, rounded);
    omp_set_num_threads(2);
    two = precondition_with(grid, precision, b, exact, rounded);
    EXPECT_EQ((one - two).norm(), 0.0);
  }
  omp_set_num_threads(previous);
}

// The tree's cut, with CHOLMOD's factor read directly: a top and two parts, and the
// substitutions exact to rounding when the values are exactly representable in floats.
TEST(RoundedFactor, TreeCutIntoATopAndTwoBalancedParts) {
  Grid grid(40);
  DirectFactor factor(grid);
  ASSERT_TRUE(factor.ok());
  // Round the factor's values to floats in place: the single copy is then exactly this factor.
  double* lx = factor.values();
  const Index count = factor.stored();
  for (Index k = 0; k < count; ++k) lx[k] = static_cast<float>(lx[k]);
  const SupernodalView v = factor.view();
  RoundedFactor single;
  single.assign(v);
  EXPECT_GT(single.top_share(), 0.0);   // a top, done on one thread
  EXPECT_LE(single.top_share(), 0.4);   // the rule's bound
  // Packed: each supernode's lower trapezoid only, not CHOLMOD's whole diagonal blocks.
  double packed = 0.0;
  for (Index s = 0; s < v.nsuper; ++s) {
    const double nscol = v.super[s + 1] - v.super[s], nsrow = v.pi[s + 1] - v.pi[s];
    packed += nscol * nsrow - nscol * (nscol - 1) / 2;
  }
  EXPECT_EQ(single.value_bytes(), packed * sizeof(float));
  EXPECT_LT(packed, count);
  std::printf("%d supernodes, %.0f packed values against %d stored by CHOLMOD\n", static_cast<int>(v.nsuper), packed,
              static_cast<int>(count));
  const VecX b = random_vector(grid.n(), 6);
  VecX x;
  single.solve(b, x);
  // CHOLMOD's own solve with the same (rounded) factor.
  const VecX reference = factor.solve(b);
  EXPECT_LT((x - reference).norm(), 1e-9 * reference.norm());
  // Assigning again (same structure) reuses the cut and gives the same solve.
  single.assign(v);
  VecX again;
  single.solve(b, again);
  EXPECT_EQ((again - x).norm(), 0.0);
}

TEST(RoundedFactor, NewtonReachesTheSameStatesInEitherPrecision) {
  std::ifstream in(std::string(FIBRA_SOURCE_DIR) + "/examples/crossed_fibers/crossed_fibers.toml");
  ASSERT_TRUE(in.good());
  std::stringstream text;
  text << in.rdbuf();
  const Solved twice = solve_toml(text.str() + "\n[solver]\nkrylov_precision = \"double\"\n");
  const Solved once = solve_toml(text.str() + "\n[solver]\nkrylov_precision = \"single\"\n");
  const Solved half = solve_toml(text.str() + "\n[solver]\nkrylov_precision = \"half\"\n");
  ASSERT_TRUE(twice.converged()) << twice.result.message;
  ASSERT_TRUE(once.converged()) << once.result.message;
  ASSERT_TRUE(half.converged()) << half.result.message;
  ASSERT_GT(once.stats.reused_factorizations, 0);
  const double scale = (twice.q - twice.model.reference).norm();
  EXPECT_LT((once.q - twice.q).norm(), 1e-6 * scale);
  EXPECT_LT((half.q - twice.q).norm(), 1e-6 * scale);
  // The rounded factor preconditions as well as the exact one: CG's count within 10 %.
  EXPECT_LE(once.stats.krylov_iterations, 1.1 * twice.stats.krylov_iterations + 2);
  // Halves: 11 bits, still a preconditioner as good as the exact factor within a few iterations.
  EXPECT_LE(half.stats.krylov_iterations, 1.25 * twice.stats.krylov_iterations + 4);
  std::printf("CG iterations: double %d, single %d, half %d; Newton iterations %d, %d, %d\n",
              twice.stats.krylov_iterations, once.stats.krylov_iterations, half.stats.krylov_iterations,
              twice.stats.iterations, once.stats.iterations, half.stats.iterations);
}

}  // namespace
}  // namespace fibra::test
