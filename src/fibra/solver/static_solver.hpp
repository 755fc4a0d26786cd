#pragma once
/// Quasi-static solution of a case: steps of linearly ramped loads and prescribed
/// displacements, adaptive load increments, Newton–Raphson with a line search.
#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fibra/contact/contact_manager.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/contact_loop.hpp"
#include "fibra/solver/krylov.hpp"
#include "fibra/solver/linear_solver.hpp"
#include "fibra/solver/problem.hpp"
#include "fibra/solver/solver_state.hpp"
#include "fibra/solver/stall_diagnosis.hpp"
#include "fibra/steps/step_driver.hpp"
#include "fibra/steps/test_edges.hpp"

namespace fibra {

/// A converged increment, as reported to observers.
struct IncrementInfo {
  std::string step;            ///< step name
  int step_index = 0;          ///< 0-based
  int increment = 0;           ///< converged increments so far in this step (1-based)
  int total_increments = 0;    ///< converged increments since the start of the run
  double load_factor = 0;      ///< in [0, 1] within the step
  int iterations = 0;          ///< Newton iterations of this increment
  double residual = 0;         ///< final relative residual
  double wall_time = 0;        ///< since the start of the run [s]
  double increment_time = 0;   ///< spent on this increment, failed attempts included [s]
  bool step_end = false;       ///< last increment of its step
  /// An equilibrium without drag: false for the increments of a biaxial or shear step, or of
  /// a load step held by its drag, that repeat a load level until its drag force is negligible
  /// (their curves skip them).
  bool settled = true;
  std::vector<double> reactions;  ///< per reaction column (see reaction_columns())
  ContactStats contact;           ///< contact statistics (zero without contact)
  std::vector<ContactResponse> contact_responses;  ///< per contact element, before the history commit
  std::vector<BodyState> bodies;  ///< per rigid body, at the accepted state
  int binding_updates = 0;        ///< augmented-Lagrangian multiplier updates
  int limited_steps = 0;          ///< Newton steps scaled down to the step limit in this increment
  double binding_violation = 0;   ///< largest binding condition |g| at the accepted state [m]
  /// Relax and test steps: the drag's force on the nodes' positions and the bodies at the end
  /// of the increment's dragged solve, relative to the reference force (what ends a relax step
  /// and settles a test level; such an increment is then solved again without it).
  double relax_residual = 0;
  /// Relax and test steps: the drag's force on the section vectors at the end of the increment
  /// (the fibers' spin about their axes, held by the drag), relative to the reference force.
  double spin_residual = 0;
  double drag = 0;                ///< drag stiffness per node the increment was solved with [N/m] (0 without drag)
  /// Load steps: negative pivots of the tangent at the accepted state (LDL^T), the unstable
  /// modes of the equilibrium (a held step's without its drag): 0 for a stable one, -1 when
  /// unknown (a singular tangent, or a held step's increment before its level settled); 0 in
  /// other steps.
  int negative_pivots = 0;
};

/// Outcome of a run.
struct RunResult {
  enum class Status { Converged, Failed, Interrupted } status = Status::Converged;
  std::string message;                 ///< why it stopped (empty when converged)
  std::string step;                    ///< step where it stopped
  double load_factor = 0;              ///< last converged load factor in that step
  double attempted_load_factor = 0;    ///< load factor of the failed attempt
  std::vector<double> residual_history;  ///< relative residuals of the last failed attempt
  /// Failed runs: what moves without resisting and what the user can change (diagnosis.text()).
  StallDiagnosis diagnosis;
  std::string status_name() const;     ///< "converged", "failed", "interrupted"
};

/// Set to request a clean stop (e.g. from a SIGINT handler); checked every iteration.
std::atomic<bool>& interrupt_flag();

/// Runs the steps of a case on its model.
class StaticSolver {
 public:
  /// Sets up the run of a resolved case (resolve_case: every reference of `c` found in
  /// `model`, the bindings resolved into `bodies`, every input error raised there; `bodies`
  /// null when the model has none); an unresolved one is a logic error.
  StaticSolver(const Case& c, const Model& model, std::unique_ptr<BodySystem> bodies);
  ~StaticSolver();

  /// Solves every step; calls `observer` after each converged increment.
  RunResult run(const std::function<void(const IncrementInfo&, const VecX&)>& observer);

