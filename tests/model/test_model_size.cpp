// The size of a model estimated before it is built (model/model_size.hpp): the counts against a
// model actually built and the stiffness matrix pattern the solver assembles, the limit of the
// 32-bit matrix indices at its exact boundary, the memory limit, and counts no integer holds.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "fibra/model/model.hpp"
#include "fibra/model/model_size.hpp"
#include "fibra/assembly/block_pattern.hpp"

namespace fibra {
namespace {

Case fibers_case(const std::vector<int>& elements, int bodies) {
  Case c;
  c.file = "<test>";
  MaterialSpec m;
  m.name = "steel";
  m.young = 2e11;
  m.poisson = 0.3;
  c.materials.push_back(m);
  for (size_t i = 0; i < elements.size(); ++i) {
    FiberSpec f;
    f.name = fmt::format("f{}", i);
    f.material = "steel";
    f.radius = f.semi_axis_1 = f.semi_axis_2 = 1e-3;
    f.elements = elements[i];
    f.path.points = {Vec3(0, 0.01 * i, 0), Vec3(1, 0.01 * i, 0)};
    c.fibers.push_back(f);
  }
  for (int b = 0; b < bodies; ++b) c.bodies.push_back({fmt::format("b{}", b), Vec3::Zero(), Mat3::Identity()});
  return c;
}

// The counts are those of the model build_model makes, and the matrix entries those of the
// pattern the beam elements' stencils give (each element couples its three nodes).
TEST(ModelSize, CountsMatchTheBuiltModelAndItsMatrixPattern) {
  const std::vector<int> elements = {1, 4, 17};
  const Case c = fibers_case(elements, 2);
  const Model model = build_model(c);
  ModelSize size;
  for (int e : elements) size += fiber_size(e);
  size.bodies = 2;
  EXPECT_EQ(size.fibers, 3.0);
  EXPECT_EQ(size.elements, static_cast<double>(model.elements.size()));
  EXPECT_EQ(size.nodes(), static_cast<double>(model.num_nodes()));
  EXPECT_EQ(size.dofs(), static_cast<double>(model.num_dofs()));

  StencilSet beams;
  for (const BeamElement& el : model.elements) {
    const Index first = el.first_dof / kNodeDofs;
    const Index groups[3] = {first, first + 1, first + 2};
    beams.add(groups);
  }
  beams.colorize(model.num_groups());
  const BlockPattern pattern(model.group_sizes(), {&beams});
  EXPECT_EQ(size.matrix_entries(), static_cast<double>(pattern.nonzeros()));
  EXPECT_EQ(size.dofs(), static_cast<double>(pattern.rows()));
}

// 45 + 333 E entries for one fiber of E elements: the largest E whose matrix the 32-bit indices
// hold passes, one more does not.
TEST(ModelSize, TheMatrixIndexLimitAtItsBoundary) {
  SizeLimits limits;
  limits.memory = std::numeric_limits<double>::infinity();
  const double largest = std::floor((2147483647.0 - 45) / 333);
  EXPECT_EQ(fiber_size(largest).matrix_entries(), 45 + 333 * largest);
  EXPECT_LE(fiber_size(largest).matrix_entries(), 2147483647.0);
  EXPECT_EQ(size_excess(fiber_size(largest), limits), "");
  const std::string why = size_excess(fiber_size(largest + 1), limits);
  EXPECT_NE(why.find("the sparse solver holds at most 2147483647 matrix entries (32-bit indices)"), std::string::npos)
      << why;
  EXPECT_EQ(why.find("this machine"), std::string::npos) << why;
}

TEST(ModelSize, TheMemoryLimit) {
  const ModelSize size = fiber_size(100000);
  // Per element: 333 matrix entries of 24 bytes, the element's data, 18 dofs of 10 doubles.
  EXPECT_GT(size.bytes(), 100000.0 * (333 * 24 + 18 * 80));
  SizeLimits limits;
  limits.memory = 1024.0 * 1024 * 1024;  // 1 GiB
  EXPECT_LT(size.bytes(), limits.memory);
  EXPECT_EQ(size_excess(size, limits), "");
  limits.memory = 512.0 * 1024 * 1024;
  const std::string why = size_excess(size, limits);
  EXPECT_NE(why.find("estimated 1e+05 elements, 2e+05 nodes, 1.8e+06 dofs, 3.33e+07 stiffness matrix entries and at "
                     "least "),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("; this machine has 512 MiB of memory"), std::string::npos) << why;
  EXPECT_EQ(why.find("32-bit"), std::string::npos) << why;
}

// Counts computed from lengths may be beyond any integer, infinite or NaN: all refused.
TEST(ModelSize, HugeInfiniteAndNaNCountsAreRefused) {
  const SizeLimits limits = machine_size_limits();
  const std::string huge = size_excess(fiber_size(2e9), limits);
  EXPECT_NE(huge.find("estimated 2e+09 elements, 4e+09 nodes, 3.6e+10 dofs, 6.66e+11 stiffness matrix entries"),
            std::string::npos)
      << huge;
  EXPECT_NE(huge.find("32-bit"), std::string::npos);
  EXPECT_NE(size_excess(fiber_size(std::numeric_limits<double>::infinity()), limits), "");
  EXPECT_NE(size_excess(fiber_size(std::numeric_limits<double>::quiet_NaN()), limits), "");
}

TEST(ModelSize, MachineLimits) {
  const SizeLimits limits = machine_size_limits();
  EXPECT_EQ(limits.matrix_entries, 2147483647.0);
  EXPECT_GT(limits.memory, 64.0 * 1024 * 1024);  // any machine that builds fibra
  EXPECT_TRUE(std::isfinite(limits.memory));
}

TEST(ModelSize, FormatBytes) {
  EXPECT_EQ(format_bytes(512), "512 B");
  EXPECT_EQ(format_bytes(1536), "1.5 KiB");
  EXPECT_EQ(format_bytes(64.0 * 1024 * 1024), "64 MiB");
  EXPECT_EQ(format_bytes(3.0 * 1024 * 1024 * 1024 * 1024), "3 TiB");
}

}  // namespace
}  // namespace fibra
