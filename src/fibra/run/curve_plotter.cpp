#include "fibra/run/curve_plotter.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "fibra/io/curve_plots.hpp"
#include "fibra/io/result_curves.hpp"

namespace fibra {

namespace fs = std::filesystem;

CurvePlotter::CurvePlotter(const Case& c, std::string dir) : m_case(c), m_dir(std::move(dir)) {
  std::error_code ec;
  for (const StepSpec& st : c.steps) {
    if (!st.is_test()) continue;
    const std::string stem = step_file_stem(st.name);
    fs::remove(fs::path(m_dir) / ("curves_" + stem + ".csv"), ec);
    for (const char* ext : {".png", ".svg", ".json"}) fs::remove(fs::path(m_dir) / "plots" / (stem + ext), ec);
  }
}

CurvePlotter::CurvePlotter(const Case& c, std::string dir, const nlohmann::json& resume)
    : m_case(c), m_dir(std::move(dir)) {
  m_plotted = resume.at("plotted").get<std::vector<int>>();
  m_files = resume.at("files").get<std::vector<std::string>>();
  m_error = resume.at("error").get<std::string>();
}

nlohmann::json CurvePlotter::resume_point() const {
  return {{"plotted", m_plotted}, {"files", m_files}, {"error", m_error}};
}

void CurvePlotter::plot(int step_index) {
  if (!m_case.output.plots || step_index < 0 || step_index >= static_cast<int>(m_case.steps.size())) return;
  if (std::find(m_plotted.begin(), m_plotted.end(), step_index) != m_plotted.end()) return;
  m_plotted.push_back(step_index);
  if (!m_error.empty()) return;
  const StepSpec& st = m_case.steps[step_index];
  const std::string stem = step_file_stem(st.name);
  const fs::path csv = fs::path(m_dir) / ("curves_" + stem + ".csv");
  std::error_code ec;
  if (!st.is_test() || !fs::is_regular_file(csv, ec)) return;
  const std::string title = m_case.title.empty() ? m_case.name : m_case.title;
  const std::string kind = StepSpec::kind_name(st.kind);
  const CurveFigure figure{st.name,
                           kind,
                           curve_figure_title(title, st.name, kind),
                           (fs::path(m_dir) / "plots" / stem).string(),
                           {{title, csv.string()}}};
  const auto t0 = std::chrono::steady_clock::now();
  const PlotOutcome outcome = plot_curves({figure});
  m_time += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const std::string& f : outcome.files) m_files.push_back(fs::path(f).lexically_relative(m_dir).generic_string());
  if (!outcome.ok())
    m_error = fmt::format(
        "{}. The curves are kept (curves_*.csv); draw them later with `fibra plot {}` (it needs "
        "Python 3 with matplotlib: /usr/bin/python3, or the one FIBRA_PYTHON names)",
        outcome.error, m_dir);
}

void CurvePlotter::add_to_summary(nlohmann::json& summary) const {
  summary["plots"] = m_files;
  if (!m_error.empty()) summary["plots_error"] = m_error;
}

}  // namespace fibra