  const VecX& state() const { return m_q; }                        ///< current nodal values
  bool has_contact() const { return m_contact != nullptr; }        ///< [contact] present
  const BodySystem* bodies() const { return m_bodies.get(); }      ///< rigid bodies (or null)
  const SolverStats& stats() const { return m_stats; }             ///< counters and timings
  const std::vector<std::string>& reaction_columns() const { return m_reaction_columns; }  ///< names
  Problem& problem() { return *m_problem; }                        ///< the assembled problem
  /// The state after the last converged increment, for state.bin (solver_state.hpp): call it
  /// at a step's end (from the observer of the step's last increment).
  SolverState save_state(const std::string& step, int steps_done) const;
  /// Starts the run from a saved state instead of the reference configuration (before run()):
  /// a state resolve_case has checked against this model (ResolvedCase::start).
  void restore_state(const SolverState& state);
  /// The state after the last converged increment and where the run is in its step, for a
  /// checkpoint (solver_state.hpp): call it from the observer. A run resumed from it
  /// (resume()) goes on exactly as this one does.
  SolverProgress progress() const;
  /// Goes on from a checkpoint's state and progress instead of the reference configuration
  /// (before run()): the step under way, its increment control, the method's adaptive values and
  /// the factorization its next solves may reuse (made again from its record). The state is
  /// one resolve_case has checked against this model.
  void resume(const SolverState& state, const SolverProgress& progress);
  /// Progress callback (one line per increment); default none.
  void set_progress(std::function<void(const std::string&)> progress) { m_progress = std::move(progress); }

 private:
  class DriverHost;  // what a step driver asks of the solver (steps/step_driver.hpp)
  /// The drag's force on `part` at the current state, relative to settling_reference().
  double drag_residual(DragPart part) const;
  /// What the drag's force and the residual with updated normals are measured against: the
  /// load in a held load step, the reference force otherwise.
  double settling_reference() const { return m_mode.held ? m_load_force : m_reference_force; }
  /// Biaxial and shear steps: the edge bodies' conditions from their positions at the step's
  /// start (prescribed start and end values of the body dofs, into `disp`).
  void test_conditions(int step, std::map<Index, std::pair<double, double>>& disp) const;
  /// Tests: moves the free nodes and bodies as the edge bodies move from the current state to
  /// load factor lambda (interpolated between opposite edges), the section vectors turned with
  /// their fiber's tangent. A starting point for the level's Newton solve, not a result.
  void predict_test_level(int step, double lambda);
  struct Program;  // resolved loads and displacements per step
  /// A step's loads and prescribed values (m_program) from the case and the current state.
  void begin_step(int step);
  /// Solves the increment to load factor `lambda` of step `step` (the contact loops,
  /// solver/contact_loop.hpp, around equilibrium()). `positions_released`: its drag holds only the section vectors
  /// (release_positions).
  bool solve_increment(int step, double lambda, std::vector<double>& history, int& iterations, double& residual,
                       bool positions_released = false);
  /// A predicted increment (IncrementMode::predicted), its contact elements detected at its
  /// start: moves the state back along the prediction, from the increment's start (its loads
  /// applied, m_unpredicted) to the predicted state, to where the potential is lowest as the
  /// parabola through the potential and its slope at the start and the potential at the
  /// prediction has it, halved until below the start's (search_prediction_length).
  void search_prediction();
  /// After a factorization of m_linear: its CG budget, and no CG solve counted against it yet.
  void begin_factor();
  /// The sparsity pattern changed (contact elements, a restored state): both solvers analyse it
  /// afresh at their next factorization.
  void pattern_changed();
  /// Factorizes m_hessian as it is (LDL^T, m_saddle, made on first use; its ordering computed
  /// once per pattern); false when singular.
  bool factorize_indefinite();
  /// Negative pivots of the exact tangent at the current state (LDL^T), without the drag of a
  /// held load step; -1 when it is singular. Its factor, when positive definite and without a
  /// drag to leave out, preconditions the next Newton solves.
  int tangent_negative_pivots();
  bool newton(std::vector<double>& history, int& iterations, double& residual);
  /// Developers' trace of a shifted factorization (FIBRA_DEBUG_NEWTON): the indefinite local
  /// Hessians and the tangent's softest mode, by inverse iteration with the current factor.
  void print_indefinite_tangent(double shift, double mean_diag);
  /// The diagnosis of an increment that cannot converge: the tangent at the last equilibrium
  /// (the current state) and its softest mode, and the motion from there to `failed`, the
  /// failed attempt's last state. Factorizes (the run stops after it).
  StallDiagnosis diagnose_stall(const VecX& failed);
  /// Inverse iteration with the current factor (of m_hessian, maybe shifted), from a uniform
  /// vector: the unit vector after `iterations` solves, fixed dofs zero.
  VecX inverse_iteration(int iterations);
  /// The tangent's softest mode by `iterations` inverse iterations with the current factor (of
  /// m_hessian, maybe shifted), scaled to unit length in weighed coordinates (every dof a
  /// length, see m_length_scale); returns its stiffness v.Hv [N/m]. `mode` is in the dofs' units.
  double softest_mode(int iterations, VecX& mode);
  /// Weaving: +1 / -1 when the contact normal from fiber fa towards fiber fb must be +z / -z
  /// (fibers of crossing tows, side from the weave matrix), 0 otherwise.
  int weave_side(int fa, int fb) const;
  /// The end of a relax step or a settled test level (an increment whose drag force on the
  /// positions is below the step's tolerance, its normals settled): the same increment (load
  /// factor `lambda`, its start and its drag's anchor) solved on from its solution with the drag
  /// on the nodes' positions and the bodies released, only the section vectors still held
  /// (DragTerm::set's position_weight 0), so that the fabric's forces balance to the Newton
  /// tolerance. Returns true and keeps the new state when it converges; otherwise puts back
  /// the increment's state, contacts, bodies and statistics. `iterations`: its Newton
  /// iterations either way.
  bool release_positions(int step, double lambda, int& iterations);
  /// Newton, then augmented-Lagrangian updates of the binding multipliers until the binding
  /// conditions hold (each update followed by Newton again).
  bool equilibrium(std::vector<double>& history, int& iterations, double& residual);
  /// Raises the current Newton tolerance to `loose` where that is looser, the bindings' alike.
  void loosen_tolerance(double loose);
  /// How much looser the current Newton solves are than residual_tolerance: the correction's
  /// tolerance and the bindings' (both lengths) are scaled by it, as the residual's is.
  double loosening() const { return m_newton_tolerance / m_case.solver.residual_tolerance; }
  /// Relative residual (scaled like Newton's, over the reference force) at the current state with
  /// the contact normals and frozen cones just updated: how far the update moved the forces.
  double normal_update_residual();
  void apply(int step, double lambda);
  /// Records the matrix just factorized with `shift` (m_hessian at m_q with the problem as it
  /// is), so that a checkpoint can make the factorization again.
  void record_factor_source(double shift);
  /// Factorizes again the matrix `source` records, the problem put back as it was after.
  void refactorize(const FactorSource& source);
  std::vector<double> reactions(const VecX& gradient) const;

