// The tests' edge conditions (fibra/steps/test_edges.hpp) on four edge bodies: which
// components a biaxial or a shear step drives, by how much, and which it frees.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/steps/test_edges.hpp"

namespace fibra::test {
namespace {

using Disp = std::map<Index, std::pair<double, double>>;

// Four edge bodies at dofs 0, 6, 12, 18 (x-, x+, y-, y+), the x ones with a tow end's body
// bound each (dofs 24, 30); every component held at 0.01 * its dof.
struct FourEdges {
  TestEdges edges;
  Disp disp;
  VecX force_end = VecX::Zero(36);
  FourEdges() {
    edges.first_dof = {0, 6, 12, 18};
    edges.bound = {std::vector<Index>{24}, std::vector<Index>{30}};
    edges.lx = 4e-3;
    edges.ly = 2e-3;
    for (Index d = 0; d < 24; ++d) disp[d] = {0.01 * d, 0.01 * d};
    for (Index d = 24; d < 36; ++d) disp[d] = {0.0, 0.0};
  }
  double end(Index d) const { return disp.at(d).second; }
};

StepSpec test_step(StepSpec::Kind kind) {
  StepSpec st;
  st.kind = kind;
  return st;
}

StepSpec biaxial(double strain, double ratio) {
  StepSpec st = test_step(StepSpec::Kind::Biaxial);
  st.strain = strain;
  st.ratio = ratio;
  return st;
}

TEST(TestEdges, ABiaxialStepPullsEachPairOfEdgesApartByHalfItsElongation) {
  FourEdges s;
  test_edge_conditions(biaxial(0.02, 0.5), s.edges, s.force_end, s.disp);
  EXPECT_DOUBLE_EQ(s.end(0), 0.0 - 0.5 * 0.02 * 4e-3);   // x- along x
  EXPECT_DOUBLE_EQ(s.end(6), 0.06 + 0.5 * 0.02 * 4e-3);  // x+ along x
  EXPECT_DOUBLE_EQ(s.end(13), 0.13 - 0.5 * 0.5 * 0.02 * 2e-3);
  EXPECT_DOUBLE_EQ(s.end(19), 0.19 + 0.5 * 0.5 * 0.02 * 2e-3);
  // Everything else held where it was, nothing freed.
  for (Index d : {1, 2, 3, 4, 5, 7, 8, 12, 14, 18, 20, 23}) EXPECT_DOUBLE_EQ(s.end(d), 0.01 * d) << d;
  EXPECT_EQ(s.disp.size(), 36u);
  for (const auto& [d, se] : s.disp) EXPECT_EQ(se.first, d < 24 ? 0.01 * d : 0.0) << d;
}

TEST(TestEdges, AUniaxialStepFreesTheWeftEdgeAlongTheWeft) {
  FourEdges s;
  test_edge_conditions(biaxial(0.01, 0.0), s.edges, s.force_end, s.disp);
  EXPECT_EQ(s.disp.count(19), 0u);
  EXPECT_DOUBLE_EQ(s.end(13), 0.13);  // y- held
  EXPECT_EQ(s.disp.size(), 35u);
}

TEST(TestEdges, AShearStepMovesBottomAndTopAndFreesTheLateralEdgesAndTheirTowEnds) {
  for (bool free_height : {false, true}) {
    FourEdges s;
    StepSpec st = test_step(StepSpec::Kind::Shear);
    st.angle = 10.0;
    st.free_height = free_height;
    s.force_end[6] = 5.0;   // x+ held along x by a force: free there
    s.force_end[19] = 1.0;  // the weft tension across
    test_edge_conditions(st, s.edges, s.force_end, s.disp);
    const double gamma = 10.0 * std::numbers::pi / 180.0;
    const double d = 0.5 * 2e-3 * (free_height ? std::sin(gamma) : std::tan(gamma));
    EXPECT_DOUBLE_EQ(s.end(12), 0.12 - d);
    EXPECT_DOUBLE_EQ(s.end(18), 0.18 + d);
    EXPECT_DOUBLE_EQ(s.end(0), 0.0);  // x- stays along x
    // Free: x+ along x; the x edges along y and about z, their tow ends about z; the top's
    // height when it is free.
    for (Index f : {6, 1, 5, 7, 11, 29, 35}) EXPECT_EQ(s.disp.count(f), 0u) << f;
    EXPECT_EQ(s.disp.count(19), free_height ? 0u : 1u);
    EXPECT_EQ(s.disp.size(), free_height ? 28u : 29u);
  }
}

TEST(TestEdges, AShearWithItsHeightFreeNeedsAForceAcross) {
  FourEdges s;
  StepSpec st = test_step(StepSpec::Kind::Shear);
  st.angle = 5.0;
  st.free_height = true;
  EXPECT_THROW(test_edge_conditions(st, s.edges, s.force_end, s.disp), std::logic_error);
}

// The edge bodies found in a model by their names, with the bodies bound to x- and x+ in the
// order of the bindings; none without all four.
TEST(TestEdges, TheEdgeBodiesAreFoundWithTheBodiesBoundToThem) {
  // Two fibers, their ends' bodies, the edges x-, x+ and y- and, with `all`, y+; x- and x+
  // bind the ends' bodies.
  auto text = [](bool all) {
    return std::string(R"(
material = [{ name = "m", young = 1e9, poisson = 0.3 }]
fiber = [{ name = "a", material = "m", radius = 0.01, elements = 1, points = [[0, 0, 0], [1, 0, 0]] },
         { name = "b", material = "m", radius = 0.01, elements = 1, points = [[0, 0.1, 0], [1, 0.1, 0]] }]
body = [{ name = "end.a0", center = [0, 0, 0] }, { name = "end.b0", center = [0, 0.1, 0] },
        { name = "end.a1", center = [1, 0, 0] }, { name = "edge.y-", center = [0.5, -0.1, 0] },
        { name = "edge.x+", center = [1, 0.05, 0] }, { name = "edge.x-", center = [0, 0.05, 0] })") +
           (all ? ", { name = \"edge.y+\", center = [0.5, 0.2, 0] }]" : "]") + R"(
binding = [{ body = "end.a0", ends = [{ fiber = "a", node = "first" }] },
           { body = "end.b0", ends = [{ fiber = "b", node = "first" }] },
           { body = "end.a1", ends = [{ fiber = "a", node = "last" }] },
           { body = "edge.x-", bodies = ["end.b0", "end.a0"] },
           { body = "edge.x+", bodies = ["end.a1"] }]
step = [{ name = "s" }]
)";
  };
  {
    const Case c = parse_case_toml(text(false), "three_edges.toml");
    EXPECT_FALSE(find_test_edges(c, build_model(c)).has_value());
  }
  const Case c = parse_case_toml(text(true), "edges.toml");
  const Model model = build_model(c);
  const std::optional<TestEdges> edges = find_test_edges(c, model);
  ASSERT_TRUE(edges.has_value());
  const char* names[4] = {"edge.x-", "edge.x+", "edge.y-", "edge.y+"};
  for (int e = 0; e < 4; ++e) {
    EXPECT_EQ(edges->body[e], model.body_index(names[e])) << names[e];
    EXPECT_EQ(edges->first_dof[e], model.bodies[edges->body[e]].first_dof) << names[e];
  }
  auto dof = [&](const char* name) { return model.bodies[model.body_index(name)].first_dof; };
  EXPECT_EQ(edges->bound[0], (std::vector<Index>{dof("end.b0"), dof("end.a0")}));
  EXPECT_EQ(edges->bound[1], (std::vector<Index>{dof("end.a1")}));
  EXPECT_EQ(edges->lx, 0.0);
  EXPECT_EQ(edges->ly, 0.0);
}

}  // namespace
}  // namespace fibra::test
