#include "fibra/io/curve_plots.hpp"

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

extern char** environ;

namespace fibra {
namespace {

namespace fs = std::filesystem;

constexpr const char* kScriptName = "plot_curves.py";
/// Longest a plotting run may take, unless $FIBRA_PLOT_TIMEOUT says otherwise [s]: a hung Python
/// must not hold up a simulation. Drawing takes about a second; matplotlib's first start on a
/// machine builds its font cache (tens of seconds).
constexpr int kDefaultTimeout = 300;

int plot_timeout() {
  const char* env = std::getenv("FIBRA_PLOT_TIMEOUT");
  const int t = env ? std::atoi(env) : 0;
  return t > 0 ? t : kDefaultTimeout;
}

/// What a child process did: its exit, and everything it wrote on stdout and stderr.
struct ChildOutput {
  std::string spawn_error;  ///< non-empty when it could not be started
  int exit_code = -1;       ///< when it exited
  int signal = 0;           ///< when a signal killed it
  bool timed_out = false;   ///< killed after `timeout` seconds
  std::string output;
};

/// Runs argv[0] (searched on PATH unless it holds a '/') with stdin from /dev/null, stdout and
/// stderr captured together. The child gets its own process group: a Ctrl-C meant for fibra
/// (which then stops cleanly and plots what it has) does not kill the plotting. Killed (with its
/// group) after `timeout` seconds.
ChildOutput run_captured(const std::vector<std::string>& argv, int timeout) {
  ChildOutput r;
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    r.spawn_error = fmt::format("cannot create a pipe: {}", std::strerror(errno));
    return r;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attr, 0);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], &actions, &attr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  close(fds[1]);
  if (rc != 0) {
    close(fds[0]);
    r.spawn_error = std::strerror(rc);
    return r;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(timeout);
  char buf[4096];
  for (;;) {
    int wait_ms = -1;  // once killed, until the pipe closes
    if (!r.timed_out) {
      wait_ms = static_cast<int>(
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count());
      if (wait_ms <= 0) {
        kill(-pid, SIGKILL);
        r.timed_out = true;
        continue;
      }
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = poll(&p, 1, wait_ms);
    if (ready < 0 && errno != EINTR) break;
    if (ready <= 0) continue;
    const ssize_t n = read(fds[0], buf, sizeof buf);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      break;
    }
    r.output.append(buf, static_cast<size_t>(n));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      r.spawn_error = fmt::format("cannot wait for it: {}", std::strerror(errno));
      return r;
    }
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  return r;
}

/// The last `count` non-blank lines of a child's output (a traceback ends with its reason).
std::string tail_lines(const std::string& text, size_t count) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (line.find_first_not_of(" \t\r") != std::string::npos) lines.push_back(line);
  const size_t first = lines.size() > count ? lines.size() - count : 0;
  std::string out;
  for (size_t k = first; k < lines.size(); ++k) out += (k > first ? "\n  " : "") + lines[k];
  return out;
}

/// The job file the script reads (see plot_curves.py).
nlohmann::json job_json(const std::vector<CurveFigure>& figures) {
  nlohmann::json figs = nlohmann::json::array();
  for (const CurveFigure& f : figures) {
    nlohmann::json runs = nlohmann::json::array();
    for (const CurveRun& r : f.runs) runs.push_back({{"label", r.label}, {"csv", r.csv}});
    figs.push_back({{"step", f.step}, {"kind", f.kind}, {"title", f.title}, {"stem", f.stem}, {"runs", runs}});
  }
  return {{"figures", figs}};
}

