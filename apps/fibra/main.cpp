// fibra: command-line program. Parses arguments, validates the case, runs it, reports.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/run_case.hpp"
#include "fibra/solver/static_solver.hpp"

namespace {

void on_interrupt(int) { fibra::interrupt_flag().store(true); }

bool interactive() { return isatty(STDERR_FILENO) && std::getenv("CI") == nullptr; }

int check(const std::string& path) {
  const fibra::Case c = fibra::read_case(path);
  const fibra::Model model = fibra::build_model(c);
  fibra::StaticSolver solver(c, model);  // resolves every node reference
  fmt::print("{}: valid: {} materials, {} fibers, {} nodes, {} dofs, {} steps\n", path, c.materials.size(),
             c.fibers.size(), model.num_nodes(), model.num_dofs(), c.steps.size());
  return 0;
}

int run(const std::string& path, std::string out, int threads) {
  const fibra::Case c = fibra::read_case(path);
  if (out.empty()) out = (std::filesystem::path("out") / c.name).string();
  fibra::RunOptions options;
  options.out_dir = out;
  options.threads = threads;
  const bool tty = interactive();
  if (tty) options.progress = [](const std::string& line) { fmt::print(stderr, "\r\033[K{}", line); };
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  const fibra::RunReport r = fibra::run_case(c, options);
  if (tty) fmt::print(stderr, "\n");
  const auto& s = r.stats;
  if (r.result.status == fibra::RunResult::Status::Converged) {
    fmt::print("{}: converged: {} increments, {} Newton iterations, {:.2f} s ({} nodes, {} dofs)\n", path,
               s.increments, s.iterations, r.wall_time, r.nodes, r.dofs);
    fmt::print("results in {}/ (fibers.pvd, history.csv, nodes.csv, summary.json)\n", out);
    return 0;
  }
  fmt::print(stderr, "{}: {}: {}\n", path, r.result.status_name(), r.result.message);
  if (!r.result.residual_history.empty()) {
    fmt::print(stderr, "  residual history of the last attempt:");
    for (double v : r.result.residual_history) fmt::print(stderr, " {:.3e}", v);
    fmt::print(stderr, "\n");
  }
  fmt::print(stderr, "outputs of every converged increment kept in {}/ (see summary.json)\n", out);
  return r.result.status == fibra::RunResult::Status::Interrupted ? 130 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  // OpenMP threads that spin after a parallel region starve CHOLMOD's BLAS threads on small
  // machines; libgomp reads its wait policy at load time, so set it and start again.
  if (std::getenv("OMP_WAIT_POLICY") == nullptr) {
    setenv("OMP_WAIT_POLICY", "passive", 1);
    execv("/proc/self/exe", argv);
  }
  CLI::App app{"fibra: woven fabrics and fiber assemblies simulated at the scale of their fibers"};
  app.require_subcommand(1);
  std::string case_path, out;
  int threads = 0;
  auto* run_cmd = app.add_subcommand("run", "run a case file (TOML or JSON)");
  run_cmd->add_option("case", case_path, "case file")->required();
  run_cmd->add_option("--out", out, "output directory (default out/<case name>)");
  run_cmd->add_option("--threads", threads, "OpenMP threads (default: all cores)")->check(CLI::NonNegativeNumber);
  auto* check_cmd = app.add_subcommand("check", "validate a case file without running it");
  check_cmd->add_option("case", case_path, "case file")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    if (*run_cmd) return run(case_path, out, threads);
    return check(case_path);
  } catch (const fibra::InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 3;
  }
}
