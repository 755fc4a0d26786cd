#pragma once
/// Step drivers: the rules by which a step's increments go, one driver per kind of step.
///
/// StaticSolver::run() takes the increments of every step alike: it solves one from the state
/// the last left, cuts its load step after a failure, reports and commits it. What differs from
/// one kind of step to another is asked of the step's driver:
/// - a load step (LoadDriver) predicts each increment from the last one's motion and ends at
///   full load;
/// - a weave step (WeaveDriver) starts each increment from the last one's motion, searched
///   along before Newton, and goes on at full load until the woven tows are apart;
/// - a relax step (RelaxDriver) takes proximal increments, its drag adapted to how easy they
///   were, and ends once the drag's force is negligible and the normals and cones settled;
/// - a biaxial or shear test (TestDriver) repeats each load level until it has so settled.
/// A driver keeps its state in the run's SolverProgress (what a checkpoint saves), so a resumed
/// run goes on with the same rules; it reaches the solver only through StepHost.
#include <memory>
#include <string>

#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/solver/solver_state.hpp"

namespace fibra {

/// What a driver asks of the solver.
class StepHost {
 public:
  virtual ~StepHost() = default;
  /// Moves the free dofs of the state to solve from by `scale` times `motion`.
  virtual void move_free_dofs(const VecX& motion, double scale) = 0;
  /// Tests: moves the interior as the edges move to `lambda` (StaticSolver::predict_test_level).
  virtual void predict_test_level(double lambda) = 0;
  /// The drag's force on the nodes' positions and the bodies at the current state, relative to
  /// the reference force.
  virtual double drag_force_residual() const = 0;
  /// Solves the converged increment on with the positions' drag released; adds its Newton
  /// iterations to `iterations` (StaticSolver::release_positions).
  virtual void release_positions(double lambda, int& iterations) = 0;
  /// The deepest penetration between crossing tows of the increment's contact set, over the
  /// penetration cap (0 without contact).
  virtual double penetration_over_cap() const = 0;
  /// Tests: the drag that applied the last load level, of this run or the run it starts from.
  virtual double test_drag() const = 0;
  virtual void set_test_drag(double drag) = 0;
  /// What a contact element's normal, lagged while its particles slide apart, pushes back per
  /// unit of slide at the increment's state: the largest normal force over the distance between
  /// the two section centres, F_n / (r_a + r_b) over the contact elements [N/m] (0 without
  /// contact).
  virtual double normal_feedback() const = 0;
};

/// How an increment of the step is solved (StaticSolver::solve_increment), as its driver sets it.
struct IncrementMode {
  /// Drag stiffness per node towards the increment's start [N/m] (0: none).
  double drag = 0;
  /// Weave: contacts between crossing tows pushed to the pattern's side, their starting
  /// penetration released over the step's first half, without friction; the normals and cones
  /// lagged (one solve, updated for the next increment).
  bool weave = false;
  /// Weave: Newton starts from a prediction (WeaveDriver::predict), searched along once the
  /// first detection's elements are set (StaticSolver::search_prediction); the drag holds the
  /// increment's start and the first detection sees the start, so the increment solves the same
  /// problem as an unpredicted one from a nearer starting point.
  bool predicted = false;
  /// Relax and tests: the drag adapts (the section vectors and the motion along a fiber
  /// weighted as in the weave); the normals and cones lagged until the drag's force is below
  /// the step's tolerance, then iterated to their fixed point.
  bool proximal = false;
  /// Tests: a level's Newton solves only as exact as the state they are part of
  /// (method.test_inexact); its first increment moves the edges (`loading`).
  bool test = false;
  bool loading = false;
  /// A load step held by its drag after a failure (LoadDriver): the drag is as stiff along the
  /// fibers as across them, and its force and the residual with updated normals and cones are
  /// measured against the load (applied forces and reactions) instead of the floored reference
  /// force.
  bool held = false;
  /// Relax, tests and held load steps: the drag's force, and the residual with updated normals
  /// and cones, below which the increment's state is settled (RelaxDriver::tolerance).
  double tolerance = 0;
};

/// An increment that converged, as its step's driver sees it.
struct SolvedIncrement {
  double step_dl = 0;      ///< its load step (0: a test level settling, or a relax at full load)
  int iterations = 0;      ///< its Newton iterations
  double drag = 0;         ///< the drag stiffness it was solved with [N/m]
  /// Its last residual with updated normals and cones, relative to the reference force (-1:
  /// not measured: only a relax step's settling increments measure it).
  double settling_moved = -1;
  const VecX* start = nullptr;  ///< the state it started from, before any prediction
  const VecX* state = nullptr;  ///< its converged state
};

/// The rules of one step's increments (see the file's comment).
class StepDriver {
 public:
  /// The driver of step `st`. `contact`: the model has contact; `k0`: the contact's initial
  /// stiffness (the drags are multiples of it).
  static std::unique_ptr<StepDriver> make(const StepSpec& st, const SolverSpec& opt, bool contact, double k0);
  virtual ~StepDriver() = default;

