// Runs that go on from an earlier run's state ([start] from = DIR): weaving once and testing
// the woven sample many times must give what one run doing it all gives; and the state files
// refuse the wrong model, a truncated file and a step that did not end.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <iterator>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "fibra/body/bodies.hpp"
#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/io/case_writer.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/resolve.hpp"
#include "fibra/run/run_case.hpp"
#include "fibra/solver/solver_state.hpp"
#include "support/example_files.hpp"
#include "support/fabric_cases.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

std::vector<std::vector<double>> read_curves(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);  // header
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<double> row;
    std::stringstream ss(line);
    std::string field;
    std::getline(ss, field, ',');  // step name
    while (std::getline(ss, field, ',')) row.push_back(std::stod(field));
    rows.push_back(row);
  }
  return rows;
}

// history.csv as rows of (column name -> text).
std::vector<std::map<std::string, std::string>> read_history(const fs::path& file) {
  std::ifstream in(file);
  std::string line, field;
  std::getline(in, line);
  std::vector<std::string> names;
  for (std::stringstream ss(line); std::getline(ss, field, ',');) names.push_back(field);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::map<std::string, std::string> row;
    std::stringstream ss(line);
    for (size_t k = 0; k < names.size() && std::getline(ss, field, ','); ++k) row[names[k]] = field;
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json read_json(const fs::path& file) {
  std::ifstream in(file);
  return nlohmann::json::parse(in);
}

class Continue : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    s_dir = fs::temp_directory_path() / ("fibra_continue_" + std::to_string(static_cast<long>(::getpid())));
    fs::remove_all(s_dir);
    fs::create_directories(s_dir);
    // Woven, relaxed and pulled in one run (its states at the end of each step are kept).
    const Case c = parse_case_toml(test::plain_friction_sample(kPull), (s_dir / "fabric.toml").string());
    RunOptions options;
    options.out_dir = (s_dir / "whole").string();
    s_whole = run_case(c, options).result.status == RunResult::Status::Converged;
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(s_dir, ec);
  }
  static Case continued(const std::string& start, const std::string& steps) {
    return parse_case_toml("[start]\n" + start + "\n" + steps, (s_dir / "continued.toml").string());
  }

  // Runs c with its output in s_dir / sub.
  static RunReport run_in(const Case& c, const std::string& sub) {
    RunOptions options;
    options.out_dir = (s_dir / sub).string();
    return run_case(c, options);
  }
  // From the relaxed state, sheared by 40 degrees in one level with at most max_iterations
  // Newton iterations per increment (pseudo-time solves to pseudo_tolerance).
  static Case sheared_in_one_level(int max_iterations) {
    Case c = continued("from = \"whole\"\nstep = \"relax\"",
                       "[solver]\nmax_iterations = " + std::to_string(max_iterations) +
                           "\n[[step]]\nname = \"shear\"\nkind = \"shear\"\nangle = 40\nincrements = 1\n"
                           "max_increments = 400\n");
    c.solver.method.test_inexact = 0.0;
    return c;
  }

  static constexpr const char* kPull = "[[step]]\nname = \"pull\"\nkind = \"biaxial\"\nstrain = 0.004\nincrements = 2\n";
  static inline fs::path s_dir;
  static inline bool s_whole = false;
};

