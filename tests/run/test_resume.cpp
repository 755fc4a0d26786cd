// `fibra run --resume`: runs killed at chosen and at random increments of every kind of step
// (weave, relax, biaxial, shear), by SIGKILL or interrupted by SIGINT, go on from their
// checkpoint and end with the outputs of the run that was never stopped: the same history
// rows (all but the timing columns), curves, final nodes and step states, byte for byte, and
// the same solver counts. An edited case, a damaged checkpoint or a directory without one is
// refused, naming what is wrong.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "support/scratch_dir.hpp"

namespace fibra::test {
namespace {

namespace fs = std::filesystem;

// The woven sample of examples/woven_sample (2 x 2 tows of 3 fibers) with a shear test after
// its biaxial one, a checkpoint after every increment.
std::string resume_case(const std::string& checkpoint = "1", const std::string& shear_angle = "5.0") {
  std::ifstream in(fs::path(FIBRA_SOURCE_DIR) / "examples" / "woven_sample" / "woven_sample.toml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str() + "\n[[step]]\nname = \"shear\"\nkind = \"shear\"\nangle = " + shear_angle +
         "\nincrements = 2\n\n[output]\ncheckpoint = " + checkpoint + "\n";
}

using Rows = std::vector<std::vector<std::string>>;

// history.csv without its timing columns (wall time, detection and solve times).
Rows history(const fs::path& dir) {
  std::ifstream in(dir / "history.csv");
  Rows rows;
  std::set<size_t> timing;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
    if (rows.empty() && timing.empty())
      for (size_t k = 0; k < cells.size(); ++k)
        if (cells[k] == "wall_time" || cells[k] == "contact:detection_time" || cells[k] == "contact:solve_time")
          timing.insert(k);
    std::vector<std::string> kept;
    for (size_t k = 0; k < cells.size(); ++k)
      if (!timing.count(k)) kept.push_back(cells[k]);
    rows.push_back(kept);
  }
  return rows;
}

nlohmann::json summary(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in);
}

class Resume : public ScratchDirTest {
 protected:
  Resume() : ScratchDirTest("fibra_resume_") {}

  void write_case(const std::string& text, const std::string& name = "case.toml") {
    std::ofstream(m_dir / name) << text;
  }

  // A run of the case never stopped, into `whole`.
  void run_whole() {
    const CliResult r = run_fibra(m_dir, "run case.toml --out whole --threads 2");
    ASSERT_EQ(r.code, 0) << r.err;
  }

  // `dir` ends with the outputs of `whole`.
  void expect_same_outputs(const std::string& dir) {
    const Rows a = history(m_dir / "whole"), b = history(m_dir / dir);
    ASSERT_EQ(a.size(), b.size()) << dir;
    for (size_t k = 0; k < a.size(); ++k) ASSERT_EQ(a[k], b[k]) << dir << ": history row " << k;
    // nodes.csv, the curves, the collections, the step states and the ParaView files.
    std::vector<fs::path> files;
    for (const auto& e : fs::recursive_directory_iterator(m_dir / "whole")) {
      const fs::path rel = e.path().lexically_relative(m_dir / "whole");
      const std::string name = rel.filename().string(), ext = rel.extension().string();
      if (e.is_regular_file() && (name == "nodes.csv" || name.rfind("curves_", 0) == 0 || ext == ".pvd" ||
                                  ext == ".vtu" || ext == ".bin"))
        files.push_back(rel);
    }
    EXPECT_GE(files.size(), 5u);
    for (const fs::path& file : files)
      EXPECT_EQ(slurp(m_dir / "whole" / file), slurp(m_dir / dir / file)) << dir << ": " << file.string();
    const nlohmann::json sa = summary(m_dir / "whole"), sb = summary(m_dir / dir);
    EXPECT_EQ(sb["status"], "converged") << dir;
    for (const char* count : {"increments", "iterations", "cuts", "factorizations", "krylov_iterations"})
      EXPECT_EQ(sa["solver"][count], sb["solver"][count]) << dir << ": " << count;
    EXPECT_EQ(sa.value("fabric", nlohmann::json()), sb.value("fabric", nlohmann::json())) << dir;
    EXPECT_FALSE(fs::exists(m_dir / dir / "state" / "checkpoint.bin")) << dir << ": a finished run keeps no checkpoint";
  }

