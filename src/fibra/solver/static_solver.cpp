#include "fibra/solver/static_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <Eigen/Geometry>
#include <numbers>
#include <numeric>
#include <fmt/format.h>
#include <map>

#include "fibra/core/debug.hpp"
#include "fibra/core/error.hpp"
#include "fibra/body/rotation.hpp"
#include "fibra/model/fabric.hpp"
#include "fibra/solver/contact_loop.hpp"
#include "fibra/solver/krylov.hpp"
#include "fibra/solver/line_search.hpp"
#include "fibra/solver/shift_search.hpp"
#include "fibra/steps/step_driver.hpp"
#include "fibra/steps/test_edges.hpp"
#include "fibra/steps/test_predictor.hpp"

namespace fibra {

std::atomic<bool>& interrupt_flag() {
  static std::atomic<bool> flag{false};
  return flag;
}

std::string RunResult::status_name() const {
  switch (status) {
    case Status::Converged: return "converged";
    case Status::Failed: return "failed";
    case Status::Interrupted: return "interrupted";
  }
  return "failed";
}

/// Loads and prescribed values of the current step, as start/end pairs ramped by lambda.
struct StaticSolver::Program {
  VecX force_start, force_end;                      // per dof
  std::map<Index, std::pair<Vec3, Vec3>> moments;   // node -> (start, end)
  std::map<Index, std::pair<double, double>> disp;  // dof -> (start, end) of u = q - ref
  std::vector<char> fix_mask;                       // [[fix]] dofs (held at reference)
};

namespace {

constexpr double kDirectorDrag = 100.0;  // weight of the section vectors' drag in weave and relax steps

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

StaticSolver::StaticSolver(const Case& c, const Model& model, std::unique_ptr<BodySystem> bodies)
    : m_case(c), m_model(model), m_bodies(std::move(bodies)),
      m_problem(std::make_unique<Problem>(model, m_bodies.get())),
      m_linear(make_linear_solver(c.solver.linear_solver, c.solver.method.ordering)), m_program(std::make_unique<Program>()),
      m_q(model.reference) {
  if ((m_bodies == nullptr) != model.bodies.empty())
    throw std::logic_error("StaticSolver: the body system does not match the model (resolve_case builds it)");
  m_linear->set_krylov_precision(krylov_precision_from(c.solver.krylov_precision));
  const Index n = model.num_dofs();
  m_program->force_start = m_program->force_end = VecX::Zero(n);
  m_program->fix_mask.assign(n, 0);
  // One reaction column triple per supported or driven node, in order of first mention.
  auto add_reaction = [&](const NodeRef& ref, Index node) {
    const std::string label = fmt::format("reaction:{}:{}", ref.fiber, ref.label());
    if (std::find(m_reaction_columns.begin(), m_reaction_columns.end(), label + ":x") != m_reaction_columns.end())
      return;
    for (const char* axis : {"x", "y", "z"}) m_reaction_columns.push_back(label + ":" + axis);
    m_reaction_nodes.push_back(node);
  };
  for (size_t i = 0; i < c.fixes.size(); ++i) {
    const FixSpec& f = c.fixes[i];
    const Index node = model.node_index(f.node, c.file, fmt::format("fix[{}]", i));
    for (int k = 0; k < 9; ++k)
      if (f.dofs[k]) m_program->fix_mask[9 * node + k] = 1;
    add_reaction(f.node, node);
  }
  for (size_t s = 0; s < c.steps.size(); ++s) {
    const StepSpec& st = c.steps[s];
    for (size_t i = 0; i < st.displacements.size(); ++i) {
      const NodeRef& ref = st.displacements[i].node;
      add_reaction(ref, model.node_index(ref, c.file, fmt::format("step[{}].displacement[{}]", s, i)));
    }
  }
  // Rigid bodies: history columns.
  if (m_bodies) {
    for (const Body& b : model.bodies)
      for (const char* col : {"fx", "fy", "fz", "mx", "my", "mz", "ux", "uy", "uz", "rx", "ry", "rz"})
        m_reaction_columns.push_back(fmt::format("body:{}:{}", b.name, col));
  }
  m_force_scale = VecX::Ones(n);
  m_length_scale = VecX::Ones(n);
  for (Index b = 0; m_bodies && b < m_bodies->num_bodies(); ++b)
    for (int k = 3; k < 6; ++k) {
      m_force_scale[model.bodies[b].first_dof + k] = 1.0 / m_bodies->size(b);
      m_length_scale[model.bodies[b].first_dof + k] = m_bodies->size(b);
    }
  for (const Fiber& f : model.fibers) {
    const Section& sec = model.sections[f.section];
    const double r = std::sqrt(sec.a * sec.b);
    for (Index k = 0; k < f.num_nodes; ++k)
      for (int d = 3; d < 9; ++d) {
        m_force_scale[9 * (f.first_node + k) + d] = 1.0 / r;
        m_length_scale[9 * (f.first_node + k) + d] = r;
      }
  }
  // Weaving: the tow (direction, index) of every fiber.
  m_edges = find_test_edges(c, model);
  m_fiber_tow.assign(model.fibers.size(), {-1, -1});
  for (size_t t = 0; t < c.tows.size(); ++t)
    for (const std::string& name : c.tows[t].fibers) {
      const int f = model.fiber_index(name);
      if (f < 0) throw std::logic_error("StaticSolver: a tow's fiber not in the model (resolve_case checks it)");
      m_fiber_tow[f] = {c.tows[t].direction == TowSpec::Direction::Warp ? 0 : 1, c.tows[t].index};
    }
  if (c.contact.enabled) {
    m_contact = std::make_unique<ContactManager>(model, c.contact);
    m_problem->set_normal_rule(m_contact.get());
    const std::string& tangent = c.solver.method.contact_tangent;
    if (tangent != "adaptive" && tangent != "exact" && tangent != "majorizing")
      throw std::invalid_argument("SolverMethod::contact_tangent: \"" + tangent +
                                  "\" (expected \"adaptive\", \"exact\" or \"majorizing\")");
    m_problem->set_contact_tangent(tangent == "majorizing" ? ContactTangent::Majorizing : ContactTangent::Exact);
    m_adaptive_tangent = tangent == "adaptive";
    m_contact_loop = std::make_unique<ContactLoop>(model, *m_contact, *m_problem);
    double rmin = std::numeric_limits<double>::infinity();
    for (const Fiber& f : model.fibers)
      rmin = std::min(rmin, std::sqrt(model.sections[f.section].a * model.sections[f.section].b));
    m_problem->set_step_limit(c.solver.method.max_step >= 0.0 ? c.solver.method.max_step : 0.5 * rmin,
                              m_length_scale);
  } else {
    m_problem->set_step_limit(std::max(0.0, c.solver.method.max_step), m_length_scale);
  }
  m_q_start = m_q;
  m_drag_anchor = m_q;
  m_newton_tolerance = c.solver.residual_tolerance;
  pattern_changed();
}

StaticSolver::~StaticSolver() = default;

void StaticSolver::apply(int step, double lambda) {
  Program& p = *m_program;
  m_problem->forces() = p.force_start + lambda * (p.force_end - p.force_start);
  auto& moments = m_problem->moments();
  moments.clear();
  for (const auto& [node, se] : p.moments) moments.push_back({node, se.first + lambda * (se.second - se.first)});
  std::vector<char>& fixed = m_problem->fixed();
  fixed = p.fix_mask;
  for (Index d = 0; d < m_q.size(); ++d)
    if (fixed[d]) m_q[d] = m_model.reference[d];
  for (const auto& [dof, se] : p.disp) {
    fixed[dof] = 1;
    m_q[dof] = m_model.reference[dof] + se.first + lambda * (se.second - se.first);
    // A body's rotation dofs hold the increment's rotation: total minus what is committed.
    if (dof >= m_model.node_dofs && (dof - m_model.node_dofs) % 6 >= 3) {
      const Index b = (dof - m_model.node_dofs) / 6;
      m_q[dof] -= m_bodies->committed_rotation(b)[(dof - m_model.node_dofs) % 6 - 3];
    }
  }
}

std::vector<double> StaticSolver::reactions(const VecX& gradient) const {
  std::vector<double> out;
  out.reserve(3 * m_reaction_nodes.size());
  for (Index node : m_reaction_nodes)
    for (int k = 0; k < 3; ++k) out.push_back(gradient[9 * node + k]);
  return out;
}

int StaticSolver::weave_side(int fa, int fb) const {
  const auto [da, ia] = m_fiber_tow[fa];
  const auto [db, ib] = m_fiber_tow[fb];
  if (da < 0 || db < 0 || da == db) return 0;
  const bool above = da == 0 ? warp_above(m_case.weave, ia, ib) : warp_above(m_case.weave, ib, ia);
  // Normal from A towards B: +z when B is above A.
  const bool b_above = da == 0 ? !above : above;
  return b_above ? 1 : -1;
}

bool StaticSolver::solve_increment(int step, double lambda, std::vector<double>& history, int& iterations,
                                   double& residual, bool positions_released) {
  apply(step, lambda);
  m_contact_stats = ContactStats{};
  m_binding_updates = 0;
  m_refusal.clear();
  m_newton_tolerance = m_case.solver.residual_tolerance;
  m_tolerance_from_drag = false;
  m_pseudo_time = false;
  if (!m_contact) return equilibrium(history, iterations, residual);
  // How the step's driver has the increment solved (steps/step_driver.hpp): the weave's
  // prescribed normals, or proximal increments (relax and tests), and the drag.
  const bool weave = m_mode.weave;
  const bool relax = m_mode.proximal;
  // In weave and relax steps the section vectors are dragged 100 times harder than their
  // boundary's motion: a fiber's rigid spin about its axis has no other stiffness where
  // friction does not hold it, and with the r^2 weight (5.8e-5 N/m per node on the 480-fiber
  // sample) any shift of an indefinite tangent swamped it and stalled Newton; in relax steps,
  // the spin of the fibers near a tow end diverged as the drag fell (docs/theory/fabric.md).
  // Weaving: along a fiber the drag is weaker (method.drag_axial, 0.01), so the fibers slide along
  // themselves as the tows crimp and the edges draw in, instead of stretching against a drag
  // that holds every node (docs/theory/fabric.md, "Drag along the fibers").
  // A held load step's drag is as stiff along the fibers as across them: its fibers are held
  // where they are, not let slide (LoadDriver).
  m_problem->set_drag(m_mode.drag, m_drag_anchor, weave || relax ? kDirectorDrag : 1.0,
                      weave || (relax && !m_mode.held) ? m_case.solver.method.drag_axial : 1.0,
                      positions_released ? 0.0 : 1.0);

  // Pseudo-time increments (weave and relax steps) do not iterate the normals and cones to
  // their fixed point: one solve, then both are updated for the next increment (a lag like
  // the drag's). Once a relax step's drag force is negligible, its increments iterate them
  // (a slow creep would turn the normals a little at every lagged increment); the step ends
  // at an increment where they did not move.
  const bool lagged = weave || (relax && !m_run.relax_settling);
  m_pseudo_time = lagged && !m_mode.held;
  // A lagged increment is a pseudo-time state, not an equilibrium: its drag force is above
  // the step's tolerance, so its Newton solves stop at the looser method.pseudo_tolerance
  // (and the correction at the displacement tolerance scaled alike).
  m_newton_tolerance = lagged ? std::max(m_case.solver.method.pseudo_tolerance, m_case.solver.residual_tolerance)
                              : m_case.solver.residual_tolerance;
  // Relax and test steps (a drag, not a held load step's): each solve only as exact as the
  // state it is part of (method.test_inexact, method.relax_inexact).
  // A lagged increment is a step of a proximal-point sequence whose drag force, relative to
  // the reference force, was 0.19, 0.13, 0.028, 0.0082, ... on the 480-fiber equibiaxial
  // test: a Newton residual a hundredth of the drag force the increment is expected to leave
  // (the last increment's, or the last level's loading increment's for a level's first)
  // changes nothing of the sequence, where 1e-6 took 6-14 iterations per solve. A relax
  // step's first increment has no earlier one to expect its drag force from: it is solved to
  // pseudo_tolerance.
  // The bindings' tolerance (a length) is scaled alike: the proximal anchors' springs are
  // reset whenever a member moved more than it, and a solve that stops at the first iteration
  // moves nothing, so with the length left as it was the multipliers grew by one update at a
  // time, each solve stopping at once, until max_binding_updates failed the increment.
  // A settling increment (drag force below the step's tolerance) ends once the residual with
  // its updated normals and cones is below that tolerance; its Newton solves stop at a
  // hundredth of it (x the step's tolerance): on the 480-fiber equibiaxial test they went on
  // to residual_tolerance, 7-8 iterations and 2-3 more after a binding update per pass, where
  // the last 2-4 changed the edge forces by less than 1e-5 of the reference force
  // (docs/performance.md, "Test levels"); the 480-fiber twill's relax settled in 7 increments
  // of 8-21 iterations, where solved to residual_tolerance its settling increments took up to
  // 56 (docs/performance.md, "Run times"). A test level's release, a point of the curves, is
  // solved as its settling increments are; a relax step's, the woven state every test and
  // export starts from, to residual_tolerance (its bindings then hold to binding_tolerance).
  // A test's first loading increment has no earlier loading increment to expect its drag
  // force from: its first minimization measures it (equilibrium()). Solved to
  // pseudo_tolerance (1e-6 of the reference force) instead, the 480-fiber plain shear's (a
  // 1.25-degree level from the relaxed state) takes 11 Newton iterations against 8.
  if (relax && !m_mode.held && m_mode.drag > 0.0 && (m_mode.test || !positions_released)) {
    const double expected = !lagged ? m_mode.tolerance : m_mode.loading ? m_run.load_residual : m_run.relax_residual;
    m_tolerance_from_drag = m_mode.test && lagged && m_mode.loading && !(m_run.load_residual > 0.0);
    const SolverMethod& method = m_case.solver.method;
    loosen_tolerance((m_mode.test ? method.test_inexact : method.relax_inexact) * expected);
  }
  const bool test_with_drag = m_mode.test && m_mode.drag > 0.0;

  // The contact loops (solver/contact_loop.hpp): detection passes, the normals and cones to
  // their fixed point, the penalties; each minimization is equilibrium().
  ContactLoopRules rules;
  rules.weave = weave;
  rules.weave_side = [this](int fa, int fb) { return weave_side(fa, fb); };
  rules.relax = relax;
  rules.lagged = lagged;
  rules.test_settling = test_with_drag && !lagged;
  rules.penetration_slack = m_case.solver.method.test_penetration_slack;
  rules.release = positions_released && m_mode.test;
  rules.tolerance = m_mode.tolerance;
  rules.lambda = lambda;
  // A predicted increment's start with its loads applied: where it is first detected, and where
  // the search along the prediction starts.
  if (m_mode.predicted) {
    m_unpredicted = m_q_start;
    const std::vector<char>& fixed = m_problem->fixed();
    for (Index d = 0; d < m_q.size(); ++d)
      if (fixed[d]) m_unpredicted[d] = m_q[d];
    rules.first_detection = &m_unpredicted;
  }
  ContactLoopHost host;
  host.minimize = [this](std::vector<double>& h, int& its, double& res) { return equilibrium(h, its, res); };
  host.pattern_changed = [this]() { pattern_changed(); };
  host.moved_residual = [this]() { return normal_update_residual(); };
  host.search_prediction = [this]() { search_prediction(); };
  return m_contact_loop->solve(rules, host, m_q, m_q_start, history, iterations, residual, m_contact_stats, m_run,
                               m_refusal);
}

// The potential along the prediction is the increment's own: its contact elements, detected at
// its start, their prescribed normals and offsets, its drag.
// The bindings' proximal anchors are set at the start (the minimization sets them again where
// it starts): left where the last solve set them, the search's potential would differ in its
// last digits between a run and the same run resumed from a checkpoint, which restores them
// elsewhere, and the two would go on differently.
void StaticSolver::search_prediction() {
  const VecX motion = m_q - m_unpredicted;
  m_problem->begin_lagged(m_unpredicted);
  m_problem->set_energy_base(m_unpredicted);
  const double e0 = m_problem->evaluate(m_unpredicted, &m_gradient, nullptr);
  const double slope = m_gradient.dot(motion);
  const StepLength found = search_prediction_length(
      [&](double t) { return m_problem->evaluate(m_unpredicted + t * motion, nullptr, nullptr); }, e0, slope);
  if (debug_newton())
    fmt::print(stderr, " prediction searched: {:.3f} of it (potential {:.3e} at the start, slope {:.3e}; {:.3e} there)\n",
               found.alpha, e0, slope, found.energy);
  m_q = m_unpredicted + found.alpha * motion;
}

double StaticSolver::normal_update_residual() {
  m_problem->evaluate(m_q, &m_update_gradient, nullptr);
  const std::vector<char>& fixed = m_problem->fixed();
  double res = 0.0;
  for (Index d = 0; d < m_q.size(); ++d)
    if (!fixed[d]) {
      const double f = m_force_scale[d] * m_update_gradient[d];
      res += f * f;
    }
  if (debug_newton()) {
    Index worst = 0;
    double worst_f = -1.0;
    for (Index g = 0; g < m_model.num_nodes(); ++g) {
      double f2 = 0.0;
      for (Index d = g * kNodeDofs; d < g * kNodeDofs + 3; ++d)
        if (!fixed[d]) f2 += std::pow(m_force_scale[d] * m_update_gradient[d], 2);
      if (f2 > worst_f) worst_f = f2, worst = g;
    }
    if (const int f = m_model.fiber_of_node(worst); f >= 0)
      fmt::print(stderr, " residual with the new normals: largest force on a node {:.3e} N, fiber \"{}\" node {}\n",
                 std::sqrt(worst_f), m_model.fibers[f].name, worst - m_model.fibers[f].first_node);
  }
  return std::sqrt(res) / std::max(settling_reference(), 1e-300);
}

double StaticSolver::drag_residual(DragPart part) const {
  return m_problem->drag_force_norm(m_q, m_force_scale, part) / std::max(settling_reference(), 1e-300);
}

void StaticSolver::loosen_tolerance(double loose) {
  m_newton_tolerance = std::max(m_newton_tolerance, loose);
}

bool StaticSolver::equilibrium(std::vector<double>& history, int& iterations, double& residual) {
  iterations = 0;
  // The lagged quantities updated between minimizations within an increment (the bindings'
  // multipliers and anchors, BindingTerm::update_lagged); the contact's are updated around
  // this loop, by solve_increment.
  m_problem->begin_lagged(m_q);
  for (int update = 0;; ++update) {
    int its = 0;
    const bool ok = newton(history, its, residual);
    iterations += its;
    if (!ok) return false;
    // A test's first loading increment: the drag force its first minimization leaves is the
    // one the increment is expected to leave (solve_increment).
    if (m_tolerance_from_drag) {
      m_tolerance_from_drag = false;
      loosen_tolerance(m_case.solver.method.test_inexact * drag_residual(DragPart::Positions));
    }
    // The bindings are held as exactly as the solve's residual and correction: their tolerance
    // (a length, like the correction's) is scaled by the solve's loosening(). Held to
    // binding_tolerance in the weave's and relax's pseudo-time increments (residual 1e-6 of the
    // reference force), the 2 x 2 weave of the paper's 48-fiber tows made 52 binding updates
    // instead of 16, each a solve of its own (358 Newton iterations instead of 322), for the
    // same crimps and curve to 1e-4.
    const double tolerance = m_case.solver.binding_tolerance * m_model.length_scale * loosening();
    if (m_problem->update_lagged(m_q, {tolerance, m_newton_tolerance * m_reference_force})) return true;
    ++m_binding_updates;
    ++m_stats.binding_updates;
    if (update >= m_case.solver.max_binding_updates) return false;
  }
}

void StaticSolver::print_indefinite_tangent(double shift, double mean_diag) {
  fmt::print(stderr, "  indefinite tangent (shift {:.2e}); local Hessians:\n{}", shift, m_problem->local_spectra(m_q));
  const Index n = m_q.size();
  const VecX v = inverse_iteration(30);
  VecX hv(n);
  std::vector<VecX> scratch;
  symmetric_multiply(m_problem->pattern(), m_hessian, 0.0, v, hv, scratch);
  fmt::print(stderr, "  softest mode: v.Hv = {:.3e} (mean diagonal {:.3e}); largest components:", v.dot(hv), mean_diag);
  std::vector<Index> order(n);
  std::iota(order.begin(), order.end(), Index{0});
  const Index shown = std::min<Index>(n, 12);
  std::partial_sort(order.begin(), order.begin() + shown, order.end(),
                    [&](Index a, Index b) { return std::abs(v[a]) > std::abs(v[b]); });
  const BlockPattern& p = m_problem->pattern();
  for (Index i = 0; i < shown; ++i) {
    const Index g = p.group_of_dof(order[i]);
    fmt::print(stderr, " {:.3f}@{}.{}", v[order[i]], g, order[i] - p.group_dof(g));
  }
  fmt::print(stderr, "\n");
}

VecX StaticSolver::inverse_iteration(int iterations) {
  const std::vector<char>& fixed = m_problem->fixed();
  const Index n = m_q.size();
  VecX v = VecX::Ones(n), x(n);
  for (int it = 0; it <= iterations; ++it) {
    for (Index d = 0; d < n; ++d)
      if (fixed[d]) v[d] = 0.0;
    v /= v.norm();
    if (it == iterations) break;
    m_linear->solve(v, x);
    v = x;
  }
  return v;
}

double StaticSolver::softest_mode(int iterations, VecX& mode) {
  // In the dofs' own coordinates, where the factor's shift is uniform, so the iteration finds
  // H's most negative mode when there is one; then scaled to unit length in weighed coordinates
  // u = L q (L = m_length_scale).
  const VecX v = inverse_iteration(iterations);
  mode = v / v.cwiseProduct(m_length_scale).norm();
  VecX hv(v.size());
  std::vector<VecX> scratch;
  symmetric_multiply(m_problem->pattern(), m_hessian, 0.0, mode, hv, scratch);
  return mode.dot(hv);
}

StallDiagnosis StaticSolver::diagnose_stall(const VecX& failed) {
  StallDiagnosis diag;
  diag.made = true;
  const std::vector<char>& fixed = m_problem->fixed();
  const Index n = m_q.size();
  VecX motion = failed - m_q;
  for (Index d = 0; d < n; ++d)
    if (fixed[d]) motion[d] = 0.0;
  if (motion.allFinite()) diag.largest_motion = describe_motion(m_model, motion, m_length_scale);
  // The tangent at the last equilibrium, factorized (shifted until a factor passes when it is
  // not positive definite: the inverse iteration needs a factor, whatever the tangent).
  m_problem->evaluate(m_q, &m_gradient, &m_hessian);
  const BlockPattern& p = m_problem->pattern();
  double mean_diag = 0.0;
  Index free = 0;
  for (Index d = 0; d < n; ++d)
    if (!fixed[d]) {
      mean_diag += std::abs(m_hessian[p.col_ptr()[d + 1] - 1]);
      ++free;
    }
  if (free == 0) return diag;
  mean_diag /= free;
  double shift = 0.0;
  FactorStatus st = m_linear->factorize(m_hessian, shift);
  const bool definite = st == FactorStatus::Ok;
  while (st == FactorStatus::NotPositiveDefinite && shift < 1e3 * mean_diag) {
    shift = shift == 0.0 ? 1e-12 * mean_diag : shift * 10.0;
    st = m_linear->factorize(m_hessian, shift);
  }
  if (st != FactorStatus::Ok) return diag;
  VecX mode;
  diag.softest_stiffness = softest_mode(40, mode);
  diag.softest_mode = describe_motion(m_model, mode, m_length_scale);
  // A stiffness is zero next to the softest thing the model holds: its most flexible fiber
  // bent as a whole cantilever, 3 E I / L^3 (the mean diagonal is no scale: on a fiber of
  // L/r = 1000 bending is 1e-10 of it); zero is a millionth of that. A factorization that
  // fails proves the tangent indefinite, whatever the inverse iteration found.
  double bending = std::numeric_limits<double>::infinity();
  for (const Fiber& f : m_model.fibers) {
    const Section& sec = m_model.sections[f.section];
    bending = std::min(bending, 3.0 * m_model.materials[f.material].young * std::min(sec.inertia_1, sec.inertia_2) /
                                    std::pow(f.length, 3));
  }
  diag.bending_stiffness = bending;
  const double zero = 1e-6 * bending;
  if (std::abs(diag.softest_stiffness) <= zero)
    diag.tangent = StallDiagnosis::Tangent::Singular;
  else if (!definite || diag.softest_stiffness < 0.0)
    diag.tangent = StallDiagnosis::Tangent::Indefinite;
  else
    diag.tangent = StallDiagnosis::Tangent::Definite;
  return diag;
}

void StaticSolver::begin_factor() {
  m_cg_excess = 0;
  m_fresh_cg = -1;
  m_krylov_budget =
      krylov_budget(m_case.solver.method.krylov_iterations, m_linear->factor_flops(), m_linear->factor_nonzeros());
}

void StaticSolver::pattern_changed() {
  m_linear->analyze(m_problem->pattern());
  m_saddle_analyzed = false;
}

bool StaticSolver::factorize_indefinite() {
  if (!m_saddle) m_saddle = make_indefinite_solver();
  if (!m_saddle_analyzed) {
    m_saddle->analyze(m_problem->pattern());
    m_saddle_analyzed = true;
  }
  ++m_stats.factorizations;
  return m_saddle->factorize(m_hessian, 0.0) == FactorStatus::Ok;
}

int StaticSolver::tangent_negative_pivots() {
  // A held load step's settled increment is an equilibrium without its drag (its force below
  // the held tolerance of the load): its stability is that of the tangent without the drag,
  // whose factor then preconditions nothing (the next increment's tangent holds the drag).
  const double drag = m_problem->drag();
  m_problem->set_drag_stiffness(0.0);
  m_problem->evaluate(m_q, nullptr, &m_hessian);
  const auto t0 = std::chrono::steady_clock::now();
  ++m_stats.factorizations;
  const bool definite = m_linear->factorize(m_hessian, 0.0) == FactorStatus::Ok;
  begin_factor();
  m_reuse_factor = definite && drag == 0.0;
  if (m_reuse_factor) record_factor_source(0.0);
  else m_factor_source.valid = false;
  const int negative = definite ? 0 : factorize_indefinite() ? static_cast<int>(m_saddle->negative_pivots()) : -1;
  m_stats.time_factorization += seconds_since(t0);
  m_problem->set_drag_stiffness(drag);
  return negative;
}

bool StaticSolver::newton(std::vector<double>& history, int& iterations, double& residual) {
  const SolverSpec& opt = m_case.solver;
  const std::vector<char>& fixed = m_problem->fixed();
  const Index n = m_q.size();
  VecX r(n), dq(n), trial(n);
  const double length = m_model.length_scale;
  double last_step = std::numeric_limits<double>::infinity();
  bool prev_small_step = false;
  bool damped = false;  // the last step came from a factorization with a non-negligible shift
  // In increments with a drag (weave, relax and tests), whose energy the drag makes convex, the
  // line search is on from the first iteration (see below).
  const bool searching = opt.method.line_search && m_problem->drag() > 0.0;
  bool shortened = false;  // the line search shortened a step of this solve
  bool spectra_printed = false;
  // Floor for the reference force: the force that strains the stiffest fiber by 1e-5. Round-off
  // in the internal forces is about eps * E A per dof, so residuals relative to a smaller
  // reference (an unloaded step) could never converge.
  const size_t first = history.size();  // this solve's residuals start here
  double force_floor = 0.0;
  for (const Fiber& f : m_model.fibers)
    force_floor = std::max(force_floor, m_model.materials[f.material].young * m_model.sections[f.section].area);
  force_floor *= 1e-5;

  m_problem->evaluate(m_q, &m_gradient, &m_hessian);
  for (iterations = 0;; ++iterations) {
    if (debug_interrupt_iteration() == m_stats.iterations + 1) interrupt_flag() = true;  // tests of --resume
    if (interrupt_flag().load()) return false;
    // Residual on free dofs and reference force (external loads and reactions).
    double ext = 0.0, react = 0.0, res = 0.0;
    for (Index d = 0; d < n; ++d) {
      const double s = m_force_scale[d];
      if (fixed[d]) {
        react += (s * m_gradient[d]) * (s * m_gradient[d]);
        r[d] = 0.0;
      } else {
        r[d] = m_gradient[d];
        res += (s * r[d]) * (s * r[d]);
      }
      ext += (s * m_problem->forces()[d]) * (s * m_problem->forces()[d]);
    }
    const double fref = std::max({std::sqrt(ext), std::sqrt(react), force_floor});
    m_reference_force = fref;
    m_load_force = std::max({std::sqrt(ext), std::sqrt(react), 1e-3 * force_floor});
    if (debug_newton()) {
      Index wr = 0;
      for (Index d = 0; d < n; ++d)
        if (std::abs(m_force_scale[d] * r[d]) > std::abs(m_force_scale[wr] * r[wr])) wr = d;
      fmt::print(stderr, "  it {:2d} largest residual {:.3e} N at dof {} (group {}, component {}), reference {:.3e} N\n",
                 iterations, m_force_scale[wr] * r[wr], wr, m_problem->pattern().group_of_dof(wr),
                 wr < m_model.node_dofs ? wr % 9 : (wr - m_model.node_dofs) % 6, fref);
    }
    residual = std::sqrt(res) / fref;
    history.push_back(residual);
    if (!std::isfinite(residual)) return false;
    const double tolerance = m_newton_tolerance;
    const bool small_step = last_step <= opt.displacement_tolerance * loosening() * length;
    // Converged: residual and correction small; or no correction needed at all.
    if (residual <= tolerance && (small_step || iterations == 0)) return true;
    // Round-off floor: on slender fibers the residual cannot fall below about eps times the
    // section stiffness forces. Two successive negligible corrections with a residual that no
    // longer falls and is near the tolerance mean the solution is as exact as doubles allow.
    const size_t h = history.size();
    // (Not after a shifted factorization: its steps are damped, small by construction.)
    if (small_step && prev_small_step && !damped && h >= 2 && history[h - 1] > 0.5 * history[h - 2] &&
        residual <= 1e3 * tolerance) {
      ++m_stats.roundoff_convergences;
      return true;
    }
    prev_small_step = small_step;
    if (iterations >= opt.max_iterations * m_iteration_factor) return false;
    if (iterations >= 4 && residual > 1e6 * history.front() && history.front() > 0) return false;

    // Solve H dq = -r. First by conjugate gradients preconditioned with the last factorization
    // (of an earlier tangent, maybe of another contact pattern), when there is one of the
    // unshifted tangent and the last such solve was quick; else, or when they do not converge
    // within the CG budget (krylov_budget, set at each factorization), factorize (shifted if
    // the tangent is not positive definite, which conjugate gradients may not notice).
    auto t0 = std::chrono::steady_clock::now();
    double shift = 0.0;
    bool solved = false;
    m_rhs = -r;
    if (m_krylov_budget > 0 && m_reuse_factor && m_linear->has_factor()) {
      // Inexact Newton: CG's relative residual times this residual is the residual the step
      // would leave were the energy quadratic, so a step need not be solved beyond half the
      // tolerance (at most to a tenth, at least to method.krylov_tolerance, 1e-3, as far from
      // it). The last iteration of a solve, whose residual is within a few times the tolerance,
      // so stops after a few CG iterations instead of going on to 1e-3 (docs/theory/solver.md,
      // "Reusing the factorization").
      // Pseudo-time increments (the weave's, and the relax and test increments whose normals
      // and cones are lagged) stop CG at 3e-2 instead (method.krylov_tolerance_pseudo): their
      // state is a step of the proximal sequence, every step is searched along on a potential
      // the drag makes convex, and the lagged normals and cones, not the linear solve, set how
      // fast the sequence goes. On three 1.25-degree levels of the 480-fiber plain shear: 658
      // CG iterations against 902, 76 Newton iterations against 73, the same 15
      // factorizations, 206 s against 228 s, the shear forces within 0.1 %. Increments whose
      // state is an equilibrium (load steps, settling increments, releases: the points of the
      // curves) keep 1e-3, and so do a held load step's: a load step's full Newton steps
      // converge quadratically (at 3e-2 the helix pulled straight took 1,215 iterations against
      // 763, the corpus's unheld three-point bending, a held load step, 23,992 against 86;
      // docs/performance.md, "Reusing factorizations").
      const double floor = m_pseudo_time ? opt.method.krylov_tolerance_pseudo : opt.method.krylov_tolerance;
      const double forcing = std::clamp(0.5 * tolerance / residual, floor, 0.1);
      // Iterations to 1e-3-equivalent ones (the factor's age, below): CG's residual falls about
      // geometrically, so iterations scale with the decades gained.
      const double to_aged = std::log(opt.method.krylov_tolerance) / std::log(std::max(forcing, 1e-300));
      // A solve that would take more than half the budget (in aged iterations) makes the next
      // iteration factorize anyway: CG gives it up as soon as its rate shows it would take more
      // than three quarters (the rate of its last iterations underestimates CG's later
      // speed-up), and this iteration factorizes instead of paying for the rest of it
      // (docs/theory/solver.md, "Reusing the factorization").
      const int abandon_beyond = std::max(1, static_cast<int>(std::floor(0.75 * m_krylov_budget / to_aged)));
      const PcgResult cg = pcg(
          m_problem->pattern(), m_hessian, 0.0, m_rhs, dq, [this](const VecX& b, VecX& x) { m_linear->precondition(b, x); },
          m_force_scale, forcing, m_krylov_budget, m_pcg, abandon_beyond);
      m_stats.krylov_iterations += cg.iterations;
      solved = cg.converged;
      if (debug_newton()) {
        // The relative residual at the start, every 10 iterations and at the end.
        std::string trace;
        const std::vector<double>& trail = m_pcg.history;
        for (size_t i = 0; i < trail.size(); ++i)
          if (i % 10 == 0 || i + 1 == trail.size()) trace += fmt::format(" {:.1e}", trail[i]);
        fmt::print(stderr, "  it {:2d} conjugate gradients: {} iterations, {} to {:.1e} ({:.2f} s); residual{}\n",
                   iterations, cg.iterations,
                   cg.converged   ? "converged"
                   : cg.breakdown ? "broke down"
                   : cg.abandoned ? "abandoned"
                                  : "not converged",
                   forcing, seconds_since(t0), trace);
      }
      if (solved) ++m_stats.reused_factorizations;
      // A slow solve (more than half of the CG budget): the factor has aged, the next
      // iteration makes a new one. So also once the solves since the last factorization took,
      // beyond the iterations of the first solve after it, the budget in all (the price of a
      // factorization in iterations, 100 on the 480-fiber tests): there a level's
      // settling solves took 32-54 iterations each with an aged factor against 3-15 with a
      // fresh one, seven solves in a row below the per-solve threshold.
      // (Counted in iterations, not seconds: the solver's path stays the same from run to run.)
      // The factor's age is judged on the iterations the solve would have taken to 1e-3.
      const int aged = static_cast<int>(std::lround(cg.iterations * to_aged));
      if (solved) {
        if (m_fresh_cg < 0) m_fresh_cg = aged;
        m_cg_excess += std::max(0, aged - m_fresh_cg);
      }
      m_reuse_factor = solved && 2 * aged <= m_krylov_budget && m_cg_excess < m_krylov_budget;
      m_stats.time_solve += seconds_since(t0);
    }
    if (!solved) {
      t0 = std::chrono::steady_clock::now();
      double mean_diag = 0.0;
      for (Index d = 0; d < n; ++d) mean_diag += std::abs(m_hessian[m_problem->pattern().col_ptr()[d + 1] - 1]);
      mean_diag /= std::max<Index>(n, 1);
      // Unshifted first, always: a shift left on once the tangent is positive again damps the
      // steps along its softest modes, and a solve then stops on small steps short of the
      // solution (a body turned by a moment ended 4e-5 off its angle). When a shift is needed,
      // the search starts at a hundredth of the last one, not at 1e-14 of the mean diagonal: a
      // tangent that needed a shift needs about as much at the next iteration. On the
      // 480-fiber twill's shear (a body's free turn about z slightly negative through its
      // bindings, -2.5 against a mean diagonal of 2.7e6) each shifted iteration went through
      // 0, 1e-14, ..., 1e-6 of the mean diagonal: up to 6 factorizations, 27 s against 8 s
      // (docs/performance.md, "Shifted factorizations").
      FactorStatus st = m_linear->factorize(m_hessian, shift);
      ++m_stats.factorizations;
      if (st == FactorStatus::Ok) m_run.project_hessians = true;
      // Not positive definite: in a load step the tangent factorized as it is (below);
      // otherwise, or when it is singular, first the terms' local Hessians projected where
      // they are indefinite (a compressed fiber's element, a moment on a turned section, a
      // turned body pulled by its members, (lambda + k g) . d2g), then, if that is not enough,
      // the shift. A moment-driven twist of a bound body
      // (BindingGroup.TwistedByItsBodyThenOneMemberPushedAside) took 39 factorizations, none
      // shifted, against 61 with shifts alone (33 shifted) for the same 42 iterations. Only
      // when the exact tangent is refused: projected at every iteration, the twist's tangent
      // lost the negative curvature its members' beams balance, and it took 2,324 iterations
      // and ended 1.2e-5 rad off its angle.
      bool projected = false;
      // A load step (no drag) follows its equilibrium path, stable or not: past a bifurcation
      // its tangent is indefinite and factorized as it is (LDL^T), and the step is Newton's own
      // (docs/theory/solver.md, "Unstable equilibria in load steps"). With shifted steps instead
      // the roll-ups free in 3D stopped near their lateral buckling moment, the residual falling
      // only linearly, after 400-540 Newton iterations; with exact ones they roll up to the full
      // circle in 112-233. A singular tangent (a mechanism) goes on to the projection and the
      // shift.
      bool saddle = false;
      if (st == FactorStatus::NotPositiveDefinite && m_problem->drag() == 0.0 && factorize_indefinite()) {
        saddle = true;
        st = FactorStatus::Ok;
      }
      if (st == FactorStatus::NotPositiveDefinite && m_run.project_hessians) {
        projected = m_problem->projected_hessian(m_q, m_hessian) > 0;
        if (projected) {
          st = m_linear->factorize(m_hessian, shift);
          ++m_stats.factorizations;
          // Not enough (a free spin, a mechanism): the next refused tangents go straight
          // to the shift until an exact one passes again. On the 2 x 2 fabrics of the corpus
          // the projected tangent was refused as well, a factorization in vain per shifted
          // iteration.
          if (st != FactorStatus::Ok) m_run.project_hessians = false;
        }
      }
      if (st == FactorStatus::NotPositiveDefinite) {
        const ShiftSearch search = factorize_shifted(*m_linear, m_hessian, mean_diag, m_last_shift);
        st = search.status;
        shift = search.shift;
        m_stats.factorizations += search.factorizations;
        m_stats.regularized_factorizations += search.factorizations;
      }
      m_stats.time_factorization += seconds_since(t0);
      if (st == FactorStatus::Ok && shift > 0.0) {
        m_last_shift = shift / mean_diag;
        ++m_stats.shifted_iterations;
      }
      if (saddle) ++m_stats.indefinite_iterations;
      begin_factor();
      if (debug_newton())
        fmt::print(stderr, "  it {:2d} factorized ({:.2f} s){}\n", iterations, seconds_since(t0),
                   projected ? ", the indefinite local Hessians projected"
                   : saddle  ? fmt::format(", indefinite ({} negative pivots)", m_saddle->negative_pivots())
                             : std::string());
      m_stats.factor_nonzeros = m_linear->factor_nonzeros();
      if (st != FactorStatus::Ok) return false;
      if (shift > 0.0 && debug_newton() && !spectra_printed) {
        spectra_printed = true;  // once per solve
        print_indefinite_tangent(shift, mean_diag);
      }
      // Only the factor of a (nearly) unshifted tangent preconditions later iterations.
      m_reuse_factor = shift <= 1e-10 * mean_diag && !projected && !saddle;
      if (m_reuse_factor) record_factor_source(shift);
      else m_factor_source.valid = false;
      damped = !m_reuse_factor && !saddle;
      t0 = std::chrono::steady_clock::now();
      (saddle ? *m_saddle : *m_linear).solve(m_rhs, dq);
      m_stats.time_solve += seconds_since(t0);
    }
    for (Index d = 0; d < n; ++d)
      if (fixed[d]) dq[d] = 0.0;
    ++m_stats.iterations;

    // Increments with a drag: every step descends. The backtracking line search (Armijo, on the
    // total potential compared from the current state) holds each step to a decrease of the
    // energy, which the drag makes convex, from the first iteration, and far above the
    // equilibrium tolerance only (near it the energy's change is round-off). A full step on the
    // frozen friction energy, only C1, cycles between stick and slip: on the 3 x 3 x 16 plain
    // weave sheared to 25 degrees in 5 levels, a level's loading solve moved one node by the
    // step limit back and forth (its residual +0.15 N, -0.13 N, +0.15 N, ...) until a rise
    // turned the search on; from the first iteration the shear took 191 Newton iterations and
    // 48 factorizations against 285 and 80 (231 and 51 against 337 and 73 at a tolerance of
    // 5e-4, the curves within 1 % but at the last level, where the path of the friction slips
    // moves them by a few percent either way), and its equibiaxial test the same 82 iterations,
    // no step shortened (docs/performance.md, "Line search").
    // Without a drag (load steps) full Newton steps go on while the residual falls: linearized
    // rotations stretch the section vectors, so a good step can raise the energy for one
    // iteration, and on a body twisting its binding group
    // (BindingGroup.TwistedByItsBodyThenOneMemberPushedAside: indefinite tangents) damped steps
    // failed increments that full steps pass. There the line search is a safeguard for the
    // iterations where the residual rose after the fourth, or made no progress over three (far
    // above the tolerance).
    // Rises are counted within this solve only: a binding update or new normals between two
    // solves of an increment raise the residual by design.
    const size_t k = history.size();
    const bool search_step =
        (searching && history[k - 1] > 1e3 * opt.residual_tolerance) || (k >= first + 4 && history[k - 1] > history[k - 2]) ||
        (k >= first + 7 && history[k - 1] > 1e3 * m_newton_tolerance &&
         history[k - 1] > 0.9 * std::min({history[k - 2], history[k - 3], history[k - 4]}));
    m_problem->set_energy_base(m_q);
    // The slope of the full Newton step, before the limit below: the sufficient decrease asked
    // of a limited step is that of the full step's slope (docs/performance.md, "Alternatives
    // measured and not used").
    const double s0 = dq.dot(r);
    double alpha = 1.0;
    // With contact, no node moves more than a fraction of the smallest radius per iteration:
    // a fiber that nothing holds yet (zero contact stiffness at first touch, a member free in
    // its averaged binding) gets a huge linearized step that would jump through its
    // neighbours; limited, it moves until contact stiffens it.
    // (The contact term's bound, ContactTerm::step_bound.)
    if (const double bound = m_problem->step_bound(m_q, dq); bound < 1.0) {
      dq *= bound;
      ++m_stats.limited_steps;
    }
    trial = m_q + dq;
    if (opt.method.line_search && search_step && s0 < 0.0) {
      const double e0 = m_problem->evaluate(m_q, nullptr, nullptr);
      const double noise = 1e-11 * std::abs(e0) + 1e-14 * std::abs(s0);
      const StepLength found = search_step_length(
          [&](double a) {
            trial = m_q + a * dq;
            return m_problem->evaluate(trial, nullptr, nullptr);
          },
          e0, s0, noise);
      alpha = found.alpha;
      m_stats.line_search_trials += found.trials;
      if (alpha != 1.0) trial = m_q + alpha * dq;
      if (alpha < 1.0 && debug_newton())
        fmt::print(stderr, "  it {:2d} step shortened to {:.3f}; the full step's energy by term:\n{}", iterations, alpha,
                   m_problem->step_energies(m_q, dq));
      // The contact elements whose exact model fell below their energy along the full step get
      // a tangent above it (docs/theory/contact.md, "A tangent above the contact energy").
      if (alpha < 1.0 && m_adaptive_tangent) {
        const Index marked = m_problem->mark_overshoots(m_q, dq);
        if (debug_newton() && marked > 0)
          fmt::print(stderr, "  it {:2d} {} contact elements take the tangent above their energy\n", iterations, marked);
      }
      if (alpha < 1.0 && !shortened) {
        shortened = true;
        ++m_stats.searched_solves;
      }
    }
    m_problem->evaluate(trial, &m_gradient, &m_hessian);
    m_q = trial;
    last_step = 0.0;
    Index worst = 0;
    for (Index d = 0; d < n; ++d)
      if (std::abs(alpha * dq[d]) * m_length_scale[d] > last_step) {
        last_step = std::abs(alpha * dq[d]) * m_length_scale[d];
        worst = d;
      }
    if (debug_newton())
      fmt::print(stderr, "  it {:2d} residual {:.3e} shift {:.2e} alpha {:.3f} step {:.3e} at dof {} (group {}) drag {:.2e}\n",
                 iterations, residual, shift, alpha, last_step, worst, m_problem->pattern().group_of_dof(worst),
                 m_problem->drag());
  }
}

void StaticSolver::test_conditions(int step, std::map<Index, std::pair<double, double>>& disp) const {
  // METHOD §7. The fabric's edge bodies are driven from where they are at the step's start:
  // strains and angles are measured from there, not from the flat starting assembly
  // (steps/test_edges.hpp).
  if (!m_edges) throw std::logic_error("StaticSolver: a test step without edge bodies (resolve_case checks it)");
  TestEdges edges = *m_edges;
  auto u = [&](Index d) { return m_q[d] - m_model.reference[d]; };
  // Every component held where it is; the test's conditions then drive some and free others.
  for (int e = 0; e < 4; ++e) {
    const Index d0 = edges.first_dof[e];
    const Vec3 rotation = m_bodies->rotation(edges.body[e], m_q);
    for (int k = 0; k < 3; ++k) {
      disp[d0 + k] = {u(d0 + k), u(d0 + k)};
      disp[d0 + 3 + k] = {rotation[k], rotation[k]};
    }
  }
  edges.lx = m_q[edges.first_dof[1]] - m_q[edges.first_dof[0]];
  edges.ly = m_q[edges.first_dof[3] + 1] - m_q[edges.first_dof[2] + 1];
  test_edge_conditions(m_case.steps[step], edges, m_program->force_end, disp);
}

void StaticSolver::predict_test_level(int step, double lambda) {
  const VecX before = m_q;  // once per load level
  apply(step, lambda);
  fibra::predict_test_level(m_model, m_bodies.get(), m_edges ? &*m_edges : nullptr, m_case.steps[step],
                            m_program->disp, m_problem->fixed(), before, m_q);
}

SolverState StaticSolver::save_state(const std::string& step, int steps_done) const {
  SolverState s;
  s.model = fingerprint(m_model, m_bodies ? m_bodies->num_bindings() : 0);
  s.reference = m_model.reference;
  s.step = step;
  s.steps_done = steps_done;
  s.q = m_q;
  if (m_bodies) s.bodies = m_bodies->snapshot();
  if (m_contact) s.contacts = m_problem->contacts();
  s.force_end = m_program->force_end;
  s.moments = m_program->moments;
  s.disp = m_program->disp;
  s.test_drag = m_test_drag;
  return s;
}

void StaticSolver::restore_state(const SolverState& s) {
  // A resolved state (resolve_case: check_state_fits, and the bodies' restore tried on a copy).
  if (!(s.model == fingerprint(m_model, m_bodies ? m_bodies->num_bindings() : 0)))
    throw std::logic_error("StaticSolver::restore_state: a state of another model (resolve_case checks it)");
  m_q = s.q;
  if (m_bodies) {
    m_bodies->restore(s.bodies);
  }
  if (m_contact && m_problem->set_contacts(s.contacts, m_contact->friction())) pattern_changed();
  m_program->force_start = m_program->force_end = s.force_end;
  m_program->moments = s.moments;
  m_program->disp = s.disp;
  m_test_drag = s.test_drag;
}

void StaticSolver::begin_step(int step) {
  Program& p = *m_program;
  const StepSpec& st = m_case.steps[step];
  const size_t s = static_cast<size_t>(step);
  // Start values: where the previous step ended. End values: listed entries replace.
  p.force_start = p.force_end;
  std::map<Index, Vec3> moment_end;
  for (auto& [node, se] : p.moments) moment_end[node] = se.second;
  std::map<Index, std::pair<Vec3, Vec3>> moments;
  for (auto& [node, m] : moment_end) moments[node] = {m, m};
  std::map<Index, Vec3> listed_force, listed_moment;
  for (size_t i = 0; i < st.loads.size(); ++i) {
    const Index node = m_model.node_index(st.loads[i].node, m_case.file, fmt::format("step[{}].load[{}]", s, i));
    // Vec3 has no zero default: start each listed node explicitly at zero.
    listed_force.try_emplace(node, Vec3::Zero()).first->second += st.loads[i].force;
    listed_moment.try_emplace(node, Vec3::Zero()).first->second += st.loads[i].moment;
  }
  for (auto& [node, f] : listed_force) p.force_end.segment<3>(9 * node) = f;
  for (auto& [node, m] : listed_moment) {
    auto it = moments.find(node);
    const Vec3 start = it == moments.end() ? Vec3::Zero() : it->second.first;
    moments[node] = {start, m};
  }
  p.moments = moments;
  std::map<Index, std::pair<double, double>> disp;
  for (auto& [dof, se] : p.disp) disp[dof] = {se.second, se.second};
  for (size_t i = 0; i < st.displacements.size(); ++i) {
    const DisplacementSpec& ds = st.displacements[i];
    const Index node = m_model.node_index(ds.node, m_case.file, fmt::format("step[{}].displacement[{}]", s, i));
    for (int k = 0; k < 3; ++k) {
      const Index dof = 9 * node + k;
      if (!ds.value[k]) {
        disp.erase(dof);
        continue;
      }
      const double start = m_q[dof] - m_model.reference[dof];
      disp[dof] = {start, *ds.value[k]};
    }
  }
  for (size_t i = 0; i < st.bodies.size(); ++i) {
    const BodyStepSpec& bs = st.bodies[i];
    const int b = m_model.body_index(bs.name);
    const Index d0 = m_model.bodies[b].first_dof;
    for (int k = 0; k < 3; ++k) {
      if (bs.has_displacement) {
        if (bs.displacement[k])
          disp[d0 + k] = {m_q[d0 + k] - m_model.reference[d0 + k], *bs.displacement[k]};
        else
          disp.erase(d0 + k);
      }
      if (bs.has_rotation) {
        if (bs.rotation[k])
          disp[d0 + 3 + k] = {m_bodies->rotation(b, m_q)[k], *bs.rotation[k]};
        else
          disp.erase(d0 + 3 + k);
      }
    }
    if (bs.force) p.force_end.segment<3>(d0) = *bs.force;
    if (bs.moment) p.force_end.segment<3>(d0 + 3) = *bs.moment;
  }
  if (st.is_test()) test_conditions(step, disp);
  p.disp = disp;

}

void StaticSolver::record_factor_source(double shift) {
  FactorSource& f = m_factor_source;
  f.valid = true;
  f.q = m_q;
  f.bodies = m_bodies ? m_bodies->snapshot() : std::vector<double>{};
  f.contacts = m_problem->contacts();
  f.marked = m_problem->marked_contacts();
  f.friction = m_problem->friction();
  f.drag = m_problem->drag_settings();
  f.moments = m_problem->moments();
  f.fixed = m_problem->fixed();
  f.shift = shift;
}

void StaticSolver::refactorize(const FactorSource& f) {
  // The problem as it is, put back after.
  const LaggedStates lagged = m_problem->save_lagged();
  const DragSettings drag = m_problem->drag_settings();
  const std::vector<NodalMoment> moments = m_problem->moments();
  const std::vector<char> fixed = m_problem->fixed();
  // The problem as the factorization saw it (a checkpoint's record of it).
  if (m_bodies) m_bodies->restore(f.bodies);
  if (m_contact && m_problem->set_contacts(f.contacts, f.friction)) pattern_changed();
  if (m_contact && !f.marked.empty()) m_problem->set_marked_contacts(f.marked);
  m_problem->set_drag(f.drag);
  m_problem->moments() = f.moments;
  m_problem->fixed() = f.fixed;
  m_problem->evaluate(f.q, nullptr, &m_hessian);
  const bool ok = m_linear->factorize(m_hessian, f.shift) == FactorStatus::Ok;
  if (m_problem->restore_lagged(lagged)) pattern_changed();
  m_problem->set_drag(drag);
  m_problem->moments() = moments;
  m_problem->fixed() = fixed;
  m_factor_source = f;
  // It factorized before; should it not now, the next solve factorizes afresh.
  if (!ok) {
    m_reuse_factor = false;
    m_factor_source.valid = false;
  }
}

SolverProgress StaticSolver::progress() const {
  SolverProgress p = m_run;
  p.force_start = m_program->force_start;
  p.last_shift = m_last_shift;
  p.reference_force = m_reference_force;
  p.reuse_factor = m_reuse_factor && m_linear->has_factor() && m_factor_source.valid;
  p.krylov_budget = m_krylov_budget;
  p.cg_excess = m_cg_excess;
  p.fresh_cg = m_fresh_cg;
  p.iteration_factor = m_iteration_factor;
  p.stats = m_stats;
  if (p.reuse_factor) p.factor = m_factor_source;
  if (m_contact) p.detection_memory = m_contact->detection_memory();
  return p;
}

void StaticSolver::resume(const SolverState& state, const SolverProgress& p) {
  if (p.step < 0 || p.step >= static_cast<int>(m_case.steps.size()))
    throw std::logic_error("StaticSolver::resume: a checkpoint of another case (resume_run checks it)");
  restore_state(state);
  m_run = p;
  m_run.factor = FactorSource{};  // (kept in m_factor_source and the detector, not here)
  m_run.detection_memory.clear();
  m_program->force_start = p.force_start;
  m_last_shift = p.last_shift;
  m_reference_force = p.reference_force;
  m_krylov_budget = p.krylov_budget;
  m_cg_excess = p.cg_excess;
  m_fresh_cg = p.fresh_cg;
  m_iteration_factor = p.iteration_factor;
  m_stats = p.stats;
  m_reuse_factor = p.reuse_factor && p.factor.valid;
  if (m_contact && !p.detection_memory.empty()) m_contact->set_detection_memory(p.detection_memory);
  if (m_reuse_factor) refactorize(p.factor);
  m_resumed = true;
}

bool StaticSolver::release_positions(int step, double lambda, int& iterations) {
  // What the increment left, put back should the release not converge.
  const VecX q = m_q, gradient = m_gradient;
  const LaggedStates lagged = m_problem->save_lagged();
  const ContactStats contact_stats = m_contact_stats;
  const int binding_updates = m_binding_updates;
  const double reference = m_reference_force;
  const DragSettings drag = m_problem->drag_settings();
  // The same increment (its start, its drag's anchor), from its solution with the drag.
  std::vector<double> history;
  double residual = 0.0;
  // A relax step's release gets four times max_iterations, as an increment with nothing to cut
  // does (run()): it starts within the step's tolerance of equilibrium and has no load to cut,
  // but what the drag held may move far under the step bound. On an 8 x 8 satin 8 of 3-fiber
  // tows the release moved nodes by half a radius per iteration for 14 iterations, then
  // converged in 56 (residual 1e-3 at the 25th). A test level's release, repeated at every
  // level, keeps max_iterations: a level whose release fails keeps its dragged state, settled
  // to the step's tolerance.
  const int iteration_factor = m_iteration_factor;
  if (!m_mode.test) m_iteration_factor = 4;
  const bool ok = solve_increment(step, lambda, history, iterations, residual, true);
  m_iteration_factor = iteration_factor;
  // The factorizations of this solve had no drag on the positions: none preconditions the next
  // step's solves (a checkpoint records the drag's weights without it, so a resumed run could
  // not make it again).
  m_reuse_factor = false;
  m_factor_source.valid = false;
  if (debug_newton())
    fmt::print(stderr, " relax end without the drag on positions: {} ({} Newton iterations, residual {:.3e})\n",
               ok ? "converged" : "did not converge, the dragged state kept", iterations, residual);
  if (ok) {
    m_binding_updates += binding_updates;
    return true;
  }
  m_q = q;
  m_gradient = gradient;
  if (m_problem->restore_lagged(lagged)) pattern_changed();
  m_problem->set_drag(drag);
  m_contact_stats = contact_stats;
  m_binding_updates = binding_updates;
  m_reference_force = reference;
  m_run.normals_settled = true;
  m_refusal.clear();
  return false;
}

// What a step driver asks of the solver (steps/step_driver.hpp).
class StaticSolver::DriverHost final : public StepHost {
 public:
  explicit DriverHost(StaticSolver& solver) : m_s(solver) {}
  void move_free_dofs(const VecX& motion, double scale) override {
    const std::vector<char>& fixed = m_s.m_problem->fixed();
    for (Index d = 0; d < m_s.m_q.size(); ++d)
      if (!fixed[d]) m_s.m_q[d] += scale * motion[d];
  }
  void predict_test_level(double lambda) override { m_s.predict_test_level(m_s.m_run.step, lambda); }
  double drag_force_residual() const override { return m_s.drag_residual(DragPart::Positions); }
  void release_positions(double lambda, int& iterations) override {
    m_s.release_positions(m_s.m_run.step, lambda, iterations);
  }
  double penetration_over_cap() const override {
    return m_s.m_contact ? m_s.m_contact_stats.max_penetration_ratio / m_s.m_contact->spec().max_penetration : 0.0;
  }
  double test_drag() const override { return m_s.m_test_drag; }
  void set_test_drag(double drag) override { m_s.m_test_drag = drag; }
  double normal_feedback() const override {
    if (!m_s.m_contact) return 0.0;
    const std::vector<ContactElement>& elements = m_s.m_problem->contacts();
    const std::vector<ContactResponse>& responses = m_s.m_problem->contact_solution();
    double largest = 0.0;
    for (size_t e = 0; e < elements.size() && e < responses.size(); ++e) {
      const Particle &a = elements[e].a, &b = elements[e].b;
      const double distance = std::hypot(a.xi1, a.xi2) + std::hypot(b.xi1, b.xi2);
      if (distance > 0.0) largest = std::max(largest, responses[e].normal_force / distance);
    }
    return largest;
  }