TEST_F(Continue, TestingFromTheRelaxedStateRepeatsTheWholeRun) {
  ASSERT_TRUE(s_whole);
  const fs::path whole = s_dir / "whole";
  for (const char* step : {"weave", "relax", "pull"}) EXPECT_TRUE(fs::is_regular_file(whole / "state" / (std::string(step) + ".bin")));
  const nlohmann::json summary = read_json(whole / "summary.json");
  ASSERT_EQ(summary["states"].size(), 3u);
  EXPECT_EQ(summary["states"][1]["step"], "relax");
  EXPECT_EQ(summary["states"][1]["file"], "state/relax.bin");

  const Case c = continued("from = \"whole\"\nstep = \"relax\"", kPull);
  EXPECT_EQ(c.start_step, "relax");
  EXPECT_EQ(c.steps.size(), 1u);
  const RunReport r = run_in(c, "pull");
  ASSERT_EQ(r.result.status, RunResult::Status::Converged) << r.result.message;
  // The same curve: rows (increment, load, strains, forces, shear, contact elements,
  // penetration) equal to the solver's tolerance. The levels' pseudo-time solves stop at a
  // hundredth of their drag force (solver.test_inexact), where the two runs' paths can part:
  // this run's first conjugate gradients have no factor left from the relax step. Measured:
  // 1.6e-6 N apart on the shear force (-0.1197 N).
  const auto a = read_curves(whole / "curves_pull.csv"), b = read_curves(s_dir / "pull" / "curves_pull.csv");
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), 3u);
  for (size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].size(), b[k].size());
    for (size_t i = 0; i < a[k].size(); ++i) {
      if (std::isnan(a[k][i])) {
        EXPECT_TRUE(std::isnan(b[k][i]));
        continue;
      }
      EXPECT_NEAR(b[k][i], a[k][i], 1e-5 * std::max(1.0, std::abs(a[k][i]))) << "row " << k << " column " << i;
    }
  }
  // The start row carries the relaxed tension (not zero: the edges hold the fabric).
  EXPECT_GT(b[0][4], 1.0);  // warp force [N]
  // So does history.csv's initial row: every body's force, moment, displacement and rotation
  // as the whole run's relax step left them.
  const auto hw = read_history(whole / "history.csv"), hp = read_history(s_dir / "pull" / "history.csv");
  ASSERT_FALSE(hp.empty());
  const auto relaxed = std::find_if(hw.rbegin(), hw.rend(), [](const auto& row) { return row.at("step") == "relax"; });
  ASSERT_NE(relaxed, hw.rend());
  EXPECT_EQ(hp.front().at("step"), "initial");
  int compared = 0;
  for (const auto& [name, text] : hp.front()) {
    if (name.rfind("body:", 0) != 0) continue;
    const double x = std::stod(text), y = std::stod(relaxed->at(name));
    EXPECT_NEAR(x, y, 1e-9 * std::max(1.0, std::abs(y))) << name;
    ++compared;
  }
  EXPECT_EQ(compared, 12 * 12);  // 8 tow ends and 4 edges, 12 columns each
  EXPECT_GT(std::abs(std::stod(hp.front().at("body:edge.x+:ux"))), 1e-7);
  // The ParaView collections: the start and each settled level (output.test_levels), not the
  // pseudo-time increments within the levels that history.csv lists.
  for (const char* collection : {"fibers.pvd", "contacts.pvd"}) {
    std::ifstream in(s_dir / "pull" / collection);
    const std::string pvd((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    size_t sets = 0;
    for (size_t at = pvd.find("<DataSet"); at != std::string::npos; at = pvd.find("<DataSet", at + 1)) ++sets;
    EXPECT_EQ(sets, std::string(collection) == "fibers.pvd" ? 3u : 2u) << collection;  // no contacts at the start
  }
  EXPECT_GT(hp.size(), 1u + 2u);  // the initial row and more increments than levels
  const nlohmann::json s = read_json(s_dir / "pull" / "summary.json");
  EXPECT_EQ(s["start"]["step"], "relax");
  EXPECT_EQ(s["states"].size(), 1u);
  EXPECT_EQ(s["states"][0]["step"], "pull");
}

TEST_F(Continue, WithoutAStepTheLastOneThatEnded) {
  ASSERT_TRUE(s_whole);
  EXPECT_EQ(continued("from = \"whole\"", kPull).start_step, "pull");
}

TEST_F(Continue, BadStartsAreNamed) {
  ASSERT_TRUE(s_whole);
  auto error = [&](const std::string& start, const std::string& text = kPull) {
    try {
      continued(start, text);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("from = \"nowhere\"").find("start.from: no result directory"), std::string::npos);
  EXPECT_NE(error("from = \"whole\"\nstep = \"relx\"").find("start.step: the run in"), std::string::npos);
  EXPECT_NE(error("from = \"whole\"\nstep = \"relx\"").find("did you mean \"relax\""), std::string::npos);
  EXPECT_NE(error("from = \"whole\"\nfrom_step = 1").find("start.from_step"), std::string::npos);
  EXPECT_NE(error("from = \"whole\"", "[fabric]\npattern = \"plain\"\n" + std::string(kPull)).find("fabric: a case with [start]"),
            std::string::npos);
  // A step whose state is missing (a run stopped within it).
  fs::copy(s_dir / "whole", s_dir / "partial", fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  fs::remove(s_dir / "partial" / "state" / "pull.bin");
  EXPECT_NE(error("from = \"partial\"\nstep = \"pull\"").find("did not end its step \"pull\""), std::string::npos);
  EXPECT_EQ(continued("from = \"partial\"", kPull).start_step, "relax");
}

TEST_F(Continue, StateFilesRefuseOtherModelsAndDamage) {
  ASSERT_TRUE(s_whole);
  const fs::path file = s_dir / "whole" / "state" / "relax.bin";
  const SolverState s = read_state_file(file.string());
  EXPECT_EQ(s.step, "relax");
  EXPECT_EQ(s.steps_done, 2);
  EXPECT_GT(s.contacts.size(), 0u);
  // Written back, read again: the same values.
  const fs::path copy = s_dir / "copy.bin";
  write_state_file(copy.string(), s);
  const SolverState t = read_state_file(copy.string());
  EXPECT_EQ(t.q, s.q);
  EXPECT_EQ(t.bodies, s.bodies);
  ASSERT_EQ(t.contacts.size(), s.contacts.size());
  EXPECT_EQ(t.contacts.back().friction_previous, s.contacts.back().friction_previous);
  EXPECT_EQ(t.disp, s.disp);
  // Truncated.
  const auto size = fs::file_size(copy);
  fs::resize_file(copy, size / 2);
  try {
    read_state_file(copy.string());
    ADD_FAILURE() << "a truncated state was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ends early"), std::string::npos) << e.what();
  }
  // Not a state file.
  std::ofstream(copy) << "title = \"x\"\n";
  EXPECT_THROW(read_state_file(copy.string()), InputError);
  // Another model: the same fabric with one more fiber per tow.
  const Case other = parse_case_toml(test::glass_fabric("plain", 2, 4, 5.0e-5, 1.25e-4, "tension = 0.5\n",
                                                        "[contact]\n[[step]]\nname = \"relax\"\nkind = \"relax\"\n"),
                                     (s_dir / "other.toml").string());
  const Model model = build_model(other);
  try {
    check_state_fits(s, model, BodySystem(other, model).num_bindings(), file.string());
    ADD_FAILURE() << "a state of another model was restored";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("belongs to another model"), std::string::npos) << e.what();
  }
}

