// Plots of the loading curves end to end (docs/outputs.md, "Plots"): the figures a run draws of
// its biaxial and shear steps (PNG, SVG, JSON sidecar), a run without Python, a run that stops
// within a test step, and `fibra plot` over one or several result directories, with its input
// errors. The sample is a flat 2 x 2 plain weave without contact, tested straight away (no
// weaving): a run takes a tenth of a second, the plotting about one second per figure batch.
//
// matplotlib is a declared dependency (scripts/deps.sh installs python3-matplotlib): the tests
// that draw fail, not skip, without it.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/curve_checks.hpp"
#include "support/fabric_cases.hpp"
#include "support/scratch_dir.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

using Result = test::CliResult;
using test::slurp;

/// A flat plain weave (2 x 2 tows of 3 fibers) without contact, pulled then sheared at once:
/// the edge bodies exist, so the test steps run and write their curves, in a tenth of a second.
std::string flat_sample(const std::string& title, const std::string& steps) {
  return "title = \"" + title + "\"\n" + test::glass_fabric("plain", 2, 3, 5.0e-5, 2.5e-4, "tension = 0.5\n", steps);
}

const std::string kPullAndShear = R"([[step]]
name = "pull"
kind = "biaxial"
strain = 0.004
increments = 2
[[step]]
name = "shear"
kind = "shear"
angle = 2
increments = 2
)";

class Plots : public test::ScratchDirTest {
 protected:
  Plots() : ScratchDirTest("fibra_plots_") {}

  /// Runs `ENV fibra ARGS` in the temporary directory, capturing stdout and stderr.
  Result fibra(const std::string& args, const std::string& env = "") const { return test::run_fibra(m_dir, args, env); }

  void write(const std::string& name, const std::string& text) const { std::ofstream(m_dir / name) << text; }
};

/// Every series of the sidecar STEM.json matches its curves file; returns the sidecar.
nlohmann::json check_sidecar(const fs::path& stem) {
  const fs::path sidecar = stem.string() + ".json";
  const nlohmann::json s = test::read_sidecar(sidecar);
  for (const nlohmann::json& series : s.at("series")) test::expect_series_matches_csv(series, sidecar);
  return s;
}

std::vector<std::string> labels(const nlohmann::json& sidecar) {
  std::vector<std::string> out;
  for (const nlohmann::json& s : sidecar.at("series")) out.push_back(s.at("label"));
  return out;
}

TEST_F(Plots, MatplotlibIsInstalled) {
  EXPECT_EQ(std::system("/usr/bin/python3 -c 'import matplotlib' 2> /dev/null"), 0)
      << "/usr/bin/python3 has no matplotlib: it is a declared dependency (scripts/deps.sh installs "
         "python3-matplotlib); the plots of the curves need it";
}

// A run draws, at the end of each biaxial and shear step, plots/STEP.png, .svg and .json; the
// sidecar's numbers are those of curves_STEP.csv; slices are drawn at those steps' ends too.
TEST_F(Plots, RunDrawsEveryTestStep) {
  write("flat.toml", flat_sample("Flat sample", kPullAndShear));
  const Result r = fibra("run flat.toml --out out");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "") << "plotting is quiet";
  const fs::path out = m_dir / "out";
  for (const char* name : {"pull.png", "pull.svg", "pull.json", "shear.png", "shear.svg", "shear.json"})
    EXPECT_TRUE(fs::is_regular_file(out / "plots" / name)) << name << "\n" << r.out;
  // 6.4 x 4.8 inches at 150 dpi.
  EXPECT_EQ(test::png_size(out / "plots" / "pull.png"), std::make_pair(960u, 720u));
  EXPECT_EQ(test::png_size(out / "plots" / "shear.png"), std::make_pair(960u, 720u));
  // The SVG keeps its text as text: the axis labels with their units, the title.
  const std::string pull_svg = slurp(out / "plots" / "pull.svg"), shear_svg = slurp(out / "plots" / "shear.svg");
  EXPECT_TRUE(pull_svg.starts_with("<?xml")) << pull_svg.substr(0, 100);
  for (const char* text :
       {"axial strain [%]", "axial force [N]", "Flat sample: step pull (biaxial)", ">warp<", ">weft<"})
    EXPECT_NE(pull_svg.find(text), std::string::npos) << text;
  for (const char* text : {"shear angle [deg]", "shear force [N]", "Flat sample: step shear (shear)"})
    EXPECT_NE(shear_svg.find(text), std::string::npos) << text;

  const nlohmann::json pull = check_sidecar(out / "plots" / "pull");
  EXPECT_EQ(pull["kind"], "biaxial");
  EXPECT_EQ(pull["x"]["unit"], "%");
  EXPECT_EQ(pull["y"]["unit"], "N");
  EXPECT_EQ(labels(pull), (std::vector<std::string>{"warp", "weft"}));
  EXPECT_EQ(pull["series"][0]["source"], "../curves_pull.csv");
  EXPECT_EQ(pull["series"][0]["x"].size(), 3u);                      // the start and two levels
  EXPECT_NEAR(pull["series"][0]["x"][2].get<double>(), 0.4, 1e-12);  // 0.004 = 0.4 %
  const nlohmann::json shear = check_sidecar(out / "plots" / "shear");
  EXPECT_EQ(shear["x"]["unit"], "deg");
  ASSERT_EQ(shear["series"].size(), 1u);
  EXPECT_EQ(shear["series"][0]["x_column"], "shear_angle_deg");
  EXPECT_EQ(shear["series"][0]["y_column"], "shear_force");
  EXPECT_NEAR(shear["series"][0]["x"][2].get<double>(), 2.0, 1e-9);

  const nlohmann::json s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["plots"], (nlohmann::json{"plots/pull.png", "plots/pull.svg", "plots/pull.json", "plots/shear.png",
                                        "plots/shear.svg", "plots/shear.json"}));
  EXPECT_FALSE(s.contains("plots_error")) << s["plots_error"];
  EXPECT_GT(s["timings"]["plots"].get<double>(), 0.0);
  // The list of results at the end of the run.
  for (const char* text :
       {"ParaView  fibers.pvd, lines.pvd, bodies.pvd", "curves    curves_pull.csv, curves_shear.csv",
        "plots     plots/pull.png, plots/pull.svg, plots/shear.png, plots/shear.svg", "slices    slices/ (8 files)"})
    EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;
  for (const char* name : {"pull_x.svg", "pull_y.png", "shear_x.png", "shear_y.svg"})
    EXPECT_TRUE(fs::is_regular_file(out / "slices" / name)) << name;
}