  // The increments (1-based, of the whole run) of each step of `whole`.
  std::map<std::string, std::vector<int>> increments_by_step() {
    std::map<std::string, std::vector<int>> out;
    const Rows rows = history(m_dir / "whole");
    for (size_t k = 2; k < rows.size(); ++k) out[rows[k][0]].push_back(static_cast<int>(k - 1));
    return out;
  }
};

TEST_F(Resume, RunsKilledInEveryKindOfStepGoOnAsIfNeverStopped) {
  write_case(resume_case());
  ASSERT_NO_FATAL_FAILURE(run_whole());
  // Kills at random increments (a fixed seed: the same ones every time), two per step; not at
  // a run's first increment, which leaves no checkpoint yet.
  std::mt19937 random(20261127);
  std::vector<int> kills;
  for (const auto& [step, incs] : increments_by_step()) {
    ASSERT_GE(incs.size(), 2u) << step;
    for (int k = 0; k < 2; ++k) {
      const int at = incs[std::uniform_int_distribution<size_t>(0, incs.size() - 1)(random)];
      kills.push_back(std::max(at, 2));
    }
  }
  for (int at : kills) {
    const std::string dir = "killed_" + std::to_string(at);
    const CliResult killed = run_fibra(m_dir, "run case.toml --out " + dir + " --threads 2",
                                       "FIBRA_DEBUG_KILL=" + std::to_string(at));
    ASSERT_NE(killed.code, 0) << "increment " << at << ": the run was not killed";
    // The killed run said how far it got; its checkpoint is the increment before.
    EXPECT_EQ(summary(m_dir / dir)["status"], "running");
    EXPECT_EQ(summary(m_dir / dir)["progress"]["total_increments"], at);
    const CliResult resumed = run_fibra(m_dir, "run case.toml --out " + dir + " --threads 2 --resume");
    ASSERT_EQ(resumed.code, 0) << "increment " << at << ": " << resumed.err;
    EXPECT_EQ(summary(m_dir / dir)["resumed_from"]["total_increments"], at - 1);
    expect_same_outputs(dir);
  }
}

// Starts `fibra run` in the background; stops it with `signal` once its summary reports at
// least `increments` converged increments; returns its exit status.
int stop_run(const fs::path& dir, const std::string& out, int increments, int signal) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (chdir(dir.c_str()) != 0) _exit(127);
    const std::string fibra = std::string(FIBRA_BINARY_DIR) + "/fibra";
    if (!freopen("/dev/null", "w", stdout) || !freopen("/dev/null", "w", stderr)) _exit(127);
    execl(fibra.c_str(), fibra.c_str(), "run", "case.toml", "--out", out.c_str(), "--threads", "2",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline) {
    int done = 0;
    try {
      std::ifstream in(dir / out / "summary.json");
      if (in) done = nlohmann::json::parse(in)["progress"]["total_increments"].get<int>();
    } catch (const std::exception&) {
      // being rewritten, or the final summary
    }
    if (done >= increments) break;
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  kill(pid, signal);
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

TEST_F(Resume, ARunKilledFromOutsideAtARandomMomentGoesOn) {
  write_case(resume_case());
  ASSERT_NO_FATAL_FAILURE(run_whole());
  const int total = summary(m_dir / "whole")["solver"]["increments"].get<int>();
  std::mt19937 random(4242);
  for (int k = 0; k < 2; ++k) {
    const int at = std::uniform_int_distribution<int>(3, total - 3)(random);
    const std::string dir = "sigkill_" + std::to_string(k);
    const int status = stop_run(m_dir, dir, at, SIGKILL);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the run ended before it was killed";
    const CliResult resumed = run_fibra(m_dir, "run case.toml --out " + dir + " --threads 2 --resume");
    ASSERT_EQ(resumed.code, 0) << resumed.err;
    expect_same_outputs(dir);
  }
}

TEST_F(Resume, AnInterruptedRunGoesOnFromItsLastIncrementWhateverTheCheckpointRate) {
  // Checkpoints only at step ends (the short steps of this case never last a minute): the
  // interrupted run writes its last converged increment's.
  write_case(resume_case("\"auto\""));
  ASSERT_NO_FATAL_FAILURE(run_whole());
  const int status = stop_run(m_dir, "interrupted", 45, SIGINT);
  ASSERT_TRUE(WIFEXITED(status)) << "not stopped cleanly";
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_EQ(summary(m_dir / "interrupted")["status"], "interrupted");
  const CliResult resumed = run_fibra(m_dir, "run case.toml --out interrupted --threads 2 --resume");
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_GE(summary(m_dir / "interrupted")["resumed_from"]["total_increments"].get<int>(), 45);
  expect_same_outputs("interrupted");
}

TEST_F(Resume, ARunInterruptedWithinAnIncrementGoesOnFromTheIncrementBefore) {
  // Ctrl-C just before the last Newton iteration of each step's last increment
  // (FIBRA_DEBUG_INTERRUPT): within the relax's release and the test levels' releases, the
  // solves a converged increment adds. The increment is the interrupted one: the run goes on
  // from the one before, as if never stopped.
  write_case(resume_case("\"auto\""));
  ASSERT_NO_FATAL_FAILURE(run_whole());
  ASSERT_EQ(summary(m_dir / "whole")["solver"]["cuts"], 0) << "the iterations below count converged increments only";
  const Rows rows = history(m_dir / "whole");
  const auto column = std::find(rows[0].begin(), rows[0].end(), "iterations");
  ASSERT_NE(column, rows[0].end());
  // Each step's last increment of two or more iterations (with one, the iteration before its
  // last is the previous increment's), and the run's Newton iterations up to its end.
  std::map<std::string, std::pair<int, int>> last;  // step: (increment, iterations to its end)
  int total = 0;
  for (size_t k = 2; k < rows.size(); ++k) {
    const int its = std::stoi(rows[k][column - rows[0].begin()]);
    total += its;
    if (its >= 2) last[rows[k][0]] = {static_cast<int>(k - 1), total};
  }
  ASSERT_EQ(last.size(), 4u);
  for (const auto& [step, at] : last) {
    const std::string dir = "interrupted_" + step;
    const CliResult stopped = run_fibra(m_dir, "run case.toml --out " + dir + " --threads 2",
                                        "FIBRA_DEBUG_INTERRUPT=" + std::to_string(at.second));
    EXPECT_EQ(stopped.code, 130) << step << ": " << stopped.err;
    EXPECT_EQ(summary(m_dir / dir)["status"], "interrupted") << step;
    const CliResult resumed = run_fibra(m_dir, "run case.toml --out " + dir + " --threads 2 --resume");
    ASSERT_EQ(resumed.code, 0) << step << ": " << resumed.err;
    EXPECT_EQ(summary(m_dir / dir)["resumed_from"]["total_increments"], at.first - 1) << step;
    expect_same_outputs(dir);
  }
}

TEST_F(Resume, AutoCheckpointsAtStepEndsOnShortSteps) {
  // Killed in the biaxial step: "auto" wrote the relax step's end, the run goes on from there.
  write_case(resume_case("\"auto\""));
  ASSERT_NO_FATAL_FAILURE(run_whole());
  const std::vector<int> pull = increments_by_step()["pull"];
  ASSERT_GE(pull.size(), 3u);
  const int at = pull[pull.size() / 2];
  ASSERT_NE(run_fibra(m_dir, "run case.toml --out killed --threads 2", "FIBRA_DEBUG_KILL=" + std::to_string(at)).code, 0);
  const CliResult resumed = run_fibra(m_dir, "run case.toml --out killed --threads 2 --resume");
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_EQ(summary(m_dir / "killed")["resumed_from"]["total_increments"].get<int>(), pull.front() - 1);
  expect_same_outputs("killed");
}

TEST_F(Resume, AnEditedCaseIsRefusedUnlessOnlyStepsNotYetStartedChanged) {
  write_case(resume_case("1", "3.0"));
  const std::vector<int> pull = [&] {
    const CliResult r = run_fibra(m_dir, "run case.toml --out whole --threads 2");
    EXPECT_EQ(r.code, 0) << r.err;
    return increments_by_step()["pull"];
  }();
  ASSERT_GE(pull.size(), 3u);
  const std::string kill = "FIBRA_DEBUG_KILL=" + std::to_string(pull[1]);
  ASSERT_NE(run_fibra(m_dir, "run case.toml --out killed --threads 2", kill).code, 0);
  // The biaxial step under way, edited: refused, naming the key, and nothing is overwritten.
  std::string text = resume_case("1", "3.0");
  const std::string strain = "strain = 0.01";
  ASSERT_NE(text.find(strain), std::string::npos);
  write_case(std::string(text).replace(text.find(strain), strain.size(), "strain = 0.02"));
  const std::string history_before = slurp(m_dir / "killed" / "history.csv");
  CliResult r = run_fibra(m_dir, "run case.toml --out killed --threads 2 --resume");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("step[2].strain"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("was 0.01, is 0.02"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(m_dir / "killed" / "history.csv"), history_before);
  // A material edited: refused likewise.
  write_case(std::string(text).replace(text.find("young = 72e9"), 12, "young = 70e9"));
  r = run_fibra(m_dir, "run case.toml --out killed --threads 2 --resume");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("material[0].young"), std::string::npos) << r.err;
  // The shear step, not yet started, edited: the run goes on, and ends as a run of the edited
  // case never stopped.
  write_case(resume_case("1", "5.0"));
  r = run_fibra(m_dir, "run case.toml --out killed --threads 2 --resume");
  ASSERT_EQ(r.code, 0) << r.err;
  fs::rename(m_dir / "whole", m_dir / "whole_3");
  ASSERT_NO_FATAL_FAILURE(run_whole());
  expect_same_outputs("killed");
}

// Load steps (no drag): the secant predictor's last motion, friction history and a pusher's
// prescribed displacement, in examples/three_point_bending.
TEST_F(Resume, LoadStepsWithFrictionGoOnAsIfNeverStopped) {
  std::ifstream in(fs::path(FIBRA_SOURCE_DIR) / "examples" / "three_point_bending" / "three_point_bending.toml");
  std::stringstream text;
  text << in.rdbuf();
  write_case(text.str() + "\n[output]\ncheckpoint = 1\n");
  ASSERT_NO_FATAL_FAILURE(run_whole());
  const int total = summary(m_dir / "whole")["solver"]["increments"].get<int>();
  ASSERT_GE(total, 4);
  std::mt19937 random(7);
  for (int k = 0; k < 3; ++k) {
    const int at = std::uniform_int_distribution<int>(2, total)(random);
    const std::string dir = "killed_" + std::to_string(k);
    ASSERT_NE(run_fibra(m_dir, "run case.toml --out " + dir + " --threads 2", "FIBRA_DEBUG_KILL=" + std::to_string(at)).code,
              0);
    const CliResult resumed = run_fibra(m_dir, "run case.toml --out " + dir + " --threads 2 --resume");
    ASSERT_EQ(resumed.code, 0) << "increment " << at << ": " << resumed.err;
    expect_same_outputs(dir);
  }
}

TEST_F(Resume, MissingDamagedAndFinishedAreNamed) {
  write_case(resume_case());
  // No run there.
  CliResult r = run_fibra(m_dir, "run case.toml --out nothing --threads 2 --resume");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--resume"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no checkpoint"), std::string::npos) << r.err;
  // A finished run.
  ASSERT_NO_FATAL_FAILURE(run_whole());
  r = run_fibra(m_dir, "run case.toml --out whole --threads 2 --resume");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("nothing to resume"), std::string::npos) << r.err;
  // A damaged checkpoint: one byte flipped in the middle.
  ASSERT_NE(run_fibra(m_dir, "run case.toml --out killed --threads 2", "FIBRA_DEBUG_KILL=30").code, 0);
  const fs::path file = m_dir / "killed" / "state" / "checkpoint.bin";
  std::string bytes = slurp(file);
  ASSERT_GT(bytes.size(), 100u);
  bytes[bytes.size() / 2] ^= 0x10;
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
  r = run_fibra(m_dir, "run case.toml --out killed --threads 2 --resume");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("checkpoint.bin"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("checksum"), std::string::npos) << r.err;
  // Truncated at every 1/16th: each refused by name, never a crash.
  bytes[bytes.size() / 2] ^= 0x10;
  for (int k = 0; k < 16; ++k) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() * k / 16);
    r = run_fibra(m_dir, "run case.toml --out killed --threads 2 --resume");
    EXPECT_EQ(r.code, 2) << k << "/16: " << r.err;
    EXPECT_NE(r.err.find("checkpoint.bin"), std::string::npos) << k << "/16: " << r.err;
  }
  // Restored whole, it resumes.
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
  r = run_fibra(m_dir, "run case.toml --out killed --threads 2 --resume");
  EXPECT_EQ(r.code, 0) << r.err;
  // A checkpoint of another case (the same fabric with 4 fibers per tow): its case differs.
  const fs::path other = m_dir / "other";
  fs::create_directories(other / "killed" / "state");
  std::string text = resume_case();
  text.replace(text.find("fibers = 3"), 10, "fibers = 4");
  std::ofstream(other / "case.toml") << text;
  std::ofstream(other / "killed" / "state" / "checkpoint.bin", std::ios::binary) << bytes;
  r = run_fibra(other, "run case.toml --out killed --threads 2 --resume");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("fabric.tow.fibers"), std::string::npos) << r.err;
  // "never": no checkpoint to go on from.
  write_case(resume_case("\"never\""));
  ASSERT_NE(run_fibra(m_dir, "run case.toml --out never --threads 2", "FIBRA_DEBUG_KILL=30").code, 0);
  r = run_fibra(m_dir, "run case.toml --out never --threads 2 --resume");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("no checkpoint"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace fibra::test