// A test step's state keeps the drag that loaded its last level, and a run going on from it
// loads its first level with at least that drag (not from relax_drag again: on the 480-fiber
// biaxial test such a restart failed twice, some 10 minutes each, before it got back there).
TEST_F(Continue, ATestGoesOnWithTheDragThatLoadedItsLastLevel) {
  ASSERT_TRUE(s_whole);
  const fs::path whole = s_dir / "whole";
  EXPECT_EQ(read_state_file((whole / "state" / "relax.bin").string()).test_drag, 0.0);
  const SolverState pulled = read_state_file((whole / "state" / "pull.bin").string());
  // The drag of the last level's loading increment: the pull's last load factor's first row.
  const auto rows = read_history(whole / "history.csv");
  double first_loading = -1.0, last_loading = -1.0, load = -1.0;
  for (const auto& row : rows) {
    if (row.at("step") != "pull") continue;
    const double lf = std::stod(row.at("load_factor"));
    if (lf > load) last_loading = std::stod(row.at("relax:drag"));
    if (first_loading < 0.0) first_loading = last_loading;  // the method's first drag x k0
    load = lf;
  }
  ASSERT_GT(first_loading, 0.0);
  EXPECT_DOUBLE_EQ(pulled.test_drag, last_loading);
  EXPECT_GE(pulled.test_drag, first_loading);

  // Going on with a first drag of 1e-4 k0: without the restored drag the first increment
  // would take that.
  Case c = continued("from = \"whole\"\nstep = \"pull\"",
                     "[[step]]\nname = \"more\"\nkind = \"biaxial\"\nstrain = 0.002\nincrements = 1\n");
  c.solver.method.relax_drag = 1e-4;
  const RunReport r = run_in(c, "more");
  ASSERT_EQ(r.result.status, RunResult::Status::Converged) << r.result.message;
  const auto more = read_history(s_dir / "more" / "history.csv");
  ASSERT_GE(more.size(), 2u);
  EXPECT_EQ(more[1].at("step"), "more");
  EXPECT_GE(std::stod(more[1].at("relax:drag")), pulled.test_drag * (1.0 - 1e-12));

  // Older versions: tests/solver/test_solver_state.cpp, StateCounts.OlderVersionsAreRead.
}

