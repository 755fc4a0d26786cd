// Output directories that cannot be written: refused before the run starts (exit code 2, the
// path named), or a write that fails during the run (exit code 3, the step and the increment
// named, the run stopped there with what it wrote before kept).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "fibra/io/case_reader.hpp"
#include "fibra/run/run_case.hpp"
#include "support/scratch_dir.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

const std::string kCase = R"(
[[material]]
name = "steel"
young = 210e9
poisson = 0.3

[[fiber]]
name = "beam"
material = "steel"
radius = 0.01
points = [[0, 0, 0], [1, 0, 0]]
elements = 4

[[fix]]
fiber = "beam"
node = "first"

[[step]]
name = "load"
increments = 5
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, -1]
)";

class OutputErrors : public test::ScratchDirTest {
 protected:
  OutputErrors() : ScratchDirTest("fibra_output_errors_") {}
  void SetUp() override {
    ScratchDirTest::SetUp();
    std::ofstream(m_dir / "beam.toml") << kCase;
  }
  test::CliResult run(const std::string& out) const { return test::run_fibra(m_dir, "run beam.toml --out '" + out + "'"); }
  static size_t lines(const fs::path& p) {
    const std::string text = test::slurp(p);
    return static_cast<size_t>(std::count(text.begin(), text.end(), '\n'));
  }
};

TEST_F(OutputErrors, AFileInPlaceOfTheDirectoryIsRefusedBeforeTheRun) {
  std::ofstream(m_dir / "taken") << "not a directory";
  const test::CliResult r = run("taken");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("error: taken: (output directory): exists and is not a directory", 0), 0u) << r.err;
  EXPECT_EQ(test::slurp(m_dir / "taken"), "not a directory");
}

TEST_F(OutputErrors, AFileInPlaceOfASubfolderIsRefusedBeforeTheRun) {
  for (const char* sub : {"fibers", "lines", "state"}) {
    SCOPED_TRACE(sub);
    fs::remove_all(m_dir / "out");
    fs::create_directories(m_dir / "out");
    std::ofstream(m_dir / "out" / sub) << "x";
    const test::CliResult r = run("out");
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.rfind("error: " + (fs::path("out") / sub).string() + ": (output directory):", 0), 0u) << r.err;
    EXPECT_FALSE(fs::exists(m_dir / "out" / "history.csv"));
  }
}

TEST_F(OutputErrors, ADirectoryThatCannotBeCreatedIsRefusedBeforeTheRun) {
  // /proc takes no new directory, not even from root.
  const test::CliResult r = run("/proc/fibra_no_such_dir/out");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("error: /proc/fibra_no_such_dir/out: (output directory): cannot create the directory", 0), 0u)
      << r.err;
}

// The .vtu of increment 3 cannot take its name (a non-empty directory is in its place, which a
// new run does not remove): the run stops there, saying where, and keeps what it wrote.
TEST_F(OutputErrors, AFailedWriteDuringTheRunStopsItAtThatIncrement) {
  fs::create_directories(m_dir / "out" / "fibers" / "fibers_000003.vtu" / "in_the_way");
  const test::CliResult r = run("out");
  EXPECT_EQ(r.code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("step \"load\" (1 of 1), increment 3 (load factor 0.6): writing the outputs failed: "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("fibers_000003.vtu"), std::string::npos) << r.err;
  // The initial row and increments 1 to 3 (the history row of an increment comes before its
  // ParaView files); the collections list the increments written whole, 0 to 2.
  EXPECT_EQ(lines(m_dir / "out" / "history.csv"), 1u + 4u);
  const std::string pvd = test::slurp(m_dir / "out" / "fibers.pvd");
  EXPECT_NE(pvd.find("fibers/fibers_000002.vtu"), std::string::npos) << pvd;
  EXPECT_EQ(pvd.find("fibers_000003.vtu"), std::string::npos) << pvd;
  EXPECT_FALSE(fs::exists(m_dir / "out" / "fibers" / "fibers_000004.vtu"));
  const nlohmann::json summary = nlohmann::json::parse(test::slurp(m_dir / "out" / "summary.json"));
  EXPECT_EQ(summary["status"], "output_failed");
  EXPECT_NE(summary["message"].get<std::string>().find("increment 3"), std::string::npos);
}

// Each ParaView series is in its own subfolder, referenced by its collection with a relative path.
TEST_F(OutputErrors, SeriesAreInSubfoldersOfTheOutputDirectory) {
  const test::CliResult r = run("out");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* series : {"fibers", "lines"}) {
    SCOPED_TRACE(series);
    const std::string pvd = test::slurp(m_dir / "out" / (std::string(series) + ".pvd"));
    const std::string first = std::string(series) + "/" + series + "_000000.vtu";
    EXPECT_NE(pvd.find("file=\"" + first + "\""), std::string::npos) << pvd;
    EXPECT_TRUE(fs::is_regular_file(m_dir / "out" / first));
    EXPECT_TRUE(fs::is_regular_file(m_dir / "out" / series / (std::string(series) + "_000005.vtu")));
  }
  for (const auto& e : fs::directory_iterator(m_dir / "out"))
    EXPECT_NE(e.path().extension(), ".vtu") << e.path();
}

// summary.json exists from the run's start, "running" with the last converged increment, so
// that a run killed by the system says how far it got; the final summary replaces it.
TEST_F(OutputErrors, TheSummarySaysHowFarARunningRunGot) {
  Case c = parse_case_toml(kCase, (m_dir / "beam.toml").string());
  RunOptions options;
  options.out_dir = (m_dir / "running").string();
  std::vector<nlohmann::json> seen;  // the summary as each increment starts being reported
  options.progress = [&](const std::string&) {
    seen.push_back(nlohmann::json::parse(test::slurp(m_dir / "running" / "summary.json")));
  };
  const RunReport r = run_case(c, options);
  ASSERT_EQ(r.result.status, RunResult::Status::Converged) << r.result.message;
  ASSERT_EQ(seen.size(), 5u);
  for (size_t k = 0; k < seen.size(); ++k) {
    EXPECT_EQ(seen[k]["status"], "running");
    // The progress line of increment k + 1 comes before its outputs: the summary has the one before.
    EXPECT_EQ(seen[k]["progress"]["total_increments"], static_cast<int>(k));
    EXPECT_EQ(seen[k]["progress"]["steps"], 1);
  }
  EXPECT_EQ(seen[4]["progress"]["step"], "load");
  EXPECT_NEAR(seen[4]["progress"]["load_factor"].get<double>(), 0.8, 1e-12);
  const nlohmann::json final = nlohmann::json::parse(test::slurp(m_dir / "running" / "summary.json"));
  EXPECT_EQ(final["status"], "converged");
  EXPECT_FALSE(final.contains("progress"));
}

}  // namespace
}  // namespace fibra
