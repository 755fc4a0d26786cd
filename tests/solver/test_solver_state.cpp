// State and checkpoint files (solver/solver_state.hpp): written and read back; truncated at
// every 1/16th of their length, with a byte flipped, of a later version or of the other kind,
// each is refused with an InputError naming the file; version 1 and 2 files (no checksum) are
// still read. Counts that announce more than the file holds are refused before anything of
// that size is allocated (found by fuzz/fuzz_state.cpp; docs/sanitizers.md): the files are a
// small state with one count overwritten and the checksum made to match.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
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
    // A directory per test: ctest runs the tests of this fixture side by side (-j), and a shared
    // state.bin was read by one while another rewrote it.
    m_dir = fs::path(FIBRA_BINARY_DIR) / "test_solver_state" /
            ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::create_directories(m_dir);
    write_state_file((m_dir / "state.bin").string(), small_state());
    m_bytes = read_bytes(m_dir / "state.bin");
  }
  // Offset of the 8-byte count written after `before` bytes of fields, counted from the end of
  // the header (magic line, version, kind, length, four sizes).
  static std::size_t offset(std::size_t before) { return 12 + 4 + 4 + 8 + 4 * 8 + before; }
  // The file with the count at `at` replaced by `count`; what reading it throws.
  std::string read_with_count(std::size_t at, std::uint64_t count) {
    std::string bytes = m_bytes;
    std::memcpy(bytes.data() + at, &count, sizeof(count));
    seal_state_bytes(bytes);
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

// What reading `bytes` as a state file (or as a checkpoint) throws; "read" when it reads.
std::string read_error(const fs::path& dir, const std::string& bytes, bool checkpoint = false) {
  const fs::path path = dir / "damaged.bin";
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  try {
    if (checkpoint)
      read_checkpoint_file(path.string());
    else
      read_state_file(path.string());
  } catch (const InputError& e) {
    return e.what();
  }
  return "read";
}

// A checkpoint of the small state: a step half done, a factorization to make again, the
// detector's memory of two fibers.
Checkpoint small_checkpoint() {
  Checkpoint c;
  c.state = small_state();
  SolverProgress& p = c.progress;
  p.step = 1;
  p.total = 17;
  p.lambda = 0.5;
  p.dl = 0.25;
  p.last_motion = VecX::Constant(18, 1e-6);
  p.done = 3;
  p.attempts = 4;
  p.relaxed = false;
  p.failed_refusal = "a refusal";
  p.force_start = VecX::Constant(18, 2.0);
  p.relax_drag = 123.0;
  p.settling_residual = 3.5e-3;
  p.project_hessians = false;
  p.reuse_factor = true;
  p.krylov_budget = 40;
  p.stats.iterations = 99;
  p.stats.factorizations = 7;
  p.stats.indefinite_iterations = 5;
  p.detection_memory = {{1, 2, 3}, {}};
  p.factor.valid = true;
  p.factor.q = VecX::LinSpaced(18, 1.0, 2.0);
  p.factor.contacts.resize(2);
  p.factor.friction = {0.2, 5e-7};
  p.factor.drag.stiffness = 1e3;
  p.factor.drag.director_weight = 100.0;
  p.factor.drag.axial_weight = 0.01;
  p.factor.drag.anchor = VecX::Zero(18);
  p.factor.moments = {{1, Vec3(0, 0, 1)}};
  p.factor.fixed.assign(18, 0);
  p.factor.fixed[0] = 1;
  p.factor.shift = 1e-12;
  c.run = R"({"writer": {}})";
  c.case_text = "title = \"x\"\n";
  c.case_file = "case.toml";
  return c;
}

TEST_F(StateCounts, ACheckpointReadsBackWhole) {
  const Checkpoint written = small_checkpoint();
  write_checkpoint_file((m_dir / "checkpoint.bin").string(), written);
  const Checkpoint c = read_checkpoint_file((m_dir / "checkpoint.bin").string());
  EXPECT_EQ(c.state.q, written.state.q);
  EXPECT_EQ(c.progress.step, 1);
  EXPECT_EQ(c.progress.total, 17);
  EXPECT_EQ(c.progress.lambda, 0.5);
  EXPECT_EQ(c.progress.last_motion, written.progress.last_motion);
  EXPECT_EQ(c.progress.failed_refusal, "a refusal");
  EXPECT_EQ(c.progress.force_start, written.progress.force_start);
  EXPECT_EQ(c.progress.relax_drag, 123.0);
  EXPECT_EQ(c.progress.settling_residual, 3.5e-3);
  EXPECT_FALSE(c.progress.project_hessians);
  EXPECT_TRUE(c.progress.reuse_factor);
  EXPECT_EQ(c.progress.krylov_budget, 40);
  EXPECT_EQ(c.progress.stats.iterations, 99);
  EXPECT_EQ(c.progress.stats.factorizations, 7);
  EXPECT_EQ(c.progress.stats.indefinite_iterations, 5);
  EXPECT_EQ(c.progress.detection_memory, written.progress.detection_memory);
  ASSERT_TRUE(c.progress.factor.valid);
  EXPECT_EQ(c.progress.factor.q, written.progress.factor.q);
  EXPECT_EQ(c.progress.factor.contacts.size(), 2u);
  EXPECT_EQ(c.progress.factor.friction.mu, 0.2);
  EXPECT_EQ(c.progress.factor.drag.stiffness, 1e3);
  EXPECT_EQ(c.progress.factor.drag.director_weight, 100.0);
  EXPECT_EQ(c.progress.factor.drag.axial_weight, 0.01);
  EXPECT_EQ(c.progress.factor.drag.anchor, written.progress.factor.drag.anchor);
  EXPECT_EQ(c.progress.factor.moments.size(), 1u);
  EXPECT_EQ(c.progress.factor.fixed, written.progress.factor.fixed);
  EXPECT_EQ(c.progress.factor.shift, 1e-12);
  EXPECT_EQ(c.run, written.run);
  EXPECT_EQ(c.case_text, written.case_text);
  EXPECT_EQ(c.case_file, "case.toml");
}

// A factorization made without the drag on the positions (a release's) is not kept: the
// record has no position weight, and a resumed run would factorize another matrix.
TEST_F(StateCounts, AReleasesFactorizationIsNotKept) {
  Checkpoint written = small_checkpoint();
  written.progress.factor.drag.position_weight = 0.0;
  write_checkpoint_file((m_dir / "checkpoint.bin").string(), written);
  const Checkpoint c = read_checkpoint_file((m_dir / "checkpoint.bin").string());
  EXPECT_FALSE(c.progress.factor.valid);
  EXPECT_EQ(c.progress.krylov_budget, 40);
  EXPECT_EQ(c.run, written.run);
}

// A state with empty lists (no bodies, contacts, moments nor prescribed dofs) reads back: in
// the sanitized build, an empty list's copy took a null pointer (found by fuzz_state).
TEST_F(StateCounts, EmptyListsReadBack) {
  SolverState s = small_state();
  s.bodies.clear();
  s.contacts.clear();
  s.moments.clear();
  s.disp.clear();
  write_state_file((m_dir / "empty.bin").string(), s);
  const SolverState t = read_state_file((m_dir / "empty.bin").string());
  EXPECT_TRUE(t.bodies.empty() && t.contacts.empty() && t.moments.empty() && t.disp.empty());
  EXPECT_EQ(t.q, s.q);
}

TEST_F(StateCounts, TruncatedFlippedForeignAndLaterFilesAreNamed) {
  write_checkpoint_file((m_dir / "checkpoint.bin").string(), small_checkpoint());
  for (const bool checkpoint : {false, true}) {
    const std::string bytes = checkpoint ? read_bytes(m_dir / "checkpoint.bin") : m_bytes;
    for (int k = 0; k < 16; ++k) {
      const std::string e = read_error(m_dir, bytes.substr(0, bytes.size() * k / 16), checkpoint);
      EXPECT_NE(e.find("damaged.bin"), std::string::npos) << k << "/16: " << e;
      EXPECT_TRUE(e.find("ends early") != std::string::npos || e.find("not a fibra state file") != std::string::npos)
          << k << "/16: " << e;
    }
    // A byte flipped anywhere after the header's length field: the checksum.
    for (const std::size_t at : {std::size_t{40}, bytes.size() / 3, bytes.size() / 2, bytes.size() - 20}) {
      std::string flipped = bytes;
      flipped[at] = static_cast<char>(flipped[at] ^ 0x01);
      EXPECT_NE(read_error(m_dir, flipped, checkpoint).find("checksum"), std::string::npos) << at;
    }
    // A later version, by its number.
    std::string later = bytes;
    const std::uint32_t version = 99;
    std::memcpy(later.data() + 12, &version, 4);
    EXPECT_NE(read_error(m_dir, later, checkpoint).find("version 99"), std::string::npos);
    // Trailing bytes: the length says so.
    EXPECT_NE(read_error(m_dir, bytes + "x", checkpoint).find("corrupt"), std::string::npos);
    // The other kind of file.
    EXPECT_NE(read_error(m_dir, bytes, !checkpoint).find(checkpoint ? "a checkpoint, not a step's state" : "not a checkpoint"),
              std::string::npos);
  }
  // Not a state file at all.
  EXPECT_NE(read_error(m_dir, "title = \"x\"\n").find("not a fibra state file"), std::string::npos);
}

// Files of versions 1 and 2 (no kind, length nor checksum) are read: a version-2 state
// written by an earlier fibra (tests/solver/fixtures/state_v2.bin: small_state() with a test
// drag of 250 N/m), and the same without the drag as version 1.
TEST_F(StateCounts, OlderVersionsAreRead) {
  const std::string v2 = read_bytes(fs::path(FIBRA_SOURCE_DIR) / "tests" / "solver" / "fixtures" / "state_v2.bin");
  ASSERT_FALSE(v2.empty());
  std::ofstream(m_dir / "v2.bin", std::ios::binary) << v2;
  const SolverState s2 = read_state_file((m_dir / "v2.bin").string());
  EXPECT_EQ(s2.q, small_state().q);
  EXPECT_EQ(s2.test_drag, 250.0);
  EXPECT_EQ(s2.disp, small_state().disp);
  const std::string end_mark = "end of state\n";
  ASSERT_EQ(v2.substr(v2.size() - end_mark.size()), end_mark);
  std::string v1 = v2;
  v1.erase(v1.size() - end_mark.size() - 8, 8);
  const std::uint32_t one = 1;
  v1.replace(12, 4, reinterpret_cast<const char*>(&one), 4);
  std::ofstream(m_dir / "v1.bin", std::ios::binary) << v1;
  const SolverState s1 = read_state_file((m_dir / "v1.bin").string());
  EXPECT_EQ(s1.test_drag, 0.0);
  EXPECT_EQ(s1.q, small_state().q);
  // A version-2 file cut short: named, as a version-3 one is.
  EXPECT_NE(read_error(m_dir, v2.substr(0, v2.size() / 2)).find("ends early"), std::string::npos);
}

// An older checkpoint, made from small_checkpoint() written today (version 6, no factor) by
// cutting `count` bytes at `offset` from the settling residual (found by its value, 3.5e-3:
// 8 bytes, then the projection flag of version 5, 1 byte, then the count of indefinite
// iterations of version 6, 4 bytes) and writing `version` into the header.
Checkpoint older_checkpoint(const fs::path& dir, std::size_t offset, std::size_t count, std::uint32_t version) {
  Checkpoint written = small_checkpoint();
  written.progress.factor = FactorSource{};
  write_checkpoint_file((dir / "checkpoint.bin").string(), written);
  std::string bytes = read_bytes(dir / "checkpoint.bin");
  const double field = 3.5e-3;
  const std::string pattern(reinterpret_cast<const char*>(&field), 8);
  const std::size_t at = bytes.find(pattern);
  EXPECT_NE(at, std::string::npos);
  EXPECT_EQ(bytes.find(pattern, at + 1), std::string::npos);
  EXPECT_EQ(bytes[at + 8], '\0');  // the projection flag, false in small_checkpoint
  const std::int32_t indefinite = 5;
  EXPECT_EQ(bytes.compare(at + 9, 4, reinterpret_cast<const char*>(&indefinite), 4), 0);
  bytes.erase(at + offset, count);
  bytes.replace(12, 4, reinterpret_cast<const char*>(&version), 4);
  seal_state_bytes(bytes);
  const fs::path file = dir / ("v" + std::to_string(version) + ".bin");
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
  return read_checkpoint_file(file.string());
}

// A version-3 checkpoint (no settling residual) is read, and resumes as before the field: the
// last settling increment's residual unknown (infinite).
TEST_F(StateCounts, VersionThreeCheckpointsAreRead) {
  const Checkpoint c = older_checkpoint(m_dir, 0, 13, 3);
  EXPECT_EQ(c.progress.settling_residual, std::numeric_limits<double>::infinity());
  EXPECT_EQ(c.progress.relax_drag, 123.0);
  EXPECT_EQ(c.progress.detection_memory, small_checkpoint().progress.detection_memory);
  EXPECT_FALSE(c.progress.factor.valid);
  EXPECT_EQ(c.case_text, small_checkpoint().case_text);
}

// A version-4 checkpoint (no projection flag) is read, and resumes with the projection on, as a
// run starts.
TEST_F(StateCounts, VersionFourCheckpointsAreRead) {
  const Checkpoint c = older_checkpoint(m_dir, 8, 5, 4);
  EXPECT_TRUE(c.progress.project_hessians);
  EXPECT_EQ(c.progress.settling_residual, 3.5e-3);
  EXPECT_EQ(c.progress.relax_drag, 123.0);
  EXPECT_FALSE(c.progress.factor.valid);
  EXPECT_EQ(c.case_text, small_checkpoint().case_text);
}

// A version-5 checkpoint (no count of indefinite iterations) is read, the count starting at 0.
TEST_F(StateCounts, VersionFiveCheckpointsAreRead) {
  const Checkpoint c = older_checkpoint(m_dir, 9, 4, 5);
  EXPECT_EQ(c.progress.stats.indefinite_iterations, 0);
  EXPECT_EQ(c.progress.stats.factorizations, 7);
  EXPECT_EQ(c.progress.settling_residual, 3.5e-3);
  EXPECT_FALSE(c.progress.project_hessians);
  EXPECT_EQ(c.case_text, small_checkpoint().case_text);
}

}  // namespace
}  // namespace fibra::test