// Without Python the run still succeeds, keeps its curves, warns once (two test steps) and says
// so in summary.json; `fibra plot DIR` draws the figures afterwards; `fibra plot` overlays runs,
// one of them killed (no summary.json: its case.toml names the steps); [output] plots = false.
TEST_F(Plots, RunWithoutPythonThenFibraPlot) {
  write("flat.toml", flat_sample("Flat sample", kPullAndShear));
  Result r = fibra("run flat.toml --out out", "FIBRA_PYTHON=/nonexistent");
  ASSERT_EQ(r.code, 0) << r.err;
  const fs::path out = m_dir / "out";
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_TRUE(r.err.starts_with("warning: no plots of the curves: cannot run /nonexistent")) << r.err;
  EXPECT_NE(r.err.find("`fibra plot out`"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("FIBRA_PYTHON"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::is_regular_file(out / "curves_pull.csv"));
  EXPECT_TRUE(fs::is_regular_file(out / "curves_shear.csv"));
  EXPECT_FALSE(fs::exists(out / "plots" / "pull.png"));
  nlohmann::json s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["status"], "converged");
  EXPECT_EQ(s["plots"], nlohmann::json::array());
  EXPECT_NE(s.value("plots_error", "").find("/nonexistent"), std::string::npos) << s.dump();
  EXPECT_EQ(r.out.find("plots "), std::string::npos) << r.out;

  // Later, with Python: the run's own figures, as the run would have drawn them.
  r = fibra("plot out");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("out/plots/pull.png"), std::string::npos) << r.out;
  check_sidecar(out / "plots" / "pull");
  EXPECT_EQ(check_sidecar(out / "plots" / "shear")["title"], "Flat sample: step shear (shear)");
  EXPECT_EQ(test::png_size(out / "plots" / "shear.png"), std::make_pair(960u, 720u));

  // Two more runs: one with another title, one killed (no summary.json).
  fs::copy(out, m_dir / "other", fs::copy_options::recursive);
  s["title"] = "Other sample";
  std::ofstream(m_dir / "other" / "summary.json") << s.dump(1);
  fs::copy(out, m_dir / "killed", fs::copy_options::recursive);
  fs::remove(m_dir / "killed" / "summary.json");
  r = fibra("plot other killed --out cmp");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json pull = check_sidecar(m_dir / "cmp" / "pull");
  // Two series per quantity (warp, weft): one per run, labelled by the runs' titles.
  EXPECT_EQ(labels(pull), (std::vector<std::string>{"Other sample: warp", "Other sample: weft", "Flat sample: warp",
                                                    "Flat sample: weft"}));
  EXPECT_EQ(pull["title"], "step pull (biaxial): Other sample vs Flat sample");
  EXPECT_EQ(pull["series"][0]["source"], "../other/curves_pull.csv");
  EXPECT_EQ(pull["series"][2]["source"], "../killed/curves_pull.csv");
  const nlohmann::json shear = check_sidecar(m_dir / "cmp" / "shear");
  EXPECT_EQ(labels(shear), (std::vector<std::string>{"Other sample", "Flat sample"}));
  EXPECT_TRUE(fs::is_regular_file(m_dir / "cmp" / "pull.svg"));
  EXPECT_NE(slurp(m_dir / "cmp" / "pull.svg").find("Other sample: warp"), std::string::npos);

  // A Python that fails: `fibra plot` stops with what it said (exit 3), nothing half-written.
  r = fibra("plot out --out failed", "FIBRA_PYTHON=/bin/false");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("/bin/false"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("exited with code 1"), std::string::npos) << r.err;
  // A Python that hangs is stopped (with what it started) after FIBRA_PLOT_TIMEOUT seconds.
  write("hang.sh", "#!/bin/sh\nsleep 30 &\nexec sleep 30\n");
  fs::permissions(m_dir / "hang.sh", fs::perms::owner_all);
  r = fibra("plot out --out hung", "FIBRA_PLOT_TIMEOUT=1 FIBRA_PYTHON=./hang.sh");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("did not finish within 1 s"), std::string::npos) << r.err;

  // Plots off: no figure, no warning.
  write("quiet.toml", flat_sample("Flat sample", kPullAndShear + "[output]\nplots = false\n"));
  r = fibra("run quiet.toml --out quiet", "FIBRA_PYTHON=/nonexistent");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_FALSE(fs::exists(m_dir / "quiet" / "plots"));
  EXPECT_EQ(nlohmann::json::parse(slurp(m_dir / "quiet" / "summary.json"))["plots"], nlohmann::json::array());
}

