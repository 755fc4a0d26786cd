#pragma once
/// The loading curves a run left in its result directory (curves_STEP.csv, listed in
/// summary.json), and the figures of `fibra plot`: one per step name, the runs overlaid.
#include <string>
#include <vector>

#include "fibra/io/curve_plots.hpp"

namespace fibra {

/// The title line of a run's own figure of a step: "TITLE: step NAME (KIND)".
std::string curve_figure_title(const std::string& run_title, const std::string& step, const std::string& kind);

/// The curves of one result directory of `fibra run`.
struct ResultCurves {
  /// One biaxial or shear step's curves.
  struct Step {
    std::string name;  ///< the step's name
    std::string kind;  ///< "biaxial" or "shear"
    std::string csv;   ///< path of its curves_STEP.csv (existing)
  };
  std::string dir;    ///< as given
  std::string title;  ///< the case title (may be empty)
  std::vector<Step> steps;
};

/// Reads the curves of result directory `dir` from its summary.json ("title", "curves"); a run
/// that was killed has no summary.json: then from its case.toml (the steps) and the
/// curves_STEP.csv present. Throws InputError naming the directory or file and what was
/// expected: no such directory, neither file, bad JSON, no biaxial or shear step, a listed
/// curves file missing.
ResultCurves read_result_curves(const std::string& dir);

/// The figures of `fibra plot`.
struct CurveOverlay {
  std::string out_dir;               ///< where the figures go
  std::vector<CurveFigure> figures;  ///< one per step name the runs share (in the first run's order)
  std::vector<std::string> notes;    ///< steps left out (not in every run, or of another kind there)
};

/// The figures of `fibra plot DIRS... [--out OUT]`: for one directory every biaxial and shear
/// step, into OUT or DIR/plots; for several, every step name all of them have with the same
/// kind, their curves overlaid, into OUT (required: the comparison belongs to no single run).
/// Legend: each run's title, or its directory when titles are missing or not distinct. Throws
/// InputError (as read_result_curves, and for a missing --out, a directory given twice, runs
/// that share no step).
CurveOverlay overlay_curves(const std::vector<std::string>& dirs, const std::string& out);

/// Draws the figures of `overlay` (plot_curves) and returns the files written; throws RunError
/// naming what failed and what the figures need when they cannot be drawn (`fibra plot` and
/// the Python module's fibra.plot).
std::vector<std::string> draw_curve_overlay(const CurveOverlay& overlay);

}  // namespace fibra
