// Every example case (examples/*/*.toml, found by globbing so that new examples are covered
// automatically) runs to convergence through run_case and writes its outputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
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
