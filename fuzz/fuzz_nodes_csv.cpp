// libFuzzer harness: a nodes.csv read back into the state of a model (read_nodes_csv,
// io/nodes_csv.hpp; `fibra slice` reads it), here the model of examples/crossed_fibers. Any input
// either gives a state or an InputError; any other exception, a crash, a sanitizer report, a
// leak or a hang is a finding (docs/sanitizers.md).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/io/nodes_csv.hpp"
#include "fibra/model/model.hpp"
#include "fuzz_input_file.hpp"

namespace {

const fibra::Model& model() {
  static const fibra::Model m =
      fibra::build_model(fibra::read_case(FIBRA_SOURCE_DIR "/examples/crossed_fibers/crossed_fibers.toml"));
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  model();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = fibra::fuzz::write_input(data, size, ".csv");
  try {
    (void)fibra::read_nodes_csv(path, model());
  } catch (const fibra::InputError&) {
    // the expected answer to bad input
  }
  return 0;
}
