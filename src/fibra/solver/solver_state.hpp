#pragma once
/// What a run saves so that another can go on from it. Two kinds of file, one format:
///  * a step's state, `state/STEP.bin`, at the end of each step: a later run goes on from it
///    (`[start] from = DIR`): weave a fabric once, test it many times. Everything the next step
///    needs: nodal and body values, the bodies' committed frames and binding multipliers, the
///    contact elements with their history, and the loads and prescribed values in force;
///  * a checkpoint, `state/checkpoint.bin`, after converged increments within a step: the same
///    state and where the run is in its step (load factor, increment size, the method's
///    adaptive drags and counters, the factorization it may reuse), the run's own outputs
///    bookkeeping and its case file, so that `fibra run --resume` goes on as if the run had
///    never stopped (docs/outputs.md, "state.bin" and "Checkpoints").
/// Both are versioned, carry their own length and a CRC-32 of their bytes: a truncated,
/// damaged or foreign file is refused with a message naming it, never read as a wrong state.
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "fibra/contact/contact_element.hpp"
#include "fibra/terms/drag_term.hpp"
#include "fibra/terms/load_term.hpp"
#include "fibra/core/types.hpp"

namespace fibra {

struct Model;

/// Identifies the model a state belongs to: its sizes (the reference configuration is stored
/// alongside and compared within round-off).
struct ModelFingerprint {
  std::int64_t dofs = 0, elements = 0, bodies = 0, bindings = 0;
  bool operator==(const ModelFingerprint&) const = default;
};

/// Fingerprint of `model` with `bindings` averaged bindings.
ModelFingerprint fingerprint(const Model& model, Index bindings);

struct SolverState {
  ModelFingerprint model;
  VecX reference;          ///< the model's reference configuration (checked on restore)
  std::string step;        ///< name of the step whose end this is
  int steps_done = 0;      ///< steps of its run completed
  VecX q;                  ///< nodal and body dofs
  std::vector<double> bodies;  ///< BodySystem::snapshot()
  std::vector<ContactElement> contacts;
  VecX force_end;                                     ///< loads in force, per dof
  std::map<Index, std::pair<Vec3, Vec3>> moments;     ///< nodal moments in force (start, end)
  std::map<Index, std::pair<double, double>> disp;    ///< prescribed dofs (start, end) of q - reference
  /// The drag stiffness [N/m] that applied the last load level of a test step (biaxial, shear)
  /// in the run that wrote the state (0 before any): a run going on from the state loads its
  /// first test level with at least that drag. Not in version-1 files (read as 0).
  double test_drag = 0.0;
};

/// Counters and timings of a run.
struct SolverStats {
  int increments = 0;
  int iterations = 0;
  int cuts = 0;
  int factorizations = 0;
  int regularized_factorizations = 0;  ///< factorizations attempted with a shift
  int shifted_iterations = 0;     ///< Newton iterations solved with a shifted factor
  /// Load steps: Newton iterations solved exactly with an indefinite tangent (LDL^T), on an
  /// unstable equilibrium path.
  int indefinite_iterations = 0;
  int line_search_trials = 0;
  int searched_solves = 0;        ///< Newton solves in which the line search shortened a step
  int roundoff_convergences = 0;  ///< increments accepted at the round-off floor of the residual
  int binding_updates = 0;        ///< augmented-Lagrangian multiplier updates
  int limited_steps = 0;          ///< Newton steps scaled down to the step limit
  int reused_factorizations = 0;  ///< Newton iterations solved by CG preconditioned with an earlier factor
  int krylov_iterations = 0;      ///< conjugate-gradient iterations (all Newton solves)
  double time_assembly = 0;
  double time_factorization = 0;
  double time_solve = 0;
  double factor_nonzeros = 0;
};

/// The matrix a factorization was made of, to make it again: the state, the contact elements,
/// friction, drag, moments, eliminated dofs and bodies it was assembled with, and its shift.
/// The solver preconditions later Newton solves with its last factorization (of an earlier
/// tangent); a run resumed from a checkpoint factorizes that same matrix again, so that its
/// solves are those of the run that was never stopped.
struct FactorSource {
  bool valid = false;             ///< a factorization the next solves may reuse
  VecX q;                         ///< the state it was assembled at
  std::vector<double> bodies;     ///< BodySystem::snapshot() then
  std::vector<ContactElement> contacts;
  std::vector<char> marked;       ///< per contact, 1 with the tangent above its energy
  FrictionParams friction;
  /// The drag (a checkpoint keeps a record only with the position weight 1: a release's
  /// factorizations, without the drag on the positions, are never reused,
  /// StaticSolver::release_positions).
  DragSettings drag;
  std::vector<NodalMoment> moments;
  std::vector<char> fixed;        ///< eliminated dofs
  double shift = 0;               ///< the diagonal shift it was factorized with
};

/// Where a run is within its step, and the state of the method's rules (StaticSolver::run):
/// what a checkpoint adds to a step's state.
struct SolverProgress {
  int step = 0;            ///< index of the step under way
  int total = 0;           ///< converged increments of the run
  double wall_time = 0;    ///< the run's wall time so far [s]
  // The step's increment control.
  double lambda = 0, dl = 0, last_dl = 0;
  VecX last_motion;        ///< load and weave steps: the last increment's motion (their predictors)
  int done = 0, attempts = 0, level_failures = 0;
  bool level_settled = true, relaxed = false, uncuttable = false;
  double failed_floor = 0, failed_first = -1, failed_dl = 0;
  /// Relax steps: the residual with the updated normals and cones that the step's last settling
  /// increment ended with (infinite before the first); a creep that does not die out lowers the drag.
  double settling_residual = std::numeric_limits<double>::infinity();
  VecX failed_state;       ///< the last failed attempt's state (for a stall's diagnosis)
  std::string failed_refusal;
  VecX force_start;        ///< the step's loads at its start (force_end is the state's)
  // The method's adaptive values.
  double relax_drag = 0;       ///< relax and test steps: drag stiffness per node of the next increment [N/m]
  double weave_depth = -1;     ///< penetration between crossing tows at the weave step's start [m] (-1: not measured)
  double relax_residual = 0;   ///< relax and test steps: drag force at the end of the last increment, relative
  double load_residual = 0;    ///< tests: the same at the end of the last level's loading increment (0: none yet)
  double last_shift = 0;
  double reference_force = 0;
  bool normals_settled = true;   ///< the last increment's normals and friction cones were a fixed point
  bool relax_settling = false;   ///< relax and test steps: the drag's force is negligible, the normals iterated
  bool reuse_factor = false;
  /// A tangent the factorization refuses is factorized next with the terms' indefinite local
  /// Hessians projected (beams, moments, bindings); false once such an attempt was refused too,
  /// until an exact tangent is positive definite again.
  bool project_hessians = true;
  int krylov_budget = 20, cg_excess = 0, fresh_cg = -1, iteration_factor = 1;
  SolverStats stats;
  FactorSource factor;
  /// The contact detector's memory of its last detection (ContactDetector::memory), per fiber;
  /// empty without contact.
  std::vector<std::vector<std::uint64_t>> detection_memory;
};

/// A checkpoint: the state, the progress, and what the run around the solver keeps.
struct Checkpoint {
  SolverState state;
  SolverProgress progress;
  std::string run;        ///< the run's outputs bookkeeping (run_case, JSON text)
  std::string case_text;  ///< the case file as the run read it (an edited case is refused)
  std::string case_file;  ///< its path then
};

/// Writes `state` to `path` (write_file_atomic: through a temporary file renamed into place;
/// throws RunError).
void write_state_file(const std::string& path, const SolverState& state);
/// Reads a step's state file (versions 1 to 4); throws InputError naming `path` if it is
/// missing, truncated, damaged, a checkpoint, or not a state file of a version this fibra reads.
SolverState read_state_file(const std::string& path);
/// Writes a checkpoint to `path` atomically (throws RunError).
void write_checkpoint_file(const std::string& path, const Checkpoint& checkpoint);
/// Reads a checkpoint; throws InputError naming `path` as read_state_file does.
Checkpoint read_checkpoint_file(const std::string& path);
/// Sets the length and checksum fields of a version-3 or later file's bytes to match its contents (for
/// tests and fuzzing that change a field and want the parser, not the checksum, to answer).
void seal_state_bytes(std::string& bytes);
/// Checks that `state` (read from `path`) belongs to `model` with `bindings` bindings: its
/// fingerprint, its reference configuration, its prescribed dofs and moments; throws
/// InputError naming `path` and what differs.
void check_state_fits(const SolverState& state, const Model& model, Index bindings, const std::string& path);

}  // namespace fibra
