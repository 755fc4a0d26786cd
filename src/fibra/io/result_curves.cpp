#include "fibra/io/result_curves.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/case.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

constexpr const char* kExpected = "expected the output directory of a `fibra run` with a biaxial or shear step";

/// The curves listed in summary.json ("curves": [{step, kind, file}, ...]).
std::vector<ResultCurves::Step> steps_from_summary(const fs::path& dir, const nlohmann::json& s,
                                                   const std::string& file) {
  if (!s.contains("curves") || !s["curves"].is_array() || s["curves"].empty())
    throw InputError(file, "curves",
                     "this run has no biaxial or shear step, so no curves_STEP.csv to plot: " + std::string(kExpected));
  std::vector<ResultCurves::Step> steps;
  for (size_t k = 0; k < s["curves"].size(); ++k) {
    const nlohmann::json& e = s["curves"][k];
    const std::string key = fmt::format("curves[{}]", k);
    if (!e.is_object() || !e.contains("step") || !e.contains("kind") || !e.contains("file") || !e["step"].is_string() ||
        !e["kind"].is_string() || !e["file"].is_string())
      throw InputError(file, key, "expected an object with strings \"step\", \"kind\" and \"file\"");
    const fs::path csv = dir / e["file"].get<std::string>();
    std::error_code ec;
    if (!fs::is_regular_file(csv, ec))
      throw InputError(csv.string(), "(file)", fmt::format("not found, though {} lists it under {}", file, key));
    steps.push_back({e["step"].get<std::string>(), e["kind"].get<std::string>(), csv.string()});
  }
  return steps;
}

/// A run without summary.json (killed, or still running): the test steps of its case.toml whose
/// curves_STEP.csv exists.
std::vector<ResultCurves::Step> steps_from_case(const fs::path& dir, const Case& c) {
  std::vector<ResultCurves::Step> steps;
  std::error_code ec;
  for (const StepSpec& st : c.steps) {
    const fs::path csv = dir / ("curves_" + step_file_stem(st.name) + ".csv");
    if (st.is_test() && fs::is_regular_file(csv, ec))
      steps.push_back({st.name, StepSpec::kind_name(st.kind), csv.string()});
  }
  if (steps.empty())
    throw InputError(dir.string(), "(directory)",
                     "no summary.json and no curves_STEP.csv of a biaxial or shear step of its case.toml: " +
                         std::string(kExpected));
  return steps;
}

/// The label of each run in a legend: its title when every run has a distinct one, else its
/// directory as given.
std::vector<std::string> run_labels(const std::vector<ResultCurves>& runs) {
  std::vector<std::string> titles;
  for (const ResultCurves& r : runs) titles.push_back(r.title);
  std::vector<std::string> sorted = titles;
  std::sort(sorted.begin(), sorted.end());
  const bool distinct = std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end() &&
                        std::none_of(titles.begin(), titles.end(), [](const std::string& t) { return t.empty(); });
  if (distinct) return titles;
  std::vector<std::string> dirs;
  for (const ResultCurves& r : runs) {
    std::string d = r.dir;
    while (d.size() > 1 && d.back() == '/') d.pop_back();
    dirs.push_back(d);
  }
  return dirs;
}

/// "A vs B" for up to three runs, else "N runs".
std::string runs_phrase(const std::vector<std::string>& labels) {
  if (labels.size() > 3) return fmt::format("{} runs", labels.size());
  std::string out;
  for (size_t k = 0; k < labels.size(); ++k) out += (k ? " vs " : "") + labels[k];
  return out;
}

const ResultCurves::Step* find_step(const ResultCurves& r, const std::string& name) {
  for (const ResultCurves::Step& s : r.steps)
    if (s.name == name) return &s;
  return nullptr;
}

std::string step_names(const ResultCurves& r) {
  std::string out;
  for (const ResultCurves::Step& s : r.steps) out += (out.empty() ? "" : ", ") + s.name + " (" + s.kind + ")";
  return out;
}

}  // namespace

std::string curve_figure_title(const std::string& run_title, const std::string& step, const std::string& kind) {
  return fmt::format("{}: step {} ({})", run_title, step, kind);
}