// A run that stops within a shear step (60 degrees in at most 4 increments: the second level
// needs its increment cut) keeps the curves of the levels that converged, and their plots.
TEST_F(Plots, FailedRunPlotsWhatConverged) {
  write("flat.toml", flat_sample("Flat sample", R"([[step]]
name = "shear"
kind = "shear"
angle = 60
increments = 4
max_increments = 4
)"));
  const Result r = fibra("run flat.toml --out out");
  ASSERT_EQ(r.code, 1) << r.out << r.err;
  const fs::path out = m_dir / "out";
  const nlohmann::json s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s["status"], "failed");
  EXPECT_EQ(s["plots"], (nlohmann::json{"plots/shear.png", "plots/shear.svg", "plots/shear.json"}));
  const nlohmann::json shear = check_sidecar(out / "plots" / "shear");
  EXPECT_GE(shear["series"][0]["x"].size(), 2u);  // the start and at least one level
  EXPECT_LT(shear["series"][0]["x"].back().get<double>(), 60.0);
  EXPECT_NE(r.out.find("plots     plots/shear.png"), std::string::npos) << r.out;
}

// `fibra plot` input errors: exit code 2 and a message naming the directory and what was
// expected. Nothing here needs Python: every directory is checked before anything is drawn.
TEST_F(Plots, PlotInputErrors) {
  auto expect_error = [&](const std::string& args, const std::vector<std::string>& words) {
    const Result r = fibra("plot " + args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    for (const std::string& w : words)
      EXPECT_NE(r.err.find(w), std::string::npos) << args << ": " << w << "\n" << r.err;
  };
  expect_error("nowhere", {"nowhere", "no such directory", "`fibra run`"});
  write("file.txt", "x");
  expect_error("file.txt", {"file.txt", "not a directory"});
  fs::create_directories(m_dir / "empty");
  expect_error("empty", {"empty", "no summary.json"});
  // A run without test steps.
  fs::create_directories(m_dir / "beam");
  write("beam/summary.json", R"({"title": "Beam", "status": "converged"})");
  expect_error("beam", {"beam/summary.json", "curves", "no biaxial or shear step"});
  write("beam/summary.json", "{ not json");
  expect_error("beam", {"beam/summary.json", "not valid JSON"});
  // A listed curves file that is missing.
  fs::create_directories(m_dir / "a");
  write("a/summary.json",
        R"({"title": "A", "curves": [{"step": "pull", "kind": "biaxial", "file": "curves_pull.csv"}]})");
  expect_error("a", {"a/curves_pull.csv", "not found", "summary.json"});
  write("a/curves_pull.csv", "step,increment\n");
  // Several runs: --out is required; a run given twice; runs that share no step.
  fs::create_directories(m_dir / "b");
  write("b/summary.json",
        R"({"title": "B", "curves": [{"step": "shear", "kind": "shear", "file": "curves_shear.csv"}]})");
  write("b/curves_shear.csv", "step,increment\n");
  expect_error("a b", {"--out", "several result directories"});
  expect_error("a a/ --out x", {"a/", "same directory"});
  expect_error("a b --out x", {"share no biaxial or shear step", "a has pull (biaxial)", "b has shear (shear)"});
  // The same name, another kind: not shared either.
  write("b/summary.json",
        R"({"title": "B", "curves": [{"step": "pull", "kind": "shear", "file": "curves_shear.csv"}]})");
  expect_error("a b --out x", {"share no biaxial or shear step"});
  EXPECT_FALSE(fs::exists(m_dir / "x"));
}

}  // namespace
}  // namespace fibra