 private:
  StaticSolver& m_s;
};

RunResult StaticSolver::run(const std::function<void(const IncrementInfo&, const VecX&)>& observer) {
  // A resumed run's wall time goes on from the checkpoint's.
  const auto t_start = std::chrono::steady_clock::now() -
                       std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                           std::chrono::duration<double>(m_resumed ? m_run.wall_time : 0.0));
  RunResult result;
  const SolverSpec& opt = m_case.solver;
  DriverHost host(*this);
  int& total = m_run.total;
  const size_t first_step = m_resumed ? static_cast<size_t>(m_run.step) : 0;
  if (!m_resumed) total = 0;
  for (size_t s = first_step; s < m_case.steps.size(); ++s) {
    const StepSpec& st = m_case.steps[s];
    const int step = static_cast<int>(s);
    // The rules of the step's increments (steps/step_driver.hpp): how each is sized,
    // predicted and judged, and when the step ends.
    const double k0 = m_contact ? m_contact->initial_stiffness() : 0.0;
    const std::unique_ptr<StepDriver> driver = StepDriver::make(st, opt, m_contact != nullptr, k0);
    // A resumed run goes on within its step as the checkpoint left it.
    const bool resumed = m_resumed;
    m_resumed = false;
    m_run.step = step;
    if (!resumed) {
      begin_step(step);
      m_run.weave_depth = -1.0;  // measured at the step's first detection
    }
    const double nominal = 1.0 / st.increments;
    const int max_increments = st.max_increments > 0 ? st.max_increments : 100 * st.increments;
    double& lambda = m_run.lambda;
    double& dl = m_run.dl;
    auto t_increment = std::chrono::steady_clock::now();
    int& done = m_run.done;
    int& attempts = m_run.attempts;
    // The first residual and load step of the last failed attempt at the current load factor.
    double& failed_first = m_run.failed_first;
    double& failed_dl = m_run.failed_dl;
    // Once a cut left the first residual unchanged, the load factor has nothing to cut until an
    // increment converges (cuts and retries no longer alternate on the same state).
    bool& uncuttable = m_run.uncuttable;
    // A failed run: the state at the last converged load factor, the attempt that failed.
    VecX& failed_state = m_run.failed_state;             // the last state of the last failed attempt
    std::string& failed_refusal = m_run.failed_refusal;  // why the contact loop refused it, if it did
    auto fail = [&](double attempted, const std::vector<double>& history, std::string message) {
      if (failed_state.size() == m_q.size()) {
        result.diagnosis = diagnose_stall(failed_state);
        result.diagnosis.refusal = failed_refusal;
      }
      result.status = RunResult::Status::Failed;
      result.step = st.name;
      result.load_factor = lambda;
      result.attempted_load_factor = attempted;
      result.residual_history = history;
      result.message = std::move(message);
      return result;
    };
    // The step may end once at full load (a relax: once relaxed; a test: its last level settled;
    // a weave with contact: its tows apart).
    bool& relaxed = m_run.relaxed;
    if (!resumed) {
      lambda = 0.0;
      dl = nominal;
      m_run.last_motion.resize(0);
      m_run.last_dl = 0.0;
      done = attempts = 0;
      m_run.level_settled = true;  // stays true but in tests, where a level repeats until it settles
      m_run.relax_drag = 0.0;
      m_run.failed_floor = 0.0;
      m_run.level_failures = 0;
      failed_first = -1.0;
      failed_dl = 0.0;
      uncuttable = false;
      m_iteration_factor = 1;
      m_run.relax_settling = false;
      failed_state.resize(0);
      failed_refusal.clear();
      m_run.settling_residual = std::numeric_limits<double>::infinity();
      // A step's first loading increment expects nothing of an earlier step's (a test after
      // another, or after a held load step, whose drag force is measured against its load),
      // nor does a relax step's first increment (solve_increment: solved to pseudo_tolerance).
      m_run.load_residual = 0.0;
      m_run.relax_residual = 0.0;
      driver->begin(m_run);
    }
    while (lambda < 1.0 - 1e-12 || !relaxed) {
      const double step_dl = driver->load_step(m_run, host);
      const VecX saved = m_q;
      m_q_start = m_q;
      driver->predict(m_run, host, step_dl);
      m_mode = driver->mode(m_run, step_dl);
      m_drag_anchor = m_mode.predicted ? m_q_start : m_q;
      const LaggedStates saved_lagged = m_problem->save_lagged();
      std::vector<double> history;
      int iterations = 0;
      double residual = 0.0;
      const bool ok = solve_increment(step, lambda + step_dl, history, iterations, residual);
      ++attempts;
      // An interrupted increment is not converged (a solve it cut short returned false), and
      // the run stops at the last one that is: the checkpoint the run writes is that one's.
      auto interrupted = [&] {
        m_q = saved;
        result.status = RunResult::Status::Interrupted;
        result.message = "interrupted by the user";
        result.step = st.name;
        result.load_factor = lambda;
        result.attempted_load_factor = lambda + step_dl;
        return result;
      };
      if (interrupt_flag().load()) return interrupted();
      if (!ok) {
        failed_state = m_q;
        failed_refusal = m_refusal;
        m_q = saved;
        if (m_problem->restore_lagged(saved_lagged)) pattern_changed();
        ++m_stats.cuts;
        if (step_dl > 0.0) ++m_run.level_failures;
        const bool stiffer = driver->failed(m_run, step_dl);
        // Nothing to cut: an increment that moves no load (a test level's settling increment,
        // a relax step's increments at lambda = 1), or one whose first residual a cut left as
        // it was (a relax from the weave's end, where no load changes: the residual is the
        // woven state's). With no stiffer drag left, the next attempt would start from the same
        // state and fail the same way, and a cut would only shrink the next level: it gets
        // twice, then four times max_iterations instead. A test at max_iterations = 5 on one
        // thread cut a level's size 12 times while each attempt settled it in the same 5
        // iterations to 2e-7 (tolerance 1e-6), one short of the small correction, and failed
        // (docs/theory/solver.md, "Steps and increments").
        const double first_residual = history.empty() ? -1.0 : history.front();
        const bool same_start = step_dl > 0.0 && step_dl < failed_dl && failed_first > 0.0 &&
                                std::abs(first_residual - failed_first) <= 1e-9 * failed_first;
        failed_first = first_residual;
        failed_dl = step_dl;
        uncuttable = uncuttable || same_start;
        const bool nothing_to_cut = step_dl == 0.0 || uncuttable;
        if (nothing_to_cut && !stiffer && attempts < max_increments) {
          if (m_iteration_factor < 4) {
            m_iteration_factor *= 2;
            if (debug_newton())
              fmt::print(stderr, " nothing to cut at load factor {:.6g}: again with {} Newton iterations\n", lambda,
                         opt.max_iterations * m_iteration_factor);
            continue;
          }
          return fail(lambda + step_dl, history, fmt::format(
              "step \"{}\": the increment at load factor {:.6g} did not converge{} within {} Newton iterations (4 x "
              "max_iterations; last relative residual {:.3e}, tolerance {:.1e}), and there is nothing to cut: {}",
              st.name, lambda, m_mode.proximal ? fmt::format(" at the stiffest drag ({:.3g} N/m)", m_run.relax_drag) : "",
              iterations, history.empty() ? 0.0 : history.back(), m_newton_tolerance,
              step_dl == 0.0 ? "its loads are held (a test level settling, or a relax step's end)"
                             : "a cut did not change its first residual (its loads do not change)"));
        }
        const int cuts_here = dl > 0.0 ? static_cast<int>(std::round(std::log2(nominal / dl))) : opt.max_cuts;
        if ((cuts_here >= opt.max_cuts && !stiffer) || attempts >= max_increments) {
          if (attempts >= max_increments)
            return fail(lambda + step_dl, history, fmt::format(
                "step \"{}\": stopped at load factor {:.6g} after {} increments tried (max_increments {}); the last "
                "one, to {:.6g}, did not converge ({} Newton iterations, last relative residual {:.3e}, tolerance {:.1e})",
                st.name, lambda, attempts, max_increments, lambda + step_dl, iterations,
                history.empty() ? 0.0 : history.back(), m_newton_tolerance));
          return fail(lambda + step_dl, history, fmt::format(
              "step \"{}\": the increment from load factor {:.6g} to {:.6g} did not converge after {} cuts "
              "({} Newton iterations, last relative residual {:.3e}, tolerance {:.1e})",
              st.name, lambda, lambda + dl, cuts_here, iterations, history.empty() ? 0.0 : history.back(),
              m_newton_tolerance));
        }
        if (!stiffer) dl *= 0.5;
        continue;
      }
      m_iteration_factor = 1;
      failed_first = -1.0;
      failed_dl = 0.0;
      uncuttable = false;
      SolvedIncrement solved;
      solved.step_dl = step_dl;
      solved.iterations = iterations;
      solved.drag = m_problem->drag();
      solved.settling_moved = m_contact_loop ? m_contact_loop->settling_moved() : -1.0;
      solved.start = &saved;
      solved.state = &m_q;
      iterations += driver->converged(m_run, host, solved);
      // The solves a converged increment may add (a relax's or a test level's release) stop
      // at an interrupt too, as not converged, and the increment would go on with what they
      // left (the dragged state): the increment is the interrupted one, not a converged one.
      if (interrupt_flag().load()) return interrupted();
      if (debug_newton() && m_mode.proximal)
        fmt::print(stderr, " drag {:.3e} N/m per node, its force {:.3e} of the {}, normals {}settled; next drag {:.3e} N/m\n",
                   solved.drag, m_run.relax_residual, m_mode.held ? "load" : "reference force",
                   m_run.normals_settled ? "" : "not ", m_run.relax_drag);
      lambda += step_dl;
      if (1.0 - lambda < 1e-12) lambda = 1.0;
      ++done;
      ++total;
      ++m_stats.increments;
      IncrementInfo info;
      info.step = st.name;
      info.step_index = step;
      info.increment = done;
      info.total_increments = total;
      info.load_factor = lambda;
      info.iterations = iterations;
      info.residual = residual;
      info.wall_time = seconds_since(t_start);
      info.increment_time = seconds_since(t_increment);
      info.step_end = lambda >= 1.0 && relaxed;
      info.settled = m_run.level_settled;
      const bool proximal = m_mode.proximal;
      info.relax_residual = proximal ? m_run.relax_residual : 0.0;
      info.spin_residual = proximal ? drag_residual(DragPart::Sections) : 0.0;
      info.drag = solved.drag;
      // A load step's equilibrium: its stability, from the exact tangent at the accepted state
      // (its factor then preconditions the next increment). A held step's increment is one
      // once its level settled (tangent_negative_pivots: without the drag); before, unknown (-1).
      if (st.kind == StepSpec::Kind::Standard)
        info.negative_pivots = m_problem->drag() == 0.0 || m_run.level_settled ? tangent_negative_pivots() : -1;
      info.reactions = reactions(m_gradient);
      if (m_bodies) {
        info.binding_updates = m_binding_updates;
        info.binding_violation = m_bodies->violation(m_q);
        for (Index b = 0; b < m_bodies->num_bodies(); ++b) {
          const BodyState bs = m_bodies->state(b, m_q);
          const Vec3 u = bs.center - m_model.bodies[b].center;
          for (const Vec3* v : {&bs.force, &bs.moment, &u, &bs.rotation})
            info.reactions.insert(info.reactions.end(), v->data(), v->data() + 3);
          info.bodies.push_back(bs);
        }
      }
      if (m_contact && debug_newton()) {
        std::vector<double> ks;
        for (const ContactElement& c : m_problem->contacts()) ks.push_back(c.law.stiffness / k0);
        std::sort(ks.begin(), ks.end());
        if (!ks.empty())
          fmt::print(stderr, " penalty / k0: median {:.3g}, 90 % {:.3g}, 99 % {:.3g}, max {:.3g}\n", ks[ks.size() / 2],
                     ks[ks.size() * 9 / 10], ks[ks.size() * 99 / 100], ks.back());
      }
      if (m_contact) {
        info.contact_responses = m_problem->contact_solution();
        info.contact = m_contact_stats;
      }
      m_problem->commit(m_q);
      m_stats.time_assembly = m_problem->times().assembly;
      if (m_progress)
        m_progress(fmt::format("step {} \"{}\"  load {:6.4f}  iterations {:2d}  residual {:.2e}  {:7.2f} s", step + 1,
                               st.name, lambda, iterations, residual, info.wall_time));
      // The next increment's size (before the observer: a checkpoint it writes holds it).
      m_run.wall_time = info.wall_time;
      driver->grow(m_run, iterations);
      observer(info, m_q);
      t_increment = std::chrono::steady_clock::now();
      const std::string stop = driver->stop(m_run, host);
      if (!stop.empty()) {
        failed_state.resize(0);  // every increment converged: nothing stalled to diagnose
        return fail(1.0, {}, stop);
      }
    }
  }
  m_stats.time_assembly = m_problem->times().assembly;
  return result;
}

}  // namespace fibra
