// The command-line program (FIBRA_BINARY_DIR/fibra) end to end: exit codes, error messages on
// stderr naming the file and the key, and the outputs of a run that fails to converge.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace fibra {
namespace {

namespace fs = std::filesystem;

struct Result {
  int code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    m_dir = fs::temp_directory_path() /
            ("fibra_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
             std::to_string(static_cast<long>(::getpid())));
    fs::remove_all(m_dir);
    fs::create_directories(m_dir);
  }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) fs::remove_all(m_dir, ec);
  }

  // Runs `fibra ARGS` in the temporary directory, capturing stdout and stderr.
  Result fibra(const std::string& args) const {
    const fs::path out = m_dir / "stdout.txt", err = m_dir / "stderr.txt";
    const std::string cmd = "cd '" + m_dir.string() + "' && '" + std::string(FIBRA_BINARY_DIR) + "/fibra' " + args +
                            " > '" + out.string() + "' 2> '" + err.string() + "'";
    const int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = m_dir / name;
    std::ofstream(p) << text;
    return p;
  }

  fs::path m_dir;
};

const std::string kGood = R"(
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
  [[step.load]]
  fiber = "beam"
  node = "last"
  force = [0, 0, -1]
)";

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST_F(Cli, CheckAcceptsTheExample) {
  const Result r = fibra("check '" + std::string(FIBRA_SOURCE_DIR) + "/examples/cantilever/cantilever.toml'");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("valid"), std::string::npos) << r.out;
}

TEST_F(Cli, CheckRejectsAnOutOfRangePoissonRatio) {
  write("poisson.toml", replace(kGood, "poisson = 0.3", "poisson = 0.6"));
  const Result r = fibra("check poisson.toml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("poisson.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("material[0].poisson"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("0.6"), std::string::npos) << r.err;
}

TEST_F(Cli, CheckRejectsAnUnknownKey) {
  write("unknown.toml", replace(kGood, "radius = 0.01", "radiuss = 0.01"));
  const Result r = fibra("check unknown.toml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unknown.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("fiber[0].radiuss"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("\"radius\""), std::string::npos) << r.err;  // the suggestion
}

TEST_F(Cli, CheckRejectsAMissingMaterial) {
  // A fiber naming a material that is not defined ...
  write("undefined.toml", replace(kGood, "material = \"steel\"", "material = \"titanium\""));
  Result r = fibra("check undefined.toml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("undefined.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("fiber[0].material"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("titanium"), std::string::npos) << r.err;
  // ... and a file without any [[material]].
  write("none.toml", replace(kGood, "[[material]]\nname = \"steel\"\nyoung = 210e9\npoisson = 0.3\n", ""));
  r = fibra("check none.toml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("none.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": material:"), std::string::npos) << r.err;
}

TEST_F(Cli, RunThatCannotConvergeFailsAndKeepsItsOutputs) {
  // A huge load (tip deflection >> L by linear theory) in one increment, two Newton iterations,
  // no cuts allowed: the first increment must fail.
  write("diverge.toml", replace(replace(kGood, "force = [0, 0, -1]", "force = [0, 0, -1e7]"), "[[step]]",
                                "[solver]\nmax_cuts = 0\nmax_iterations = 2\n\n[[step]]\nname = \"crush\""));
  const Result r = fibra("run diverge.toml --out out");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.code, 2);  // not an input error
  EXPECT_NE(r.err.find("failed"), std::string::npos) << r.err;
  ASSERT_TRUE(fs::is_regular_file(m_dir / "out" / "history.csv")) << r.err;
  EXPECT_NE(slurp(m_dir / "out" / "history.csv").find("step,step_index,increment"), std::string::npos);
  ASSERT_TRUE(fs::is_regular_file(m_dir / "out" / "summary.json"));
  const nlohmann::json s = nlohmann::json::parse(slurp(m_dir / "out" / "summary.json"));
  EXPECT_EQ(s.value("status", ""), "failed");
  EXPECT_EQ(s.value("converged", true), false);
  ASSERT_TRUE(s.contains("stopped_at")) << s.dump(2);
  EXPECT_EQ(s["stopped_at"].value("step", ""), "crush");
  EXPECT_EQ(s["stopped_at"].value("load_factor", -1.0), 0.0);
  EXPECT_EQ(s["stopped_at"].value("attempted_load_factor", -1.0), 1.0);
  EXPECT_FALSE(s.value("message", "").empty());
}

TEST_F(Cli, RunOfAValidCaseSucceeds) {
  write("good.toml", kGood);
  const Result r = fibra("run good.toml --out out");
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* name : {"history.csv", "nodes.csv", "fibers.pvd", "summary.json"})
    EXPECT_TRUE(fs::is_regular_file(m_dir / "out" / name)) << name;
}

}  // namespace
}  // namespace fibra