  /// A fresh step: the rules' starting values in `run` (the solver has reset the rest).
  virtual void begin(SolverProgress& run) const { run.relaxed = true; }
  /// Before an increment: sets its size in `run.dl` and returns its load step (`run.dl`, or 0
  /// for a test level's settling increment); may change the drag it is solved with.
  virtual double load_step(SolverProgress& run, StepHost& host) const;
  /// Before an increment, once its start is saved: moves the state it is solved from.
  virtual void predict(const SolverProgress& run, StepHost& host, double step_dl) const;
  /// How the increment about to be solved, with load step `step_dl`, is solved.
  virtual IncrementMode mode(const SolverProgress& run, double step_dl) const {
    (void)run;
    (void)step_dl;
    return {};
  }
  /// After a failed attempt: returns true when the next attempt takes a stiffer drag instead
  /// of a smaller load step.
  virtual bool failed(SolverProgress& run, double step_dl) const {
    (void)run;
    (void)step_dl;
    return false;
  }
  /// After a converged increment, before the load factor moves on: the rules' values for the
  /// next one, and whether the step may end at full load (`run.relaxed`). Returns the Newton
  /// iterations it spent itself (a release).
  virtual int converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const;
  /// After a converged increment has been reported: grows the next increment's size back
  /// towards the step's own.
  virtual void grow(SolverProgress& run, int iterations) const;
  /// After a converged increment: why the step stops there though it has not ended (empty: it
  /// goes on).
  virtual std::string stop(const SolverProgress& run, StepHost& host) const {
    (void)run;
    (void)host;
    return {};
  }

 protected:
  StepDriver(const StepSpec& st, const SolverSpec& opt) : m_step(st), m_solver(opt), m_nominal(1.0 / st.increments) {}
  const StepSpec& m_step;
  const SolverSpec& m_solver;
  double m_nominal;  ///< the step's own load step (1 / increments)
};


/// Weave steps: with contact, they go on at full load until the crossing tows are within the
/// penetration cap, at most twice the step's increments.
class WeaveDriver : public StepDriver {
 public:
  WeaveDriver(const StepSpec& st, const SolverSpec& opt, bool contact, double k0)
      : StepDriver(st, opt), m_contact(contact), m_k0(k0) {}
  void begin(SolverProgress& run) const override { run.relaxed = !m_contact; }
  void predict(const SolverProgress& run, StepHost& host, double step_dl) const override;
  IncrementMode mode(const SolverProgress& run, double step_dl) const override;
  int converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const override;
  std::string stop(const SolverProgress& run, StepHost& host) const override;

 private:
  bool m_contact;
  double m_k0;
};

/// Relax steps with contact: proximal increments whose drag adapts; the step ends at full load
/// once the drag's force is below the step's tolerance and the normals and cones settled.
class RelaxDriver : public StepDriver {
 public:
  /// The drag's force, relative to the step's tolerance, below which a settling increment whose
  /// normals do not settle is not creeping: nothing the drag holds still moves (adapt_drag).
  static constexpr double kCreepDragForce = 0.1;
  RelaxDriver(const StepSpec& st, const SolverSpec& opt, double k0);
  void begin(SolverProgress& run) const override;
  IncrementMode mode(const SolverProgress& run, double step_dl) const override;
  bool failed(SolverProgress& run, double step_dl) const override;
  int converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const override;

