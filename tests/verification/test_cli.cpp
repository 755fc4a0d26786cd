// The command-line program (FIBRA_BINARY_DIR/fibra) end to end: exit codes, error messages on
// stderr naming the file and the key, the outputs of a run that fails to converge, and the
// rigid-body outputs and binding errors.
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
#include <vector>

#include "fibra/io/case_reader.hpp"

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

// ------------------------------------------------------------------------------------------
// Rigid bodies and averaged bindings through the program: the bundle_pull example's outputs,
// and the binding errors that are found when the model is built (still exit code 2).

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string field;
  while (std::getline(ss, field, ',')) out.push_back(field);
  return out;
}

TEST_F(Cli, RunOfTheBundleExampleWritesTheBodyOutputs) {
  const fs::path file = fs::path(FIBRA_SOURCE_DIR) / "examples" / "bundle_pull" / "bundle_pull.toml";
  const Result r = fibra("run '" + file.string() + "' --out out");
  ASSERT_EQ(r.code, 0) << r.err;
  const fs::path out = m_dir / "out";

  // history.csv: the body's and the binding's columns.
  std::ifstream in(out / "history.csv");
  std::string header, line, last;
  ASSERT_TRUE(std::getline(in, header));
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  const std::vector<std::string> columns = split_csv(header);
  for (const char* name : {"body:grip:fx", "body:grip:mz", "body:grip:ux", "body:grip:rz", "binding:updates",
                           "binding:max_violation"})
    EXPECT_NE(std::find(columns.begin(), columns.end(), name), columns.end()) << name << " not in " << header;

  // The last row: the grip is where the example's last step puts it.
  const Case c = read_case(file.string());
  ASSERT_FALSE(c.steps.empty());
  ASSERT_EQ(c.steps.back().bodies.size(), 1u);
  ASSERT_TRUE(c.steps.back().bodies[0].displacement[0].has_value());
  const double prescribed = *c.steps.back().bodies[0].displacement[0];
  EXPECT_GT(prescribed, 0.0);
  const std::vector<std::string> row = split_csv(last);
  ASSERT_EQ(row.size(), columns.size()) << last;
  const size_t ux = std::find(columns.begin(), columns.end(), "body:grip:ux") - columns.begin();
  ASSERT_LT(ux, row.size());
  EXPECT_NEAR(std::stod(row[ux]), prescribed, 1e-12 * prescribed) << last;
  EXPECT_EQ(row[0], c.steps.back().name);

  // bodies.pvd and its .vtu files.
  EXPECT_TRUE(fs::is_regular_file(out / "bodies.pvd"));
  int vtus = 0;
  for (const fs::directory_entry& f : fs::directory_iterator(out)) {
    const std::string name = f.path().filename().string();
    if (name.rfind("bodies_", 0) == 0 && f.path().extension() == ".vtu") ++vtus;
  }
  EXPECT_GE(vtus, 1);
  EXPECT_NE(slurp(out / "bodies.pvd").find("bodies_"), std::string::npos);

  // summary.json counts the body and the binding.
  const nlohmann::json s = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(s.value("status", ""), "converged");
  ASSERT_TRUE(s.contains("counts")) << s.dump(2);
  EXPECT_EQ(s["counts"].value("bodies", -1), 1) << s.dump(2);
  EXPECT_EQ(s["counts"].value("bindings", -1), 1) << s.dump(2);
}

// Three fibers whose ends, bound to "grip", are not on one line (b is out of the plane z = 0).
const std::string kBound = R"(
[[material]]
name = "steel"
young = 210e9
poisson = 0.3

[[fiber]]
name = "a"
material = "steel"
radius = 1e-4
points = [[0, -1e-3, 0], [0.01, -1e-3, 0]]
elements = 2

[[fiber]]
name = "b"
material = "steel"
radius = 1e-4
points = [[0, 0, 1e-3], [0.01, 0, 1e-3]]
elements = 2

[[fiber]]
name = "c"
material = "steel"
radius = 1e-4
points = [[0, 1e-3, 0], [0.01, 1e-3, 0]]
elements = 2

[[fix]]
fiber = "a"
node = "first"

[[fix]]
fiber = "b"
node = "first"

[[fix]]
fiber = "c"
node = "first"

[[body]]
name = "grip"
center = [0.01, 0, 0]

[[binding]]
body = "grip"
ends = [{ fiber = "a", node = "last" }, { fiber = "b", node = "last" }, { fiber = "c", node = "last" }]

[[step]]
  [[step.body]]
  name = "grip"
  displacement = [1e-5, 0, 0]
)";

TEST_F(Cli, CheckAcceptsABindingOfThreeEndsNotOnALine) {
  write("bound.toml", kBound);
  const Result r = fibra("check bound.toml");
  EXPECT_EQ(r.code, 0) << r.err;
}

TEST_F(Cli, CheckRejectsABindingWhoseEndsLieOnOneLine) {
  // b moved into the plane z = 0: the three ends lie on the line x = 0.01, z = 0.
  write("collinear.toml",
        replace(kBound, "points = [[0, 0, 1e-3], [0.01, 0, 1e-3]]", "points = [[0, 0, 0], [0.01, 0, 0]]"));
  const Result r = fibra("check collinear.toml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("collinear.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("binding[0]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("one line"), std::string::npos) << r.err;
}

TEST_F(Cli, CheckRejectsABodyWithoutMembers) {
  // A second body that no [[binding]] names.
  write("lonely.toml", replace(kBound, "[[binding]]", "[[body]]\nname = \"spare\"\ncenter = [0, 0, 0]\n\n[[binding]]"));
  const Result r = fibra("check lonely.toml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("lonely.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("body[1]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("spare"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("has no members"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace fibra
