#pragma once
/// The resolution stage between a case and its solver. The reader checks every name a case
/// file gives (fibers, bodies, tows, steps); what it cannot check needs the model or the steps
/// as a whole, and is resolved here, before anything is computed: the nodes references point
/// to, the bindings against the geometry, loads on components prescribed since earlier steps,
/// the test steps' conditions, and the state a [start] goes on from. `fibra check` resolves a
/// case and builds no solver, and a run that starts does not stop on an input error an hour
/// later (a shear step's conditions, say, once the weaving is done). The solver takes a
/// resolved case and raises no input error.
#include <memory>
#include <optional>
#include <string>

#include "fibra/body/bodies.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/solver_state.hpp"

namespace fibra {

/// A case whose references are resolved: its model, its body system, and the state its [start]
/// goes on from. The body system refers to `model`, so a resolved case stays where
/// resolve_case built it (not copied nor moved); the solver takes the body system
/// (StaticSolver(c, model, std::move(bodies))).
struct ResolvedCase {
  explicit ResolvedCase(const Case& c);
  ResolvedCase(const ResolvedCase&) = delete;
  ResolvedCase& operator=(const ResolvedCase&) = delete;

  Model model;
  std::unique_ptr<BodySystem> bodies;  ///< the bindings resolved against the model; null without bodies
  std::optional<SolverState> start;    ///< the [start] state, checked against the model
};

/// Builds the model and its body system and checks every reference and condition of the case
/// against them; throws InputError (file, key, what was expected) on the first that fails.
ResolvedCase resolve_case(const Case& c);

/// Checks that `state`, read from `file`, belongs to the model of `c` (check_state_fits, and
/// the bodies' part restored into the case's body system); throws InputError naming `file`.
/// resolve_case does it for a [start] state.
void check_start_state(const Case& c, const Model& model, const SolverState& state, const std::string& file);

}  // namespace fibra
