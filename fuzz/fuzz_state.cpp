// libFuzzer harness: a state file or checkpoint (read_state_file, read_checkpoint_file,
// solver/solver_state.hpp), then, when a state is
// read, its check against the woven sample's model and its restoring into a solver of it
// (check_start_state, StaticSolver::restore_state, as a run with [start] does). Any input either is restored or gives an InputError; any other exception,
// a crash, a sanitizer report, a leak or a hang is a finding (docs/sanitizers.md). The seeds are
// the state files of runs of examples/woven_sample and examples/crossed_fibers.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/run/resolve.hpp"
#include "fibra/solver/solver_state.hpp"
#include "fibra/solver/static_solver.hpp"
#include "fuzz_input_file.hpp"

namespace {

struct Target {
  fibra::Case c = fibra::read_case(FIBRA_SOURCE_DIR "/examples/woven_sample/woven_sample.toml");
  fibra::ResolvedCase resolved{c};
  const fibra::Model& model = resolved.model;
  fibra::StaticSolver solver{c, model, std::move(resolved.bodies)};
};

Target& target() {
  static Target t;
  return t;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  target();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // As given, then sealed (its length and checksum made to match, seal_state_bytes) so that
  // the fields behind the checksum are fuzzed too; read as a step's state and as a checkpoint.
  std::string bytes(reinterpret_cast<const char*>(data), size);
  for (int sealed = 0; sealed < 2; ++sealed) {
    if (sealed) fibra::seal_state_bytes(bytes);
    const std::string& path =
        fibra::fuzz::write_input(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), ".bin");
    try {
      const fibra::SolverState state = fibra::read_state_file(path);
      fibra::check_start_state(target().c, target().model, state, path);
      target().solver.restore_state(state);
    } catch (const fibra::InputError&) {
      // the expected answer to bad input
    }
    try {
      const fibra::Checkpoint checkpoint = fibra::read_checkpoint_file(path);
      fibra::check_start_state(target().c, target().model, checkpoint.state, path);
    } catch (const fibra::InputError&) {
    }
  }
  return 0;
}
