#pragma once
/// Running a whole case: model, solver, outputs and summary, as `fibra run` does.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fibra/model/case.hpp"
#include "fibra/model/fabric_report.hpp"
#include "fibra/solver/static_solver.hpp"

namespace fibra {

/// Options of a run.
struct RunOptions {
  std::string out_dir;   ///< output directory (created)
  int threads = 0;       ///< OpenMP threads (0 = default)
  /// Go on from the checkpoint in out_dir (state/checkpoint.bin) instead of starting afresh:
  /// the outputs are those of a run never stopped. InputError when there is none, it is
  /// damaged, or the case changed in more than the steps not yet started.
  bool resume = false;
  std::function<void(const std::string&)> progress;  ///< one line per increment (may be empty)
  /// Called after each converged increment, once its outputs are written (may be empty). To
  /// stop the run from it, set interrupt_flag(): the run ends as interrupted, outputs kept.
  std::function<void(const IncrementInfo&)> on_increment;
  /// The case's text and its file name (".toml" or ".json" says the format), kept in the
  /// checkpoints and compared on --resume; empty: the case file's text (c.file), or the case
  /// written as TOML when it has none. A case built in Python gives the JSON it was read from.
  std::string case_text, case_text_file;
};

/// What a run did.
struct RunReport {
  RunResult result;
  SolverStats stats;
  Index fibers = 0, nodes = 0, dofs = 0, elements = 0;
  double wall_time = 0;  ///< [s]
  /// Load steps' increments whose equilibrium is unstable (IncrementInfo::negative_pivots > 0),
  /// and where the first of them is ("step \"NAME\" at load factor ..."; empty when none).
  int unstable_increments = 0;
  std::string first_unstable;
  VecX final_state;      ///< nodal values at the last converged increment
  std::optional<FabricReport> fabric;  ///< with tows: the report at the end of the last completed step
  // Files written, relative to the output directory (for the list a run prints at its end).
  std::vector<std::string> paraview;  ///< the .pvd collections (fibers, lines, contacts, bodies)
  std::vector<std::string> curves;    ///< curves_STEP.csv of the biaxial and shear steps
  std::vector<std::string> plots;     ///< plots/STEP.png, .svg, .json of those steps
  std::vector<std::string> states;    ///< state/STEP.bin at the end of each step (for [start])
  std::vector<std::string> slices;    ///< slices/STEP_x.svg, .png, STEP_y.svg, .png
  /// Why plots are missing (Python, matplotlib or the script failed) and how to draw them
  /// later; empty when every plot was drawn (or [output] plots = false).
  std::string plots_error;
};

/// Builds the model of `c`, solves every step, writes case.toml (the expanded case, at the
/// start), history.csv, fibers.pvd/.vtu, nodes.csv and summary.json into options.out_dir; with
/// tows also the fabric report (summary.json "fabric", "fabric_steps", history columns
/// fabric:*) and, at the end of every weave, relax, biaxial and shear step, slices/STEP_x and
/// STEP_y (.svg, .png) across the middle of the sample; for biaxial and shear steps
/// curves_STEP.csv and, when the step ends (or the run stops within it), plots/STEP.png, .svg,
/// .json (CurvePlotter; a failure to draw is reported in plots_error, not thrown). Throws
/// InputError for invalid input; a non-converged run returns normally with result.status !=
/// Converged (outputs kept).
RunReport run_case(const Case& c, const RunOptions& options);

}  // namespace fibra