// Test levels grow back after a cut. A 40-degree shear of the woven 2 x 2 sample asked in one
// level, with 4 Newton iterations per increment at most: the level is cut, and each level whose
// loading increment (the one that moves the edges) converges at the first attempt lets the next one
// grow by half. So from one level to the next the size is multiplied by 1.5 (grown) or 1 (the
// loading had failed), then halved once per failure of the new level's loading; the last level may
// take a remainder of less than a quarter of its size along (and be halved if it then fails).
// The pseudo-time solves go to pseudo_tolerance (test_inexact = 0). Each level is loaded at the
// stiffest drag (the weave's, which loads the first level); the sizes go 0.5, 0.25, 0.0625,
// 0.0625, 0.02344, 0.02344, 0.01758, 0.01758, 0.02637, 0.0166 (under ctest, one BLAS thread):
// grown once outright, twice then halved, every ratio allowed. With 6 to 8 iterations the levels
// load at their first attempt from the first cut on, the last taking the remainder (0.5, 0.25,
// 0.25); with 5 every level's loading fails at the size of the last one and is halved down to a
// remainder (0.5, 0.25, 0.125, 0.0625, 0.0625): nothing grows, so those do not test the rule;
// with 3 the shear does not reach its end.
TEST_F(Continue, TestLevelsGrowBackAfterACut) {
  ASSERT_TRUE(s_whole);
  const Case c = sheared_in_one_level(4);
  const RunReport r = run_in(c, "grow");
  ASSERT_EQ(r.result.status, RunResult::Status::Converged) << r.result.message;
  std::vector<double> levels;  // load factors of the levels, in order
  for (const auto& row : read_history(s_dir / "grow" / "history.csv")) {
    if (row.at("step") != "shear") continue;
    const double lf = std::stod(row.at("load_factor"));
    if (levels.empty() || lf > levels.back()) levels.push_back(lf);
  }
  ASSERT_GE(levels.size(), 3u);
  EXPECT_LT(levels[0], 1.0);  // the step's one level was cut
  EXPECT_DOUBLE_EQ(levels.back(), 1.0);
  std::vector<double> sizes;
  for (size_t k = 0; k < levels.size(); ++k) sizes.push_back(levels[k] - (k ? levels[k - 1] : 0.0));
  int grown = 0;
  std::printf("level sizes:");
  for (double size : sizes) std::printf(" %.4g", size);
  std::printf("\n");
  for (size_t k = 1; k + 1 < sizes.size(); ++k) {
    const double ratio = sizes[k] / sizes[k - 1];
    bool allowed = false;
    for (double base : {1.0, 1.5})
      for (double f = base; f > 1e-6; f *= 0.5) allowed = allowed || std::abs(ratio - f) < 1e-6 * f;
    // ... or a last level that took the remainder along, failed and was halved.
    for (double f = 0.5 * (1.0 - levels[k - 1]); f > 1e-6; f *= 0.5) allowed = allowed || std::abs(sizes[k] - f) < 1e-9;
    EXPECT_TRUE(allowed) << "level " << k << ": " << sizes[k - 1] << " then " << sizes[k];
    if (std::abs(ratio - 1.5) < 1e-6) ++grown;
  }
  EXPECT_GE(grown, 1);
  EXPECT_LE(sizes.back(), 1.25 * 1.5 * sizes[sizes.size() - 2] * (1.0 + 1e-9));
}

// A test level's settling increment (the edges held) that fails at the stiffest drag would
// fail again from the same state: it gets twice, then four times max_iterations, instead of
// cutting the next level's size. Sheared by 40 degrees in one level with 4 Newton iterations
// per increment, the settling at load factor 0.5 needs 5-8 of them: before this rule the level
// size was cut 12 times while every attempt stopped at the same residual (1e-4 on one thread,
// 4e-6 on two, tolerance 1e-6) and the run failed there.
TEST_F(Continue, SettlingAtTheStiffestDragGetsMoreIterations) {
  ASSERT_TRUE(s_whole);
  const Case c = sheared_in_one_level(4);
  const RunReport r = run_in(c, "settle");
  ASSERT_EQ(r.result.status, RunResult::Status::Converged) << r.result.message;
  const auto rows = read_history(s_dir / "settle" / "history.csv");
  ASSERT_FALSE(rows.empty());
  EXPECT_DOUBLE_EQ(std::stod(rows.back().at("load_factor")), 1.0);
}

