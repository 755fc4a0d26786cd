// The malformed-input corpus (tests/malformed): case files broken as users and tools break
// them — syntax, types, ranges, references, degenerate geometry, sizes too large for memory,
// non-finite numbers, files that are not case files. Each one, given to `fibra check` and to
// `fibra run`, ends with exit code 2 and one message naming the file and the key, never a crash
// or an exception's own text. A TOML case names its key on its first line (`# expect: KEY`);
// the other files name theirs in kExpected below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "support/scratch_dir.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(FIBRA_SOURCE_DIR) / "tests" / "malformed";

/// The key named in the message for the files that cannot hold a `# expect:` line.
const std::map<std::string, std::string> kExpected = {
    {"binary_garbage.json", "(file)"},
    {"binary_garbage.toml", "(file)"},
    {"empty.toml", "material"},  // nothing in it: the first required key
    {"json_deep_nesting.json", "title"},
    {"json_duplicate_key.json", "material[0].young"},
    {"json_elements_float.json", "fiber[0].elements"},
    {"json_elements_uint64_max.json", "fiber[0].elements"},
    {"json_empty.json", "(file)"},
    {"json_fix_node_negative.json", "fix[0].node"},
    {"json_null_radius.json", "fiber[0].radius"},
    {"json_point_minus_1e999.json", "fiber[0].points[1][0]"},
    {"json_root_array.json", "(file)"},
    {"json_syntax_trailing_comma.json", "(file)"},
    {"json_syntax_truncated.json", "(file)"},
    {"json_type_young_string.json", "material[0].young"},
    {"json_young_1e999.json", "material[0].young"},
    {"nodes.csv", "(file)"},
    {"nodes_renamed.toml", "(file)"},
    {"picture.png", "(file)"},
    {"picture_renamed.toml", "(file)"},
};

/// The key a corpus file expects: its `# expect:` line, else kExpected ("" when neither).
std::string expected_key(const fs::path& file) {
  if (const auto it = kExpected.find(file.filename().string()); it != kExpected.end()) return it->second;
  std::ifstream in(file, std::ios::binary);
  std::string line;
  std::getline(in, line);
  const std::string tag = "# expect: ";
  return line.rfind(tag, 0) == 0 ? line.substr(tag.size()) : std::string();
}

std::vector<std::string> corpus_files() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(kCorpus, ec))
    if (e.is_regular_file()) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

/// Text that only an unhandled exception or a crash puts on stderr.
const char* const kCrashText[] = {"std::", "bad_alloc", "max_size()", "basic_string", "terminate called",
                                  "Segmentation fault", "core dumped", "Aborted"};

class Malformed : public test::ScratchDirTest, public ::testing::WithParamInterface<std::string> {
 protected:
  Malformed() : ScratchDirTest("fibra_malformed_") {}

  void expect_refused(const std::string& args, const fs::path& file, const std::string& key) const {
    const test::CliResult r = test::run_fibra(m_dir, args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out << r.err;
    for (const char* crash : kCrashText) EXPECT_EQ(r.err.find(crash), std::string::npos) << crash << "\n" << r.err;
    // "error: FILE: KEY: ..." on one line.
    EXPECT_EQ(r.err.rfind("error: " + file.string() + ": " + key + ":", 0), 0u)
        << "expected the file and the key \"" << key << "\"\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
};

TEST_P(Malformed, CheckAndRunRefuseItNamingTheFileAndTheKey) {
  const fs::path file = kCorpus / GetParam();
  const std::string key = expected_key(file);
  ASSERT_FALSE(key.empty()) << file << ": no `# expect: KEY` first line and no entry in kExpected";
  expect_refused("check '" + file.string() + "'", file, key);
  expect_refused("run '" + file.string() + "' --out out", file, key);
  // Nothing was run: no results.
  EXPECT_FALSE(fs::exists(m_dir / "out" / "history.csv"));
}

INSTANTIATE_TEST_SUITE_P(Corpus, Malformed, ::testing::ValuesIn(corpus_files()),
                         [](const ::testing::TestParamInfo<std::string>& param) {
                           std::string name = param.param;
                           for (char& ch : name)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return name;
                         });

// The corpus covers its kinds of input, and every entry of kExpected is a file of it.
TEST(MalformedCorpus, HoldsAtLeastFortyCasesOfEveryKind) {
  const std::vector<std::string> files = corpus_files();
  EXPECT_GE(files.size(), 40u);
  for (const char* prefix : {"toml_syntax_", "json_syntax_", "type_", "range_", "ref_", "degen_", "huge_",
                             "nonfinite_", "json_young_1e999", "binary_garbage", "empty", "picture", "nodes"})
    EXPECT_TRUE(std::any_of(files.begin(), files.end(), [&](const std::string& f) { return f.rfind(prefix, 0) == 0; }))
        << prefix;
  for (const auto& [name, key] : kExpected)
    EXPECT_TRUE(std::find(files.begin(), files.end(), name) != files.end()) << name;
}

}  // namespace
}  // namespace fibra
