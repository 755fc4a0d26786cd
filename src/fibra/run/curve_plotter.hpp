#pragma once
/// The plots a run draws of its biaxial and shear steps (plots/STEP.png, .svg, .json from
/// curves_STEP.csv; docs/outputs.md, "Plots"): one figure per step as it ends, and one for the
/// step under way when the run stops early, so a failed or interrupted run keeps the picture of
/// what it computed. Drawing is optional: a missing Python or matplotlib is recorded (once),
/// never thrown, and the run goes on.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fibra/model/case.hpp"

namespace fibra {

/// Draws the plots of a run's test steps into DIR/plots, quietly.
class CurvePlotter {
 public:
  /// For the run of `c` into `dir`; removes what an earlier run left for the test steps of `c`
  /// (their curves_STEP.csv and plots/STEP.*), so no stale curve or figure passes for this run's.
  CurvePlotter(const Case& c, std::string dir);
  /// For a run resumed into `dir` from `resume_point` (resume_point() then): the figures drawn
  /// until then are kept.
  CurvePlotter(const Case& c, std::string dir, const nlohmann::json& resume_point);
  /// The steps drawn and the files, for a checkpoint.
  nlohmann::json resume_point() const;

  /// Draws the figure of step `step_index` from DIR/curves_STEP.csv: once per step; nothing
  /// when the step has no curves, when [output] plots = false, or after a failure (one warning
  /// per run: the next attempt would fail alike).
  void plot(int step_index);

  const std::vector<std::string>& files() const { return m_files; }  ///< written, relative to DIR
  /// Empty when every figure asked for was drawn; else what failed and how to draw them later.
  const std::string& error() const { return m_error; }
  double time() const { return m_time; }  ///< spent drawing [s]

  /// Adds "plots" (the files) and, after a failure, "plots_error" to a summary with curves.
  void add_to_summary(nlohmann::json& summary) const;

 private:
  const Case& m_case;
  std::string m_dir;
  std::vector<int> m_plotted;  ///< steps already drawn (or attempted)
  std::vector<std::string> m_files;
  std::string m_error;
  double m_time = 0;
};

}  // namespace fibra
