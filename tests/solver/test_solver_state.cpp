// State files (solver/solver_state.hpp) whose counts announce more than the file holds: each is
// refused with an InputError before anything of that size is allocated (found by
// fuzz/fuzz_state.cpp; docs/sanitizers.md). The files are a small state written by
// write_state_file with one count overwritten.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "fibra/core/error.hpp"
#include "fibra/solver/solver_state.hpp"

namespace fibra::test {
namespace {

namespace fs = std::filesystem;

// A state of 18 dofs, two body values, one contact element, one moment and one prescribed dof.
SolverState small_state() {
  SolverState s;
  s.model = {18, 1, 0, 0};
  s.reference = VecX::LinSpaced(18, 0.0, 1.0);
  s.step = "press";
  s.steps_done = 1;
  s.q = s.reference;
  s.bodies = {1.0, 2.0};
  s.contacts.resize(1);
  s.force_end = VecX::Zero(18);
  s.moments[1] = {Vec3(1, 2, 3), Vec3(4, 5, 6)};
  s.disp[4] = {0.0, 1e-3};
  return s;
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class StateCounts : public ::testing::Test {
 protected:
  void SetUp() override {
    m_dir = fs::path(FIBRA_BINARY_DIR) / "test_solver_state";
    fs::create_directories(m_dir);
    write_state_file((m_dir / "state.bin").string(), small_state());
    m_bytes = read_bytes(m_dir / "state.bin");
  }
  // Offset of the 8-byte count written after `before` bytes of fields, counted from the end of
  // the header (magic line, version, four sizes).
  static std::size_t offset(std::size_t before) { return 12 + 4 + 4 * 8 + before; }
  // The file with the count at `at` replaced by `count`; what reading it throws.
  std::string read_with_count(std::size_t at, std::uint64_t count) {
    std::string bytes = m_bytes;
    std::memcpy(bytes.data() + at, &count, sizeof(count));
    const fs::path path = m_dir / "patched.bin";
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    try {
      read_state_file(path.string());
    } catch (const InputError& e) {
      return e.what();
    }
    return "read";
  }
  fs::path m_dir;
  std::string m_bytes;
};

TEST_F(StateCounts, TheSmallStateReadsBack) {
  const SolverState s = read_state_file((m_dir / "state.bin").string());
  EXPECT_EQ(s.q, small_state().q);
  EXPECT_EQ(s.bodies.size(), 2u);
  EXPECT_EQ(s.contacts.size(), 1u);
}

TEST_F(StateCounts, CountsBeyondTheFileAreRefusedBeforeAllocating) {
  // Fields before each count: reference (8 + 18 * 8), step (8 + 5), steps_done (4), q (8 + 18 * 8).
  const std::size_t reference = offset(0);
  const std::size_t bodies = offset(8 + 144 + 8 + 5 + 4 + 8 + 144);
  const std::size_t contacts = bodies + 8 + 2 * 8;
  // The bodies' count: up to 2^40 values passed the former bound (8 TiB).
  EXPECT_NE(read_with_count(bodies, std::uint64_t{1} << 39).find("ends early"), std::string::npos);
  // The contacts' count: 2^39 elements of a few hundred bytes each.
  EXPECT_NE(read_with_count(contacts, std::uint64_t{1} << 39).find("ends early"), std::string::npos);
  // A count within the file's bounds but beyond what is left of it.
  EXPECT_NE(read_with_count(bodies, 1000).find("ends early"), std::string::npos);
  // The dofs' own bound still applies first.
  EXPECT_NE(read_with_count(reference, 19).find("at most 18 expected"), std::string::npos);
}

}  // namespace
}  // namespace fibra::test
