#pragma once
/// The resolution stage between a case and its solver. The reader checks every name a case
/// file gives (fibers, bodies, tows, steps); what it cannot check needs the model or the steps
/// as a whole, and is resolved here, before anything is computed: the nodes references point
/// to, the bindings against the geometry, loads on components prescribed since earlier steps,
/// the test steps' conditions, and the state a [start] goes on from. `fibra check` resolves a
/// case and builds no solver, and a run that starts does not stop on an input error an hour
/// later (a shear step's conditions, say, once the weaving is done). The solver takes a
/// resolved case and raises no input error.
#include <optional>
#include <string>

#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/solver_state.hpp"

namespace fibra {

/// A case whose references are resolved: its model, and the state its [start] goes on from.
struct ResolvedCase {
  Model model;
  std::optional<SolverState> start;  ///< the [start] state, checked against the model
};

/// Builds the model and checks every reference and condition of the case against it; throws
/// InputError (file, key, what was expected) on the first that fails.
ResolvedCase resolve_case(const Case& c);

/// Checks that `state`, read from `file`, belongs to the model of `c` (check_state_fits, and
/// the bodies' part restored into the case's body system); throws InputError naming `file`.
/// resolve_case does it for a [start] state.
void check_start_state(const Case& c, const Model& model, const SolverState& state, const std::string& file);

}  // namespace fibra