 protected:
  /// Sets `run.relaxed`, `run.level_settled` and `run.relax_settling` from the increment's end;
  /// returns whether it is solved on with the positions released.
  virtual bool settle(SolverProgress& run, double lambda_end) const;
  /// A failure of an increment with load step `step_dl` raises the settling drag's floor.
  virtual bool floors(double step_dl) const {
    (void)step_dl;
    return true;
  }
  /// Whether a settling increment whose residual with updated normals and cones does not halve
  /// lets the drag fall (the relax's creep rule, RelaxDriver::converged).
  virtual bool releases_creep() const { return true; }
  /// The drag's force below which a level is settled, relative to what the solver measures it
  /// against (the reference force; the load in a held load step).
  virtual double tolerance() const { return m_step.tolerance; }
  /// The drag's rule after a converged increment of `iterations` Newton iterations.
  void adapt_drag(SolverProgress& run, int iterations, bool creeping) const;
  double m_k0;
  double m_drag_max, m_drag_min;  ///< the drag's bounds [N/m]
};

/// Biaxial and shear tests with contact: relax increments, each load level repeated at the same
/// load factor until its drag force is negligible and its normals settled.
class TestDriver : public RelaxDriver {
 public:
  TestDriver(const StepSpec& st, const SolverSpec& opt, double k0) : RelaxDriver(st, opt, k0) {}
  double load_step(SolverProgress& run, StepHost& host) const override;
  void predict(const SolverProgress& run, StepHost& host, double step_dl) const override;
  IncrementMode mode(const SolverProgress& run, double step_dl) const override;
  int converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const override;
  void grow(SolverProgress& run, int iterations) const override;

 protected:
  bool settle(SolverProgress& run, double lambda_end) const override;
  bool floors(double step_dl) const override { return step_dl == 0.0; }
  /// The size of the next increment (`run.dl`) and its load step: 0 while the level settles.
  double level_step(SolverProgress& run) const;
  /// A level's settling drag is the one its loading ended with, kept while the level settles.
  bool releases_creep() const override { return false; }
  /// A level's increment converged: the relax's rules (RelaxDriver::converged), and once the
  /// level settled, the next level's loading increment is a lagged one again.
  int level_converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const;
};

/// Load steps (and any step without a drag): each increment predicted from the last one's
/// motion; ends at full load. With contact, a load step whose increment fails is held from then
/// on: each load level is applied with a drag towards the increment's start and repeated at the
/// same load factor, as a test level is, until the drag's force and the residual with updated
/// normals are below method.held_tolerance of the load (docs/theory/solver.md, "Held load
/// steps").
class LoadDriver : public TestDriver {
 public:
  LoadDriver(const StepSpec& st, const SolverSpec& opt, bool contact, double k0)
      : TestDriver(st, opt, k0), m_contact(contact && opt.method.relax_drag > 0.0) {}
  void begin(SolverProgress& run) const override { run.relaxed = true; }
  double load_step(SolverProgress& run, StepHost& host) const override;
  void predict(const SolverProgress& run, StepHost& host, double step_dl) const override;
  IncrementMode mode(const SolverProgress& run, double step_dl) const override;
  bool failed(SolverProgress& run, double step_dl) const override;
  int converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const override;
  void grow(SolverProgress& run, int iterations) const override;

 protected:
  bool settle(SolverProgress& run, double lambda_end) const override;
  double tolerance() const override { return m_solver.method.held_tolerance; }

 private:
  /// Held: the step's increment failed once (the drag is on from then on).
  static bool held(const SolverProgress& run) { return run.relax_drag > 0.0; }
  bool m_contact;  ///< the model has contact (and the drag is on): the step can be held
};

}  // namespace fibra
