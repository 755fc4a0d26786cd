#pragma once
/// The tests' level predictor: where a biaxial or shear level's first increment starts from.
#include <map>
#include <utility>
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"
#include "fibra/steps/test_edges.hpp"

namespace fibra {

class BodySystem;

/// Moves the free nodes and bodies of `q` as the edge bodies moved from `before` (the last
/// level's state) to `q` (the edges' prescribed dofs already at the new level: `fixed` marks
/// them), interpolated between opposite edges, the section vectors turned with their fiber's
/// tangent; the bodies follow their members. A starting point for the level's Newton solve, not
/// a result. `disp`: the step's prescribed dofs (start and end values), for a shear with its
/// height free; `edges`: the model's edge bodies (find_test_edges), null for a model without
/// them, where the predictor does nothing.
void predict_test_level(const Model& model, const BodySystem* bodies, const TestEdges* edges, const StepSpec& st,
                        const std::map<Index, std::pair<double, double>>& disp, const std::vector<char>& fixed,
                        const VecX& before, VecX& q);

}  // namespace fibra
