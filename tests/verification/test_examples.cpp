// Every example case (examples/*/*.toml, found by globbing so that new examples are covered
// automatically) runs to convergence through run_case and writes its outputs. A woven example
// is crimped at the end of each weave and relax step, and each of its test curves
// (curves_STEP.csv) ends at the strain or angle its step prescribes, a biaxial pull's forces
// growing from level to level.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/run_case.hpp"
#include "support/example_files.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

// The examples that go on from an earlier run ([start]) are read by test_continue.cpp.
std::vector<fs::path> example_cases() { return test::standalone_examples(); }

TEST(Examples, ThereAreExamples) {
  const std::vector<fs::path> cases = example_cases();
  EXPECT_FALSE(cases.empty());
  EXPECT_NE(std::find(cases.begin(), cases.end(),
                      fs::path(FIBRA_SOURCE_DIR) / "examples" / "cantilever" / "cantilever.toml"),
            cases.end());
  // The default example (scripts/quickstart.sh): woven, then pulled.
  EXPECT_NE(std::find(cases.begin(), cases.end(),
                      fs::path(FIBRA_SOURCE_DIR) / "examples" / "woven_sample" / "woven_sample.toml"),
            cases.end());
}

// The cases of bench/cases (solver measurements, docs/performance.md) stay readable and build.
TEST(Examples, BenchCasesBuild) {
  int read = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(FIBRA_SOURCE_DIR) / "bench" / "cases")) {
    if (entry.path().extension() != ".toml") continue;
    SCOPED_TRACE(entry.path().string());
    const Case c = read_case(entry.path().string());
    const Model model = build_model(c);
    EXPECT_GT(model.fibers.size(), 0u);
    ++read;
  }
  EXPECT_GE(read, 1);
}

// The columns of a CSV file with one header line: name -> values ("nan" reads as NaN).
std::map<std::string, std::vector<double>> read_columns(const fs::path& file) {
  std::map<std::string, std::vector<double>> out;
  std::ifstream in(file);
  std::string line, cell;
  std::vector<std::string> names;
  if (std::getline(in, line)) {
    std::istringstream header(line);
    while (std::getline(header, cell, ',')) names.push_back(cell);
  }
  while (std::getline(in, line)) {
    std::istringstream row(line);
    for (size_t k = 0; k < names.size() && std::getline(row, cell, ','); ++k) {
      try {
        out[names[k]].push_back(std::stod(cell));
      } catch (const std::exception&) {
        out[names[k]].push_back(std::numeric_limits<double>::quiet_NaN());  // a text column (the step)
      }
    }
  }
  return out;
}

// The checks of a woven example's summary: crimped after weaving and relaxing, crossings
// resolved; each test curve ends where its step says, biaxial forces growing at every level.
void expect_woven_results(const fs::path& file, const fs::path& dir, const nlohmann::json& summary) {
  for (const nlohmann::json& st : summary.value("fabric_steps", nlohmann::json::array())) {
    const std::string kind = st.value("kind", "");
    if (kind != "weave" && kind != "relax") continue;
    EXPECT_GT(st.value("warp_crimp", 0.0), 0.0) << file << ": step " << st.value("step", "");
    EXPECT_GT(st.value("weft_crimp", 0.0), 0.0) << file << ": step " << st.value("step", "");
    EXPECT_LT(st.value("max_penetration_ratio", 1.0), 0.1) << file << ": step " << st.value("step", "");
  }
  for (const nlohmann::json& curve : summary.value("curves", nlohmann::json::array())) {
    const fs::path csv = dir / curve.value("file", "");
    ASSERT_TRUE(fs::is_regular_file(csv)) << file << ": no " << csv.filename();
    const auto col = read_columns(csv);
    const std::vector<double>& warp_strain = col.at("warp_strain");
    ASSERT_GE(warp_strain.size(), 2u) << csv;  // the step's start and at least one level
    EXPECT_EQ(warp_strain.front(), 0.0) << csv;
    if (curve.value("kind", "") == "biaxial") {
      const double strain = curve.value("strain", 0.0), ratio = curve.value("ratio", 0.0);
      EXPECT_NEAR(warp_strain.back(), strain, 1e-9) << csv;
      if (ratio > 0) {
        EXPECT_NEAR(col.at("weft_strain").back(), ratio * strain, 1e-9) << csv;
      }
      const std::vector<double>& warp = col.at("warp_force");
      const std::vector<double>& weft = col.at("weft_force");
      for (size_t k = 1; k < warp.size(); ++k) {
        EXPECT_GT(warp[k] * strain, warp[k - 1] * strain) << csv << ": row " << k;  // grows with the pull's sense
        if (ratio > 0) {
          EXPECT_GT(weft[k] * strain, weft[k - 1] * strain) << csv << ": row " << k;
        }
      }
    } else if (curve.value("kind", "") == "shear") {
      EXPECT_NEAR(col.at("shear_angle_deg").back(), curve.value("angle", 0.0), 1e-6) << csv;
    }
  }
}

class Example : public ::testing::TestWithParam<fs::path> {};

TEST_P(Example, RunsToConvergenceAndWritesItsOutputs) {
  const fs::path file = GetParam();
  const Case c = read_case(file.string());
  // Samples that take tens of minutes (examples/durville2010: 480 fibers) are read and meshed
  // here, run by hand and by their benchmark (a NOT_IN_TESTS file in the directory says why).
  if (fs::exists(file.parent_path() / "NOT_IN_TESTS")) {
    const Model m = build_model(c);
    EXPECT_GT(m.fibers.size(), 0u) << file;
    EXPECT_GT(m.num_dofs(), 0) << file;
    return;
  }
  const fs::path dir = fs::temp_directory_path() /
                       ("fibra_example_" + c.name + "_" + std::to_string(static_cast<long>(::getpid())));
  std::error_code ec;
  fs::remove_all(dir, ec);
  RunOptions options;
  options.out_dir = dir.string();
  const RunReport report = run_case(c, options);
  EXPECT_EQ(report.result.status, RunResult::Status::Converged) << file << ": " << report.result.message;
  for (const char* name : {"history.csv", "nodes.csv", "fibers.pvd", "summary.json"})
    EXPECT_TRUE(fs::is_regular_file(dir / name)) << file << ": no " << name;
  std::ifstream in(dir / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in, nullptr, false);
  ASSERT_FALSE(summary.is_discarded()) << file << ": summary.json does not parse";
  EXPECT_EQ(summary.value("status", ""), "converged") << file;
  EXPECT_TRUE(report.final_state.allFinite()) << file;
  if (c.fabric || !c.tows.empty()) expect_woven_results(file, dir, summary);
  std::printf("%s: %d increments, %d iterations, %.2f s\n", file.filename().c_str(), report.stats.increments,
              report.stats.iterations, report.wall_time);
  fs::remove_all(dir, ec);
}

INSTANTIATE_TEST_SUITE_P(All, Example, ::testing::ValuesIn(example_cases()), [](const auto& p) {
  std::string name = p.param.parent_path().filename().string() + "_" + p.param.stem().string();
  for (char& ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return name;
});

}  // namespace
}  // namespace fibra