ResultCurves read_result_curves(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(dir, "(directory)",
                     std::string(fs::exists(dir, ec) ? "not a directory: " : "no such directory: ") + kExpected);
  ResultCurves r;
  r.dir = dir;
  const fs::path summary = fs::path(dir) / "summary.json", case_file = fs::path(dir) / "case.toml";
  if (fs::is_regular_file(summary, ec)) {
    std::ifstream in(summary);
    std::stringstream text;
    text << in.rdbuf();
    nlohmann::json s;
    try {
      s = nlohmann::json::parse(text.str());
    } catch (const nlohmann::json::exception& e) {
      throw InputError(summary.string(), "(file)",
                       fmt::format("not valid JSON ({}): expected the summary `fibra run` writes", e.what()));
    }
    if (!s.is_object())
      throw InputError(summary.string(), "(file)", "expected a JSON object, the summary `fibra run` writes");
    if (s.contains("title") && s["title"].is_string()) r.title = s["title"].get<std::string>();
    r.steps = steps_from_summary(dir, s, summary.string());
  } else if (fs::is_regular_file(case_file, ec)) {
    const Case c = read_case(case_file.string());
    r.title = c.title;
    r.steps = steps_from_case(dir, c);
  } else {
    throw InputError(dir, "(directory)", fmt::format("no summary.json (nor case.toml): {}", kExpected));
  }
  return r;
}

CurveOverlay overlay_curves(const std::vector<std::string>& dirs, const std::string& out) {
  if (dirs.empty()) throw InputError("fibra plot", "RESULT", "expected at least one result directory");
  if (dirs.size() > 1 && out.empty())
    throw InputError("fibra plot", "--out",
                     fmt::format("required with several result directories ({} given): the overlaid figures belong "
                                 "to no single run, e.g. --out compare",
                                 dirs.size()));
  std::vector<ResultCurves> runs;
  std::vector<fs::path> seen;
  for (const std::string& d : dirs) {
    runs.push_back(read_result_curves(d));
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(d, ec);
    for (size_t k = 0; k < seen.size(); ++k)
      if (seen[k] == canonical)
        throw InputError("fibra plot", d, fmt::format("the same directory as {}: give each run once", dirs[k]));
    seen.push_back(canonical);
  }
  CurveOverlay overlay;
  overlay.out_dir = out.empty() ? (fs::path(dirs.front()) / "plots").string() : out;
  const std::vector<std::string> labels = run_labels(runs);
  for (const ResultCurves::Step& step : runs.front().steps) {
    CurveFigure fig;
    fig.step = step.name;
    fig.kind = step.kind;
    fig.stem = (fs::path(overlay.out_dir) / step_file_stem(step.name)).string();
    std::string missing;
    for (size_t k = 0; k < runs.size(); ++k) {
      const ResultCurves::Step* s = find_step(runs[k], step.name);
      if (!s)
        missing += fmt::format("{}not in {}", missing.empty() ? "" : ", ", runs[k].dir);
      else if (s->kind != step.kind)
        missing += fmt::format("{}{} in {}", missing.empty() ? "" : ", ", s->kind, runs[k].dir);
      else
        fig.runs.push_back({labels[k], s->csv});
    }
    if (!missing.empty()) {
      overlay.notes.push_back(
          fmt::format("step {} ({} in {}) not drawn: {}", step.name, step.kind, runs.front().dir, missing));
      continue;
    }
    fig.title = runs.size() == 1 ? curve_figure_title(runs.front().title.empty() ? labels.front() : runs.front().title,
                                                      step.name, step.kind)
                                 : fmt::format("step {} ({}): {}", step.name, step.kind, runs_phrase(labels));
    overlay.figures.push_back(fig);
  }
  for (size_t k = 1; k < runs.size(); ++k)
    for (const ResultCurves::Step& s : runs[k].steps)
      if (!find_step(runs.front(), s.name))
        overlay.notes.push_back(
            fmt::format("step {} ({} in {}) not drawn: not in {}", s.name, s.kind, runs[k].dir, runs.front().dir));
  if (overlay.figures.empty()) {
    std::string have;
    for (const ResultCurves& r : runs) have += fmt::format("; {} has {}", r.dir, step_names(r));
    throw InputError("fibra plot", "RESULT",
                     "the runs share no biaxial or shear step (a step of the same name and kind in every "
                     "directory)" +
                         have);
  }
  return overlay;
}

std::vector<std::string> draw_curve_overlay(const CurveOverlay& overlay) {
  const PlotOutcome outcome = plot_curves(overlay.figures);
  if (!outcome.ok())
    throw RunError(
        fmt::format("no plots: {} (the figures need Python 3 with matplotlib: /usr/bin/python3 by "
                    "default, or set FIBRA_PYTHON)",
                    outcome.error));
  return outcome.files;
}

}  // namespace fibra