// Where nothing is left to cut and the drag is at its stiffest, a run that still does not
// converge stops with a message that says so (not "after 12 cuts" of a load it did not move).
TEST_F(Continue, RelaxThatCannotConvergeSaysWhy) {
  ASSERT_TRUE(s_whole);
  const Case c = continued("from = \"whole\"\nstep = \"weave\"",
                           "[solver]\nmax_iterations = 1\n[[step]]\nname = \"settle\"\nkind = \"relax\"\n"
                           "increments = 1\n");
  const RunReport r = run_in(c, "stuck");
  ASSERT_EQ(r.result.status, RunResult::Status::Failed);
  EXPECT_NE(r.result.message.find("stiffest drag"), std::string::npos) << r.result.message;
  EXPECT_NE(r.result.message.find("nothing to cut"), std::string::npos) << r.result.message;
  EXPECT_NE(r.result.message.find("within 4 Newton iterations"), std::string::npos) << r.result.message;
}

TEST_F(Continue, OutputIntoItsOwnStartIsRefused) {
  ASSERT_TRUE(s_whole);
  const Case c = continued("from = \"whole\"\nstep = \"relax\"", kPull);
  RunOptions options;
  options.out_dir = (s_dir / "whole").string();
  EXPECT_THROW(run_case(c, options), InputError);
  EXPECT_TRUE(fs::is_regular_file(s_dir / "whole" / "state" / "relax.bin"));
}

// The paper's tests (examples/durville2010/*_biaxial*.toml, *_shear.toml) go on from the run of
// plain.toml or twill.toml (480 fibers, too long for the suite): each is read here against a
// stand-in result directory of its base case, holding that case as run and a state at the
// reference configuration (same model), so that their keys, steps and edge bodies are checked.
TEST(ContinueExamples, PaperTestsReadAgainstTheirBase) {
  const fs::path examples = fs::path(FIBRA_SOURCE_DIR) / "examples" / "durville2010";
  const fs::path tmp = fs::temp_directory_path() / ("fibra_continue_examples_" + std::to_string(static_cast<long>(::getpid())));
  fs::remove_all(tmp);
  int read = 0;
  for (const char* base : {"plain", "twill"}) {
    const Case c = read_case((examples / (std::string(base) + ".toml")).string());
    const Model model = build_model(c);
    const fs::path dir = tmp / base;
    fs::create_directories(dir / "state");
    std::ofstream(dir / "case.toml") << write_case_toml(c);
    const Case as_run = read_case((dir / "case.toml").string());
    ResolvedCase same = resolve_case(as_run);
    StaticSolver solver(as_run, same.model, std::move(same.bodies));
    write_state_file((dir / "state" / "relax.bin").string(), solver.save_state("relax", 2));
    for (const char* test : {"_biaxial", "_biaxial_half", "_shear"}) {
      const fs::path file = examples / (std::string(base) + test + ".toml");
      std::ifstream in(file);
      std::stringstream text;
      text << in.rdbuf();
      const std::string original = text.str();
      // Its [start] from, pointed at the stand-in.
      const std::string from = "from = \"../../out/durville2010_" + std::string(base) + "\"";
      const size_t at = original.find(from);
      ASSERT_NE(at, std::string::npos) << file << " does not go on from out/durville2010_" << base;
      const std::string edited =
          original.substr(0, at) + "from = \"" + dir.string() + "\"" + original.substr(at + from.size());
      const Case t = parse_case_toml(edited, file.string());
      EXPECT_EQ(t.start_step, "relax") << file;
      ASSERT_EQ(t.steps.size(), 1u) << file;
      EXPECT_TRUE(t.steps[0].is_test()) << file;
      EXPECT_EQ(build_model(t).num_dofs(), model.num_dofs()) << file;
      ++read;
    }
  }
  EXPECT_EQ(read, 6);
  // Every example that goes on from an earlier run is one of those read here.
  int continued = 0;
  for (const fs::directory_entry& dir : fs::directory_iterator(fs::path(FIBRA_SOURCE_DIR) / "examples"))
    if (dir.is_directory())
      for (const fs::directory_entry& f : fs::directory_iterator(dir.path()))
        continued += f.path().extension() == ".toml" && test::goes_on_from_an_earlier_run(f.path());
  EXPECT_EQ(continued, read);
  fs::remove_all(tmp);
}

}  // namespace
}  // namespace fibra
