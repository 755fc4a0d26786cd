// libFuzzer harness: a TOML case file (parse_case_toml, io/case_reader.hpp). Any input either
// gives a Case or an InputError; any other exception, a crash, a sanitizer report, a leak or a
// hang is a finding (docs/sanitizers.md).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fuzz_limits.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)fibra::parse_case_toml(text, "fuzz.toml", fibra::fuzz::size_limits());
  } catch (const fibra::InputError&) {
    // the expected answer to bad input
  }
  return 0;
}
