#pragma once
/// The loads of the mechanical tests (METHOD §7): how a biaxial or a shear step drives the
/// fabric's edge bodies from where they are at the step's start.
#include <array>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// A test's edge bodies at the step's start, as its conditions need them.
struct TestEdges {
  /// Each edge body's index in the model, in kEdgeBodies' order (x-, x+, y-, y+).
  std::array<int, 4> body{};
  /// Each edge body's first dof (3 displacements, then 3 rotations), in kEdgeBodies' order
  /// (x-, x+, y-, y+).
  std::array<Index, 4> first_dof{};
  /// x- and x+: the first dofs of the bodies bound to them (the tow ends' bodies).
  std::array<std::vector<Index>, 2> bound{};
  double lx = 0;  ///< distance along x between the x- and x+ edges' centres [m]
  double ly = 0;  ///< distance along y between the y- and y+ edges' centres [m]
};

/// The edge bodies of `model` (model/fabric.hpp, kEdgeBodies) and the bodies `c`'s bindings
/// bind to x- and x+, their distances left at 0 (they are measured at a step's start); nullopt
/// for a model without the four edge bodies.
std::optional<TestEdges> find_test_edges(const Case& c, const Model& model);

/// Sets test step `st`'s conditions on its edges in `disp` (dof -> its displacement or rotation
/// at the step's start and end), which holds every edge component where it is on entry:
/// moves the driven components' ends and frees the free ones. `force_end`: the step's loads at
/// its end (a shear's x+ edge is free along x when a force holds it; its height free only under
/// a force across).
void test_edge_conditions(const StepSpec& st, const TestEdges& edges, const VecX& force_end,
                          std::map<Index, std::pair<double, double>>& disp);

}  // namespace fibra
