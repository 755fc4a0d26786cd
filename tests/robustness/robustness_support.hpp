#pragma once
/// Helpers of the robustness corpus (tests/robustness, docs/robustness.md): run a case file of
/// tests/robustness/cases/ with the library's default settings under a wall-time budget, keep
/// every converged increment, collect the checks of the case's reference, and report a case
/// marked in known_failures.hpp as skipped while it fails (as a failure once it passes).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <mutex>
#include <numbers>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/resolve.hpp"
#include "fibra/solver/static_solver.hpp"
#include "robustness/known_failures.hpp"
#include "verification/verification_support.hpp"

namespace fibra::test {

/// Path of the corpus case file `name` (tests/robustness/cases/NAME.toml).
inline std::string case_path(const std::string& name) {
  return std::string(FIBRA_SOURCE_DIR) + "/tests/robustness/cases/" + name + ".toml";
}

/// One converged increment: what the solver reports and the state.
struct Snapshot {
  IncrementInfo info;
  VecX q;
};

/// A case file run to its end, to a failure or to its wall-time budget.
struct CaseRun {
  std::string name;
  Case c;
  Model model;
  RunResult result;
  SolverStats stats;
  VecX q;                                   ///< last converged state
  std::vector<Snapshot> snaps;              ///< every converged increment
  std::vector<std::string> reaction_columns;  ///< names of IncrementInfo::reactions
  double seconds = 0;                       ///< wall time of the run [s]
  double budget = 0;                        ///< wall-time budget [s]
  bool out_of_time = false;                 ///< stopped by the budget

  bool converged() const { return result.status == RunResult::Status::Converged; }
  /// Index of fiber `name` in the model.
  int fiber(const std::string& fiber_name) const {
    for (size_t i = 0; i < model.fibers.size(); ++i)
      if (model.fibers[i].name == fiber_name) return static_cast<int>(i);
    ADD_FAILURE() << "no fiber " << fiber_name;
    return 0;
  }
  /// Global index of local node `local` of fiber `f` (negative: from the end, -1 = last).
  Index node(Index local, int f = 0) const {
    const Fiber& fb = model.fibers.at(f);
    return fb.first_node + (local < 0 ? fb.num_nodes + local : local);
  }
  Index num_nodes(int f = 0) const { return model.fibers.at(f).num_nodes; }  ///< nodes of fiber f
  Vec3 x0(const VecX& s, Index local, int f = 0) const { return s.segment<3>(9 * node(local, f)); }  ///< centroid
  Vec3 g1(const VecX& s, Index local, int f = 0) const { return s.segment<3>(9 * node(local, f) + 3); }  ///< g1
  Vec3 g2(const VecX& s, Index local, int f = 0) const { return s.segment<3>(9 * node(local, f) + 6); }  ///< g2
  Vec3 ref_x0(Index local, int f = 0) const { return x0(model.reference, local, f); }  ///< reference centroid
  /// Displacement of a node's centroid at state s.
  Vec3 u(const VecX& s, Index local, int f = 0) const { return x0(s, local, f) - ref_x0(local, f); }
  /// Reaction column `col` (history.csv naming) of a snapshot.
  double reaction(const Snapshot& snap, const std::string& col) const {
    for (size_t i = 0; i < reaction_columns.size(); ++i)
      if (reaction_columns[i] == col) return snap.info.reactions[i];
    ADD_FAILURE() << "no reaction column " << col;
    return 0.0;
  }
  /// Reaction force on node `node_label` ("first", "last" or the index as written) of a fiber.
  Vec3 reaction(const Snapshot& snap, const std::string& fiber_name, const std::string& node_label) const {
    const std::string p = "reaction:" + fiber_name + ":" + node_label + ":";
    return {reaction(snap, p + "x"), reaction(snap, p + "y"), reaction(snap, p + "z")};
  }
  /// Sum of the reaction forces of every fixed or driven node of a fiber.
  Vec3 fiber_reaction(const Snapshot& snap, const std::string& fiber_name) const {
    Vec3 sum = Vec3::Zero();
    const std::string p = "reaction:" + fiber_name + ":";
    for (size_t i = 0; i < reaction_columns.size(); ++i) {
      const std::string& col = reaction_columns[i];
      if (col.rfind(p, 0) != 0) continue;
      const char axis = col.back();
      sum[axis - 'x'] += snap.info.reactions[i];
    }
    return sum;
  }
  /// Snapshots at the ends of steps, in order.
  std::vector<const Snapshot*> step_ends() const {
    std::vector<const Snapshot*> out;
    for (const Snapshot& s : snaps)
      if (s.info.step_end) out.push_back(&s);
    return out;
  }
  /// One line on how the run ended.
  std::string outcome() const {
    if (converged()) return "converged";
    if (out_of_time)
      return fmt::format("stopped by its wall-time budget of {:g} s in step \"{}\" at load factor {:.4g}", budget,
                         result.step, result.load_factor);
    return fmt::format("{} in step \"{}\" at load factor {:.4g} (attempted {:.4g}): {}", result.status_name(),
                       result.step, result.load_factor, result.attempted_load_factor, result.message);
  }
};

/// Sets interrupt_flag() after `seconds` unless stopped first (the solver checks it at every
/// Newton iteration, so a run that cannot converge ends within the budget).
class WallTimeBudget {
 public:
  explicit WallTimeBudget(double seconds)
      : m_thread([this, seconds] {
          std::unique_lock<std::mutex> lock(m_mutex);
          if (!m_cv.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return m_done; })) {
            m_expired = true;
            interrupt_flag().store(true);
          }
        }) {}
  ~WallTimeBudget() { stop(); }
  /// Stops the watch; returns true when the budget had expired.
  bool stop() {
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_done = true;
    }
    m_cv.notify_all();
    if (m_thread.joinable()) m_thread.join();
    interrupt_flag().store(false);
    return m_expired;
  }

 private:
  std::mutex m_mutex;
  std::condition_variable m_cv;
  bool m_done = false;
  bool m_expired = false;
  std::thread m_thread;
};