/// Writes the job next to the first figure (a directory we write into anyway) under a unique
/// name; returns its path, or empty with `error` set.
std::string write_job(const std::vector<CurveFigure>& figures, std::string& error) {
  const fs::path dir = fs::path(figures.front().stem).parent_path();
  std::error_code ec;
  if (!dir.empty()) fs::create_directories(dir, ec);
  if (ec) {
    error = fmt::format("cannot create the directory '{}': {}", dir.string(), ec.message());
    return "";
  }
  std::string name = ((dir.empty() ? fs::path(".") : dir) / ".plot_job_XXXXXX.json").string();
  const int fd = mkstemps(name.data(), 5);
  if (fd < 0) {
    error = fmt::format("cannot create a job file in '{}': {}", dir.string(), std::strerror(errno));
    return "";
  }
  close(fd);
  std::ofstream out(name, std::ios::trunc);
  out << job_json(figures).dump(1) << "\n";
  out.close();
  if (!out) {
    error = fmt::format("cannot write '{}'", name);
    fs::remove(name, ec);
    return "";
  }
  return name;
}

}  // namespace

std::string plot_python() {
  const char* env = std::getenv("FIBRA_PYTHON");
  return env && *env ? env : "/usr/bin/python3";
}

std::string plot_script_places() {
  if (const char* env = std::getenv("FIBRA_SHARE_DIR"); env && *env) return fmt::format("{} (FIBRA_SHARE_DIR)", env);
  std::string places;
#ifdef FIBRA_SHARE_SOURCE_DIR
  places = std::string(FIBRA_SHARE_SOURCE_DIR) + " (the source tree), ";
#endif
  return places + "<directory of the fibra program>/../share/fibra; set FIBRA_SHARE_DIR to the directory of " +
         kScriptName;
}

std::string plot_script() {
  std::error_code ec;
  // An explicit FIBRA_SHARE_DIR is the only place looked at: a wrong one must show, not be
  // papered over by another copy of the script.
  if (const char* env = std::getenv("FIBRA_SHARE_DIR"); env && *env) {
    const fs::path p = fs::path(env) / kScriptName;
    return fs::is_regular_file(p, ec) ? p.string() : "";
  }
#ifdef FIBRA_SHARE_SOURCE_DIR
  if (const fs::path p = fs::path(FIBRA_SHARE_SOURCE_DIR) / kScriptName; fs::is_regular_file(p, ec)) return p.string();
#endif
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path p = (exe.parent_path() / ".." / "share" / "fibra" / kScriptName).lexically_normal();
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  return "";
}

PlotOutcome plot_curves(const std::vector<CurveFigure>& figures) {
  PlotOutcome outcome;
  if (figures.empty()) return outcome;
  const std::string script = plot_script();
  if (script.empty()) {
    outcome.error = fmt::format("{} not found in {}", kScriptName, plot_script_places());
    return outcome;
  }
  const std::string python = plot_python();
  const std::string job = write_job(figures, outcome.error);
  if (job.empty()) return outcome;
  const int timeout = plot_timeout();
  const ChildOutput child = run_captured({python, script, "--job", job}, timeout);
  std::error_code ec;
  fs::remove(job, ec);
  const std::string command = python + " " + script;
  const std::string said = tail_lines(child.output, 12);
  if (!child.spawn_error.empty())
    outcome.error = fmt::format("cannot run {}: {}", python, child.spawn_error);
  else if (child.timed_out)
    outcome.error = fmt::format("{} did not finish within {} s and was stopped", command, timeout);
  else if (child.signal != 0)
    outcome.error = fmt::format("{} was killed by signal {} ({})", command, child.signal, strsignal(child.signal));
  else if (child.exit_code != 0)
    outcome.error = fmt::format("{} exited with code {}{}{}", command, child.exit_code, said.empty() ? "" : ": ", said);
  if (!outcome.ok()) return outcome;
  for (const CurveFigure& f : figures)
    for (const char* ext : {".png", ".svg", ".json"}) {
      const std::string file = f.stem + ext;
      if (fs::is_regular_file(file, ec))
        outcome.files.push_back(file);
      else if (outcome.ok())
        outcome.error = fmt::format("{} exited normally but did not write '{}'", command, file);
    }
  return outcome;
}

}  // namespace fibra