  const Case& m_case;
  const Model& m_model;
  std::unique_ptr<BodySystem> m_bodies;  // null without [[body]]
  std::unique_ptr<Problem> m_problem;
  std::unique_ptr<LinearSolver> m_linear;
  std::unique_ptr<LinearSolver> m_saddle;  // load steps' indefinite tangents (exact Newton steps)
  bool m_saddle_analyzed = false;           // m_saddle has analysed the current pattern
  std::unique_ptr<Program> m_program;
  std::unique_ptr<ContactManager> m_contact;  // null without [contact]
  std::unique_ptr<ContactLoop> m_contact_loop;  // the contact loops of an increment (null without [contact])
  ContactStats m_contact_stats;
  VecX m_q;
  VecX m_q_start;  // state at the start of the current increment (friction slips, crossings)
  VecX m_drag_anchor;  // where the drag pulls: the increment's start, or a test level's predicted state
  VecX m_unpredicted;  // a predicted increment's start with its loads applied (search_prediction)
  VecX m_gradient;
  VecX m_update_gradient;  // gradient at the converged state with updated normals (normal_update_residual)
  std::vector<double> m_hessian;
  VecX m_force_scale;   // residual weights: 1 on x0, 1/radius on g
  VecX m_length_scale;  // increment weights: 1 on x0, radius on g
  std::vector<std::string> m_reaction_columns;
  std::vector<Index> m_reaction_nodes;
  int m_binding_updates = 0;  // in the current increment
  std::string m_refusal;      // why the contact loop refused the current increment (empty: it did not)
  std::vector<std::pair<int, int>> m_fiber_tow;  // per fiber: (0 warp / 1 weft / -1 none, tow index)
  std::optional<TestEdges> m_edges;  // the fabric's edge bodies (tests), nullopt without them
  double m_test_drag = 0;        // drag that applied the last test level, of this run or its start's [N/m]
  bool m_reuse_factor = false;    // the last factorization may precondition the next Newton solve
  bool m_adaptive_tangent = false;  // SolverMethod::contact_tangent is "adaptive": shortened steps mark contact elements
  double m_last_shift = 0;        // last shift a factorization needed, relative to its tangent's mean diagonal
  int m_krylov_budget = 20;       // CG iterations a factorization is worth (krylov_budget())
  int m_cg_excess = 0;            // CG iterations since the last factorization beyond the first solve's, summed
  int m_fresh_cg = -1;            // iterations of the first CG solve after the last factorization (-1: none yet)
  VecX m_rhs;                     // right-hand side of the Newton solve
  PcgWorkspace m_pcg;             // conjugate gradients' work vectors
  double m_reference_force = 0;  // reference force of the last Newton iteration [N]
  // The load of the last Newton iteration: applied forces and reactions, floored at 1e-3 of
  // the reference force's floor only [N] (what a held load step measures against).
  double m_load_force = 0;
  double m_newton_tolerance = 0;  // residual tolerance of the current Newton solves (relative; >= residual_tolerance)
  bool m_pseudo_time = false;  // the increment being solved is a pseudo-time one (lagged normals and cones)
  bool m_tolerance_from_drag = false;  // the next minimization's drag force sets the Newton tolerance (equilibrium())
  IncrementMode m_mode;          // how the increment being solved is solved (its step's driver)
  int m_iteration_factor = 1;    // the current increment may take this many times max_iterations (1, 2 or 4)
  SolverProgress m_run;          // where run() is: its step, the step's increment control (progress())
  bool m_resumed = false;        // run() goes on from m_run (resume())
  FactorSource m_factor_source;  // the last factorization the next solves may reuse
  SolverStats m_stats;
  std::function<void(const std::string&)> m_progress;
};

}  // namespace fibra
