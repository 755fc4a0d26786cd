// Tests that write files: a scratch directory per test, and running the fibra program in it.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fibra::test {

/// The whole content of a file, byte for byte ("" if it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A fixture with a fresh directory TMP/PREFIX_TEST_PID per test, kept when the test fails
/// (to look at what it wrote) and removed otherwise.
class ScratchDirTest : public ::testing::Test {
 protected:
  explicit ScratchDirTest(std::string prefix) : m_prefix(std::move(prefix)) {}
  void SetUp() override {
    m_dir = std::filesystem::temp_directory_path() /
            (m_prefix + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
             std::to_string(static_cast<long>(::getpid())));
    std::filesystem::remove_all(m_dir);
    std::filesystem::create_directories(m_dir);
  }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) std::filesystem::remove_all(m_dir, ec);
  }
  std::string m_prefix;
  std::filesystem::path m_dir;
};

/// What a run of the fibra program gave.
struct CliResult {
  int code = -1;  ///< exit code (-1: did not exit normally)
  std::string out, err;
};

/// Runs `ENV fibra ARGS` (the program of this build) in `dir`, capturing stdout and stderr.
inline CliResult run_fibra(const std::filesystem::path& dir, const std::string& args, const std::string& env = "") {
  const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string cmd = "cd '" + dir.string() + "' && " + env + " '" + std::string(FIBRA_BINARY_DIR) + "/fibra' " +
                          args + " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace fibra::test
