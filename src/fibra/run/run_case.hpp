#pragma once
/// Running a whole case: model, solver, outputs and summary, as `fibra run` does.
#include <functional>
#include <optional>
#include <string>

#include "fibra/model/case.hpp"
#include "fibra/model/fabric_report.hpp"
#include "fibra/solver/static_solver.hpp"

namespace fibra {

/// Options of a run.
struct RunOptions {
  std::string out_dir;   ///< output directory (created)
  int threads = 0;       ///< OpenMP threads (0 = default)
  std::function<void(const std::string&)> progress;  ///< one line per increment (may be empty)
};

/// What a run did.
struct RunReport {
  RunResult result;
  SolverStats stats;
  Index fibers = 0, nodes = 0, dofs = 0, elements = 0;
  double wall_time = 0;  ///< [s]
  VecX final_state;      ///< nodal values at the last converged increment
  std::optional<FabricReport> fabric;  ///< with tows: the report at the end of the last completed step
};

/// Builds the model of `c`, solves every step, writes case.toml (the expanded case, at the
/// start), history.csv, fibers.pvd/.vtu, nodes.csv and summary.json into options.out_dir; with
/// tows also the fabric report (summary.json "fabric", "fabric_steps", history columns
/// fabric:*) and, at the end of every weave and relax step, slices/STEP_x and STEP_y (.svg,
/// .png) across the middle of the sample. Throws InputError for invalid input; a
/// non-converged run returns normally with result.status != Converged (outputs kept).
RunReport run_case(const Case& c, const RunOptions& options);

}  // namespace fibra
