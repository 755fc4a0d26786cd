// The robustness corpus's run time (tests/robustness/cases, docs/robustness.md): every case
// solved with the library as `fibra run` solves it (default settings, no output files), one
// benchmark per case and one for the whole corpus, so that the regression check
// (scripts/bench.sh) catches a solver change that makes the user's cases slower.
//
//   BM_Corpus/<case>        one case: wall time; counters newton (iterations), increments, converged,
//                           factorizations, shifted (iterations solved with a shifted factor)
//   BM_RobustnessCorpus     every case in turn: the corpus's total wall time
//
// Cases that fail today (known failures) are timed too: the time to fail is what a user waits.
// Run with OMP_WAIT_POLICY=passive (scripts/bench.sh sets it).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/resolve.hpp"
#include "fibra/solver/static_solver.hpp"

namespace {

using namespace fibra;

std::vector<std::filesystem::path> corpus_cases() {
  std::vector<std::filesystem::path> files;
  const std::filesystem::path dir = std::filesystem::path(FIBRA_SOURCE_DIR) / "tests" / "robustness" / "cases";
  if (!std::filesystem::is_directory(dir)) return files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".toml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

struct Outcome {
  bool converged = false;
  int iterations = 0;
  int increments = 0;
  int factorizations = 0;
  int shifted = 0;  // Newton iterations solved with a shifted factor
};

Outcome solve(const std::filesystem::path& file) {
  const Case c = read_case(file.string());
  ResolvedCase resolved = resolve_case(c);
  StaticSolver solver(c, resolved.model, std::move(resolved.bodies));
  const RunResult r = solver.run([](const IncrementInfo&, const VecX&) {});
  const SolverStats& st = solver.stats();
  return {r.status == RunResult::Status::Converged, st.iterations, st.increments, st.factorizations,
          st.shifted_iterations};
}

void BM_Corpus(benchmark::State& state, const std::filesystem::path& file) {
  Outcome o;
  for (auto _ : state) o = solve(file);
  state.counters["newton"] = o.iterations;
  state.counters["increments"] = o.increments;
  state.counters["converged"] = o.converged ? 1 : 0;
  state.counters["factorizations"] = o.factorizations;
  state.counters["shifted"] = o.shifted;
}

void BM_RobustnessCorpus(benchmark::State& state) {
  const std::vector<std::filesystem::path> files = corpus_cases();
  int converged = 0, iterations = 0;
  for (auto _ : state) {
    converged = iterations = 0;
    for (const auto& f : files) {
      const Outcome o = solve(f);
      converged += o.converged ? 1 : 0;
      iterations += o.iterations;
    }
  }
  state.counters["cases"] = static_cast<double>(files.size());
  state.counters["converged"] = converged;
  state.counters["newton"] = iterations;
}

const bool registered = [] {
  for (const auto& f : corpus_cases())
    benchmark::RegisterBenchmark(("BM_Corpus/" + f.stem().string()).c_str(), BM_Corpus, f)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1)
        ->UseRealTime();
  benchmark::RegisterBenchmark("BM_RobustnessCorpus", BM_RobustnessCorpus)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1)
      ->UseRealTime();
  return true;
}();

}  // namespace
