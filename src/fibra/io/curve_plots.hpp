#pragma once
/// Plots of the loading curves (curves_STEP.csv) of biaxial and shear steps: for each figure a
/// PNG, an SVG and a JSON sidecar with the exact series drawn. The drawing is done by
/// share/fibra/plot_curves.py (matplotlib) in a child process, so fibra itself needs no plotting
/// library and a missing Python only costs the pictures, never a result. Files and their
/// content: docs/outputs.md, "Plots".
#include <string>
#include <vector>

namespace fibra {

/// One run's curves in a figure.
struct CurveRun {
  std::string label;  ///< legend text: the run's title, or its directory
  std::string csv;    ///< path of its curves_STEP.csv
};

/// One figure: the curves of one step, of one run or overlaid from several.
struct CurveFigure {
  std::string step;   ///< the step's name
  std::string kind;   ///< "biaxial" (axial force against strain, warp and weft) or "shear"
  std::string title;  ///< drawn on top
  std::string stem;   ///< output path without extension: STEM.png, STEM.svg, STEM.json
  std::vector<CurveRun> runs;
};

/// What one call of the plotting script did.
struct PlotOutcome {
  std::vector<std::string> files;  ///< files written: STEM.png, .svg, .json of each figure
  std::string error;               ///< empty on success, else what failed: the command, its exit, its output
  bool ok() const { return error.empty(); }
};

/// The Python interpreter that draws: $FIBRA_PYTHON, else /usr/bin/python3 (Debian's, which
/// python3-matplotlib serves; a `python3` first on PATH may be another one without it).
std::string plot_python();

/// The plotting script plot_curves.py, looked for in $FIBRA_SHARE_DIR when set (there only),
/// else in the source tree's share/fibra (known at compile time), else in <exe dir>/../share/fibra
/// (an installed fibra). Empty when not found.
std::string plot_script();

/// Where plot_script() looks, for messages.
std::string plot_script_places();

/// Draws `figures` in one run of the script, quietly (its output is captured, shown only in
/// `error` when it fails). Never throws for a missing Python, matplotlib or script: the outcome
/// says what failed. The caller's signals (Ctrl-C) do not reach the child, so a run stopped by
/// the user still gets the plots of what it computed; a child that hangs is killed after
/// $FIBRA_PLOT_TIMEOUT seconds (default 300).
PlotOutcome plot_curves(const std::vector<CurveFigure>& figures);

}  // namespace fibra