/// Reads tests/robustness/cases/NAME.toml and solves it with StaticSolver and the case's own
/// settings (the corpus has no [solver] tables), keeping every converged increment; the run
/// is stopped after `budget_seconds` of wall time. FIBRA_VERBOSE=1 prints every increment.
inline CaseRun solve_file(const std::string& name, double budget_seconds) {
  CaseRun s;
  s.name = name;
  s.budget = budget_seconds;
  s.c = read_case(case_path(name));
  ResolvedCase r = resolve_case(s.c);
  s.model = r.model;
  const bool verbose = std::getenv("FIBRA_VERBOSE") != nullptr;
  const auto t0 = std::chrono::steady_clock::now();
  {
    StaticSolver solver(s.c, r.model, std::move(r.bodies));
    s.reaction_columns = solver.reaction_columns();
    if (verbose) solver.set_progress([](const std::string& line) { std::printf("  %s\n", line.c_str()); });
    WallTimeBudget watch(budget_seconds);
    s.result = solver.run([&](const IncrementInfo& info, const VecX& q) { s.snaps.push_back({info, q}); });
    s.out_of_time = watch.stop() && s.result.status == RunResult::Status::Interrupted;
    s.stats = solver.stats();
    s.q = solver.state();
  }
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[robustness] %s: %s; %d increments, %d iterations, %d cuts, %.2f s\n", name.c_str(),
              s.outcome().c_str(), s.stats.increments, s.stats.iterations, s.stats.cuts, s.seconds);
  return s;
}

/// The checks of one case against its reference. Each check is recorded with a line saying
/// what was measured and expected; finish() turns them into the test's result: failures for
/// an ordinary case; for a case of known_failures.hpp a skip that quotes its diagnosis while
/// a check fails, and a failure once every check passes (its mark must then go).
class Checks {
 public:
  explicit Checks(std::string case_name) : m_name(std::move(case_name)) {}

  /// Records `ok`; `what` says what was measured against what.
  bool expect(bool ok, const std::string& what) {
    std::printf("  [%s] %s\n", ok ? "ok" : "FAILED", what.c_str());
    if (!ok) m_failures.push_back(what);
    ++m_count;
    return ok;
  }
  /// |value - reference| <= tolerance.
  bool near(const std::string& what, double value, double reference, double tolerance) {
    return expect(std::abs(value - reference) <= tolerance,
                  fmt::format("{}: {:.8g}, reference {:.8g}, |difference| {:.3g} (tolerance {:.3g})", what, value,
                              reference, std::abs(value - reference), tolerance));
  }
  /// |value / reference - 1| <= tolerance.
  bool relative(const std::string& what, double value, double reference, double tolerance) {
    const double e = std::abs(value / reference - 1.0);
    return expect(e <= tolerance, fmt::format("{}: {:.8g}, reference {:.8g}, relative difference {:.3g} (tolerance {:.3g})",
                                              what, value, reference, e, tolerance));
  }
  /// value <= bound.
  bool at_most(const std::string& what, double value, double bound) {
    return expect(value <= bound, fmt::format("{}: {:.6g} (at most {:.6g})", what, value, bound));
  }
  /// value >= bound.
  bool at_least(const std::string& what, double value, double bound) {
    return expect(value >= bound, fmt::format("{}: {:.6g} (at least {:.6g})", what, value, bound));
  }
  /// The run reached the end of its last step.
  bool converged(const CaseRun& s) { return expect(s.converged(), "run to the end of its steps: " + s.outcome()); }

  /// Ends the test (see the class comment). Call it last.
  void finish() {
    const KnownFailure* known = find_known_failure(m_name);
    if (!known) {
      for (const std::string& f : m_failures) ADD_FAILURE() << m_name << ": " << f;
      return;
    }
    if (m_failures.empty()) {
      FAIL() << "known failure now passes: remove its mark (" << m_name << " in tests/robustness/known_failures.hpp, "
             << "docs/robustness.md); " << m_count << " checks passed";
    }
    GTEST_SKIP() << "known failure: " << known->diagnosis << " [this run: " << m_failures.front() << "]";
  }

 private:
  std::string m_name;
  std::vector<std::string> m_failures;
  int m_count = 0;
};

}  // namespace fibra::test
