#pragma once
/// The contact's lagged loops around an increment's minimizations (METHOD §4;
/// docs/theory/contact.md, "The solver's loops"): detection passes while the element set
/// changes, and within each pass the minimization repeated while the terms' fixed-point
/// quantities move (EnergyTerm::update_fixed_point: the contact normals and the friction
/// cones); the penalty of a zone that penetrates beyond the cap raised between passes. The
/// minimization itself (Newton with the bindings' updates) is the solver's; the increment's
/// rules (a weave's prescribed normals, a lagged pseudo-time increment, a test level's settling)
/// come from its step's driver (steps/step_driver.hpp, IncrementMode).
#include <functional>
#include <string>
#include <vector>

#include "fibra/contact/contact_manager.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/problem.hpp"
#include "fibra/solver/solver_state.hpp"

namespace fibra {

/// How an increment's contact loops run.
struct ContactLoopRules {
  /// Weaving (METHOD §6): contacts between crossing tows pushed to the side `weave_side` gives
  /// them (+1 / -1: the normal from the first fiber towards the second is +z / -z; 0: not a
  /// crossing), the penetration found at the step's first detection released over its first
  /// half; frictionless; the tows may pass through each other.
  bool weave = false;
  std::function<int(int, int)> weave_side;
  /// A predicted weave increment (WeaveDriver::predict): its start, its loads applied. The first
  /// detection is made there, and once its elements are set the state is searched along the
  /// prediction (ContactLoopHost::search_prediction) before the first minimization.
  const VecX* first_detection = nullptr;
  /// Proximal increments (relax, tests, held load steps): once the normals iterate (not
  /// `lagged`), the increment is settled when the residual with the updated normals and cones is
  /// below `tolerance`, and ends when that residual no longer halves.
  bool relax = false;
  /// Pseudo-time increments: one minimization per pass, the normals, cones and raised penalties
  /// updated for the next increment; fresh elements that penetrate, and penetrations up to twice
  /// the cap, wait for it too.
  bool lagged = false;
  /// A test level's settling increment: its deepest penetration may exceed the cap by
  /// `penetration_slack` (a fraction of it), the penalties raised acting from the next increment.
  bool test_settling = false;
  double penetration_slack = 0;
  /// The solve that ends a test level with the drag on the positions taken off
  /// (StaticSolver::release_positions): its state is the level's point, so it is accepted only
  /// with its normals and cones settled to `tolerance`; where they stop settling it is refused
  /// and the level's dragged state, settled to that tolerance, stays. (A relax step's release
  /// ends at its stall, an equilibrium of the forces with its last normals: its dragged state
  /// leaves the drag's force, up to the relax's tolerance, across the fabric's edges, which a
  /// relaxed state must balance.)
  bool release = false;
  double tolerance = 0;  ///< the step's settling tolerance (relative to the reference force)
  double lambda = 0;     ///< the increment's load factor in its step
};

/// What the loops ask of the solver.
struct ContactLoopHost {
  /// Minimizes at the current elements (Newton, the bindings' updates); false when it fails.
  std::function<bool(std::vector<double>& history, int& iterations, double& residual)> minimize;
  /// The sparsity pattern changed (new element pairs).
  std::function<void()> pattern_changed;
  /// The residual at the current state with the fixed-point quantities just updated, relative to
  /// the reference force.
  std::function<double()> moved_residual;
  /// A predicted increment: moves the state to where Newton starts along its prediction, from
  /// ContactLoopRules::first_detection (StaticSolver::search_prediction).
  std::function<void()> search_prediction;
};

/// The contact loops of one increment.
class ContactLoop {
 public:
  /// How far a loaded pair's particles may lie apart across its normal (relative to the sum of
  /// their radii; detected, they face each other) before a settling increment ends at that
  /// normal update: its elements no longer describe the contacts.
  static constexpr double kStaleSlide = 0.1;
  /// For `model` with its contact bookkeeping `manager` and assembled problem `problem` (all kept
  /// by reference).
  ContactLoop(const Model& model, ContactManager& manager, Problem& problem)
      : m_model(model), m_manager(manager), m_problem(problem) {}

  /// Solves the increment from state `q` (updated in place; `q_start` the increment's start):
  /// true when the loops settled, false with `refusal` saying why when they refused it (empty
  /// when the minimization failed). `history`, `iterations` and `residual` gather the
  /// minimizations'; `stats` counts the passes and gets the state's statistics; `run` keeps the
  /// weave's released depth and whether the normals settled (what ends a relax step or settles
  /// a test level).
  bool solve(const ContactLoopRules& rules, const ContactLoopHost& host, VecX& q, const VecX& q_start,
             std::vector<double>& history, int& iterations, double& residual, ContactStats& stats, SolverProgress& run,
             std::string& refusal);
  /// The last residual with updated normals and cones of the last solve (-1: not measured; only
  /// a proximal increment whose normals iterate measures it).
  double settling_moved() const { return m_settling_moved; }

 private:
  /// A beam element as a user finds it: its fiber's name and its index along the fiber.
  std::string element_name(Index element) const;
  const Model& m_model;
  ContactManager& m_manager;
  Problem& m_problem;
  double m_settling_moved = -1;
};

}  // namespace fibra
