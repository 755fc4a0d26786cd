#include "fibra/steps/step_driver.hpp"

#include <algorithm>
#include <fmt/format.h>

namespace fibra {

std::unique_ptr<StepDriver> StepDriver::make(const StepSpec& st, const SolverSpec& opt, bool contact, double k0) {
  if (st.kind == StepSpec::Kind::Weave) return std::make_unique<WeaveDriver>(st, opt, contact, k0);
  // A proximal step without contact (or with the drag switched off) has nothing its drag
  // would hold: its increments go as a load step's.
  if (st.is_proximal() && contact && opt.method.relax_drag > 0.0) {
    if (st.is_test()) return std::make_unique<TestDriver>(st, opt, k0);
    return std::make_unique<RelaxDriver>(st, opt, k0);
  }
  return std::make_unique<LoadDriver>(st, opt, contact, k0);
}

double StepDriver::load_step(SolverProgress& run, StepHost& host) const {
  (void)host;
  run.dl = std::min(run.dl, 1.0 - run.lambda);
  return run.dl;
}

void StepDriver::predict(const SolverProgress& run, StepHost& host, double step_dl) const {
  (void)run;
  (void)host;
  (void)step_dl;
}

int StepDriver::converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const {
  (void)run;
  (void)host;
  (void)inc;
  return 0;
}

// Grow back towards the requested increment size after an easy increment.
void StepDriver::grow(SolverProgress& run, int iterations) const {
  if (iterations <= 4) run.dl = std::min(m_nominal, run.dl * 1.5);
}

// METHOD §6: the tows are pushed apart until no interpenetration remains. Once the pattern's
// offsets are released and the loads applied, the step goes on at full load, each increment
// from the last one's state, until the crossing tows are within the penetration cap; at most
// twice the step's increments in all (stop). The plain weave of the paper's 12-fiber tows
// ended its ten increments 0.50 r deep, 10 times the cap, and two increments more bring it
// within (docs/theory/fabric.md, "The weave ends with the tows apart"). Measured on the contact
// set the increment solved (its statistics): a fresh detection's particles, laid out between
// the solved ones, can measure deeper where nothing raises their zones' penalty (on the
// 480-fiber twill beyond the cap for four increments at full load while the solved set went
// from 0.049 r to 0.046 r); the relax step takes such elements in.
// Weaving is a pseudo-time process: a drag towards the increment's start (stiffness per node a
// multiple of the contact penalty) keeps each increment well posed while loose fibers are
// pushed through their crossing partners; the relax step removes it.
IncrementMode WeaveDriver::mode(const SolverProgress& run, double step_dl) const {
  (void)step_dl;
  IncrementMode m;
  m.weave = m_contact;
  m.drag = m_contact ? m_solver.method.weave_drag * m_k0 : 0.0;
  m.predicted = m_contact && run.last_motion.size() > 0;
  return m;
}

// The weave's increments move alike from one to the next: the tows crimp and the edges draw in
// a little further at each, pushed by the same prescribed normals. Each increment with contact
// starts from the last one's motion, scaled to its load step (at full load, the last motion as
// it was): a secant predictor, as a load step's. Unlike a load step's, the prediction changes
// only where Newton starts, not what it solves: the drag holds the increment's start, and its
// contacts are detected there (IncrementMode::predicted). Detected at the predicted state
// instead, the contact set is that of tows the prediction carried into each other: elements
// whose normals turned to the far side of a fiber, their zones' penalties raised (median 90 k0
// against 38 k0 on the 48-fiber sample at the end of the offsets' release), and the weave took
// another path, which the relax then took longer to settle than the weave had saved. The
// prediction is searched along before Newton (StaticSolver::search_prediction): a full
// prediction overshoots where the motion slows down, at the end of the offsets' release.
void WeaveDriver::predict(const SolverProgress& run, StepHost& host, double step_dl) const {
  if (!m_contact || run.last_motion.size() == 0) return;
  host.move_free_dofs(run.last_motion, step_dl > 0.0 && run.last_dl > 0.0 ? step_dl / run.last_dl : 1.0);
}

int WeaveDriver::converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const {
  if (!m_contact) return 0;
  run.relaxed = run.lambda + inc.step_dl >= 1.0 - 1e-12 && host.penetration_over_cap() <= 1.0;
  run.last_motion = *inc.state - *inc.start;
  run.last_dl = inc.step_dl;
  return 0;
}

std::string WeaveDriver::stop(const SolverProgress& run, StepHost& host) const {
  if (!m_contact || run.lambda < 1.0 || run.relaxed || run.done < 2 * m_step.increments) return {};
  return fmt::format(
      "step \"{}\": after {} increments (twice the step's `increments`) the woven tows are still {:.3g} times the "
      "penetration cap (contact.max_penetration) deep in each other; the weave needs smaller increments (raise the "
      "step's `increments`) or tows that fit between each other (fabric.tow width and thickness against the spacing)",
      m_step.name, run.done, host.penetration_over_cap());
}

// Every increment is a proximal-point step, a drag towards the increment's start whose
// stiffness starts at the weave's drag, k0 (method.relax_drag: the stiffest), is divided by 4
// or 2 after an easy increment and quadrupled (up to k0) after a failed one; a failure at k0 is
// cut. The step ends once the loads are applied (lambda = 1), the drag's force at the end of an
// increment is below the step's tolerance times the reference force and the increment's
// normals, cones and penalties did not move: the state is then an equilibrium without drag.
RelaxDriver::RelaxDriver(const StepSpec& st, const SolverSpec& opt, double k0)
    : StepDriver(st, opt),
      m_k0(k0),
      m_drag_max(std::max(opt.method.weave_drag, opt.method.relax_drag) * k0),
      m_drag_min(1e-9 * k0) {}

void RelaxDriver::begin(SolverProgress& run) const {
  run.relax_drag = m_solver.method.relax_drag * m_k0;
  run.relaxed = false;
}

IncrementMode RelaxDriver::mode(const SolverProgress& run, double step_dl) const {
  (void)step_dl;
  IncrementMode m;
  m.proximal = true;
  m.drag = run.relax_drag;
  m.tolerance = tolerance();
  return m;
}

// Relax: a stiffer drag first (at lambda = 1 nothing else can be cut). Twice the last drag that
// failed is the floor of the drag (run.failed_floor): it does not fall straight back to a level
// that just failed (each failure costs a whole Newton solve; on the 480-fiber relax the drag
// went 35 (failed), 141 (failed), 563, then 141 again).
bool RelaxDriver::failed(SolverProgress& run, double step_dl) const {
  const bool stiffer = run.relax_drag < m_drag_max;
  if (floors(step_dl)) run.failed_floor = std::max(run.failed_floor, 2.0 * run.relax_drag);
  run.relax_drag = std::min(4.0 * run.relax_drag, m_drag_max);
  return stiffer;
}

bool RelaxDriver::settle(SolverProgress& run, double lambda_end) const {
  const bool loaded = lambda_end >= 1.0 - 1e-12;
  run.relaxed = loaded && run.relax_residual <= tolerance() && run.normals_settled;
  run.relax_settling = loaded && run.relax_residual <= tolerance();
  return run.relaxed;
}

int RelaxDriver::converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const {
  // Drag force left at the end of the increment (scaled like the residual), relative to the
  // reference force, on the nodes' positions and the bodies: the forces the fabric's edges
  // feel. Its force on the section vectors holds the fibers' spin about their own axes, which
  // only friction resists and which creeps on after the forces have settled
  // (docs/theory/fabric.md, "The spins stay held"): it ends nothing. The increment that ends a
  // relax step or settles a test level is then solved on with the positions released
  // (release_positions).
  run.relax_residual = host.drag_force_residual();
  // A test level's loading increment: its drag force is what the next increments' solves are
  // measured against (solve_increment, method.test_inexact), the release's included.
  if (mode(run, inc.step_dl).loading) run.load_residual = run.relax_residual;
  const double lambda_end = run.lambda + inc.step_dl;
  const bool release = settle(run, lambda_end);
  // A settling increment (it measured the residual with its updated normals and cones) that
  // ended with them unsettled creeps on if that residual is not at least half the last such
  // increment's, and if something still moves: the drag's force, the drag times how far the
  // increment moved, is at least a tenth of the tolerance (adapt_drag).
  bool creeping = false;
  if (releases_creep() && inc.settling_moved >= 0.0) {
    creeping = !run.normals_settled && inc.settling_moved > 0.5 * run.settling_residual &&
               run.relax_residual >= kCreepDragForce * tolerance();
    run.settling_residual = inc.settling_moved;
  }
  int released = 0;  // Newton iterations of the release (not counted by the drag's rule)
  if (release) host.release_positions(lambda_end, released);
  adapt_drag(run, inc.iterations, creeping);
  return released;
}

// Easy increments: the drag falls, faster the easier they were. Once its force is below the
// tolerance and only the normals and cones are left to settle, it stays: a weaker drag would
// only risk a failure (the 480-fiber plain relax, at a drag force of 8.3e-5, went from 8.8 to
// 4.4 N/m and failed there after 25 iterations; let fall at every settling increment, the same
// relax failed at 2.2 N/m and took 7 minutes more). But not in a relax step whose settling
// creeps on: what still moves then is a mechanism only friction and the drag resist, and it
// moves per increment only as far as the drag lets it. On the 480-fiber twill the outermost
// fibers on one side of a weft tow, squeezed out sideways, crept by 2-15 um per increment at
// 66 N/m, the residual with their updated normals 1e-3 to 8e-3 at every increment, and the
// relax had not ended 20 increments later (docs/theory/fabric.md, "What still creeps").
//
// A state whose drag force is below a tenth of the tolerance does not creep: what the drag
// holds has stopped, and the residual with the updated normals stalls because the normals of
// fibers rolling on each other within the tows turn by 1e-2 rad from one update to the next
// with their particles hardly sliding (under 1 um). A weaker drag there frees the spins and the
// tows' inner rearrangements it held: on the 480-fiber twill, let fall from 4.2 to 0.49 N/m at
// drag forces of 9e-6 to 4e-7, the spins moved again (their drag force from 3e-6 to 2.4e-3),
// increments took 39-43 Newton iterations and the relax had not ended at 40 minutes; held at
// 4.2 N/m from the same state, it ended 9 increments later (docs/theory/fabric.md, "What still
// creeps").
//
// The floor keeps the drag above twice one that failed. How fast it falls depends on how far
// the fabric still moves. Far from equilibrium (drag force above 100 times the step's
// tolerance) the state changes much from one increment to the next and a failure says little
// about the next states: the floor falls as the drag does, and an early failure at a high drag
// does not set the pace of the whole step (decaying by 0.7, such a floor took 22 easy
// increments to bring the 480-fiber relax's drag from 7e4 to 7 N/m). Close to it the states
// hardly change and a level that failed fails again (twice at 4.4 N/m in the 480-fiber relax,
// with the fast floor): there the floor decays by 0.7 per increment (docs/performance.md, "The
// relax drag and its floor").
void RelaxDriver::adapt_drag(SolverProgress& run, int iterations, bool creeping) const {
  const double fall = run.relax_settling && !creeping ? 1.0 : iterations <= 12 ? 0.25 : iterations <= 30 ? 0.5 : 1.0;
  run.relax_drag = std::max(std::max(fall * run.relax_drag, m_drag_min), std::min(run.failed_floor, m_drag_max));
  run.failed_floor *= run.relax_residual > 100.0 * tolerance() ? fall : 0.7;
}

// A test level that would leave less than a quarter of itself for a last level takes it along
// (every level costs its settling, however small). A level's settling increments repeat its
// load factor (load step 0).
//
// A level's first increment moves the edges; at the low drag the previous level settled with it
// failed twice on the 480-fiber biaxial test (at 288 and 1 152 N/m, about 10 minutes each)
// before it converged at 4 608 N/m, so the next level starts at the drag that applied this one
// (StepHost::test_drag). It goes on from the last test step of the run, or of the run whose
// state this one starts from (a restart from a test's checkpoint whose first level started at a
// lower drag failed twice on the 480-fiber biaxial test before it reached that drag again).
double TestDriver::level_step(SolverProgress& run) const {
  if (run.level_settled && 1.0 - run.lambda < 1.25 * run.dl) run.dl = 1.0 - run.lambda;
  run.dl = std::min(run.dl, 1.0 - run.lambda);
  return run.level_settled ? run.dl : 0.0;
}

double TestDriver::load_step(SolverProgress& run, StepHost& host) const {
  const double step_dl = level_step(run);
  if (run.level_settled && step_dl > 0.0) run.relax_drag = std::max(run.relax_drag, std::min(host.test_drag(), m_drag_max));
  return step_dl;
}

// A test level's first increment starts from the interior moved as the edges move (the drag
// then holds it there, not at the last level's state); friction slips and crossings are still
// measured from the last level's state.
void TestDriver::predict(const SolverProgress& run, StepHost& host, double step_dl) const {
  if (step_dl > 0.0 && m_solver.method.test_predictor) host.predict_test_level(run.lambda + step_dl);
}

IncrementMode TestDriver::mode(const SolverProgress& run, double step_dl) const {
  IncrementMode m = RelaxDriver::mode(run, step_dl);
  m.test = true;
  m.loading = step_dl > 0.0;  // the level's first increment: it moves the edges
  return m;
}

// A settled level's release is solved as its settling increments are (run.relax_settling: the
// normals and friction cones iterated until the residual with them is within the step's
// tolerance), so the released state, the point of the curves, is an equilibrium to that
// tolerance. Solved as a lagged increment instead (one normal update after the solve), the
// residual with its updated normals and cones was 3e-3 to 2e-2 at half the levels of a
// 3 x 3 x 16 plain weave sheared to 25 degrees in 20 levels (tolerance 2e-3); iterated, it is
// within it at every level, for 499 Newton iterations in all against 526 and shear forces
// within 0.2 %. The next level's loading increment is a lagged one again.
int TestDriver::converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const {
  if (inc.step_dl > 0.0) host.set_test_drag(inc.drag);
  return level_converged(run, host, inc);
}

int TestDriver::level_converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const {
  const int released = RelaxDriver::converged(run, host, inc);
  if (run.level_settled) run.relax_settling = false;
  return released;
}

bool TestDriver::settle(SolverProgress& run, double lambda_end) const {
  run.level_settled = run.relax_residual <= tolerance() && run.normals_settled;
  run.relaxed = lambda_end >= 1.0 - 1e-12 && run.level_settled;
  run.relax_settling = run.relax_residual <= tolerance();
  return run.level_settled;
}

// A level whose loading increment converged at the first attempt lets the next level grow by
// half, back towards the requested size: a test level's loading increment takes 12-16 Newton
// iterations on the fabrics, so the rule of the other steps (grow after at most 4) never fired
// there and the 480-fiber biaxial test, once cut to 1/32 of a level, stayed at that size (2 %
// would have taken 5 hours; docs/performance.md, "Test levels"). A level costs about as many
// settling increments whatever its size, so small levels waste time; a level that fails costs
// one Newton solve and a cut.
void TestDriver::grow(SolverProgress& run, int iterations) const {
  (void)iterations;
  if (!run.level_settled) return;
  if (run.level_failures == 0) run.dl = std::min(m_nominal, run.dl * 1.5);
  run.level_failures = 0;
}

// An increment starts from the last converged state moved on by the last increment's motion
// scaled to this one's size (a secant predictor), not from that state with only the
// prescribed dofs moved: the first residual is then of the order of the path's curvature times
// the increment squared instead of the increment's whole load. docs/theory/solver.md, "Steps
// and increments". (A body's rotation dofs are its rotation over the increment: they restart
// from zero at each commit, so they scale like the rest.) A held step's settling increments
// repeat their level's load factor: they start where the last one ended.
void LoadDriver::predict(const SolverProgress& run, StepHost& host, double step_dl) const {
  if (step_dl > 0.0 && run.last_dl > 0.0) host.move_free_dofs(run.last_motion, step_dl / run.last_dl);
}

// Held load steps (docs/theory/solver.md, "Held load steps"). A load step's increment fails
// where the model has a mechanism that nothing but the lagged contact normals holds: on a beam
// resting on frictionless supports, a frozen normal joins two material particles, so once the
// beam slides the normal tilts and its force pushes the beam further along; within one Newton
// solve the beam slid by millimetres and every cut failed the same way. From its first failure
// on, the step is held: each load level is applied by a proximal increment, a drag towards its
// start as stiff along the fibers as across them (weak along them, the same beam pushed 2.5
// times deeper had not settled its last level after 12 600 increments), and repeated at the
// same load factor, as a test level is (TestDriver::level_step), until the drag's force and the
// residual with updated normals are below method.held_tolerance of the load: the drag does no
// work at the level's end. The drag adapts as a test's does, above the normals' feedback
// (converged).
double LoadDriver::load_step(SolverProgress& run, StepHost& host) const {
  return held(run) ? level_step(run) : StepDriver::load_step(run, host);
}

IncrementMode LoadDriver::mode(const SolverProgress& run, double step_dl) const {
  if (!held(run)) return {};
  IncrementMode m = RelaxDriver::mode(run, step_dl);
  m.held = true;
  m.loading = step_dl > 0.0;
  return m;
}

// The first failure holds the step: the same increment is tried again with the drag, at its
// stiffest (the weave's), before anything is cut.
bool LoadDriver::failed(SolverProgress& run, double step_dl) const {
  if (!m_contact) return false;
  if (held(run)) return RelaxDriver::failed(run, step_dl);
  RelaxDriver::begin(run);
  run.level_settled = true;
  return true;
}

// A held step's drag stays above what the lagged normals feed back (StepHost::normal_feedback):
// a normal that tilts as its particles slide apart pushes them further with a stiffness of
// about F_n / (r_a + r_b), and a drag below that lets the beam run away. Let fall as a test's
// does, the unheld three-point bending pushed 2.5 times deeper (0.2 mm) ended its step with the
// beam slid off its supports, the pusher's force 0; floored, it converges in 30 increments with
// its reactions balanced to 5e-7 of the load.
int LoadDriver::converged(SolverProgress& run, StepHost& host, const SolvedIncrement& inc) const {
  if (inc.step_dl > 0.0) {
    run.last_motion = *inc.state - *inc.start;
    run.last_dl = inc.step_dl;
  }
  if (!held(run)) return 0;
  const int released = level_converged(run, host, inc);
  run.relax_drag = std::max(run.relax_drag, std::min(host.normal_feedback(), m_drag_max));
  return released;
}

// A level's increments iterate their normals and cones once the drag's force is below the
// step's tolerance (1e-4, as a relax step's), and the level settles at such an increment (its
// Newton solves went to the residual tolerance, not to method.pseudo_tolerance) with the drag's
// force below method.held_tolerance of the load: it is then an equilibrium to that tolerance
// without its drag, and nothing is left to release. The held tolerance is 1e-5: on the unheld
// three-point bending the first level does not settle below 1.2e-6 of the load, the beam
// creeping along the supports by the same few nanometres at every increment, pushed by their
// contact normals tilted by 1e-4 rad along them (the section centres of each element's
// particles 0.15 um apart along the support); at 1e-6 it crept for 80 000 increments.
bool LoadDriver::settle(SolverProgress& run, double lambda_end) const {
  const bool iterated = run.relax_settling;
  run.relax_settling = run.relax_residual <= m_step.tolerance;
  run.level_settled = iterated && run.relax_residual <= tolerance() && run.normals_settled;
  run.relaxed = lambda_end >= 1.0 - 1e-12 && run.level_settled;
  return false;
}

void LoadDriver::grow(SolverProgress& run, int iterations) const {
  if (held(run))
    TestDriver::grow(run, iterations);
  else
    StepDriver::grow(run, iterations);
}

}  // namespace fibra
